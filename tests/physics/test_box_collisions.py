"""Boxes that collide with one another (``Scene(boxes_collide=True)``): the named scenes of
``physics.scenes`` against what physics says (rest, conservation, closed forms, symmetry), the
robust solver's guarantees, validation, and that a scene whose boxes cannot meet compiles nothing
of it. The bounds are measured figures (docs/box_collisions.md)."""

import dataclasses
import json
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from benchmarks.scene_quality import overlaps
from box_toss_env.physics import Box, KernelFlags, Scene, Simulator, make_kernel, scenes, simulate

MIRROR = np.array([-1.0, 1.0, -1.0, -1.0, 1.0, -1.0])  # x -> -x: x, angle, vx, spin change sign


def masses(scene):
    return np.array([b.mass for b in scene.boxes]), np.array([b.inertia for b in scene.boxes])


def energy(scene, states):
    """Kinetic + potential energy of the scene in each row of ``states`` (T, n, 6) [J]."""
    m, inertia = masses(scene)
    return (
        0.5 * m * (states[..., 3] ** 2 + states[..., 4] ** 2)
        + 0.5 * inertia * states[..., 5] ** 2
        - scene.gravity * m * states[..., 1]
    ).sum(-1)


def drift(scene, states):
    """Largest distance of any box centre from where it started [m]."""
    return float(np.abs(states[:, :, :2] - scene.initial_state()[None, :, :2]).max())


# -- resting ---------------------------------------------------------------------------------------
def test_a_stack_of_ten_rests_60_s_within_a_millimetre():
    scene = scenes.stack(n=10)
    result = simulate(scene, duration=60.0, record=True, sleep=False)  # kept awake: the solver holds it
    assert drift(scene, result.trajectory.state) < 1e-3  # measured: 1.1e-11 m
    assert np.all(result.n_impacts == 0)  # resting contacts take no restitution


def test_a_pyramid_of_fifteen_holds():
    scene = scenes.pyramid(rows=5)
    assert scene.n_bodies == 15
    result = simulate(scene, duration=20.0, record=True, sleep=False)
    assert drift(scene, result.trajectory.state) < 1e-6  # measured: 2.7e-12 m in 60 s


@pytest.mark.parametrize("ratio", [1000.0, 1e-3])
def test_a_stack_with_mass_ratio_1_to_1000_stays_stable(ratio):
    # boxes alternating 2 kg and 2000 kg (or 2 g), bottom first
    scene = scenes.stack(n=10, masses=[2.0 * ratio ** (k % 2) for k in range(10)])
    result = simulate(scene, duration=10.0, record=True, sleep=False)
    assert drift(scene, result.trajectory.state) < 1e-6  # measured: 2.0e-11 m (both), 60 s: 2.0e-11 m


def test_a_pile_of_100_settles():
    # 200 contacts: beyond the exact solve's 64, the Gauss-Seidel path
    scene = scenes.pile(n=100)
    settled = simulate(scene, duration=10.0, sleep=False).final_state  # kept awake: the sweeps hold it
    later = simulate(scene, duration=20.0, sleep=False).final_state
    assert np.abs(settled[:, 3:]).max() < 1e-3
    assert np.abs(later[:, :2] - settled[:, :2]).max() < 1e-4  # measured: 1.0e-7 m from 10 s to 20 s
    assert settled[:, 1].min() > 0.099  # lying on the floor, not in it


def test_the_pile_sweeps_stop_at_the_scene_tolerance_or_its_iterations():
    # 200 contacts, the Gauss-Seidel path: with a tolerance of 1e-9 every substep takes the 16 sweeps (more
    # change the pile); with 0.1 no substep reaches 32 (so a cap of 64 changes nothing)
    def pile(tolerance, iterations):
        scene = scenes.pile(n=100, solver_tolerance=tolerance, solver_iterations=iterations)
        return simulate(scene, duration=0.5).final_state

    assert not np.array_equal(pile(1e-9, 16), pile(1e-9, 32))
    assert np.array_equal(pile(0.1, 32), pile(0.1, 64))


