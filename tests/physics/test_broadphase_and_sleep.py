"""The multi-body engine at scale: the sort-and-sweep broadphase finds exactly the pairs that testing every
pair finds, islands fall asleep and wake, bodies placed at rest sleep from the start, and a box that no other
can reach is advanced by the floor-only solver: free flight in closed form, impacts with the floor located."""

import dataclasses
import math

import numba
import numpy as np
import pytest
from physics_checks import advance_in_runs

from box_toss_env.physics import Box, Scene, Simulator, layout, make_settings, scenes, simulate, warm_start_memory
from box_toss_env.physics.colliding.alone import bounds_touch, steps_alone
from box_toss_env.physics.colliding.broadphase import SMALL_SORT, candidate_pairs, kept_pairs, sort_keys, sweep_axis
from box_toss_env.physics.colliding.groups import search_holds, search_padded
from box_toss_env.physics.colliding.islands import sleeps_through, wake_touched
from box_toss_env.physics.colliding.narrowphase import separation, update_geometry
from box_toss_env.physics.colliding.state import (
    Bodies,
    Sleep,
    StepContext,
    grown_sweep,
    initial_capacity,
    make_sleep,
    make_sweep,
    with_axis,
)
from box_toss_env.physics.robust.flight import time_to_contact
from box_toss_env.physics.tunables import QUIET_STRIDE


@numba.njit
def compiled_pairs(pose, bound, reach, include, moving, axis, order, low, keys):
    """``candidate_pairs`` as the kernels call it (a stage has no Python wrapper of its own)."""
    return candidate_pairs(pose, bound, reach, include, moving, axis, order, low, keys)


@numba.njit
def compiled_kept_search(searched_at, now, bound, reach, awake_then, awake_now, margin):
    """The step's pair search as ``groups.step_pairs`` keeps it: searched at the poses ``searched_at`` (bodies awake
    ``awake_then``), then at the poses ``now``: whether the kept search holds, and the pairs it gives."""
    n = now.shape[0]
    sweep = make_sweep(n)
    sweep.bound[:] = bound
    sweep.reach[:] = reach
    sweep.order[:] = np.arange(n)
    while search_padded(searched_at, sweep, awake_then, margin) < 0:  # room for the pairs, as the kernel grows it
        sweep = grown_sweep(sweep)
    holds = search_holds(now, bound, reach, awake_now, sweep.kept)
    found = kept_pairs(now, bound, reach, awake_now, sweep.kept.pairs, sweep.kept.found[0], sweep.pairs)
    return holds, sweep.pairs[:found].copy()


@numba.njit
def compiled_sleeps_through(warm, state, params, dt, stats, end_step):
    """``sleeps_through`` as the colliding kernel calls it, with the kernel's room for contacts."""
    return sleeps_through(warm, state, params, dt, initial_capacity(state.shape[0]), stats, end_step)


@numba.njit
def compiled_wake(pose, half, reach, awake, island, axis, struck):
    """``islands.wake_touched`` on bodies awake as ``awake``, the sleeping ones in islands ``island``: the bodies awake
    after it, and for the all-pairs check each pair's separation."""
    n = pose.shape[0]
    sweep, sleep = with_axis(make_sweep(n), axis), make_sleep(n)
    sweep.reach[:] = reach
    sweep.order[:] = np.arange(n)
    sleep.awake[:] = awake
    sleep.island[:] = island
    update_geometry(pose, half, sleep.everyone, sweep.trig, sweep.bound)
    wake_touched(pose, half, sweep, sleep, struck)
    apart = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            apart[i, j] = separation(min(i, j), max(i, j), pose, sweep.trig, half) if i != j else 0.0
    return sleep.awake.copy(), sweep.bound.copy(), apart


@numba.njit
def compiled_sort(keys, count):
    sort_keys(keys, count)


@numba.njit
def compiled_bounds_touch(pose, half, radius, awake):
    return bounds_touch(pose, half, radius, awake)


@numba.njit
def compiled_axis(pose, include):
    return sweep_axis(pose, include)


def all_pairs(pose, bound, reach, include, moving):
    """The broadphase's test on every pair, in plain numpy terms."""
    n = len(pose)
    keys = []
    for i in range(n):
        for j in range(i + 1, n):
            if not (include[i] and include[j] and (moving[i] or moving[j])):
                continue
            margin = reach[i] + reach[j]
            if (
                abs(pose[j, 0] - pose[i, 0]) <= bound[i, 0] + bound[j, 0] + margin
                and abs(pose[j, 1] - pose[i, 1]) <= bound[i, 1] + bound[j, 1] + margin
            ):
                keys.append(i * n + j)
    return keys


