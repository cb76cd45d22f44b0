"""Scenes reject bad input with an error naming the parameter and its allowed range."""

import math
from pathlib import Path

import numba
import numpy as np
import pytest

from box_toss_env.physics import (
    Box,
    KernelFlags,
    Scene,
    Simulator,
    layout,
    make_kernel,
    make_settings,
    scenes,
    simulate,
)
from box_toss_env.physics.ranges import ENGINE_RANGES


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("length", 0.0, r"length must be in \[0.0001, 1000\] m, got 0"),
        ("length", 1e-300, r"length must be in \[0.0001, 1000\] m, got 1e-300"),
        ("width", 1e-160, r"width must be in \[0.0001, 1000\] m"),
        ("width", 1e4, r"width must be in \[0.0001, 1000\] m"),
        ("mass", -2.0, r"mass must be in \[1e-6, 1e6\] kg, got -2"),
        ("mass", 1e300, r"mass must be in \[1e-6, 1e6\] kg, got 1e\+300"),
        ("mass", 1e-300, r"mass must be in \[1e-6, 1e6\] kg"),
        ("mass", math.nan, r"mass must be a finite real number, got nan"),
        ("angle", math.inf, r"angle must be a finite real number"),
        ("position", (0.0, math.nan), r"position\[1\] must be a finite real number"),
        ("velocity", (1.0, 2.0, 3.0), r"velocity must be a sequence of 2 finite numbers"),
        ("restitution", 1.5, r"restitution must be in \[0, 1\], got 1.5"),
        ("friction", -0.1, r"friction must be in \[0, 10\]"),
        ("friction", 1e39, r"friction must be in \[0, 10\]"),
    ],
)
def test_bad_box_values_name_the_parameter_and_range(field, value, message):
    with pytest.raises(ValueError, match=message):
        Box(**{field: value})


@pytest.mark.parametrize(
    "field, value",
    [
        ("mass", "2"),
        ("mass", True),
        ("length", np.bool_(True)),
        ("spin", "fast"),
        ("angle", 1j),
        ("position", "01"),
        ("velocity", (1.0, "2")),
        ("restitution", True),
        ("friction", "0.5"),
    ],
)
def test_values_of_the_wrong_type_are_type_errors_naming_the_parameter(field, value):
    with pytest.raises(TypeError, match=rf"^{field}(\[\d\])? must be"):
        Box(**{field: value})


@pytest.mark.parametrize("value", [2, 2.0, np.float32(2.0), np.int64(2), np.array(2.0)])
def test_python_and_numpy_numbers_are_numbers(value):
    assert Box(mass=value).mass == 2.0 and Scene(gravity=value).gravity == 2.0


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("dt", 0.0, r"dt must be in \[1e-7, 1\] s, got 0"),
        ("dt", -0.01, r"dt must be in \[1e-7, 1\] s"),
        ("dt", 1e-300, r"dt must be in \[1e-7, 1\] s, got 1e-300"),
        ("dt", 1e-12, r"dt must be in \[1e-7, 1\] s"),
        ("dt", 2.0, r"dt must be in \[1e-7, 1\] s"),
        ("dt", math.nan, r"dt must be a finite real number"),
        ("gravity", math.inf, r"gravity must be a finite real number"),
        ("restitution", -0.1, r"restitution must be in \[0, 1\], got -0.1"),
        ("restitution", 1.01, r"restitution must be in \[0, 1\]"),
        ("friction", -1.0, r"friction must be in \[0, 10\]"),
        ("penalty_stiffness", -5.0, r"penalty_stiffness must be in \[0, inf\) N/m"),
        ("solver", "verlet", r"solver must be one of \('robust', 'seed'\)"),
        ("sleep_time", -1.0, r"sleep_time must be in \[0, inf\) s"),
        ("solver_tolerance", 1.5, r"solver_tolerance must be in \[0, 1\], got 1.5"),
        ("solver_tolerance", -1e-9, r"solver_tolerance must be in \[0, 1\]"),
        ("solver_iterations", 0, r"solver_iterations must be an integer in \[1, 10000\], got 0"),
        ("boxes", (), r"boxes must hold at least one Box"),
    ],
)
def test_bad_scene_values_name_the_parameter_and_range(field, value, message):
    with pytest.raises(ValueError, match=message):
        Scene(**{field: value})


@pytest.mark.parametrize(
    "field, value",
    [
        ("dt", True),
        ("dt", "0.01"),
        ("gravity", "-9.81"),
        ("restitution", True),
        ("penalty_stiffness", 1e5 + 0j),
        ("use_impulses", "yes"),
        ("use_penalty", 1),
        ("quiet_steps", 1),
        ("solver", 1),
        ("solver_iterations", 16.0),
        ("solver_iterations", True),
        ("boxes", ("box",)),
    ],
)
def test_scene_values_of_the_wrong_type_are_type_errors(field, value):
    with pytest.raises(TypeError, match=field):
        Scene(**{field: value})