def test_the_exact_solve_of_up_to_64_contacts_runs_where_unlike_masses_meet_whatever_the_tolerance():
    # 4 light boxes under one 1,000 times heavier, 10 contacts: the exact solve, which neither solver_iterations nor
    # solver_tolerance touches (Gauss-Seidel let the heavy box sink through the light ones); a pile of 10 like
    # boxes (up to 40 contacts): the sweeps, which solver_iterations does change (the exact solve's pivots on tens of
    # contacts made a dropped pile of 16 cost 900 times Box2D v3), and the pile still settles and sleeps
    def heavy(tolerance, iterations):
        scene = scenes.stack(5, masses=(1.0, 1.0, 1.0, 1.0, 1000.0))
        return scene, simulate(
            scene.replace(solver_tolerance=tolerance, solver_iterations=iterations), duration=2.0, sleep=False
        )

    def pile(iterations):
        scene = scenes.pile(n=10, solver_iterations=iterations)
        return simulate(scene, duration=3.0, until_rest=True)

    scene, exact = heavy(1e-9, 16)
    for tolerance, iterations in ((1e-9, 1), (1e-4, 32), (1e-2, 2)):
        assert np.array_equal(heavy(tolerance, iterations)[1].final_state, exact.final_state)
    # each contact may sink PENALTY_FLOOR (1.1e-8 m at this size) before the penalty acts: measured 7.5e-11 m at
    # the top (1.04e-9 m with a floor of 1e-9 m, where the penalty started)
    assert np.abs(exact.final_state[:, :2] - scene.initial_state()[:, :2]).max() < 1e-8
    assert not np.array_equal(pile(1).final_state, pile(32).final_state)
    settled = pile(16)
    assert np.all(settled.at_rest) and settled.final_state[:, 1].min() > 0.099


def test_a_box_dropped_on_another_comes_to_rest_on_it():
    scene = scenes.drop_on_box()
    result = simulate(scene, duration=5.0, until_rest=True)
    lower, upper = result.final_state
    assert np.all(result.at_rest)
    assert upper[1] == pytest.approx(0.3, abs=1e-3)  # lying on the lower box's top face (y = 0.2)
    assert abs(math.remainder(upper[2], math.pi / 2)) < 1e-3
    assert abs(upper[0] - lower[0]) < 0.2  # its centre above the lower box
    assert lower[1] == pytest.approx(0.1, abs=1e-3)
    assert result.n_impacts[1] >= 1


def test_the_seed_scheme_keeps_a_dropped_box_on_the_other():
    # with a penalty soft enough for its explicit spring (dt sqrt(k K_n) < 2 for two bodies)
    result = simulate(scenes.drop_on_box(solver="seed", penalty_stiffness=1e4), duration=3.0)
    lower, upper = result.final_state
    assert upper[1] == pytest.approx(0.3, abs=5e-3)  # measured: 2.4 mm into the lower box
    assert abs(upper[0] - lower[0]) < 0.2 and abs(math.remainder(upper[2], math.pi / 2)) < 1e-2


# -- in flight: conservation and the closed form ----------------------------------------------------
@pytest.mark.parametrize("solver", ["robust", "seed"])
@pytest.mark.parametrize("friction", [0.0, 0.5])
def test_boxes_colliding_in_flight_keep_momentum_and_angular_momentum(solver, friction):
    scene = scenes.flight_collision(spin=1.0, friction=friction, solver=solver, penalty_stiffness=1e3)
    result = simulate(scene, duration=1.0, record=True)
    assert np.all(result.n_impacts >= 1)
    states = result.trajectory.state
    m, inertia = masses(scene)
    momentum = (m[None, :, None] * states[:, :, 3:5]).sum(1)
    orbital = states[..., 0] * states[..., 4] - states[..., 1] * states[..., 3]
    angular = (m * orbital + inertia * states[..., 5]).sum(1)
    assert np.abs(momentum - momentum[0]).max() <= 1e-9 * np.abs(momentum[0]).max()
    assert np.abs(angular - angular[0]).max() <= 1e-9 * abs(angular[0])


def cross(r, v):
    return r[0] * v[1] - r[1] * v[0]