@pytest.mark.parametrize("seed", range(6))
def test_sort_and_sweep_finds_the_pairs_of_the_all_pairs_test(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 300))
    spread = rng.uniform(0.5, 20.0, 2)
    pose = np.column_stack([rng.uniform(0, spread[0], n), rng.uniform(0, spread[1], n), rng.uniform(-3, 3, n)])
    half = rng.uniform(0.02, 0.5, (n, 2))
    c, s = np.abs(np.cos(pose[:, 2])), np.abs(np.sin(pose[:, 2]))
    bound = np.column_stack([c * half[:, 0] + s * half[:, 1], s * half[:, 0] + c * half[:, 1]])
    reach = rng.uniform(0, 0.05, n)
    if seed % 2:  # boxes touching exactly, corner to corner: the boundary case of the test
        pose[1:, 0] = pose[0, 0] + np.arange(1, n) * 2 * bound[0, 0]
        pose[:, 1] = 0.0
        bound[:] = bound[0]
        reach[:] = 0.0
    include = rng.random(n) < 0.9
    moving = rng.random(n) < 0.7
    order = rng.permutation(n).astype(np.int64)  # any order: the sort repairs it
    keys = np.zeros(n * n, np.int64)
    for axis in (compiled_axis(pose, include), 0, 1):
        count = compiled_pairs(pose, bound, reach, include, moving, axis, order, np.zeros(n), keys)
        assert keys[:count].tolist() == all_pairs(pose, bound, reach, include, moving)
    assert compiled_pairs(pose, bound, reach, include, moving, 0, order, np.zeros(n), keys[:0]) in (-1, 0)


@pytest.mark.parametrize("seed", range(4))
def test_a_kept_pair_search_gives_the_pairs_of_a_new_search_while_every_body_stays_in_its_padded_box(seed):
    # groups.step_pairs searches with every reach padded by a margin and keeps the pairs while every awake body stays
    # within its padded box: the kept pairs filtered by the exact test are those of the all-pairs test at the new poses
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 200))
    pose = np.column_stack([rng.uniform(0, 5, n), rng.uniform(0, 2, n), rng.uniform(-3, 3, n)])
    half = rng.uniform(0.05, 0.3, (n, 2))
    c, s = np.abs(np.cos(pose[:, 2])), np.abs(np.sin(pose[:, 2]))
    bound = np.column_stack([c * half[:, 0] + s * half[:, 1], s * half[:, 0] + c * half[:, 1]])
    reach = rng.uniform(0, 0.01, n)
    awake = rng.random(n) < 0.8
    awake[:2] = True, False
    margin = 0.02
    moved = pose.copy()
    moved[:, :2] += rng.uniform(-0.99, 0.99, (n, 2)) * margin  # each within the margin: the search holds
    holds, pairs = compiled_kept_search(pose, moved, bound, reach, awake, awake, margin)
    assert holds and pairs.tolist() == all_pairs(moved, bound, reach, awake, awake)
    fewer = awake & (rng.random(n) < 0.5)  # bodies fell asleep: it still holds, without their pairs
    holds, pairs = compiled_kept_search(pose, moved, bound, reach, awake, fewer, margin)
    assert holds and pairs.tolist() == all_pairs(moved, bound, reach, fewer, fewer)
    far = moved.copy()
    far[0, 0] += 2 * margin  # an awake body left its padded box
    assert not compiled_kept_search(pose, far, bound, reach, awake, awake, margin)[0]
    woken = awake.copy()
    woken[1] = True  # a body asleep at the search woke
    assert not compiled_kept_search(pose, moved, bound, reach, awake, woken, margin)[0]


@pytest.mark.parametrize("seed", range(6))
def test_waking_gives_the_islands_every_pair_reaches_whether_few_or_many_bodies_are_awake(seed):
    # islands.wake_touched sweeps from every box when half or more are awake and from the awake ones alone (looking
    # back along the sweep too) when fewer are: the islands woken are the closure of "an awake body reaches it"
    # over every pair either way
    rng = np.random.default_rng(seed)
    n = int(rng.integers(50, 150))
    pose = np.column_stack([rng.uniform(0, 20, n), rng.uniform(0, 1, n), rng.uniform(-3, 3, n)])
    half = rng.uniform(0.01, 0.15, (n, 2))  # long and short boxes: the look back must reach past short ones
    reach = rng.uniform(0, 0.02, n)
    cell = np.floor(pose[:, 0] / 0.5) + 10 * np.floor(pose[:, 1] / 0.5)  # islands of the boxes of a cell
    island = np.array([np.flatnonzero(cell == c)[0] for c in cell])  # each labelled by its smallest body
    awake = rng.random(n) < (0.05 if seed % 2 else 0.7)
    awake[0] = True
    island[awake] = -1
    woken, bound, apart = compiled_wake(pose, half, reach, awake, island, int(rng.integers(0, 2)), 0.01)
    expected = awake.copy()
    while True:
        reached = {
            island[j]
            for i in np.flatnonzero(expected)
            for j in np.flatnonzero(~expected)
            if abs(pose[j, 0] - pose[i, 0]) <= bound[i, 0] + bound[j, 0] + reach[i] + reach[j]
            and abs(pose[j, 1] - pose[i, 1]) <= bound[i, 1] + bound[j, 1] + reach[i] + reach[j]
            and apart[i, j] <= reach[i] + reach[j] + 0.01
        }
        if not reached:
            break
        expected |= np.isin(island, list(reached)) & ~expected
    assert woken.tolist() == expected.tolist()
    assert awake.sum() < expected.sum() < n  # some islands woke, not all


