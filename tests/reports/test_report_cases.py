"""The report cases: exact answers that are right, throws drawn as the env draws them, and the helpers."""

import math

import numpy as np
import pytest

from box_toss_env.physics import Box, scenes, simulate
from reports import cases, document
from reports.timing import best_of, best_time


@pytest.fixture(scope="module")
def exact():
    return {case.name: case for case in cases.exact_cases()}


def test_the_corner_impact_case_is_a_single_impact_then_free_flight(exact):
    case = exact["corner_impact"]
    assert 0.0 < case.contact_time < case.duration
    assert not case.touches_again()
    assert case.after_impact[1] > 0.0  # it leaves the floor


@pytest.mark.parametrize("name", ["free_flight", "corner_impact", "flat_drop", "resting"])
def test_the_robust_solver_meets_the_closed_forms_to_rounding(exact, name):
    """The closed forms agree with the solver that is exact on them: a check of the answers themselves."""
    case = exact[name]
    for exponent in (5, 9):
        dt = cases.dt_of(exponent)
        final = simulate(case.scene("robust", dt), steps=case.steps(dt)).final_state[0]
        assert case.error(final, dt) <= 1e-12


def test_free_flight_error_of_the_seed_is_g_t_dt_over_2(exact):
    case = exact["free_flight"]
    dt = cases.dt_of(8)
    final = simulate(case.scene("seed", dt), steps=case.steps(dt)).final_state[0]
    assert case.error(final, dt) == pytest.approx(-case.base.gravity * 1.0 * dt / 2, rel=1e-9)


def test_flat_drop_apex_time_and_slide_distance_follow_the_formulas(exact):
    drop = exact["flat_drop"]
    assert drop.height == pytest.approx(1.0)
    assert drop.duration == pytest.approx(1.5 * math.sqrt(2.0 / 9.81))
    slide = exact["slide"]
    box = slide.box
    stopped = np.array([box.position[0] + 2.0**2 / (2 * 0.3 * 9.81), 0.1, 0.0, 0.0, 0.0, 0.0])
    assert slide.error(stopped, 0.01) == pytest.approx(0.0, abs=1e-12)


def test_energy_is_kinetic_plus_potential():
    box = Box(length=2.0, width=1.0, mass=3.0)
    state = np.array([0.0, 2.0, 0.0, 1.0, -2.0, 0.5])
    expected = 0.5 * 3.0 * 5.0 + 0.5 * box.inertia * 0.25 + 3.0 * 9.81 * 2.0
    assert cases.energy(box, -9.81, state) == pytest.approx(expected)
    assert cases.lowest_corner(box, np.array([0.0, 0.5, 0.0, 0, 0, 0])) == pytest.approx(0.0)


def test_other_engines_get_the_same_toss(exact):
    toss = exact["corner_impact"].toss
    box = exact["corner_impact"].box
    assert (toss.length, toss.width, toss.mass, toss.angle, toss.omega) == (
        box.length,
        box.width,
        box.mass,
        box.angle,
        box.spin,
    )
    assert toss.gravity == 0.0 and toss.friction == 0.0 and toss.restitution == 0.5


def test_seeded_throws_are_the_envs_throws_and_reproducible():
    first, second = cases.seeded_throws(8, seed=3), cases.seeded_throws(8, seed=3)
    np.testing.assert_array_equal(first.initial, second.initial)
    assert first.initial.shape == (8, 6) and first.params.shape == (8, 7)
    config = first.config
    assert np.all(
        (first.initial[:, 1] >= config.release_height_range[0])
        & (first.initial[:, 1] <= config.release_height_range[1])
    )
    assert np.all(np.hypot(first.initial[:, 3], first.initial[:, 4]) <= config.max_speed + 1e-12)
    assert not np.array_equal(cases.seeded_throws(8, seed=4).initial, first.initial)
    states, stats = first.run("robust", 1 / 256)
    assert not first.blown_up(states, stats).any()


def test_report_scenes_are_what_they_say():
    assert cases.embedded(0.25).boxes[0].position[1] == pytest.approx(0.25)
    assert cases.far_toss(1e5).boxes[0].position[0] == 1e5
    assert cases.thin_toss(200).boxes[0].width == pytest.approx(0.005)
    assert cases.mass_toss(1e3).boxes[0].mass == 1e3
    assert cases.fast_impact(50.0).boxes[0].velocity == (0.0, -50.0)
    assert cases.friction_corner_hit(1.0, 0.5).gravity == 0.0
    assert scenes.toss().boxes[0].length == cases.thin_toss(10).boxes[0].length * 0.4


def test_best_time_warms_up_then_takes_the_minimum():
    calls = []

    def work():
        calls.append(1)

    assert best_time(work, repeats=3, budget=1.0) > 0.0
    assert len(calls) > 3  # warm-up and batched repeats
    durations = iter([5.0, 3.0, 1.0, 2.0])
    assert best_of(lambda: next(durations), repeats=3, budget=100.0) == 1.0  # 5.0 was the warm-up


def test_readme_section_is_created_then_only_its_block_rewritten(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text("# Title\n\ntext\n")
    document.update_readme("precision", "first", readme)
    document.update_readme("stability", "other", readme)
    document.update_readme("precision", "second | row", readme)
    text = readme.read_text()
    assert text.startswith("# Title\n\ntext\n\n<!-- reports:start -->")
    assert text.rstrip().endswith("<!-- reports:end -->")
    assert "second | row" in text and "first" not in text and "other" in text
    assert text.index("reports:precision:start") < text.index("reports:stability:start")
