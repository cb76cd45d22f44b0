"""SceneRenderer: frames show the state they are given, deterministically; the window opens and closes."""

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from gymnasium.error import DependencyNotInstalled

import box_toss_env.rendering
from box_toss_env.rendering import RENDER_INSTALL_HINT, Camera, Palette, SceneRenderer
from box_toss_env.rendering.renderer import floor_tick_step

# Headless window. SDL reads this when pygame.display is initialised (the first `show`), and nothing above
# imports pygame: the renderer imports it on its first draw.
os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

WIDTH_PX, HEIGHT_PX = 320, 240
CAMERA = Camera.from_view(-1.0, 5.0, -1.0, 3.5, WIDTH_PX, HEIGHT_PX)  # 53.3 px/m
PALETTE = Palette()
HALF_EXTENTS = np.array([[0.5, 0.25]])
CENTRE = np.array([[2.0, 1.5]])
MISSING_PYGAME_MESSAGE = re.escape('pip install "box_toss_env[render]"')


def make_renderer() -> SceneRenderer:
    return SceneRenderer(WIDTH_PX, HEIGHT_PX, camera=CAMERA)


def colour_at(frame: np.ndarray, point_m) -> tuple[int, int, int]:
    row, column = CAMERA.pixel_index(point_m)
    return tuple(int(channel) for channel in frame[row, column])


def has_colour(frame: np.ndarray, colour) -> np.ndarray:
    """(H, W) mask of pixels with exactly this colour."""
    return np.all(frame == np.array(colour, dtype=np.uint8), axis=-1)


def rotate(angle: float, vector) -> np.ndarray:
    cos, sin = np.cos(angle), np.sin(angle)
    return np.array([[cos, -sin], [sin, cos]]) @ np.asarray(vector, dtype=np.float64)


@pytest.fixture
def renderer():
    scene_renderer = make_renderer()
    yield scene_renderer
    scene_renderer.close()


def test_frame_shape_and_dtype(renderer):
    frame = renderer.render_rgb(CENTRE, [0.3], HALF_EXTENTS, target_x=3.0, text_lines=["t = 0.00 s"])
    assert frame.shape == (HEIGHT_PX, WIDTH_PX, 3)
    assert frame.dtype == np.uint8
    assert frame.flags.c_contiguous and frame.flags.writeable


def test_box_is_drawn_at_its_position(renderer):
    frame = renderer.render_rgb(CENTRE, [0.3], HALF_EXTENTS)
    assert colour_at(frame, CENTRE[0]) == PALETTE.box_fill
    assert colour_at(frame, [4.5, 3.0]) == PALETTE.background
    assert colour_at(frame, [-0.5, 1.5]) == PALETTE.background


def test_box_moves_with_its_state(renderer):
    moved_centre = CENTRE[0] + [1.5, -0.5]
    frame = renderer.render_rgb([moved_centre], [0.0], HALF_EXTENTS)
    assert colour_at(frame, moved_centre) == PALETTE.box_fill
    assert colour_at(frame, CENTRE[0]) == PALETTE.background


def test_floor_is_drawn_below_zero(renderer):
    frame = renderer.render_rgb(np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2)))
    for x in (-0.5, 1.0, 4.5):
        assert colour_at(frame, [x, -0.3]) == PALETTE.ground
        assert colour_at(frame, [x, -0.9]) == PALETTE.ground
        assert colour_at(frame, [x, 0.3]) == PALETTE.background
    floor_row = CAMERA.world_to_pixel([0.0, 0.0])[1]
    ground_rows = np.flatnonzero(np.any(has_colour(frame, PALETTE.ground), axis=1))
    assert abs(ground_rows.min() - floor_row) <= 2