@pytest.mark.parametrize("count", [0, 1, 2, SMALL_SORT, SMALL_SORT + 1, 1_000])
def test_the_pair_keys_are_sorted_in_place_by_insertion_or_heapsort(count):
    rng = np.random.default_rng(count)
    keys = rng.permutation(10 * count + 5)[: count + 3].astype(np.int64)  # distinct, as pair keys are
    expected = np.concatenate([np.sort(keys[:count]), keys[count:]])
    compiled_sort(keys, count)
    assert keys.tolist() == expected.tolist()  # the first count sorted, the rest untouched


def test_a_pile_gives_the_same_states_whichever_order_the_sweep_starts_from():
    # the pairs are visited in key order whatever the sweep found first: a pile is bit for bit reproducible
    scene = scenes.pile(n=30)
    a = simulate(scene, duration=0.5).final_state
    b = simulate(scene.replace(boxes=scene.boxes), duration=0.5).final_state
    assert np.array_equal(a, b)


def test_a_resting_box_falls_asleep_and_wakes_when_struck():
    lower = Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 0.1))
    upper = Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 1.3))  # 1 m above it: lands after 0.45 s
    scene = Scene(
        boxes=(lower, upper), boxes_collide=True, restitution=0.0, friction=0.5, penalty_stiffness=1e5, dt=1 / 256
    )
    result = simulate(scene, duration=3.0, until_rest=True, record=True)
    states = result.trajectory.state
    landing = math.sqrt(2 * 1.0 / 9.81)
    # the lower box slept after sleep_time (0.1 s) until the impact woke it, and the upper box, once alone awake,
    # flew in closed form: neither was integrated in the steps between (0.1 s to about 0.45 s)
    steps = result.rest_time * 256
    assert np.all(result.n_steps < steps - 0.25 * 256)
    assert np.all(result.at_rest)
    assert result.final_state[1, 1] == pytest.approx(0.3, abs=1e-6)
    assert result.final_state[0, 1] == pytest.approx(0.1, abs=1e-6)
    # the lower box lay still until the upper one arrived, and once asleep did not move at all
    before = states[: int(0.9 * landing * 256), 0]
    assert np.abs(before[:, :3] - states[0, 0, :3]).max() < 1e-12
    asleep = before[int(0.15 * 256) :]
    assert np.all(asleep == asleep[0]) and np.all(asleep[:, 3:] == 0.0)


def test_a_box_whose_bounds_overlap_a_sleeping_one_but_not_within_reach_does_not_wake_it():
    # without gravity, a box placed at rest on the floor sleeps from the start; another, turned 45 degrees, glides
    # at 1 m/s towards the corner of its top and stops being simulated 8 cm from it, where its bounds have
    # overlapped the sleeping box's for the last 12 mm: the bounds alone woke the sleeping box
    # (islands.wake_touched; its own separation is now the test)
    lying = Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 0.1))
    gliding = Box(length=0.4, width=0.2, mass=2.0, position=(1.4, 0.4), angle=math.pi / 4, velocity=(-1.0, 0.0))
    scene = Scene(boxes=(lying, gliding), boxes_collide=True, gravity=0.0, friction=0.5, penalty_stiffness=1e5)
    result = simulate(scene.replace(dt=1 / 256), duration=1.0)
    assert result.n_steps[0] == 0 and result.rest_time[0] == 0.0  # asleep throughout
    np.testing.assert_allclose(result.final_state[1], [0.4, 0.4, math.pi / 4, -1.0, 0.0, 0.0], atol=1e-12)


def test_a_box_woken_by_one_passing_within_reach_and_left_untouched_sleeps_again_at_once():
    """A box flying 2 cm over a sleeping one wakes it (``islands.wake_touched``: within reach) without striking it.
    The woken box keeps the still time it slept through (``islands.wake_island``): it sleeps again once the flyer is
    out of reach, after fewer steps than ``sleep_time`` (6 at 1/60 s), which a timer started at zero would need, and
    it has not moved."""
    base = Box(length=0.2, width=0.1, mass=1.0, position=(0.0, 0.05))
    flyer = Box(length=0.2, width=0.1, mass=1.0, position=(-0.4, 0.17), velocity=(6.0, 0.5))
    scene = Scene(boxes=(base, flyer), dt=1 / 60, restitution=0.3, friction=0.5, boxes_collide=True)
    state, stats = scene.initial_state(), np.zeros((2, layout.STATS_SIZE))
    settings = make_settings(scene, 240, until_rest=True)
    Simulator.for_scene(scene, parallel=False).run(state, scene.body_params(), settings, stats)
    assert stats[0, layout.N_IMPACTS] == 0 and state[1, 0] > 3.0  # never struck; the flyer flew on past it
    assert 0 < stats[0, layout.N_STEPS] < scene.sleep_time / scene.dt  # woken, and asleep again before the timer
    assert not math.isnan(stats[0, layout.REST_TIME])
    np.testing.assert_allclose(state[0], [0.0, 0.05, 0.0, 0.0, 0.0, 0.0], atol=1e-12)


