"""Frames of whole throws read at a glance: the box is in every frame, the target too, the floor is labelled
in metres, and the last frames say how the throw ended.

The 1,000-throw check is geometric: every recorded state of each throw goes through the camera of the frame
that draws it (``ThrowRenderer.plan_throw``, the layout ``throw_frames`` rasterises), and all four box
corners must land inside the image. A few throws are rasterised to check the drawing agrees.
"""

import os

import numpy as np
import pytest

from box_toss_env.envs import BoxTossEnv, record_throws
from box_toss_env.envs.render import RESULT_HOLD_S, ThrowOutcome, ThrowRenderer, frame_rows
from box_toss_env.physics import layout
from box_toss_env.rendering import Palette, box_vertices

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

WIDTH_PX, HEIGHT_PX = 600, 400
N_THROWS = 1000
PALETTE = Palette()
LONG_HIGH_THROW = np.array([1.0, 0.55, 0.3], dtype=np.float32)  # 8 m/s at 63 degrees: 4 m high, 7.5 m long


def throw(env: BoxTossEnv, seed: int, action) -> tuple[np.ndarray, ThrowOutcome, dict]:
    """One episode; returns the recorded trajectory (T, 6), its outcome and info (nothing is drawn)."""
    env.reset(seed=seed)
    _, reward, _, _, info = env.step(np.asarray(action, dtype=np.float32))
    return env._throw_trajectory().copy(), env._outcome, info


def corners_px(renderer: ThrowRenderer, camera, states: np.ndarray) -> np.ndarray:
    """(n, 4, 2) pixel (column, row) of the box corners in engine states (n, 6)."""
    half_extents = np.broadcast_to(renderer.half_extents, (len(states), 2))
    return camera.world_to_pixel(box_vertices(states[:, :2], states[:, layout.ANGLE], half_extents))


def inside_image(pixels: np.ndarray, top_px: float = 0.0) -> np.ndarray:
    """Which points (..., 2) lie inside the image (below ``top_px``)."""
    columns, rows = pixels[..., 0], pixels[..., 1]
    return (columns >= 0) & (columns <= WIDTH_PX) & (rows >= top_px) & (rows <= HEIGHT_PX)


@pytest.fixture(scope="module")
def random_throws():
    """1,000 throws with uniform random actions (seeded), their trajectories and the env that threw them."""
    env = BoxTossEnv(render_mode="rgb_array_list", render_width=WIDTH_PX, render_height=HEIGHT_PX)
    actions = np.random.default_rng(12).uniform(-1.0, 1.0, size=(N_THROWS, 3))
    throws = [throw(env, seed, action)[0] for seed, action in enumerate(actions)]
    return env, throws


def test_the_box_is_inside_every_frame_of_1000_random_throws(random_throws):
    env, throws = random_throws
    renderer = env._renderer_for_env()
    home_misses = 0
    for trajectory in throws:
        planned = renderer.plan_throw(trajectory, env.dt)
        camera = planned[0].camera
        assert all(frame.camera is camera for frame in planned)  # one camera for the whole recorded throw
        # every recorded state, drawn or between two frames, with the top band left to the caption
        assert inside_image(corners_px(renderer, camera, trajectory), renderer.padding_px[2]).all()
        drawn_rows = [frame.row for frame in planned]
        assert inside_image(corners_px(renderer, camera, trajectory[drawn_rows])).all()
        home_misses += not inside_image(corners_px(renderer, renderer.home_camera, trajectory)).all()
    # the fixed home view alone would have lost a good share of them (about a quarter with the defaults)
    assert home_misses > 0.1 * N_THROWS


def test_the_target_stays_in_view_whatever_the_throw(random_throws):
    env, throws = random_throws
    renderer = env._renderer_for_env()
    config = env.config
    lowest, highest = config.target_x_range
    for trajectory in throws[:200]:
        camera = renderer.plan_throw(trajectory, env.dt)[0].camera
        x_min, x_max, y_min, _ = camera.view_bounds
        assert x_min <= lowest - config.position_tolerance and highest + config.position_tolerance <= x_max
        assert y_min < 0.0  # the floor line and a band of ground under it


def test_a_following_camera_keeps_the_box_in_every_frame_and_moves_smoothly(random_throws):
    env, throws = random_throws
    renderer = env._renderer_for_env()
    for trajectory in throws[:300]:
        planned = renderer.plan_throw(trajectory, env.dt, follow=True)
        for frame in planned:
            assert inside_image(corners_px(renderer, frame.camera, trajectory[[frame.row]])).all()
        # no jumps: from one frame to the next the scale changes by a few per cent at most
        scales = np.array([frame.camera.pixels_per_metre for frame in planned])
        assert np.abs(np.diff(np.log(scales))).max() < 0.1