@pytest.mark.parametrize("angle", [0.0, np.pi / 2, np.pi, -np.pi / 2, 0.4])
def test_marked_face_is_on_the_side_its_normal_points_to(renderer, angle):
    """Face 0 (local -y) is at the bottom at angle 0, right at pi/2, on top at pi, left at -pi/2."""
    frame = renderer.render_rgb(CENTRE, [angle], HALF_EXTENTS)
    face_0_direction = rotate(angle, [0.0, -1.0])
    inset_m = 3.0 / CAMERA.pixels_per_metre  # mid-stripe: the face 0 stripe is 6 px wide
    half_width = HALF_EXTENTS[0, 1]
    near_face_0 = CENTRE[0] + face_0_direction * (half_width - inset_m)
    near_face_2 = CENTRE[0] - face_0_direction * (half_width - inset_m)
    assert colour_at(frame, near_face_0) == PALETTE.face_colours[0]
    assert colour_at(frame, near_face_2) != PALETTE.face_colours[0]


def test_all_four_faces_have_their_colours_at_angle_zero(renderer):
    frame = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS)
    hx, hy = HALF_EXTENTS[0]
    inset_m = 1.5 / CAMERA.pixels_per_metre  # mid-stripe of the 3 px stripes
    inside_each_face = {
        0: [0.0, -hy + 2 * inset_m],
        1: [hx - inset_m, 0.0],
        2: [0.0, hy - inset_m],
        3: [-hx + inset_m, 0.0],
    }
    for face, offset in inside_each_face.items():
        assert colour_at(frame, CENTRE[0] + offset) == PALETTE.face_colours[face], f"face {face}"


def test_target_marker_is_drawn_near_target_x(renderer):
    target_x = 3.0
    no_boxes = (np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2)))
    frame = renderer.render_rgb(*no_boxes, target_x=target_x)
    empty_frame = renderer.render_rgb(*no_boxes)
    target_column, floor_row = CAMERA.world_to_pixel([target_x, 0.0])

    target_pixels = has_colour(frame, PALETTE.target)
    rows, columns = np.nonzero(target_pixels)
    assert len(rows) > 0
    assert not np.any(has_colour(empty_frame, PALETTE.target))
    # the bracket straddles target_x on the floor; the flag and its label are above and to the right
    bracket_columns = columns[np.abs(rows - floor_row) <= 2]
    assert bracket_columns.min() < target_column < bracket_columns.max()
    assert np.all(np.abs(bracket_columns - target_column) <= 15)
    assert columns.min() >= target_column - 15
    assert rows.max() <= floor_row + 3


def test_target_tolerance_sets_bracket_width(renderer):
    tolerance_m = 1.0
    frame = renderer.render_rgb(np.zeros((0, 2)), [], np.zeros((0, 2)), target_x=2.0, target_tolerance_m=tolerance_m)
    target_column, floor_row = CAMERA.world_to_pixel([2.0, 0.0])
    rows, columns = np.nonzero(has_colour(frame, PALETTE.target))
    bracket_columns = columns[np.abs(rows - floor_row) <= 2]
    half_width_px = tolerance_m * CAMERA.pixels_per_metre
    assert abs(bracket_columns.min() - (target_column - half_width_px)) <= 2
    assert abs(bracket_columns.max() - (target_column + half_width_px)) <= 2


@pytest.mark.parametrize("target_face", [0, 1, 2, 3])
def test_target_face_icon_shows_that_face_colour_near_the_flag(renderer, target_face):
    target_x = 1.0
    frame = renderer.render_rgb(np.zeros((0, 2)), [], np.zeros((0, 2)), target_x=target_x, target_face=target_face)
    target_column, floor_row = CAMERA.world_to_pixel([target_x, 0.0])
    near_flag = frame[: int(floor_row), int(target_column) : int(target_column) + 80]
    for face in range(4):
        assert np.any(has_colour(near_flag, PALETTE.face_colours[face]))  # the icon is a whole striped box
    # the target face's stripe is the thick one, at the bottom of the icon
    rows_of_face = {face: np.nonzero(has_colour(near_flag, PALETTE.face_colours[face]))[0] for face in range(4)}
    assert rows_of_face[target_face].max() == max(rows.max() for rows in rows_of_face.values())
    counts = {face: len(rows) for face, rows in rows_of_face.items()}
    assert counts[target_face] == max(counts.values())


