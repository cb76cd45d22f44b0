"""Quiet steps (``colliding.quiet``): a colliding scene whose awake boxes are all nearly still takes QUIET_STRIDE grid
steps as one, and keeps what the grid steps keep: a resting pile or structure stays where it lies, a moving box steps
every grid step, runs in chunks of a multiple of QUIET_STRIDE are the run at once, and ``quiet_steps=False`` or a
scene of unlike masses steps every grid step."""

import numpy as np
import pytest
from physics_checks import advance_in_runs

from box_toss_env.physics import Simulator, layout, make_settings, scenes, simulate, warm_start_memory
from box_toss_env.physics.tunables import QUIET_MASS_RATIO, QUIET_STRIDE


def kept_awake(scene, seconds: tuple[float, ...]) -> list[tuple[np.ndarray, np.ndarray]]:
    """(state, steps integrated) at the end of each of consecutive runs of ``seconds``, sleeping off, the warm start
    carried from run to run (as a caller stepping a scene on keeps it)."""
    simulator = Simulator.for_scene(scene, parallel=False)
    state, params, warm = scene.initial_state(), scene.body_params(), warm_start_memory(scene.n_bodies)
    ends = []
    for duration in seconds:
        stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
        settings = make_settings(scene, round(duration / scene.dt), until_rest=False, sleep=False)
        simulator.run(state, params, settings, stats, warm_start=warm)
        ends.append((state.copy(), stats[:, layout.N_STEPS].copy()))
    return ends


@pytest.mark.parametrize(
    "scene",
    [scenes.stack(10), scenes.pyramid(rows=6), scenes.stack(5, masses=(1.0, 1.0, 1.0, 1.0, 100.0))],
    ids=["stack of 10", "pyramid of 21", "stack of 5, 100:1"],
)
def test_a_structure_built_at_rest_and_kept_awake_steps_quietly_and_stays_where_it_stands(scene):
    steps = 256
    quiet = simulate(scene, steps=steps, sleep=False)
    every = simulate(scene.replace(quiet_steps=False), steps=steps, sleep=False)
    assert QUIET_STRIDE > 1 and np.all(quiet.n_steps == steps // QUIET_STRIDE)
    assert np.all(every.n_steps == steps)
    start = scene.initial_state()
    for result in (quiet, every):  # both stand to rounding: the penalty's nanometre and less
        assert np.abs(result.final_state[:, :3] - start[:, :3]).max() < 1e-8
        assert np.abs(result.final_state[:, 3:]).max() < 1e-8


def test_a_settled_pile_kept_awake_lies_as_still_stepped_quietly_as_at_every_grid_step():
    for scene in (scenes.pile(16), scenes.pile(16, quiet_steps=False)):
        (settled, _), (end, stepped) = kept_awake(scene, (3.0, 2.0))
        assert np.abs(end[:, :2] - settled[:, :2]).max() < 1e-9 and np.abs(end[:, 3:]).max() < 1e-9
        assert stepped.max() == 512 // (QUIET_STRIDE if scene.quiet_steps else 1)


def test_a_moving_box_steps_every_grid_step_and_quiet_steps_resume_once_all_lie_still():
    scene = scenes.drop_on_box()  # a box falling onto another: every grid step while it falls and bounces
    quiet = simulate(scene, duration=4.0, sleep=False)
    every = simulate(scene.replace(quiet_steps=False), duration=4.0, sleep=False)
    assert every.n_steps.max() > quiet.n_steps.max() > (every.n_steps.max() - 256) // QUIET_STRIDE
    assert quiet.first_contact_time[0] == every.first_contact_time[0]  # the same fall, grid step for grid step
    assert np.abs(quiet.final_state[:, :2] - every.final_state[:, :2]).max() < 1e-3  # both lie on the box
    assert np.abs(quiet.final_state[:, 3:]).max() < 1e-6


def test_unlike_masses_step_every_grid_step():
    ratio = 10 * QUIET_MASS_RATIO
    scene = scenes.stack(5, masses=(1.0, 1.0, 1.0, 1.0, ratio))
    result = simulate(scene, steps=64, sleep=False)
    assert np.all(result.n_steps == 64)
    assert np.abs(result.final_state[:, :2] - scene.initial_state()[:, :2]).max() < 1e-8


def test_a_recorded_run_steps_every_grid_step():
    scene = scenes.stack(3)
    result = simulate(scene, steps=64, sleep=False, record=True)
    assert np.all(result.n_steps == 64) and result.trajectory.state.shape[0] == 65


def test_runs_in_chunks_of_the_quiet_stride_are_the_run_at_once():
    scene = scenes.pile(10, dt=1 / 120, sleep_time=1e6)
    chunk = 4 * QUIET_STRIDE
    once, stats_once = advance_in_runs(scene, 1, 30 * chunk)
    chunked, _ = advance_in_runs(scene, 30, chunk)
    assert np.array_equal(chunked, once)
    assert stats_once[:, layout.N_STEPS].max() < 30 * chunk  # the settled pile stepped quietly