def test_sleeping_is_per_island():
    # a stack that rests at once, and far from it a box still sliding: the stack sleeps alone, the slider later
    stack = scenes.stack(n=3).boxes
    slider = Box(length=0.4, width=0.2, mass=2.0, position=(5.0, 0.1), velocity=(1.5, 0.0))
    scene = scenes.stack(n=3).replace(boxes=(*stack, slider))
    result = simulate(scene, duration=5.0, until_rest=True)
    assert np.all(result.at_rest)
    assert np.all(result.rest_time[:3] <= 0.2)
    assert result.rest_time[3] > 0.2  # it slides 1.5^2 / (2 mu g) = 0.23 m first
    assert np.all(result.n_steps[:3] < result.n_steps[3])


def test_free_flight_beside_a_sleeping_box_is_the_exact_parabola():
    lower = Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 0.1))
    thrown = Box(length=0.4, width=0.2, mass=2.0, position=(-3.0, 1.5), angle=0.3, velocity=(2.0, 3.0), spin=4.0)
    scene = Scene(
        boxes=(lower, thrown), boxes_collide=True, restitution=0.3, friction=0.5, penalty_stiffness=1e5, dt=1 / 128
    )
    states = simulate(scene, duration=0.5, until_rest=True, record=True).trajectory.state
    t = np.arange(len(states)) / 128
    expected_y = 1.5 + 3.0 * t - 0.5 * 9.81 * t**2
    np.testing.assert_allclose(states[:, 1, 1], expected_y, atol=1e-12)
    np.testing.assert_allclose(states[:, 1, 2], 0.3 + 4.0 * t, atol=1e-12)


def thrown_and_resting(distance: float, **scene):
    resting = Box(length=0.4, width=0.2, mass=2.0, position=(distance, 0.1))
    thrown = Box(length=0.3, width=0.1, mass=1.0, position=(0.0, 1.2), angle=0.4, velocity=(1.5, 2.0), spin=-6.0)
    return Scene(boxes=(thrown, resting), restitution=0.4, friction=0.5, penalty_stiffness=1e5, dt=1 / 128, **scene)


def test_a_box_no_other_can_reach_moves_as_it_does_on_the_floor_alone():
    # thrown 10 m from a resting box: flight, impacts, sliding and rest as in the floor-only scene, to rounding
    # (the flight is taken in pieces of whole steps between the checks that no box is near)
    alone = simulate(thrown_and_resting(10.0), duration=4.0, until_rest=True, record=True)
    beside = simulate(thrown_and_resting(10.0, boxes_collide=True), duration=4.0, until_rest=True, record=True)
    assert np.all(beside.at_rest) and beside.rest_time[0] == alone.rest_time[0] > 1.0
    assert beside.n_impacts[0] == alone.n_impacts[0] >= 2
    assert beside.first_contact_time[0] == pytest.approx(alone.first_contact_time[0], abs=1e-12)
    steps = len(alone.trajectory.state)
    np.testing.assert_allclose(beside.trajectory.state[:steps, 0], alone.trajectory.state[:, 0], atol=1e-9)
    np.testing.assert_array_equal(
        beside.trajectory.state[:, 1, :3], np.broadcast_to([10.0, 0.1, 0.0], (len(beside.trajectory.state), 3))
    )


def test_bodies_placed_at_rest_sleep_from_the_start_and_others_do_not():
    stack = scenes.stack(n=2).boxes  # at rest, but on one another: stepped until they have been still a while
    lone = Box(length=0.4, width=0.2, mass=2.0, position=(3.0, 0.1))
    creeping = Box(length=0.4, width=0.2, mass=2.0, position=(6.0, 0.1), velocity=(1e-9, 0.0))
    tilted = Box(length=0.4, width=0.2, mass=2.0, position=(9.0, 0.1 + 1e-3), angle=0.01)
    scene = scenes.stack(n=2).replace(boxes=(*stack, lone, creeping, tilted))
    result = simulate(scene, duration=2.0, until_rest=True)
    assert np.all(result.at_rest)
    assert result.rest_time[2] == 0.0 and result.n_steps[2] == 0
    assert np.all(result.rest_time[[0, 1, 3, 4]] >= scene.sleep_time)
    assert np.array_equal(result.final_state[2], lone_state := np.array([3.0, 0.1, 0.0, 0.0, 0.0, 0.0]))
    assert np.array_equal(
        simulate(scene.replace(boxes=(lone,)), duration=1.0, until_rest=True).final_state[0], lone_state
    )
    # sleeping is simulate's default (the run going on to its end); with it off nothing sleeps: the box is stepped
    sleeping = simulate(scene, duration=2.0)
    assert np.all(sleeping.at_rest) and np.all(sleeping.end_time == 2.0) and sleeping.n_steps[2] == 0
    assert np.array_equal(sleeping.final_state, result.final_state)
    assert simulate(scene, duration=0.2, sleep=False).n_steps[2] > 0


