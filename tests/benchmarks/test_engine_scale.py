"""The Box2D v3 adapter and the side-by-side scale benchmark, on tiny cases (no timing asserted)."""

import math

import numpy as np
import pytest

from benchmarks import engine_scale
from benchmarks.other_scenes import BOX2D3_DT, available_scene_engines, simulate_scene
from box_toss_env.physics import Box, Scene


def lone_box(y: float, angle: float = 0.0) -> Scene:
    return Scene(
        boxes=(Box(length=0.4, width=0.2, mass=2.0, position=(0.0, y), angle=angle),),
        dt=BOX2D3_DT,
        restitution=0.3,
        friction=0.5,
    )


def test_box2d3_keeps_a_resting_box_where_its_surface_meets_the_floor():
    """No skin in v3: a 20 cm high box placed on the floor stays with its centre at 10 cm (its soft contact
    lets it sink a fraction of a millimetre)."""
    pytest.importorskip("pyb2d3")
    final = simulate_scene("box2d3", lone_box(0.1), 120, record=False).final_state[0]
    assert final[1] == pytest.approx(0.1, abs=5e-4)
    assert abs(final[2]) < 1e-4
    assert np.abs(final[3:]).max() < 1e-3


@pytest.mark.parametrize("sleep", [True, False])
def test_box2d3_a_dropped_box_comes_to_rest_on_a_long_side(sleep):
    pytest.importorskip("pyb2d3")
    final = simulate_scene("box2d3", lone_box(1.0, angle=0.3), 300, record=False, sleep=sleep).final_state[0]
    assert final[1] == pytest.approx(0.1, abs=1e-3)
    assert math.remainder(final[2], math.pi) == pytest.approx(0.0, abs=1e-3)
    assert np.abs(final[3:]).max() < 1e-2


@pytest.mark.parametrize("allowed", [True, False])
def test_box2d23_needs_sleeping_allowed_false_to_keep_a_body_awake(allowed):
    """Why ``build_box2d(sleep=False)`` sets every body's sleepingAllowed: doSleep=False alone lets a Box2D 2.3
    body resting on the floor fall asleep."""
    Box2D = pytest.importorskip("Box2D")
    world = Box2D.b2World(gravity=(0.0, -9.81), doSleep=False)
    world.CreateStaticBody(position=(0.0, 0.0)).CreateEdgeFixture(vertices=[(-10.0, 0.0), (10.0, 0.0)])
    body = world.CreateDynamicBody(position=(0.0, 0.11))
    body.CreatePolygonFixture(box=(0.19, 0.09), density=1.0)
    body.sleepingAllowed = allowed
    for _ in range(240):
        world.Step(1 / 60, 8, 3)
    assert body.awake is not allowed


def test_the_scale_rows_cover_every_engine_with_finite_positive_figures():
    engines = [engine_scale.OURS, *available_scene_engines()]
    rows, settlers = engine_scale.scale_rows(sizes=(1, 3), engines=engines, window=0.1, budget=0.5, pyramid=False)
    assert {(r.engine, r.case, r.mode) for r in rows} == {
        (e, c, m) for e in engines for c in ("pile 1", "pile 3") for m in engine_scale.MODES
    }
    assert set(settlers) == {"pile 1", "pile 3"}
    for row in rows:
        assert row.steps >= engine_scale.MIN_STEPS, row
        for value in (row.ns_per_body_step, row.us_per_body_second):
            assert math.isfinite(value) and value > 0, row
        assert 0 <= row.penetration < 0.05, row
    lines = engine_scale.table(rows)
    assert len(lines) == 2 + 2 * len(engines)


def test_a_wide_pile_is_low():
    scene = engine_scale.wide_pile(100, layers=4)
    assert scene.n_bodies == 100 and scene.boxes_collide
    assert max(box.position[1] for box in scene.boxes) == pytest.approx(0.15 + 0.3 * 3)


