"""A large scene whose boxes collide runs its large stages on threads (``colliding.parallel``): the same results
bit for bit on one thread and on two, in every stage that runs on threads (the broadphase's sweep, the
narrowphase, and the sweeps of the velocities, the penalty and the restitution block by block); a run off threads
(``parallel=False``, or one share of a grouped run) runs them on its own thread alone."""

import numba
import numpy as np
import pytest

from box_toss_env.physics import KernelFlags, Simulator, layout, make_settings, scenes, simulate, warm_start_memory
from box_toss_env.physics.colliding.parallel import PARALLEL_BODIES, PARALLEL_CONTACTS, reaches_threads
from box_toss_env.physics.colliding.threads import restore_threads, use_threads
from box_toss_env.physics.compile.background_compile import interpreted_copy
from box_toss_env.physics.grouped import GroupedSimulator

TWO = pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="numba has one thread here")


def run(scene, steps, threads):
    """(final state, stats, warm start) of ``steps`` steps of ``scene`` on ``threads`` threads, kept awake."""
    state, warm = scene.initial_state(), warm_start_memory(scene.n_bodies)
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    settings = make_settings(scene, steps, until_rest=False, sleep=False)
    Simulator.for_scene(scene, threads=threads).run(state, scene.body_params(), settings, stats, warm_start=warm)
    return state, stats, warm


@TWO
@pytest.mark.parametrize(
    ("name", "scene", "steps"),
    [
        ("pile", scenes.pile(700, restitution=0.3), 450),  # dropped: impacts (restitution), substeps, the penalty
        ("pyramid", scenes.pyramid(rows=30), 40),  # one island of 465 boxes at rest
    ],
)
def test_one_and_two_threads_give_the_same_results_bit_for_bit(name, scene, steps):
    assert scene.n_bodies >= PARALLEL_BODIES
    one_state, one_stats, one_warm = run(scene, steps, threads=1)
    two_state, two_stats, two_warm = run(scene, steps, threads=2)
    assert one_warm[0, 0] >= PARALLEL_CONTACTS  # the last substep's contacts: the sweeps ran block by block
    assert np.array_equal(one_state, two_state)
    assert np.array_equal(one_stats, two_stats, equal_nan=True)
    assert np.array_equal(one_warm, two_warm)
    assert np.isfinite(one_state).all()


@TWO
def test_simulate_takes_its_threads_and_sleeps_the_same_on_any():
    scene = scenes.pile(300)
    one = simulate(scene, duration=1.0, until_rest=True, threads=1)
    two = simulate(scene, duration=1.0, until_rest=True, threads=2)
    assert np.array_equal(one.final_state, two.final_state)
    assert np.array_equal(one.rest_time, two.rest_time, equal_nan=True)
    assert np.array_equal(one.max_penetration, two.max_penetration)


def test_a_large_pyramid_stands_when_its_sweeps_go_block_by_block():
    scene = scenes.pyramid(rows=30)
    state, stats, warm = run(scene, 128, threads=1)
    assert warm[0, 0] >= PARALLEL_CONTACTS
    assert np.abs(state[:, :3] - scene.initial_state()[:, :3]).max() < 1e-6
    assert stats[:, layout.MAX_PENETRATION].max() < 1e-4


@TWO
@pytest.mark.parametrize("n", [4, 40])
def test_a_run_leaves_the_callers_thread_count_as_it_found_it(n):
    """A run sets numba's thread count (the calling thread's own) only for itself: to its ``threads`` where that
    differs, and back after (a scene with boxes enough to reach a stage on threads: the kernel sets it,
    ``colliding.threads``); a scene too small for a stage on threads leaves it alone. The results do not depend
    on it."""
    scene = scenes.pile(n)
    assert reaches_threads(n) == (n == 40)
    results = []
    before = numba.get_num_threads()
    try:
        for count in (1, 2):
            numba.set_num_threads(count)
            for parallel, threads in ((True, 1), (True, 2), (False, None)):
                state, stats = scene.initial_state(), np.zeros((scene.n_bodies, layout.STATS_SIZE))
                simulator = Simulator.for_scene(scene, parallel=parallel, threads=threads)
                simulator.run(state, scene.body_params(), make_settings(scene, 64, until_rest=False), stats)
                assert numba.get_num_threads() == count
                results.append(state)
    finally:
        numba.set_num_threads(before)
    assert all(np.array_equal(state, results[0]) for state in results)