@pytest.mark.parametrize("solver", ["robust", "seed"])
@pytest.mark.parametrize("restitution", [0.0, 0.5, 1.0])
def test_a_frictionless_corner_on_face_impact_matches_the_two_body_formula(solver, restitution):
    scene = scenes.flight_collision(gap=1e-3, restitution=restitution, solver=solver, use_penalty=False)
    a, b = scene.boxes
    corners = [
        (
            math.cos(a.angle) * sx * 0.5 - math.sin(a.angle) * sy * 0.25,
            math.sin(a.angle) * sx * 0.5 + math.cos(a.angle) * sy * 0.25,
        )
        for sx in (-1, 1)
        for sy in (-1, 1)
    ]
    r1 = np.array(max(corners))  # the right-most corner hits B's left face, normal n = (-1, 0) onto A
    r2 = np.array(a.position) + r1 - np.array(b.position)
    n = np.array([-1.0, 0.0])
    u_rel = np.array(a.velocity) - np.array(b.velocity)
    j = (
        -(1 + restitution)
        * u_rel
        @ n
        / (1 / a.mass + 1 / b.mass + cross(r1, n) ** 2 / a.inertia + cross(r2, n) ** 2 / b.inertia)
    )
    expected = np.array(
        [
            [*(np.array(a.velocity) + j * n / a.mass), j * cross(r1, n) / a.inertia],
            [*(-j * n / b.mass), -j * cross(r2, n) / b.inertia],
        ]
    )
    result = simulate(scene, steps=3)
    np.testing.assert_allclose(result.final_state[:, 3:], expected, rtol=0, atol=1e-12)  # measured: 7e-15


def test_a_row_with_e_1_and_mu_0_passes_momentum_along():
    scene = scenes.newton_row(n=5, speed=1.0)
    result = simulate(scene, duration=3.0, record=True)
    velocity = result.final_state[:, 3]
    np.testing.assert_allclose(velocity, [0, 0, 0, 0, 1.0], atol=1e-9)  # measured: 1.7e-11
    e = energy(scene, result.trajectory.state)
    assert e.max() <= e[0] * (1 + 1e-12)
    assert e[-1] >= e[0] * (1 - 1e-9)  # measured: 2.5e-12 of it lost


def test_a_touching_row_struck_with_e_1_moves_as_one_body():
    # five boxes touching side by side (gaps 0), struck by a sixth at 1 m/s, e = 1, mu = 0. The row's own
    # contacts approached at 0 before the impact's substep, so they are resting contacts (no restitution);
    # the simultaneous solve then treats the row as one body of 5 m: an elastic impact of m on 5 m, the
    # striker returns at (1 - 5) / 6 v0 = -2/3 m/s and the whole row moves on at 2 / 6 v0 = 1/3 m/s, not
    # Newton's cradle (docs/box_collisions.md, "Measured")
    row = scenes.newton_row(n=5, speed=0.0, spacing=0.0)
    striker = Box(length=0.4, width=0.2, mass=2.0, position=(-0.5, 0.1), velocity=(1.0, 0.0))
    scene = dataclasses.replace(row, boxes=(striker, *row.boxes))
    result = simulate(scene, duration=2.0, record=True)
    states = result.trajectory.state
    m, _ = masses(scene)
    momentum = states[..., 3] @ m
    np.testing.assert_allclose(momentum, m[0] * 1.0, rtol=1e-9, atol=0)  # measured: 0 (exactly 2.0 kg m/s)
    e = energy(scene, states)
    kinetic = 0.5 * m[0] * 1.0**2  # [J] all the scene's kinetic energy, the striker's
    assert e.max() <= e[0] * (1 + 1e-12)  # measured: no rise
    assert e[-1] >= e[0] - 1e-9 * kinetic  # measured: 6.9e-12 of the kinetic energy lost
    assert result.max_penetration.max() < 1e-9  # measured: 1.3e-13 m
    # atol 1e-9: the exact normal solve stops once its impulses change by less than CONVERGED = 1e-9 of their
    # sum (measured: 3.4e-12 m/s off for the striker, 6.9e-13 m/s for the row)
    np.testing.assert_allclose(result.final_state[:, 3], [-2 / 3, *[1 / 3] * 5], rtol=0, atol=1e-9)
    np.testing.assert_allclose(result.final_state[:, 4:], 0.0, atol=1e-9)  # level, not turning
    np.testing.assert_allclose(np.diff(result.final_state[1:, 0]), 0.4, atol=1e-9)  # still touching


