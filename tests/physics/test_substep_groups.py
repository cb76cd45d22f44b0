"""Substeps per group (``colliding.groups``): awake bodies that cannot touch within a grid step take their substeps
apart, each group with its own count, so a box thrown fast far from a pile leaves the pile's substeps as they
were: the pile ends bit for bit as it does without the box, in chunks as in one run, in a batch as alone."""

import numpy as np
import pytest
from physics_checks import advance_in_runs

from box_toss_env.physics import Box, KernelFlags, Scene, Simulator, layout, make_settings
from box_toss_env.physics.grouped import GroupedSimulator

SIZE = dict(length=0.4, width=0.2, mass=1.0)


def pair_and_far_boxes(far: bool) -> Scene:
    """A box dropped 3 cm onto a box on the floor (bodies 0 and 1, a substep or two a step), and with ``far`` two
    boxes sliding on the floor, at 100 m/s (body 2, 34 substeps a step: its speed against the floor) and at 15 m/s
    (body 3, 5), both moving away from the pair, 20 m and more from it: apart, the pair's substeps save more than
    ``SPLIT_SAVING``."""
    boxes = [Box(**SIZE, position=(0.0, 0.1)), Box(**SIZE, position=(0.05, 0.35), angle=0.1)]
    if far:
        boxes.append(Box(**SIZE, position=(20.0, 0.1), velocity=(100.0, 0.0)))
        boxes.append(Box(**SIZE, position=(-30.0, 0.1), velocity=(-15.0, 0.0)))
    return Scene(boxes=tuple(boxes), dt=1 / 60, restitution=0.3, friction=0.5, boxes_collide=True)


def test_a_pile_far_from_fast_boxes_takes_its_own_substeps_bit_for_bit():
    """With one substep count for every awake body, the pair would take the fastest box's 34 and end
    elsewhere (by rounding at least); with its own it ends exactly as without the far boxes."""
    with_far, far_stats = advance_in_runs(pair_and_far_boxes(far=True), 1, 36)
    alone, alone_stats = advance_in_runs(pair_and_far_boxes(far=False), 1, 36)
    assert with_far[:2].tobytes() == alone.tobytes()
    np.testing.assert_array_equal(far_stats[:2, layout.N_IMPACTS], alone_stats[:, layout.N_IMPACTS])
    assert alone_stats[1, layout.N_IMPACTS] > 0  # the dropped box struck the lower one
    assert with_far[2, 0] > 70.0 and with_far[3, 0] < -35.0  # the far boxes slid on, away from the pair


def test_groups_run_in_chunks_with_their_warm_start_as_in_one_run():
    """Each group's impulses are kept for the next step's warm start (scaled to one substep length), and so in
    the warm start memory between runs: in chunks as in one run."""
    scene = pair_and_far_boxes(far=True)
    once, _ = advance_in_runs(scene, 1, 36)
    chunked, _ = advance_in_runs(scene, 6, 6)
    assert chunked.tobytes() == once.tobytes()
    cold, _ = advance_in_runs(scene, 6, 6, warm_start=False)
    assert not np.array_equal(cold, once)  # the warm start carried something


@pytest.mark.parametrize("threads", [1, 2])
def test_a_batch_of_scenes_with_groups_ends_as_each_scene_alone(threads):
    scenes = [pair_and_far_boxes(far=True) for _ in range(3)]
    scenes[1] = scenes[1].replace(friction=0.2)
    settings = make_settings(scenes[0], 36, until_rest=True)
    state = np.concatenate([s.initial_state() for s in scenes])
    params = np.concatenate([s.body_params() for s in scenes])
    stats = np.zeros((len(state), layout.STATS_SIZE))
    GroupedSimulator(KernelFlags(boxes_collide=True, parallel=True), 4, threads=threads).run(
        state, params, settings, stats
    )
    for i, scene in enumerate(scenes):
        alone, alone_stats = scene.initial_state(), np.zeros((4, layout.STATS_SIZE))
        Simulator(KernelFlags(boxes_collide=True)).run(alone, scene.body_params(), settings, alone_stats)
        assert state[4 * i : 4 * i + 4].tobytes() == alone.tobytes()
        np.testing.assert_array_equal(stats[4 * i : 4 * i + 4], alone_stats)


def sliding_pair_and_far_boxes(far: bool) -> Scene:
    """``pair_and_far_boxes`` with the upper box resting on the lower one and sliding on it at 0.3 m/s (touching
    from the start: no box is placed at rest, and no step is taken alone against the floor)."""
    scene = pair_and_far_boxes(far)
    pair = (Box(**SIZE, position=(0.0, 0.1)), Box(**SIZE, position=(0.0, 0.3), velocity=(0.3, 0.0)))
    return scene.replace(boxes=(*pair, *scene.boxes[2:]))


def test_a_pile_beside_fast_boxes_falls_asleep_as_alone():
    """Sleep joins each group's islands (``islands.join_contacts`` group by group): the pair falls asleep at the
    step it does without the far boxes, in the same state, while they slide on."""
    results = {}
    for far in (True, False):
        scene = sliding_pair_and_far_boxes(far)
        state, stats = scene.initial_state(), np.zeros((scene.n_bodies, layout.STATS_SIZE))
        settings = make_settings(scene, 150, until_rest=True)
        Simulator.for_scene(scene, parallel=False).run(state, scene.body_params(), settings, stats)
        results[far] = state, stats
    (with_far, far_stats), (alone, alone_stats) = results[True], results[False]
    assert np.isfinite(alone_stats[:, layout.REST_TIME]).all() and alone_stats[0, layout.N_STEPS] < 150
    np.testing.assert_array_equal(far_stats[:2, layout.REST_TIME], alone_stats[:, layout.REST_TIME])
    assert with_far[:2].tobytes() == alone.tobytes()
    assert np.isnan(far_stats[2, layout.REST_TIME])  # the fast box still slides