def test_rasterised_frames_show_the_box_where_the_plan_puts_it():
    env = BoxTossEnv(render_mode="rgb_array_list", render_width=WIDTH_PX, render_height=HEIGHT_PX)
    renderer = env._renderer_for_env()
    for seed, action in ((3, [0.2, 0.0, 0.3]), (7, LONG_HIGH_THROW), (11, [-0.6, -0.2, -0.5])):
        trajectory, _, _ = throw(env, seed, action)
        frames = env.render()
        planned = renderer.plan_throw(trajectory, env.dt)
        assert len(frames) == len(planned)
        for frame, plan in zip(frames, planned, strict=True):
            row, column = plan.camera.pixel_index(trajectory[plan.row, :2])
            assert tuple(frame[row, column]) == PALETTE.box_fill
        # the last frame is not empty: the box rests where the throw ended
        row, column = planned[-1].camera.pixel_index(trajectory[-1, :2])
        assert tuple(frames[-1][row, column]) == PALETTE.box_fill
    env.close()


def test_a_long_high_throw_is_zoomed_out_and_stays_in_the_frame():
    env = BoxTossEnv(render_mode="rgb_array_list", render_width=WIDTH_PX, render_height=HEIGHT_PX)
    renderer = env._renderer_for_env()
    trajectory, _, _ = throw(env, 7, LONG_HIGH_THROW)
    assert trajectory[:, 1].max() > renderer.home_bounds[3] and trajectory[:, 0].max() > renderer.home_bounds[1]
    camera = renderer.plan_throw(trajectory, env.dt)[0].camera
    assert camera.pixels_per_metre < renderer.home_camera.pixels_per_metre
    assert inside_image(corners_px(renderer, camera, trajectory)).all()