def test_the_seed_vertex_test_misses_faces_that_meet_corner_to_corner():
    # the seed extension's documented fault: in the row the boxes are level at the same height, so every
    # corner lies exactly on the next box's face line, never strictly inside it: the first box passes through
    scene = scenes.newton_row(solver="seed", penalty_stiffness=1e4)
    result = simulate(scene, duration=3.0)
    assert result.final_state[0, 0] > result.final_state[-1, 0]
    np.testing.assert_allclose(result.final_state[1:, 3], 0.0, atol=1e-3)


# -- the robust solver's guarantees -----------------------------------------------------------------
@pytest.mark.parametrize("speed", [50.0, 500.0, 5000.0])
def test_no_tunnelling_in_a_fast_body_body_impact(speed):
    scene = scenes.flight_collision(speed=speed, gap=0.5)
    result = simulate(scene, duration=0.5)
    moving, still = result.final_state
    assert moving[0] < still[0]  # it bounced off the left face, it did not pass through
    assert result.final_state[0, 3] < 0 < result.final_state[1, 3]
    assert result.max_penetration.max() < 1e-9  # measured: 0


def test_a_fast_box_dropped_on_a_resting_one_stays_above_it():
    scene = scenes.drop_on_box(offset=0.0, angle=0.0)
    lower, upper = scene.boxes
    scene = scene.replace(
        boxes=(lower, Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 2.0), velocity=(0.0, -300.0)))
    )
    result = simulate(scene, duration=2.0)
    assert result.final_state[1, 1] > result.final_state[0, 1] + 0.19
    assert result.final_state[0, 1] > 0.09


@pytest.mark.parametrize("mirror", [1.0, -1.0])
def test_a_corner_passing_beside_a_corner_meets_it(mirror):
    # the lower-left corner of a level box 0.8 mm beside and 1.05 mm above a resting box's top corner, moving
    # 0.7 m/s down and across: the face under it lies wholly beside the other's top face, so clipping kept no
    # contact and the corner went 1.7 mm into the box in one step (narrowphase.corner_contact)
    rest = Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 0.1))
    corner = (mirror * (0.2 + 0.0008 + 0.2), 0.2 + 0.00105 + 0.1)
    moving = Box(length=0.4, width=0.2, mass=2.0, position=corner, velocity=(-mirror * 0.7, -0.7))
    scene = Scene(boxes=(rest, moving), boxes_collide=True, restitution=0.3, friction=0.5, penalty_stiffness=1e5)
    scene = scene.replace(dt=1 / 256)
    states = simulate(scene, duration=0.1, record=True).trajectory.state
    half = np.array([[0.2, 0.1], [0.2, 0.1]])
    deepest = max(max(overlaps(state, half, np.zeros(2, np.bool_))) for state in states)
    assert deepest < 1e-5  # measured 1.5e-14 m, both mirror images (was 1.76 mm)


@pytest.mark.parametrize("speed", [50.0, 200.0])
def test_a_box_struck_from_above_is_not_pushed_into_the_floor(speed):
    # the stability report's body_impacts row: the restitution stage solved the impact without the struck box's
    # floor contacts, and its floor contacts were found only within its own (resting) reach, so the lower box
    # went 6 mm (50 m/s) and 1.3 cm (200 m/s) into the floor at dt 2^-11
    angle = 0.3
    reach_y = 0.2 * math.sin(angle) + 0.1 * math.cos(angle)
    boxes = (
        Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 0.1)),
        Box(length=0.4, width=0.2, mass=2.0, position=(0.05, 0.7 + reach_y), angle=angle, velocity=(0.0, -speed)),
    )
    scene = Scene(boxes=boxes, boxes_collide=True, restitution=0.0, friction=0.5, penalty_stiffness=1e5, dt=2.0**-11)
    states = simulate(scene, duration=0.25, record=True).trajectory.state
    lower = states[:, 0]
    bottom = lower[:, 1] - 0.2 * np.abs(np.sin(lower[:, 2])) - 0.1 * np.abs(np.cos(lower[:, 2]))
    assert -bottom.min() < 2e-4  # measured: 1.2e-5 m (50 m/s), 2.6e-5 m (200 m/s)