@pytest.mark.parametrize("speed", [1.0, 4.0, 12.0])
def test_boxes_sliding_at_one_another_are_handed_to_the_substeps_before_they_meet(speed):
    # two boxes slide at one another on the floor, each alone against the floor while the energy bound keeps
    # them apart; they must meet in the colliding substeps: no overlap, the left box stays left, momentum turned
    left = Box(length=0.4, width=0.2, mass=2.0, position=(-1.0, 0.1), velocity=(speed, 0.0))
    right = Box(length=0.4, width=0.2, mass=1.0, position=(1.0, 0.1), velocity=(-speed, 0.0))
    scene = Scene(
        boxes=(left, right), boxes_collide=True, restitution=0.5, friction=0.02, penalty_stiffness=1e5, dt=1 / 128
    )
    result = simulate(scene, duration=3.0, until_rest=True, record=True)
    states = result.trajectory.state
    gap = states[:, 1, 0] - states[:, 0, 0] - 0.4
    assert gap.min() > -1e-6 and np.all(result.max_penetration < 1e-6)
    assert result.n_impacts[0] == result.n_impacts[1] == 1  # they met once (starting on the floor, no other impact)
    met = int(result.impacts[1][0, 0] * 128)
    assert gap[met] < 2 * speed / 128 + 1e-3  # within a step's travel of one another then
    assert np.all(states[met + 1 :, 1, 3] >= 0.0) and states[met + 1, 1, 3] > 0.0  # the heavier box drove it back


@pytest.mark.parametrize("name", ["flat_drop", "corner_impact", "toss", "bouncing", "slide"])
def test_one_box_in_a_colliding_scene_is_the_floor_only_solver_bit_for_bit(name):
    scene = getattr(scenes, name)()
    alone = simulate(scene, duration=3.0, until_rest=True)
    colliding = simulate(scene.replace(boxes_collide=True), duration=3.0, until_rest=True)
    assert np.array_equal(colliding.final_state, alone.final_state)
    assert np.array_equal(colliding.rest_time, alone.rest_time, equal_nan=True)
    assert np.array_equal(colliding.n_impacts, alone.n_impacts)


@numba.njit
def floor_contact_time(y, vy, resolution):
    return time_to_contact(y, 0.0, vy, 0.0, 0.4, 0.2, -9.81, 1.0, 1e-12, resolution)


def test_the_search_for_whole_steps_alone_stops_at_its_resolution():
    """A box lying on the floor whose centre separates at 1e-200 m/s: advancement steps of about 1e-200 s never
    reach the floor; with a resolution the search stops at once, reporting no contact before the time reached."""
    tau, touched = floor_contact_time(0.2, 1e-200, 0.25 / 128)
    assert not touched and tau < 0.25 / 128
    tau, touched = floor_contact_time(0.7, 0.0, 0.25 / 128)  # half a metre up: the fall takes sqrt(2 h / g)
    assert touched and tau == pytest.approx(math.sqrt(2 * 0.5 / 9.81), abs=1e-9)


@numba.njit
def compiled_steps_alone(pose, vel, half, awake, params):
    radius = np.sqrt(half[:, 0] ** 2 + half[:, 1] ** 2)
    bodies = Bodies(pose, vel, half, params, 1.0 / params[:, layout.MASS], 1.0 / params[:, layout.INERTIA], radius)
    n = pose.shape[0]
    sleep = Sleep(awake, awake, np.zeros(n, np.int64), np.zeros(n), np.zeros(n), np.zeros(n, np.int64), awake)
    context = StepContext(
        1.0 / 128, -9.81, 1_000, False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 1, 1e-12, 0.1, True, True, False
    )
    return steps_alone(bodies, sleep, context, 1_000)


@pytest.mark.parametrize("gap", [-1e-9, 0.0, 1e-6, 0.3])
def test_a_box_resting_on_another_gets_no_whole_steps_alone_and_one_clear_of_it_does(gap):
    """Box 1 at rest (asleep) on the floor, box 0 above it, its bottom ``gap`` above box 1's top, falling at 1 m/s:
    while their bounding boxes touch the search answers at once (``bounds_touch``), as the flight and energy
    bounds would; with 30 cm between them the box flies whole steps alone."""
    half = np.array([[0.2, 0.1], [0.3, 0.1]])
    pose = np.array([[0.05, 0.3 + gap, 0.0], [0.0, 0.1, 0.0]])
    vel = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 0.0]])
    params = np.zeros((2, layout.PARAM_SIZE))
    params[:, layout.HALF_LENGTH], params[:, layout.HALF_WIDTH] = half[:, 0], half[:, 1]
    params[:, layout.MASS], params[:, layout.INERTIA] = 1.0, (0.4**2 + 0.2**2) / 12
    awake = np.array([True, False])
    radius = np.hypot(half[:, 0], half[:, 1])
    assert compiled_bounds_touch(pose, half, radius, awake) == (gap <= 0.0)
    steps = compiled_steps_alone(pose, vel, half, awake, params)
    assert steps == 0 if gap < 0.3 else steps > 10  # 1e-6 m apart: a step of 1 m/s closes it
    assert not compiled_bounds_touch(pose, half, radius, np.array([False, False]))  # only an awake box asks


