"""Scenes reject bad input with an error naming the parameter and its allowed range."""

import math

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


@pytest.mark.parametrize("field, value, message", [
    ("length", 0.0, r"length must be in \(0, inf\], got 0.0"),
    ("width", -1.0, r"width must be in \(0, inf\]"),
    ("mass", -2.0, r"mass must be in \(0, inf\], got -2.0"),
    ("mass", math.nan, r"mass must be a finite real number, got nan"),
    ("angle", math.inf, r"angle must be a finite real number"),
    ("spin", "fast", r"spin must be a finite real number"),
    ("position", (0.0, math.nan), r"position\[1\] must be a finite real number"),
    ("velocity", (1.0, 2.0, 3.0), r"velocity must be a sequence of 2 finite numbers"),
    ("restitution", 1.5, r"restitution must be in \[0, 1\], got 1.5"),
    ("friction", -0.1, r"friction must be in \[0, inf\]"),
])
def test_bad_box_values_name_the_parameter_and_range(field, value, message):
    with pytest.raises(ValueError, match=message):
        Box(**{field: value})


@pytest.mark.parametrize("field, value, message", [
    ("dt", 0.0, r"dt must be in \(0, 1\], got 0.0"),
    ("dt", -0.01, r"dt must be in \(0, 1\]"),
    ("dt", math.nan, r"dt must be a finite real number"),
    ("gravity", math.inf, r"gravity must be a finite real number"),
    ("restitution", -0.1, r"restitution must be in \[0, 1\], got -0.1"),
    ("restitution", 1.01, r"restitution must be in \[0, 1\]"),
    ("friction", -1.0, r"friction must be in \[0, inf\]"),
    ("penalty_stiffness", -5.0, r"penalty_stiffness must be in \[0, inf\]"),
    ("solver", "verlet", r"solver must be one of \('robust', 'seed'\)"),
    ("use_impulses", "yes", r"use_impulses must be True or False"),
    ("sleep_time", -1.0, r"sleep_time must be in \[0, inf\]"),
    ("boxes", (), r"boxes must hold at least one Box"),
    ("boxes", ("box",), r"boxes\[0\] must be a Box"),
])
def test_bad_scene_values_name_the_parameter_and_range(field, value, message):
    with pytest.raises(ValueError, match=message):
        Scene(**{field: value})


def test_robust_solver_needs_impulses():
    with pytest.raises(ValueError, match="use_impulses must be True with solver='robust'"):
        Scene(use_impulses=False)


@pytest.mark.parametrize("kwargs, message", [
    (dict(), "exactly one of steps"),
    (dict(steps=10, duration=1.0), "exactly one of steps"),
    (dict(steps=-1), r"steps must be an integer >= 0"),
    (dict(steps=2.5), r"steps must be an integer >= 0"),
    (dict(duration=math.nan), r"duration must be a finite real number"),
])
def test_bad_run_lengths_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        simulate(Scene(), **kwargs)


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
    assert no_friction.flags == KernelFlags(solver="robust", use_impulses=True, use_penalty=True,
                                            use_friction=False, record=False, parallel=False)
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