def test_the_first_impact_of_a_box_dropped_on_a_box_is_the_simultaneous_impulse_lcp():
    # the corner (2.732 m/s at x = -0.139) slides on the lower box, which sticks at its left floor corner and lifts
    # its right one: the closed form of the three-contact impulse LCP (Newton e 0.3, Coulomb mu 0.5; docs/
    # box_collisions.md). Restitution solved alone, without friction and the floor, gave a nearly frictionless
    # impact: lower box about -0.02 m/s and -0.5 rad/s (the collisions report), (-0.008, -0.02) m/s and 0 rad/s
    # with the floor kept in it
    scene = scenes.drop_on_box(dt=2.0**-12)
    states = simulate(scene, duration=0.3, record=True).trajectory.state
    first = np.flatnonzero(np.abs(states[:, 0, 3:]).max(axis=1) > 1e-3)[0]
    np.testing.assert_allclose(states[first, 0, 3:], [-0.0855, 0.1711, 0.8553], atol=0.01)  # measured: 1e-3
    np.testing.assert_allclose(states[first, 1, 3:], [0.7307, -1.2709, -11.3366], atol=0.02)  # measured: 1.3e-3


@pytest.mark.parametrize("name", ["pile", "drop_on_box", "newton_row"])
def test_no_energy_gained(name):
    # no step gains energy where nothing overlaps (measured: 1.4e-14 J of 77 J at most, rounding) ...
    scene = scenes.SCENES[name](use_penalty=False)
    e = energy(scene, simulate(scene, duration=3.0, record=True).trajectory.state)
    assert np.all(np.diff(e) <= 1e-12 * abs(e[0]))
    # ... and the penalty's correction of an overlap returns potential energy that it takes from the moved
    # bodies' kinetic energy, as far as they have it (measured: +2.3e-3 J in one step of the pile), so the
    # scene never ends a step above the energy it started with
    scene = scenes.SCENES[name]()
    e = energy(scene, simulate(scene, duration=3.0, record=True).trajectory.state)
    assert e.max() <= e[0] * (1 + 1e-12)


def test_friction_never_reverses_sliding_on_a_box():
    # a box sliding on a long resting box: its slip relative to the lower box stops, never turns round
    lower = Box(length=4.0, width=0.2, mass=20.0, position=(0.0, 0.1))
    upper = Box(length=0.4, width=0.2, mass=2.0, position=(-1.0, 0.3), velocity=(2.0, 0.0))
    scene = Scene(
        boxes=(lower, upper), boxes_collide=True, friction=0.3, restitution=0.0, penalty_stiffness=1e5, dt=1 / 256
    )
    states = simulate(scene, duration=2.0, record=True).trajectory.state
    slip = states[:, 1, 3] - states[:, 0, 3]
    assert slip[0] > 0 and np.all(slip >= -1e-10) and abs(slip[-1]) < 1e-9  # measured: -1.3e-11 at worst


def test_mirror_image_gives_the_mirrored_trajectory():
    a = simulate(scenes.drop_on_box(offset=0.05, angle=0.1), duration=3.0, record=True).trajectory.state
    b = simulate(scenes.drop_on_box(offset=-0.05, angle=-0.1), duration=3.0, record=True).trajectory.state * MIRROR
    difference = np.abs(a - b).max(axis=(1, 2))
    first_impact = 70  # the flight (exact on both) ends at step 74
    assert difference[:first_impact].max() <= 1e-12
    # Gauss-Seidel friction over a manifold's two points runs in an order that mirroring reverses:
    # measured 5.2e-5 at worst (during the impacts), 4.0e-7 at the end
    assert difference.max() < 1e-3 and difference[-1] < 1e-5


@pytest.mark.parametrize("solver", ["robust", "seed"])
def test_deterministic(solver):
    scene = scenes.pile(n=10, solver=solver, penalty_stiffness=1e4)
    a = simulate(scene, duration=1.0, record=True).trajectory.state
    b = simulate(scene, duration=1.0, record=True).trajectory.state
    assert np.array_equal(a, b)


def test_a_colliding_scene_runs_its_boxes_together_whatever_parallel_says():
    scene = scenes.pile(n=10)
    assert Simulator.for_scene(scene, parallel=False).shares == 1
    assert Simulator.for_scene(scene, parallel=True, threads=1).shares == 1  # its large stages' threads (one here)
    assert Simulator.for_scene(scene).shares == 1  # one thread unless told: a second does not pay on piles
    assert Simulator.for_scene(scene, threads=2).shares == 2
    assert np.array_equal(
        simulate(scene, duration=0.5).final_state, simulate(scene, duration=0.5, threads=2).final_state
    )