@pytest.mark.parametrize("n", [10, 100])  # the exact solves, and Gauss-Seidel (more than 64 contacts)
def test_a_pile_run_in_chunks_with_its_warm_start_is_the_pile_run_at_once(n):
    # chunks of 15 steps: every grid step a step (quiet steps keep to chunks of their stride: test_quiet_steps)
    scene = scenes.pile(n, dt=1 / 120, sleep_time=1e6, quiet_steps=False)
    once, _ = advance_in_runs(scene, 1, 120, warm_start=True)
    assert np.array_equal(advance_in_runs(scene, 8, 15, warm_start=True)[0], once)
    # without it each run starts its contacts from zero: the pile settles anew (measured 0.63 mm a run at 100)
    assert not np.array_equal(advance_in_runs(scene, 8, 15, warm_start=False)[0], once)


def test_the_warm_start_is_checked_and_only_for_colliding_scenes():
    scene = scenes.pile(2)
    simulator = Simulator.for_scene(scene)
    state, params, stats = scene.initial_state(), scene.body_params(), np.zeros((2, layout.STATS_SIZE))
    settings = make_settings(scene, 1, until_rest=False)
    with pytest.raises(ValueError, match="warm_start must be a C-contiguous float64 array"):
        simulator.run(state, params, settings, stats, warm_start=np.zeros((4, 2)))
    floor_only = Simulator.for_scene(scenes.toss())
    assert simulator.carries_warm_start and not floor_only.carries_warm_start
    with pytest.raises(ValueError, match="warm_start is for scenes whose boxes collide"):
        floor_only.run(state[:1], params[:1], settings, stats[:1], warm_start=warm_start_memory(1))


def settle_in_runs(scene, runs: int, steps: int, warm_start: bool) -> tuple[np.ndarray, int]:
    """(state, steps integrated in all) after ``runs`` calls of ``steps`` steps each until rest, with one warm
    start carried through the calls or none."""
    simulator = Simulator.for_scene(scene, parallel=False)
    state, params = scene.initial_state(), scene.body_params()
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    warm = warm_start_memory(scene.n_bodies) if warm_start else None
    stepped = 0
    for _ in range(runs):
        simulator.run(state, params, make_settings(scene, steps, until_rest=True), stats, warm_start=warm)
        stepped += int(stats[:, layout.N_STEPS].max())
    return state, stepped