def test_rendering_is_deterministic(renderer):
    scene = dict(
        position=[[1.0, 0.25], [3.0, 1.2]],
        angle=[0.0, 0.7],
        half_extents=HALF_EXTENTS,
        target_x=3.5,
        target_face=2,
        text_lines=["t = 1.23 s", "reward = 0.5"],
    )
    first = renderer.render_rgb(**scene)
    renderer.render_rgb([[0.0, 2.0]], [1.0], HALF_EXTENTS)  # a different frame in between
    second = renderer.render_rgb(**scene)
    from_new_renderer = make_renderer().render_rgb(**scene)
    np.testing.assert_array_equal(first, second)
    np.testing.assert_array_equal(first, from_new_renderer)


def test_text_lines_are_drawn_top_left(renderer):
    without_text = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS)
    with_text = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS, text_lines=["t = 1.23 s", "second line"])
    rows, columns = np.nonzero(np.any(with_text != without_text, axis=-1))
    assert len(rows) > 0
    assert rows.max() < HEIGHT_PX // 3 and columns.max() < WIDTH_PX // 2


def test_missing_font_module_skips_text_with_a_warning(monkeypatch):
    import pygame

    def font_unavailable(*args, **kwargs):
        raise NotImplementedError("font module not available")

    monkeypatch.setattr(pygame.font, "Font", font_unavailable)
    renderer = make_renderer()
    with pytest.warns(RuntimeWarning, match="font"):
        frame = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS, text_lines=["t = 1.23 s"])
    np.testing.assert_array_equal(frame, make_renderer().render_rgb(CENTRE, [0.0], HALF_EXTENTS))


def test_single_box_shapes_broadcast(renderer):
    np.testing.assert_array_equal(
        renderer.render_rgb([2.0, 1.5], 0.3, [0.5, 0.25]),
        renderer.render_rgb(CENTRE, [0.3], HALF_EXTENTS),
    )


def test_boxes_out_of_view_or_not_finite_are_skipped(renderer):
    empty = renderer.render_rgb(np.zeros((0, 2)), [], np.zeros((0, 2)))
    far_and_nan = renderer.render_rgb([[1e9, 1.0], [np.nan, 1.0]], [0.0, 0.0], HALF_EXTENTS)
    np.testing.assert_array_equal(far_and_nan, empty)


@pytest.mark.parametrize(
    ("position", "angle", "half_extents"),
    [([[1.0, 2.0, 3.0]], [0.0], HALF_EXTENTS), ([[1.0, 2.0]], [0.0, 1.0], HALF_EXTENTS)],
)
def test_bad_shapes_raise(renderer, position, angle, half_extents):
    with pytest.raises(ValueError):
        renderer.render_rgb(position, angle, half_extents)


def test_bad_target_face_raises(renderer):
    with pytest.raises(ValueError, match="target_face"):
        renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS, target_x=1.0, target_face=4)


def test_camera_of_another_size_raises(renderer):
    with pytest.raises(ValueError, match="camera"):
        renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS, camera=Camera.from_view(0, 1, 0, 1, 10, 10))


def test_show_opens_window_with_the_rendered_frame_and_close_twice_is_safe():
    import pygame

    renderer = make_renderer()
    renderer.close()  # never opened: nothing to do
    scene = dict(position=CENTRE, angle=[0.2], half_extents=HALF_EXTENTS, target_x=3.0, text_lines=["t = 0"])
    assert renderer.show(**scene, fps=1000) is True
    window_pixels = pygame.surfarray.array3d(pygame.display.get_surface()).transpose(1, 0, 2)
    np.testing.assert_array_equal(window_pixels, renderer.render_rgb(**scene))
    assert renderer.show(**scene) is True  # reuses the window
    renderer.close()
    assert not pygame.display.get_init()
    renderer.close()
    assert renderer.render_rgb(**scene).shape == (HEIGHT_PX, WIDTH_PX, 3)  # still renders offscreen


def test_show_frame_blits_a_recorded_frame():
    import pygame

    with make_renderer() as renderer:
        frame = np.random.default_rng(2).integers(0, 256, size=(HEIGHT_PX, WIDTH_PX, 3), dtype=np.uint8)
        assert renderer.show_frame(frame) is True
        window_pixels = pygame.surfarray.array3d(pygame.display.get_surface()).transpose(1, 0, 2)
        np.testing.assert_array_equal(window_pixels, frame)
        with pytest.raises(ValueError, match="frame must be"):
            renderer.show_frame(frame[:10])
    assert not pygame.display.get_init()