def test_max_penetration_finds_the_floor_and_a_corner_inside_a_box():
    boxes = (Box(length=0.4, width=0.2, position=(0.0, 0.1)), Box(length=0.4, width=0.2, position=(0.1, 0.3)))
    scene = Scene(boxes=boxes, boxes_collide=True)
    state = scene.initial_state()
    assert engine_scale.max_penetration(scene, state) == pytest.approx(0.0, abs=1e-12)
    state[0, 1] = 0.097  # 3 mm into the floor
    assert engine_scale.max_penetration(scene, state) == pytest.approx(0.003)
    state[1, 1] = 0.287  # and 1 cm into the lower box
    assert engine_scale.max_penetration(scene, state) == pytest.approx(0.01)


def test_the_budget_option_names_its_range(capsys):
    with pytest.raises(SystemExit):
        engine_scale.main(["--budget", "0"])
    assert "--budget" in capsys.readouterr().err


def test_docs_and_plot_are_written_between_markers(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("before\n<!-- engine-scale:start -->\nold\n<!-- engine-scale:end -->\nafter\n")
    engine_scale.write_docs("new table", page=page)
    assert page.read_text() == "before\n<!-- engine-scale:start -->\nnew table\n<!-- engine-scale:end -->\nafter\n"
    rows = [engine_scale.Row("pile 1", 1, "ours", 1 / 256, mode, 10, 1e-3) for mode in engine_scale.MODES]
    engine_scale.plot(rows, path=tmp_path / "scale.png")
    assert (tmp_path / "scale.png").stat().st_size > 0


def test_the_pareto_rows_turn_every_knob_with_finite_figures(tmp_path):
    from benchmarks import pile_pareto

    rows = pile_pareto.pareto_rows(window=0.02, pile=3)
    engines = {row[1] for row in rows}
    ours = {engine_scale.OURS, pile_pareto.OURS_BY_TOLERANCE, pile_pareto.OURS_BY_SLOP}
    assert ours <= engines <= {*ours, *available_scene_engines()}
    assert {row[0] for row in rows} == {"pyramid", "pile 3"}
    for case, engine, knob, cost, penetration, drift in rows:
        assert math.isfinite(cost) and cost > 0, (case, engine, knob)
        assert 0 <= penetration < 0.1 and 0 <= drift < 1, (case, engine, knob)
    pile_pareto.plot(rows, path=tmp_path / "pareto.png")
    assert (tmp_path / "pareto.png").stat().st_size > 0


def test_the_readme_summary_is_written_from_the_rows():
    rows = [
        engine_scale.Row("pile 100", 100, engine_scale.OURS, 1 / 120, "awake", 240, 0.2, 1e-6, 0.0),
        engine_scale.Row("pile 100", 100, "box2d3", 1 / 60, "awake", 120, 0.1, 2e-3, 0.0),
        engine_scale.Row("pile 100", 100, "pymunk", 1 / 60, "awake", 120, 0.1, 1e-3, 0.0),
        engine_scale.Row("pile 10", 10, engine_scale.OURS, 1 / 120, "awake", 240, 0.02, 1e-6, 0.0),
    ]
    onbox = [("BoxToss-v0", 1, 20.0, 50.0, 19.0), ("BoxToss-OnBox-v0", 2, 60.0, 60.0, 70.0)]
    text = engine_scale.readme_summary(rows, onbox, "header.")
    assert "| pile 100 | 1,000.0 | 500.0 | 2.0 | 1.0e-06 | 2.0e-03 | 0.0e+00 | 0.0e+00 |" in text  # drift: every case
    assert "costs the engine 60 us, 3.0 times a floor throw's 20 us" in text
    assert "pymunk" not in text and "pile 10 |" not in text  # Box2D v3 beside ours, on the goals' cases
    assert "asleep" not in text  # no settled and asleep rows: no sentence about them
    rows += [
        engine_scale.Row("pile 100", 100, engine, dt, mode, 120, wall)
        for engine, dt in ((engine_scale.OURS, 1 / 120), ("box2d3", 1 / 60))
        for mode, wall in (("settled", 0.05), ("asleep", 0.001))
    ]
    text = engine_scale.readme_summary(rows, onbox, "header.")
    assert "pile 100: ours 500.0 and 10.00, Box2D v3 250.0 and 5.00." in text