@pytest.mark.parametrize("n", [10, 30])
def test_a_pile_settling_in_chunks_with_its_warm_start_sleeps_as_in_one_run(n):
    """Sleep carries in the warm start: islands asleep at the end of a call sleep in the next, the awake
    bodies' sleep timers go on, so chunks of 32 steps (a multiple of the quiet steps' stride, ``colliding.quiet``)
    are one run of 480 bit for bit, steps integrated included; without it each call wakes the pile and steps it
    until it falls asleep again."""
    scene = scenes.pile(n, dt=1 / 120)
    once, stepped = settle_in_runs(scene, 1, 480, warm_start=True)
    assert 0 < stepped < 480  # the pile fell asleep within the run
    assert 32 % QUIET_STRIDE == 0
    chunked, stepped_in_chunks = settle_in_runs(scene, 15, 32, warm_start=True)
    assert np.array_equal(chunked, once) and stepped_in_chunks == stepped
    cold, stepped_cold = settle_in_runs(scene, 15, 32, warm_start=False)
    # re-stepped at every call: sleep_time (12 grid steps, quiet steps of QUIET_STRIDE once the pile is still) and more
    assert stepped_cold > stepped + 10 * (12 // QUIET_STRIDE)
    assert not np.array_equal(cold, once)


def test_a_sleeping_pile_costs_no_step_until_a_body_of_it_is_moved_pushed_changed_or_reached():
    scene = scenes.pile(10, dt=1 / 120)
    simulator = Simulator.for_scene(scene, parallel=False)
    state, params = scene.initial_state(), scene.body_params()
    stats = np.zeros((10, layout.STATS_SIZE))
    warm = warm_start_memory(11)  # room for a box thrown later
    settings = make_settings(scene, 480, until_rest=True)
    simulator.run(state, params, settings, stats, warm_start=warm)
    asleep = state.copy()
    simulator.run(state, params, settings, stats, warm_start=warm)
    assert np.array_equal(state, asleep) and not stats[:, layout.N_STEPS].any()
    assert np.all(stats[:, layout.REST_TIME] == 0.0)  # asleep from the start, as bodies placed at rest
    top = int(np.argmax(state[:, 1]))
    for change in ("pushed", "moved", "changed"):
        state, changed = asleep.copy(), params.copy()
        warm_then = warm.copy()
        if change == "pushed":
            state[top, 3] = 0.5
        elif change == "moved":
            state[top, 0] += 1e-3
        else:
            changed[top, layout.FRICTION] *= 0.5
        simulator.run(state, changed, settings, stats, warm_start=warm_then)
        assert stats[top, layout.N_STEPS] > 0  # its island woke (the caller changed one of its bodies)
    # a box dropped onto the sleeping pile: a body past the ones kept, awake; it wakes the pile when it reaches it
    dropped = dataclasses.replace(
        scene.boxes[top], position=(float(asleep[top, 0]), float(asleep[top, 1]) + 1.0), angle=0.0
    )
    scene11 = scene.replace(boxes=(*scene.boxes, dropped))
    state11 = np.vstack([asleep, scene11.initial_state()[10:]])
    stats11 = np.zeros((11, layout.STATS_SIZE))
    Simulator.for_scene(scene11, parallel=False).run(
        state11, scene11.body_params(), make_settings(scene11, 480, True), stats11, warm_start=warm
    )
    assert stats11[10, layout.N_STEPS] > 0 and stats11[top, layout.N_STEPS] > 0
    assert state11[10, 1] > asleep[top, 1]  # it lies on the pile


@pytest.mark.parametrize("until_rest", [True, False])
def test_a_run_on_a_pile_asleep_throughout_leaves_what_the_stepping_run_leaves(until_rest):
    """A call on bodies all kept asleep and untouched skips the run's set-up (``islands.sleeps_through``), ended
    at once (``until_rest``) or at its last step (sleeping, ``simulate``'s default): its state, stats and warm
    start are those of the recording kernel, which sets everything up and finds nothing awake to step."""
    scene = scenes.pile(100, dt=1 / 60)
    state, params = scene.initial_state(), scene.body_params()
    stats, warm = np.zeros((100, layout.STATS_SIZE)), warm_start_memory(100)
    Simulator.for_scene(scene, parallel=False).run(
        state, params, make_settings(scene, 600, until_rest=True), stats, warm_start=warm
    )
    assert not np.isnan(stats[:, layout.REST_TIME]).any()  # the pile fell asleep
    settings = make_settings(scene, 600, until_rest=until_rest, sleep=True)
    results = []
    for record in (False, True):
        simulator = Simulator.for_scene(scene, parallel=False, record=record)
        again, again_stats, again_warm = state.copy(), np.full_like(stats, -7.0), warm.copy()
        extra = {}
        if record:
            extra = dict(trajectory=np.zeros((601, 100, 6)), events=np.zeros((100, layout.MAX_EVENTS, 3)))
        simulator.run(again, params, settings, again_stats, warm_start=again_warm, **extra)
        results.append((again, again_stats, again_warm))
    (skipped, skipped_stats, skipped_warm), (stepped, stepped_stats, stepped_warm) = results
    assert np.array_equal(skipped, state) and np.array_equal(stepped, state)
    assert np.array_equal(skipped_stats, stepped_stats, equal_nan=True)
    assert np.array_equal(skipped_warm, stepped_warm)
    assert not skipped_stats[:, layout.N_STEPS].any() and np.all(skipped_stats[:, layout.REST_TIME] == 0.0)
    assert np.all(skipped_stats[:, layout.END_TIME] == (0.0 if until_rest else 600 * scene.dt))
    probe_stats = np.zeros_like(stats)  # the skip itself, on what the run above was given
    end_step = 0 if until_rest else 600
    assert compiled_sleeps_through(warm.copy(), state.copy(), params, scene.dt, probe_stats, end_step)
    assert np.array_equal(probe_stats, stepped_stats, equal_nan=True)


@pytest.mark.parametrize("change", ["moved", "set moving", "turned", "made heavier", "label lost"])
@pytest.mark.parametrize("body", [0, 50, 99])
def test_a_run_does_not_sleep_through_a_body_changed_since(change, body):
    """``islands.sleeps_through`` checks every body at once (no branch a comparison): any one body moved by a
    rounding, set moving, turned, given another mass, or whose kept island label is damaged (NaN), first, middle
    or last, and the call is not skipped (the kernel then sets up and steps, and writes every body's stats)."""
    scene = scenes.pile(100, dt=1 / 60)
    state, params = scene.initial_state(), scene.body_params()
    stats, warm = np.zeros((100, layout.STATS_SIZE)), warm_start_memory(100)
    Simulator.for_scene(scene, parallel=False).run(
        state, params, make_settings(scene, 600, until_rest=True), stats, warm_start=warm
    )
    assert compiled_sleeps_through(warm.copy(), state.copy(), params, scene.dt, np.zeros_like(stats), 0)
    state, params, warm = state.copy(), params.copy(), warm.copy()
    if change == "moved":
        state[body, 0] = np.nextafter(state[body, 0], np.inf)
    elif change == "set moving":
        state[body, 4] = 1e-9
    elif change == "turned":
        state[body, 2] += 1e-12
    elif change == "made heavier":
        params[body, layout.MASS] *= 1.0 + 1e-12
    else:
        warm[1 + layout.WARM_BODY_ROWS * body, 0] = np.nan
    assert not compiled_sleeps_through(warm, state, params, scene.dt, np.zeros_like(stats), 0)


def test_a_column_of_40_boxes_starting_cold_stays_at_rest():
    """Over 64 contacts a cold start begins from the resting loads (``warm_start.resting_loads``): each
    contact carries the weight above it, so a column of 40 boxes built exactly on one another stays at rest in
    its first step of 1/60 s (from zero, its 16 Gauss-Seidel sweeps cannot carry the load down 40 layers:
    it sank at 0.24 m/s)."""
    boxes = tuple(Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 0.1 + 0.2 * k)) for k in range(40))
    scene = Scene(boxes=boxes, dt=1 / 60, restitution=0.3, friction=0.5, penalty_stiffness=1e5, boxes_collide=True)
    state, params = scene.initial_state(), scene.body_params()
    stats = np.zeros((40, layout.STATS_SIZE))
    for _ in range(3):  # three cold starts, one step each
        Simulator.for_scene(scene, parallel=False).run(state, params, make_settings(scene, 1, False), stats)
        assert np.abs(state[:, 3:]).max() < 1e-12
    np.testing.assert_allclose(state, scene.initial_state(), atol=1e-12)