def test_robust_solver_needs_impulses():
    with pytest.raises(ValueError, match="use_impulses must be True with solver='robust'"):
        Scene(use_impulses=False)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(), "exactly one of steps"),
        (dict(steps=10, duration=1.0), "exactly one of steps"),
        (dict(steps=-1), r"steps must be an integer in \[0, 100000000\]"),
        (dict(steps=10**9), r"steps must be an integer in \[0, 100000000\]"),
        (dict(duration=math.nan), r"duration must be a finite real number"),
        (dict(duration=1e6), r"duration / dt must be at most 1e8 steps"),
    ],
)
def test_bad_run_lengths_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        simulate(Scene(), **kwargs)


@pytest.mark.parametrize("kwargs", [dict(steps=2.5), dict(steps=True), dict(duration="1")])
def test_run_lengths_of_the_wrong_type_are_type_errors(kwargs):
    with pytest.raises(TypeError, match=next(iter(kwargs))):
        simulate(Scene(), **kwargs)


def test_threads_beyond_numbas_count_are_refused_before_running():
    with pytest.raises(ValueError, match=rf"threads must be an integer in \[1, {numba.config.NUMBA_NUM_THREADS}\]"):
        Simulator(KernelFlags(), threads=numba.config.NUMBA_NUM_THREADS + 1)


def test_the_ranges_page_lists_the_engine_ranges():
    """docs/ranges.md is the one place the ranges are written down; it agrees with the code."""
    text = (Path(__file__).parents[2] / "docs" / "ranges.md").read_text()
    for name, allowed in ENGINE_RANGES.items():
        assert f"| `{name}` | {allowed} |" in text, name


def test_inertia_is_that_of_a_uniform_rectangle():
    assert Box(length=2.0, width=1.0, mass=3.0).inertia == pytest.approx(3.0 * 5.0 / 12.0)


def test_per_box_material_overrides_the_scene():
    scene = Scene(boxes=(Box(restitution=0.9, friction=0.1), Box()), restitution=0.2, friction=0.4)
    params = scene.body_params()
    np.testing.assert_array_equal(params[:, 4], [0.9, 0.2])
    np.testing.assert_array_equal(params[:, 5], [0.1, 0.4])


def test_the_kernel_is_built_for_exactly_what_the_scene_has():
    """A scene without friction, or without penalty, or with one box, gets a kernel compiled
    without that stage; kernels are cached per combination."""
    no_friction = Simulator.for_scene(scenes.flat_drop(friction=0.0))
    assert no_friction.flags == KernelFlags(
        solver="robust", use_impulses=True, use_penalty=True, use_friction=False, record=False, parallel=False
    )
    no_penalty = Simulator.for_scene(scenes.toss(penalty_stiffness=0.0), record=True)
    assert not no_penalty.flags.use_penalty and no_penalty.flags.use_friction and no_penalty.flags.record
    many = Simulator.for_scene(scenes.seed_demo())
    assert many.flags.parallel and many.flags.solver == "seed"
    assert make_kernel(no_friction.flags) is no_friction.kernel
    assert no_friction.kernel is not make_kernel(KernelFlags())


@pytest.mark.parametrize("solver", ["robust", "seed"])
def test_leaving_out_friction_changes_nothing_when_friction_is_zero(solver):
    """The kernel without the friction stage and the one with it (at mu = 0) agree: exactly for the
    seed scheme, to rounding for the robust one (whose friction pass repeats the normal solve)."""
    scene = scenes.toss(solver=solver, friction=0.0, penalty_stiffness=2e3)
    state = scene.initial_state()
    results = []
    for flags_friction in (False, True):
        flags = KernelFlags(solver=solver, use_friction=flags_friction, record=False)
        simulator = Simulator(flags)
        final = state.copy()
        stats = np.zeros((1, layout.STATS_SIZE))
        simulator.run(final, scene.body_params(), make_settings(scene, 512, False), stats)
        results.append(final)
    np.testing.assert_allclose(results[0], results[1], rtol=0, atol=0.0 if solver == "seed" else 1e-12)


@pytest.mark.parametrize("stiffness", [1e12, 1e308])
def test_any_finite_stiffness_is_honoured_at_the_ends_of_the_mass_and_size_ranges(stiffness):
    """The smallest, lightest box resting under the stiffest penalty, robust solver: finite, and it stays
    on the floor (the implicit correction takes its limit where k K_ii overflows)."""
    solver = "robust"
    tiny = Box(length=1e-4, width=1e-4, mass=1e-6, position=(0.0, 4e-5))
    final = simulate(Scene(boxes=(tiny,), solver=solver, penalty_stiffness=stiffness, dt=1e-4), steps=100).final_state
    assert np.isfinite(final).all() and 0.0 < final[0, layout.Y] < 1e-4