@TWO
def test_a_run_off_threads_is_given_one_thread_in_its_settings():
    """``parallel=False`` runs on the calling thread alone: a scene with boxes enough to reach a stage on threads
    (``reaches_threads``) goes to the kernel with THREADS at 1 (the count the kernel sets for the run), one told
    ``threads=2`` at 2, a scene too small for one at 0 (numba's count as it is); the caller's settings are left as
    they were."""
    seen = []
    for n, threads, expected in ((31, None, 1), (PARALLEL_BODIES, None, 1), (30, None, 0), (31, 2, 2)):
        assert reaches_threads(n) == (n != 30)
        scene = scenes.pile(n)
        simulator = Simulator.for_scene(scene, parallel=threads is not None, threads=threads)
        simulator.kernel = lambda state, params, settings, *rest: seen.append(settings[layout.THREADS])  # noqa: ARG005
        simulator._ready = True  # the recording stand-in needs no compiling
        state, stats = scene.initial_state(), np.zeros((n, layout.STATS_SIZE))
        settings = make_settings(scene, 1, until_rest=False)
        given = settings.copy()
        simulator.run(state, scene.body_params(), settings, stats)
        assert seen[-1] == expected
        assert np.array_equal(settings, given)


@numba.njit
def _use_and_note(settings, seen):
    """``use_threads`` then ``restore_threads`` as the kernel calls them, numba's count noted in between."""
    before = use_threads(settings)
    seen[0] = numba.get_num_threads()
    restore_threads(settings, before)
    return before


@TWO
@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "interpreted"])
def test_the_kernel_sets_numbas_thread_count_for_the_run_and_back(compiled):
    """``colliding.threads``: numba's count at the settings' THREADS between the two stages (0: as it was), and back
    after; compiled (the kernel's calls into numba's threading layer by symbol) and in the kernel's interpreted
    copy (numba's Python functions)."""
    use, restore = interpreted_copy(use_threads), interpreted_copy(restore_threads)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(2)
        settings = np.zeros(layout.SETTINGS_SIZE)
        for wanted, during in ((1, 1), (2, 2), (0, 2)):
            settings[layout.THREADS] = wanted
            seen = np.zeros(1, np.int64)
            if compiled:
                was = _use_and_note(settings, seen)
            else:
                was = use(settings)
                seen[0] = numba.get_num_threads()
                restore(settings, was)
            assert was == 2 and seen[0] == during
            assert numba.get_num_threads() == 2
    finally:
        numba.set_num_threads(before)


@TWO
def test_a_grouped_run_gives_each_share_of_large_groups_one_thread():
    """``GroupedSimulator``'s threads are its shares of groups: each share's call of groups large enough to reach
    a stage on threads goes to the kernel with THREADS at 1 (the count the colliding kernel sets for each group's
    run), on one share and on two; smaller groups at 0 (numba's count as it is); the caller's settings are left as
    they were. With the real kernel, a run of groups of 31 leaves numba's count as it found it, with the results
    of one share."""
    seen: list[float] = []
    for size, expected in ((31, 1.0), (30, 0.0)):
        scene = scenes.pile(size)
        state = np.concatenate([scene.initial_state()] * 2)
        params = np.concatenate([scene.body_params()] * 2)
        for threads in (1, 2):
            seen.clear()
            simulator = GroupedSimulator(KernelFlags(boxes_collide=True, parallel=True), size, threads=threads)
            simulator.kernel = lambda state, params, settings, *rest: seen.append(settings[layout.THREADS])  # noqa: ARG005
            simulator._ready = True  # the recording stand-in needs no compiling
            settings = make_settings(scene, 1, until_rest=False)
            given = settings.copy()
            simulator.run(state.copy(), params, settings, np.zeros((2 * size, layout.STATS_SIZE)))
            assert seen == [expected] * threads
            assert np.array_equal(settings, given)
    scene = scenes.pile(31)
    ends = []
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(2)
        for threads in (1, 2):
            state = np.concatenate([scene.initial_state()] * 2)
            params = np.concatenate([scene.body_params()] * 2)
            simulator = GroupedSimulator(KernelFlags(boxes_collide=True, parallel=True), 31, threads=threads)
            stats = np.zeros((62, layout.STATS_SIZE))
            simulator.run(state, params, make_settings(scene, 32, until_rest=False), stats)
            assert numba.get_num_threads() == 2
            ends.append(state)
    finally:
        numba.set_num_threads(before)
    assert np.array_equal(ends[0], ends[1])