def test_sleeping_a_resting_stack():
    result = simulate(scenes.stack(n=10), duration=10.0, until_rest=True)
    assert np.all(result.at_rest) and np.all(result.rest_time <= 0.2)


def test_one_colliding_box_lands_as_the_floor_only_solver_lands_it():
    drop = scenes.flat_drop(height=1.0, restitution=0.5, friction=0.5)
    alone = simulate(drop, duration=3.0).final_state
    colliding = simulate(drop.replace(boxes_collide=True), duration=3.0).final_state
    np.testing.assert_allclose(colliding[:, :3], alone[:, :3], atol=1e-3)


# -- validation ------------------------------------------------------------------------------------
def test_boxes_collide_must_be_a_bool():
    with pytest.raises(TypeError, match="boxes_collide must be True or False"):
        Scene(boxes_collide=1)


def test_a_colliding_scene_must_not_start_with_overlapping_boxes():
    boxes = (Box(position=(0.0, 1.0)), Box(position=(0.5, 1.2)), Box(position=(5.0, 1.0)))
    with pytest.raises(ValueError, match=r"boxes\[0\] and boxes\[1\] overlap by"):
        Scene(boxes=boxes, boxes_collide=True)
    Scene(boxes=boxes)  # boxes that do not collide may overlap
    touching = (Box(position=(0.0, 0.5)), Box(position=(0.0, 1.5)))
    Scene(boxes=touching, boxes_collide=True)


def test_the_named_scenes_check_their_counts():
    with pytest.raises(ValueError, match="masses must hold one mass per box"):
        scenes.stack(n=3, masses=(1.0, 2.0))
    for make, name in ((scenes.stack, "n"), (scenes.pyramid, "rows"), (scenes.newton_row, "n"), (scenes.pile, "n")):
        with pytest.raises(TypeError, match=f"{name} must be an integer"):
            make(**{name: 2.5})
        with pytest.raises(ValueError, match=f"{name} must be an integer >= 1"):
            make(**{name: 0})


# -- a scene that cannot collide compiles no pair finding -------------------------------------------
def test_boxes_collide_false_is_todays_kernel():
    for solver in ("robust", "seed"):
        today = KernelFlags(solver=solver)
        assert make_kernel(KernelFlags(solver=solver, boxes_collide=False)) is make_kernel(today)
        assert make_kernel(KernelFlags(solver=solver, boxes_collide=True)) is not make_kernel(today)
    scene = scenes.toss()
    assert Simulator.for_scene(scene).kernel is Simulator.for_scene(scene.replace(boxes_collide=False)).kernel


NOT_COMPILED_PROBE = textwrap.dedent("""
    import json
    from numba.core.registry import CPUDispatcher
    from box_toss_env.physics import scenes, simulate
    import importlib, pkgutil
    from box_toss_env.physics import colliding
    from box_toss_env.physics import kernel_support
    from box_toss_env.physics.reference import colliding_reference
    for solver in ("robust", "seed"):
        simulate(scenes.toss(solver=solver), duration=2.0, until_rest=True)
    colliding_only = [colliding_reference] + [importlib.import_module(f"{colliding.__name__}.{info.name}")
                                              for info in pkgutil.iter_modules(colliding.__path__)]
    compiled = [f"{module.__name__}.{name}" for module in colliding_only
                for name, function in vars(module).items()
                if isinstance(function, CPUDispatcher) and function.py_func.__module__ == module.__name__
                and function.overloads]
    seen = [name for name, function in vars(kernel_support).items()  # the stages every kernel calls
            if isinstance(function, CPUDispatcher) and function.overloads]
    print(json.dumps([compiled, seen]))
""")


def test_non_colliding_scenes_compile_no_pair_finding(tmp_path):
    # an empty numba cache: every stage a kernel calls is compiled (a kernel loaded from the cache would
    # leave its stages' dispatchers empty whatever it calls)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    out = subprocess.run(
        [sys.executable, "-c", NOT_COMPILED_PROBE], capture_output=True, text=True, check=True, env=env
    )
    compiled, seen = json.loads(out.stdout.strip().splitlines()[-1])
    assert compiled == []
    assert "write_stats" in seen  # the probe sees the stages the floor-only kernels compiled
