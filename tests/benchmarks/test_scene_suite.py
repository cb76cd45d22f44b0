"""The engine comparison's scenes: the suite covers the engine goals' rows, our scenes keep the scene defaults, and
Box2D's benchmark scenes are laid out as Box2D's benchmark code lays them out (no timing asserted)."""

import numpy as np
import pytest

from benchmarks import scene_suite
from box_toss_env.physics import Scene, scenes

REQUIRED = {
    "pile 16", "pile 100", "pile 1000", "pile 5000", "pyramid 210", "tower 20", "heavy 100:1", "heavy 1000:1",
    "thin 100", "tiny 16", "huge 16", "throw 10 m/s", "throw 30 m/s", "throw 100 m/s", "large_pyramid",
    "many_pyramids",
}  # fmt: skip


def test_the_suite_covers_every_row_of_the_engine_goals_with_their_windows():
    cases = {case.name: case for case in scene_suite.suite()}
    assert set(cases) == REQUIRED
    assert set(cases["pile 1000"].labels) == {"drop", "rest", "awake"}
    assert cases["pyramid 210"].labels == ("stand", "awake")
    assert cases["throw 30 m/s"].labels == ("throw",)
    assert cases["large_pyramid"].labels == ("published",)
    assert all(not plan.sleep for plan in cases["large_pyramid"].plans)  # Box2D's benchmark turns sleeping off
    awake = [plan for plan in cases["pile 100"].plans if not plan.sleep]
    assert [s.label for s in awake[0].segments] == [None, "awake"]  # settled by the engine itself, then timed


def test_our_scenes_keep_every_engine_setting_at_the_scene_defaults():
    """A case sets what exists (boxes, material), never our step or solver settings."""
    defaults = scenes.pile(1)
    settings = ("dt", "penalty_stiffness", "solver_tolerance", "solver_iterations", "penetration_slop", "sleep_time",
                "sleep_speed", "restitution_threshold", "solver")  # fmt: skip
    quick = {case.name: case for case in scene_suite.suite(quick=True)}
    for case in [*quick.values(), scene_suite.suite()[1]]:
        for name in settings:
            assert getattr(case.scene, name) == getattr(defaults, name), (case.name, name)


def test_the_wide_tiny_huge_and_thin_piles():
    wide = scene_suite.wide_pile(100, layers=4)
    assert wide.n_bodies == 100 and wide.boxes_collide
    assert max(box.position[1] for box in wide.boxes) == pytest.approx(0.15 + 0.3 * 3)
    tiny, base = scene_suite.scaled_pile(16, 1 / 400), scenes.pile(16)
    assert tiny.boxes[0].length == pytest.approx(1e-3) and tiny.boxes[0].mass == pytest.approx(2.0 / 400**2)
    np.testing.assert_allclose(tiny.initial_state()[:, :2] * 400, base.initial_state()[:, :2])
    huge = scene_suite.scaled_pile(16, 250)
    assert huge.boxes[0].length == pytest.approx(100.0) and huge.boxes[0].width == pytest.approx(50.0)
    thin = scene_suite.thin_pile(100)
    assert {(b.length, b.width) for b in thin.boxes} == {(0.5, 0.01)}


def test_the_thrown_box_waits_far_away_and_is_launched_left_of_the_pile():
    scene, (x, y) = scene_suite.throw_scene(16)
    assert scene.n_bodies == 17 and scene.boxes[-1].position[0] == scene_suite.PARKED_AT
    left = min(b.position[0] for b in scene.boxes[:-1]) - 0.2
    assert x == pytest.approx(left - scene_suite.THROW_STANDOFF) and y == pytest.approx(0.4)
    plan = scene_suite.throw_plan(30.0, 16, (x, y), 2.0, 3.0)[0]
    assert plan.sleep and plan.segments[1].throw == (16, (x, y, 0.0, 30.0, 0.0, 0.0))


def test_large_pyramid_is_box2ds():
    """CreateLargePyramid: row i at y = i + 1/2, its squares side by side from x = (i + 1) / 2 - base / 2."""
    scene, layout = scene_suite.large_pyramid(4)
    assert scene.n_bodies == 10 and isinstance(scene, Scene)
    assert (scene.friction, scene.restitution, scene.gravity) == (0.6, 0.0, -10.0)
    state = scene.initial_state()
    assert {(b.length, b.width, b.mass) for b in scene.boxes} == {(1.0, 1.0, 1.0)}
    np.testing.assert_allclose(state[:4, :2], [[-1.5, 0.5], [-0.5, 0.5], [0.5, 0.5], [1.5, 0.5]])
    np.testing.assert_allclose(state[4:7, :2], [[-1.0, 1.5], [0.0, 1.5], [1.0, 1.5]])
    assert layout.ground_box == (100.0, 1.0, -1.0)  # b2MakeBox(100, 1) at y = -1
    assert scene_suite.LARGE_PYRAMID_BASE * (scene_suite.LARGE_PYRAMID_BASE + 1) // 2 == 5050


def test_many_pyramids_lays_box2ds_levels_end_to_end_for_ours_and_keeps_them_for_the_others():
    scene, layout = scene_suite.many_pyramids(grid=2, base=3)
    assert scene.n_bodies == 2 * 2 * 6
    state = scene.initial_state()
    others = state[:, :2] + layout.offsets
    level_height = 2 * 0.5 * (3 + 1)
    assert sorted({round(y, 9) for y in others[:, 1]}) == [0.5, 1.5, 2.5, 4.5, 5.5, 6.5]  # two levels, 4 m apart
    assert [f[0] for f in layout.floors] == [0.0, level_height]
    assert np.all(state[:, 1] < 3.0)  # ours: every level on the one floor
    level_width = 2 * 0.5 * 2 * (3 + 1)
    assert layout.floors[0][1:] == (-0.5 * level_width, 0.5 * level_width)
    first = others[:6]  # CreateSmallPyramid at centerX = -level_width / 2 + 2 extent: its bottom row from x = -3
    np.testing.assert_allclose(sorted(first[first[:, 1] == 0.5, 0]), [-3.0, -2.0, -1.0])


def test_quick_cases_are_small():
    assert all(case.scene.n_bodies <= 60 for case in scene_suite.suite(quick=True))
