"""physics.grouped: many scenes of colliding boxes in one compiled call, each group as it runs alone."""

import numpy as np
import pytest

from box_toss_env.physics import Box, KernelFlags, Scene, Simulator, layout, make_settings, warm_start_memory
from box_toss_env.physics.grouped import GroupedSimulator, make_simulator

FLAGS = KernelFlags(boxes_collide=True, parallel=True)


def toss_scenes(n, seed=0):
    """n scenes of a box thrown at a box resting on the floor (what BoxToss-OnBox-v0 simulates)."""
    rng = np.random.default_rng(seed)
    scenes = []
    for _ in range(n):
        length, height = rng.uniform(0.6, 1.0), rng.uniform(0.2, 0.5)
        base = Box(length=length, width=height, mass=10.0, position=(rng.uniform(1.5, 3.0), 0.5 * height))
        thrown = Box(
            length=0.4,
            width=0.2,
            mass=2.0,
            position=(0.0, 1.4),
            velocity=(rng.uniform(0.5, 4.0), rng.uniform(-1.0, 5.0)),
            spin=rng.uniform(-10.0, 10.0),
        )
        scenes.append(
            Scene(
                boxes=(thrown, base),
                dt=1 / 128,
                gravity=-9.81,
                restitution=0.3,
                friction=0.5,
                penalty_stiffness=1e5,
                boxes_collide=True,
            )
        )
    return scenes


def run_alone(scene, settings):
    state, params = scene.initial_state(), scene.body_params()
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    Simulator(KernelFlags(boxes_collide=True)).run(state, params, settings, stats)
    return state, stats


def push_even_scenes(state, size):
    """Set the first box of every other scene moving (its island wakes in the next run)."""
    state[0 :: 2 * size, 3] += 0.5


@pytest.mark.parametrize("threads", [1, 2])
def test_each_group_ends_bit_for_bit_as_its_scene_alone(threads):
    scenes = toss_scenes(7)
    settings = make_settings(scenes[0], 1280, until_rest=True)
    state = np.concatenate([s.initial_state() for s in scenes])
    params = np.concatenate([s.body_params() for s in scenes])
    stats = np.zeros((len(state), layout.STATS_SIZE))
    GroupedSimulator(FLAGS, 2, threads=threads).run(state, params, settings, stats)
    moved = 0
    for i, scene in enumerate(scenes):
        alone_state, alone_stats = run_alone(scene, settings)
        assert state[2 * i : 2 * i + 2].tobytes() == alone_state.tobytes()
        np.testing.assert_array_equal(stats[2 * i : 2 * i + 2], alone_stats)
        moved += not np.array_equal(alone_state[0, :2], scene.initial_state()[0, :2])
    assert moved == len(scenes)


def test_make_simulator_keeps_the_plain_simulator_where_boxes_cannot_meet():
    plain = make_simulator(KernelFlags(parallel=True), 1)
    assert type(plain) is Simulator and not plain.flags.boxes_collide
    assert type(make_simulator(FLAGS, 2)) is GroupedSimulator
    assert type(make_simulator(KernelFlags(boxes_collide=True, record=True), 2)) is Simulator  # one recorded scene


def test_bad_use_is_refused_with_clear_errors():
    with pytest.raises(ValueError, match="boxes_collide=True"):
        GroupedSimulator(KernelFlags(), 2)
    with pytest.raises(ValueError, match="record"):
        GroupedSimulator(KernelFlags(boxes_collide=True, record=True), 2)
    with pytest.raises(ValueError, match=r"group_size must be an integer in \[1, 64\]"):
        GroupedSimulator(FLAGS, 0)
    simulator = GroupedSimulator(FLAGS, 2)
    with pytest.raises(ValueError, match="whole groups of group_size=2"):
        simulator.run(np.zeros((3, 6)), np.ones((3, 7)), np.zeros(8), np.zeros((3, 9)))


@pytest.mark.parametrize("threads", [1, 2])
def test_each_group_carries_its_own_warm_start_as_its_scene_alone(threads):
    """Two runs with one warm start a group (its contacts and its sleep, ``warm_start_memory``), every other
    scene pushed between them: each group ends each run as its scene run alone with its own warm start."""
    scenes = toss_scenes(5, seed=1)
    settings = make_settings(scenes[0], 1280, until_rest=True)
    state = np.concatenate([s.initial_state() for s in scenes])
    params = np.concatenate([s.body_params() for s in scenes])
    stats = np.zeros((len(state), layout.STATS_SIZE))
    warm = np.stack([warm_start_memory(2) for _ in scenes])
    alone = [(s.initial_state(), warm_start_memory(2)) for s in scenes]
    simulator, single = GroupedSimulator(FLAGS, 2, threads=threads), Simulator(KernelFlags(boxes_collide=True))
    for run in range(2):
        if run == 1:
            push_even_scenes(state, 2)
            for alone_state, _ in alone[::2]:
                alone_state[0, 3] += 0.5
        simulator.run(state, params, settings, stats, warm_start=warm)
        for i, (alone_state, alone_warm) in enumerate(alone):
            alone_stats = np.zeros((2, layout.STATS_SIZE))
            single.run(alone_state, params[2 * i : 2 * i + 2], settings, alone_stats, warm_start=alone_warm)
            assert state[2 * i : 2 * i + 2].tobytes() == alone_state.tobytes()
            np.testing.assert_array_equal(stats[2 * i : 2 * i + 2], alone_stats)
            np.testing.assert_array_equal(warm[i], alone_warm)
    # the scenes not pushed slept through the second run; the pushed ones were stepped
    assert not stats[2::4, layout.N_STEPS].any() and stats[0::4, layout.N_STEPS].all()


def test_the_group_warm_starts_are_checked():
    scenes = toss_scenes(2)
    state = np.concatenate([s.initial_state() for s in scenes])
    params = np.concatenate([s.body_params() for s in scenes])
    stats = np.zeros((4, layout.STATS_SIZE))
    settings = make_settings(scenes[0], 16, until_rest=True)
    with pytest.raises(ValueError, match=r"warm_start must be .* \(2 groups"):
        GroupedSimulator(FLAGS, 2).run(state, params, settings, stats, warm_start=warm_start_memory(2))