@pytest.mark.parametrize("depth_in_slops", [1.5, 3.0])
def test_the_penalty_starts_at_twice_the_slop_and_stops_at_it(depth_in_slops):
    """Two boxes side by side (stepped together), both sunk into the floor: less than twice the slop deep they
    are left alone; deeper, the penalty lifts them to between one and two slops."""
    slop = 1e-4
    boxes = tuple(Box(length=0.4, width=0.2, mass=2.0, position=(x, 0.1 - depth_in_slops * slop)) for x in (0.0, 0.4))
    scene = Scene(
        boxes=boxes, dt=1 / 120, friction=0.5, penalty_stiffness=1e5, boxes_collide=True, penetration_slop=slop
    )
    state, params = scene.initial_state(), scene.body_params()
    stats = np.zeros((2, layout.STATS_SIZE))
    Simulator.for_scene(scene, parallel=False).run(state, params, make_settings(scene, 60, False), stats)
    depth = 0.1 - state[:, 1]
    if depth_in_slops < 2.0:
        np.testing.assert_allclose(depth, depth_in_slops * slop, rtol=1e-9)
    else:
        assert np.all((depth > slop) & (depth <= 2.0 * slop + 1e-12))


@pytest.mark.parametrize("per_island", [2, 20])  # the exact solve (24 contacts), Gauss-Seidel (over 64)
def test_the_penalty_acts_island_by_island(per_island):
    """Two rows of boxes side by side, apart (two islands): the row sunk 3 slops into the floor is lifted to between
    one and two slops, the row sunk 1.5 slops, in the same scene, is left alone."""
    slop = 1e-4
    boxes = tuple(
        Box(length=0.4, width=0.2, mass=2.0, position=(row * 20.0 + 0.4 * k, 0.1 - sunk * slop))
        for row, sunk in enumerate((3.0, 1.5))
        for k in range(per_island)
    )
    scene = Scene(
        boxes=boxes, dt=1 / 120, friction=0.5, penalty_stiffness=1e5, boxes_collide=True, penetration_slop=slop
    )
    state, params = scene.initial_state(), scene.body_params()
    stats = np.zeros((2 * per_island, layout.STATS_SIZE))
    Simulator.for_scene(scene, parallel=False).run(state, params, make_settings(scene, 60, False), stats)
    depth = 0.1 - state[:, 1]
    assert np.all((depth[:per_island] > slop) & (depth[:per_island] <= 2.0 * slop + 1e-12))
    np.testing.assert_allclose(depth[per_island:], 1.5 * slop, rtol=1e-9)


def test_a_leaning_column_starting_cold_stays_at_rest():
    """The cold start's guess balances moments too (``warm_start.lever_shares``): in a column of 40 boxes
    (over 64 contacts), each 5 mm right of the one below, every pair of contacts carries the load above it split
    by the lever rule (the load's line of action runs right of the middle), so the column stays at rest in its
    first step of 1/60 s; split equally (as before), the boxes turned at up to 6.6 mm/s."""
    boxes = tuple(Box(length=0.4, width=0.2, mass=2.0, position=(0.005 * k, 0.1 + 0.2 * k)) for k in range(40))
    scene = Scene(boxes=boxes, dt=1 / 60, restitution=0.3, friction=0.5, penalty_stiffness=1e5, boxes_collide=True)
    state, params = scene.initial_state(), scene.body_params()
    stats = np.zeros((40, layout.STATS_SIZE))
    Simulator.for_scene(scene, parallel=False).run(state, params, make_settings(scene, 1, False), stats)
    assert np.abs(state[:, 3:]).max() < 1e-9


def test_the_sweeps_stop_only_once_every_contact_is_solved():
    """``sweeps.gauss_seidel`` stops once a sweep changes the impulses by less than the tolerance of their
    sum *and* none by more than SINGLE_CHANGE times that share of their mean. Beside 2,000 boxes lying apart (4,000
    contacts whose sum hides one column's), a box dropped from 1 mm onto a column of 10 passes its load down the
    column within the penalty's band (under 4 slops, 0.2 mm); stopped by the sum alone, the column took 0.33 mm."""
    slop = 5e-5
    boxes = [Box(length=0.4, width=0.2, mass=2.0, position=(2.0 + k, 0.1)) for k in range(2000)]
    boxes += [
        Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 0.1 + 0.2 * k + (1e-3 if k == 10 else 0.0)))
        for k in range(11)
    ]
    scene = Scene(
        boxes=tuple(boxes),
        dt=1 / 60,
        friction=0.5,
        penalty_stiffness=1e5,
        boxes_collide=True,
        solver_tolerance=1e-4,
        solver_iterations=32,
        penetration_slop=slop,
    )
    state, params = scene.initial_state(), scene.body_params()
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    Simulator.for_scene(scene, parallel=False).run(state, params, make_settings(scene, 60, False), stats)
    assert stats[:, layout.MAX_PENETRATION].max() < 4 * slop