def test_missing_pygame_raises_error_naming_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "pygame", None)  # makes `import pygame` raise ImportError
    renderer = make_renderer()  # constructing needs no pygame
    with pytest.raises(DependencyNotInstalled, match=MISSING_PYGAME_MESSAGE):
        renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS)
    with pytest.raises(DependencyNotInstalled, match=MISSING_PYGAME_MESSAGE):
        renderer.show(CENTRE, [0.0], HALF_EXTENTS)
    renderer.close()
    assert RENDER_INSTALL_HINT == 'pip install "box_toss_env[render]"'


def test_importing_the_package_does_not_import_pygame():
    repo_root = Path(box_toss_env.rendering.__file__).resolve().parents[2]
    code = "import sys, box_toss_env.rendering; assert 'pygame' not in sys.modules, 'pygame was imported'"
    environment = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(repo_root), os.environ.get("PYTHONPATH", "")]),
    }
    subprocess.run([sys.executable, "-c", code], check=True, env=environment, cwd=repo_root)


def test_target_label_replaces_the_default_text(renderer):
    default = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS, target_x=2.0)
    labelled = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS, target_x=2.0, target_label="a long side down")
    again = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS, target_x=2.0, target_label="a long side down")
    assert not np.array_equal(default, labelled)
    np.testing.assert_array_equal(labelled, again)


def test_floor_ticks_are_labelled_in_metres(renderer):
    frame = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS)
    assert renderer.drawn_text["floor"] == ["0", "1 m", "2 m", "3 m", "4 m"]  # -1 m and 5 m would be cut
    blank = SceneRenderer(WIDTH_PX, HEIGHT_PX, camera=CAMERA, palette=Palette(floor_label=PALETTE.ground))
    rows, columns = np.nonzero(np.any(frame != blank.render_rgb(CENTRE, [0.0], HALF_EXTENTS), axis=-1))
    floor_row = CAMERA.world_to_pixel([0.0, 0.0])[1]
    assert len(rows) > 0 and rows.min() > floor_row  # the labels are in the ground, under the ticks
    for x in range(5):
        assert np.any(np.abs(columns - CAMERA.world_to_pixel([x, 0.0])[0]) < 4)


def test_floor_tick_step_grows_when_zoomed_out():
    assert floor_tick_step(100.0, 0.0, 6.0) == 1.0
    assert floor_tick_step(20.0, 0.0, 30.0) == 2.0
    assert floor_tick_step(5.0, 0.0, 100.0) == 10.0


def test_result_lines_are_drawn_top_right_in_a_box(renderer):
    without = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS)
    lines = ["success: yes", "distance to target: 0.04 m"]
    with_result = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS, result_lines=lines, result_success=True)
    assert renderer.drawn_text["result"] == lines
    rows, columns = np.nonzero(np.any(with_result != without, axis=-1))
    assert rows.max() < HEIGHT_PX // 2 and columns.min() > WIDTH_PX // 3 and columns.max() >= WIDTH_PX - 10
    assert np.any(has_colour(with_result, PALETTE.success))


def test_trace_is_drawn_under_the_box(renderer):
    trace = np.array([[0.0, 1.0], [1.0, 2.0], [2.0, 1.5]])
    frame = renderer.render_rgb(CENTRE, [0.0], HALF_EXTENTS, trace=trace)
    assert colour_at(frame, [0.5, 1.5]) == PALETTE.trace
    assert colour_at(frame, CENTRE[0]) == PALETTE.box_fill  # the box covers the end of its trace


def test_target_label_moves_left_of_the_flag_at_the_right_edge(renderer):
    no_boxes = (np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2)))
    frame = renderer.render_rgb(*no_boxes, target_x=4.6, target_label="a long side down")
    assert renderer.drawn_text["target"] == ["a long side down"]
    target_column = CAMERA.world_to_pixel([4.6, 0.0])[0]
    columns = np.nonzero(has_colour(frame, PALETTE.target))[1]
    assert columns.min() < target_column - 40  # the label, on the left