# -- the result on the last frames -----------------------------------------------------------------
def test_the_last_frames_write_the_result_and_earlier_ones_do_not():
    env = BoxTossEnv(render_mode="rgb_array_list", render_width=WIDTH_PX, render_height=HEIGHT_PX)
    renderer = env._renderer_for_env()
    trajectory, outcome, info = throw(env, 3, [0.2, 0.0, 0.3])
    planned = renderer.plan_throw(trajectory, env.dt)
    n_rows = len(frame_rows(len(trajectory), env.dt, renderer.fps))
    n_held = round(RESULT_HOLD_S * renderer.fps)
    assert len(planned) == n_rows + n_held
    assert [frame.shows_result for frame in planned] == [False] * (n_rows - 1) + [True] * (n_held + 1)

    frames = env.render()
    result = renderer.renderer.drawn_text["result"]  # the text of the last frame drawn
    assert result[0] == f"success: {'yes' if info['success'] else 'no'}"
    assert f"distance to target: {info['distance']:.2f} m" in result
    assert any(line.startswith(f"face down: {info['face_down']} (") for line in result)
    assert f"reward: {outcome.reward:+.2f}" in result
    np.testing.assert_array_equal(frames[-1], frames[-n_held])  # held, so a GIF pauses on it

    # the result's pixels: the same scene without the result differs only in a box top-right
    plan = planned[-1]
    target_x, target_faces = float(env._episodes.target_x[0]), env._episodes.target_faces[0]
    scene = dict(
        state=trajectory[plan.row], target_x=target_x, target_faces=target_faces, caption="at rest", camera=plan.camera
    )
    with_result = renderer.renderer.render_rgb(**renderer._scene(**scene, outcome=outcome))
    without = renderer.renderer.render_rgb(**renderer._scene(**scene, outcome=None))
    assert renderer.renderer.drawn_text["result"] == []
    rows, columns = np.nonzero(np.any(with_result != without, axis=-1))
    assert len(rows) > 200
    assert rows.max() < HEIGHT_PX // 3 and columns.min() > WIDTH_PX // 2
    # earlier frames carry no result
    middle = planned[n_rows // 2]
    renderer.renderer.render_rgb(
        **renderer._planned_scene(trajectory, middle, 1.0, env._episodes.target_faces[0], outcome)
    )
    assert renderer.renderer.drawn_text["result"] == []
    env.close()


@pytest.mark.parametrize("success", [True, False])
def test_the_result_headline_is_green_on_success_and_red_otherwise(success):
    renderer = ThrowRenderer(BoxTossEnv().config, WIDTH_PX, HEIGHT_PX, 30)
    outcome = ThrowOutcome(success=success, distance=0.05, face_down=2, on_target_face=True, reward=0.9, at_rest=True)
    frame = renderer.frame(np.array([2.0, 0.1, 0.0, 0.0, 0.0, 0.0]), 2.0, np.ones(4), "at rest", outcome)
    top_right = frame[: HEIGHT_PX // 3, WIDTH_PX // 2 :]
    colour = PALETTE.success if success else PALETTE.failure
    other = PALETTE.failure if success else PALETTE.success
    assert np.all(top_right == colour, axis=-1).sum() > 100
    assert not np.all(top_right == other, axis=-1).any()
    assert renderer.renderer.drawn_text["result"][0] == f"success: {'yes' if success else 'no'}"


def test_outcome_lines_name_face_by_colour_and_flag_a_throw_not_at_rest():
    outcome = ThrowOutcome(success=False, distance=1.234, face_down=1, on_target_face=False, reward=-1.5, at_rest=False)
    assert outcome.lines() == (
        "success: no",
        "distance to target: 1.23 m",
        "face down: 1 (blue), not a target face",
        "reward: -1.50",
        "still moving at max_sim_time",
    )


def test_rgb_array_after_a_throw_shows_the_result():
    env = BoxTossEnv(render_mode="rgb_array", render_width=WIDTH_PX, render_height=HEIGHT_PX)
    env.reset(seed=0)
    env.render()
    assert env._renderer_for_env().renderer.drawn_text["result"] == []
    _, _, _, _, info = env.step(np.array([0.0, 0.0, 0.2], dtype=np.float32))
    env.render()
    assert env._renderer_for_env().renderer.drawn_text["result"][0] == f"success: {'yes' if info['success'] else 'no'}"
    env.close()


# -- recordings ----------------------------------------------------------------------------------------
def test_a_recording_draws_the_hand_with_the_throws_camera_unless_it_was_returned_before():
    env = BoxTossEnv(render_mode="rgb_array_list", render_width=WIDTH_PX, render_height=HEIGHT_PX)
    renderer = env._renderer_for_env()
    trajectory, _, _ = throw(env, 7, LONG_HIGH_THROW)  # reset, step, then render: the hand is t = 0
    frames = env.render()
    planned = renderer.plan_throw(trajectory, env.dt)
    assert len(frames) == len(planned) and env.render() == []
    row, column = planned[0].camera.pixel_index(trajectory[0, :2])
    assert tuple(frames[0][row, column]) == PALETTE.box_fill

    env.reset(seed=7)
    hand = env.render()  # the hand alone: the home view, which the play window's mouse uses
    assert len(hand) == 1
    row, column = renderer.home_camera.pixel_index(env._state[0, :2])
    assert tuple(hand[0][row, column]) == PALETTE.box_fill
    env.step(LONG_HIGH_THROW)
    assert len(env.render()) == len(planned) - 1
    env.close()


def test_record_throws_writes_a_gif_ending_on_the_result_with_the_trace(tmp_path):
    from PIL import Image

    env = BoxTossEnv(render_mode="rgb_array_list", render_width=320, render_height=240, render_fps=20)
    path = record_throws(env, tmp_path / "throws.gif", n_throws=2, seed=1)
    with Image.open(path) as gif:
        gif.seek(gif.n_frames - 1)
        last = np.asarray(gif.convert("RGB")).astype(np.int64)

    def near(colour) -> np.ndarray:  # GIF palettes shift colours a little
        return np.abs(last - np.array(colour)).max(axis=-1) <= 12

    renderer = env._renderer_for_env()
    trajectory = env._throw_trajectory()
    row, column = renderer.plan_throw(trajectory, env.dt)[-1].camera.pixel_index(trajectory[-1, :2])
    assert near(PALETTE.box_fill)[row, column]  # the GIF ends on the box at rest, not on an empty frame
    assert renderer.renderer.drawn_text["result"][0].startswith("success: ")
    assert near(PALETTE.trace).sum() > 20
    assert env._renderer_for_env().trace is False  # the env's own frames are as they were
    env.close()


# -- metre labels ----------------------------------------------------------------------------------------
def test_the_floor_ticks_carry_metre_labels():
    renderer = ThrowRenderer(BoxTossEnv().config, WIDTH_PX, HEIGHT_PX, 30)
    state = np.array([0.0, 1.4, 0.0, 0.0, 0.0, 0.0])
    frame = renderer.frame(state, 2.0, np.ones(4))
    assert renderer.renderer.drawn_text["floor"] == ["0", "1 m", "2 m", "3 m", "4 m", "5 m"]
    camera = renderer.home_camera
    floor_row = camera.world_to_pixel(np.zeros(2))[1]
    for x in (0.0, 3.0):
        column = int(camera.world_to_pixel(np.array([x, 0.0]))[0])
        below_tick = frame[int(floor_row) + 4 : int(floor_row) + 24, column - 12 : column + 12].astype(np.int64)
        assert (np.abs(below_tick - np.array(PALETTE.floor_label)).max(axis=-1) < 40).sum() > 5
    # zoomed out, the labels thin out to every 2 or 5 m instead of crowding
    far = np.array([30.0, 0.2, 0.0, 0.0, 0.0, 0.0])
    renderer.frame(far, 2.0, np.ones(4))
    labels = renderer.renderer.drawn_text["floor"]
    metres = [0.0 if label == "0" else float(label.removesuffix(" m")) for label in labels]
    assert len(labels) >= 3 and len(set(np.diff(metres))) == 1 and np.diff(metres)[0] >= 2
