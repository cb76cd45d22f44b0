"""physics.grouped: many scenes of colliding boxes in one compiled call, each group as it runs alone."""

import numpy as np
import pytest

from box_toss_env.physics import Box, KernelFlags, Scene, Simulator, layout, make_settings
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
