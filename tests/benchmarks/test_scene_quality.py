"""The measures of what a run did: penetration, energy, rise, tunnelling, crossing, sleep, jitter, standing."""

import math

import numpy as np
import pytest

from benchmarks import scene_quality
from box_toss_env.physics import Box, Scene


def two_boxes(*boxes) -> Scene:
    """Boxes (length, width, position, angle); the measures take any state, overlapping or not."""
    return Scene(boxes=tuple(Box(length=l, width=w, position=p, angle=a) for l, w, p, a in boxes))


def depths(scene: Scene, state: np.ndarray) -> tuple[float, float, np.ndarray]:
    deep = np.zeros(scene.n_bodies, dtype=np.bool_)
    between, floor = scene_quality.overlaps(state, scene_quality.box_arrays(scene)[0], deep)
    return between, floor, deep


def test_a_corner_inside_a_face_and_the_floor():
    scene = two_boxes((0.4, 0.2, (0.0, 0.1), 0.0), (0.4, 0.2, (0.1, 0.3), 0.0))
    state = scene.initial_state()
    assert depths(scene, state)[:2] == pytest.approx((0.0, 0.0), abs=1e-12)
    state[0, 1] = 0.097  # 3 mm into the floor
    state[1, 1] = 0.287  # 1 cm into the lower box
    between, floor, deep = depths(scene, state)
    assert between == pytest.approx(0.01) and floor == pytest.approx(0.003)
    assert not deep.any()


def test_crossed_thin_boxes_overlap_by_their_thickness_and_count_as_tunnelled():
    """No corner of either lies inside the other: the separating-axis depth still finds the overlap."""
    scene = two_boxes((0.5, 0.01, (0.0, 1.0), 0.0), (0.5, 0.01, (0.0, 1.0), math.pi / 2))
    between, _, deep = depths(scene, scene.initial_state())
    assert between == pytest.approx(0.01)
    assert deep.all()


def test_a_rotated_box_resting_on_a_corner_is_measured_exactly():
    angle = 0.3
    scene = two_boxes((0.4, 0.2, (0.0, 1.0), angle), (0.4, 0.2, (5.0, 0.1), 0.0))
    lowest = 0.2 * math.sin(angle) + 0.1 * math.cos(angle)
    state = scene.initial_state()
    state[0, 1] = lowest - 2e-3
    assert depths(scene, state)[1] == pytest.approx(2e-3)


def test_the_track_of_a_box_shot_up_through_the_floor():
    scene = two_boxes((0.4, 0.2, (0.0, 0.1), 0.0), (0.4, 0.2, (2.0, 0.1), 0.0))
    start = scene.initial_state()
    track = scene_quality.Track(scene, start)
    asleep = np.array([False, False])
    track.add(start, asleep, 0.1)
    assert track.stands and track.quality.rise == 0.0 and not track.quality.gains_energy
    moved = start.copy()
    moved[1, 1], moved[1, 4] = 3.0, 5.0  # shot 2.9 m up at 5 m/s
    track.add(moved, asleep, 0.2)
    q = track.quality
    assert q.rise == pytest.approx(2.9) and q.gains_energy and q.energy_gain > 2.9 * 9.81
    assert not track.stands and q.top_drift == pytest.approx(0.0, abs=1e-12) and q.moving_end == 1
    below = moved.copy()
    below[0, 1] = -0.05
    track.add(below, np.array([True, True]), 0.3)
    assert track.quality.tunnelled == 1 and track.quality.asleep_at == pytest.approx(0.3)
    assert track.quality.asleep_end == 2 and track.quality.moving_end == 0  # asleep bodies do not jitter
    assert track.quality.penetration == pytest.approx(0.15)  # deepest over the window
    assert track.quality.samples == 3


def test_a_thrown_box_that_passes_the_pile_below_its_top_crossed_it():
    boxes = [(0.4, 0.2, (x, 0.1), 0.0) for x in (0.0, 0.5)] + [(0.4, 0.2, (-3.0, 0.5), 0.0)]
    scene = two_boxes(*boxes)
    start = scene.initial_state()
    for path, crossed in (([(-1.0, 0.15), (1.5, 0.15)], True), ([(-1.0, 0.6), (1.5, 0.6)], False)):
        track = scene_quality.Track(scene, start, thrown=2)
        for x, y in path:
            state = start.copy()
            state[2, :2] = x, y
            track.add(state, np.zeros(3, dtype=bool), 0.0)
        assert track.quality.crossed is crossed, path


def test_stands_and_jitter_scale_with_the_boxes():
    scene = two_boxes((1e-3, 5e-4, (0.0, 2.5e-4), 0.0), (1e-3, 5e-4, (1.0, 2.5e-4), 0.0))
    start = scene.initial_state()
    state = start.copy()
    state[0, 0] += 1e-3  # a box length: far for a 1 mm box
    state[1, 3] = 1e-3  # 1 mm/s: fast for it
    track = scene_quality.Track(scene, start, scale=1 / 400)
    track.add(state, np.zeros(2, dtype=bool), 0.0)
    assert not track.stands and track.quality.moving_end == 1
    big = scene_quality.Track(scene, start)
    big.add(state, np.zeros(2, dtype=bool), 0.0)
    assert big.stands and big.quality.moving_end == 0
