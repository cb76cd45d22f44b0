"""Pixel observations (``observation_mode="pixels"``, ``envs.pixels``): the image shows each episode's box, target
and base where they are, batched as the single env draws it, and passes Gymnasium's and SB3's checkers."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import box_toss_env  # noqa: F401  (registers the BoxToss envs)
from box_toss_env.envs.pixels import OTHER, TARGET, THROWN, PixelView
from box_toss_env.physics import layout


@pytest.mark.parametrize("env_id", ["BoxToss-Pixels-v0", "BoxToss-ThisSideUp-Pixels-v0", "BoxToss-OnBox-Pixels-v0"])
def test_both_checkers_pass(env_id):
    env = gym.make(env_id)
    assert env.observation_space == gym.spaces.Box(0, 255, (40, 96, 3), np.uint8)
    check_env(env.unwrapped, skip_render_check=True)
    sb3_check_env(gym.make(env_id))


def world_to_pixel(view: PixelView, height: int, x: float, y: float) -> tuple[float, float]:
    """(column, row) coordinates of a world point, rows counted from the top (pixel centres at k + 0.5)."""
    return (x - view.x0) * view.scale, height - (y - view.y0) * view.scale


def test_the_box_and_the_target_are_where_the_state_says():
    env = gym.make("BoxToss-v0", observation_mode="pixels", pixel_size=(192, 80))
    renderer = env.unwrapped.pixels
    for seed in range(5):
        image, info = env.reset(seed=seed)
        state = env.unwrapped._state[0]
        red = image[:, :, THROWN].astype(np.float64)
        rows, cols = np.mgrid[0 : image.shape[0], 0 : image.shape[1]] + 0.5
        col, row = world_to_pixel(renderer.view, image.shape[0], state[layout.X], state[layout.Y])
        assert (red * cols).sum() / red.sum() == pytest.approx(col, abs=0.1)  # the centroid, to a tenth of a pixel
        assert (red * rows).sum() / red.sum() == pytest.approx(row, abs=0.1)
        area = 0.4 * 0.2 * renderer.view.scale**2  # the box's area in pixels: the coverage sums to it
        assert red.sum() / 255 == pytest.approx(area, rel=0.03)
        band = image[0, :, TARGET].astype(np.float64)  # the top row: the target band alone
        tolerance = env.unwrapped.config.position_tolerance
        assert band.sum() / 255 == pytest.approx(2 * tolerance * renderer.view.scale, abs=0.02)
        target_col = (info["target_x"] - renderer.view.x0) * renderer.view.scale
        assert (band * cols[0]).sum() / band.sum() == pytest.approx(target_col, abs=0.02)


@pytest.mark.parametrize("face", [0, 1, 2, 3])
def test_the_target_face_is_marked_on_its_side_of_the_box(face):
    env = gym.make("BoxToss-ThisSideUp-v0", observation_mode="pixels", pixel_size=(384, 160))
    seed = next(s for s in range(200) if env.reset(seed=s)[1]["target_faces"][face])
    image, _ = env.reset(seed=seed)
    state = env.unwrapped._state[0]
    renderer = env.unwrapped.pixels
    in_box = image[:, :, THROWN] > 0
    marked = (image[:, :, TARGET] > 0) & in_box
    rows, cols = np.nonzero(marked)
    x = renderer.view.x0 + (cols + 0.5) / renderer.view.scale - state[layout.X]
    y = renderer.view.y0 + (image.shape[0] - rows - 0.5) / renderer.view.scale - state[layout.Y]
    angle = state[layout.ANGLE]
    local = np.stack([np.cos(angle) * x + np.sin(angle) * y, -np.sin(angle) * x + np.cos(angle) * y])
    normal = {0: (0, -1), 1: (1, 0), 2: (0, 1), 3: (-1, 0)}[face]
    assert (np.asarray(normal) @ local > 0).mean() > 0.95  # the marked strip lies on that face's side


def test_the_base_box_is_in_its_own_channel_and_the_batch_draws_as_the_single_env():
    vector = gym.make_vec("BoxToss-OnBox-Pixels-v0", num_envs=3, vectorization_mode="vector_entry_point", threads=1)
    images, _ = vector.reset(seed=4)
    single = gym.make("BoxToss-OnBox-Pixels-v0")
    for i in range(3):
        np.testing.assert_array_equal(images[i], single.reset(seed=4 + i)[0])
        assert images[i][:, :, OTHER].sum() > 0
    actions = np.zeros((3, 3), dtype=np.float32)
    next_images, _, _, _, info = vector.step(actions)
    for i in range(3):
        single.reset(seed=4 + i)
        final, *_ = single.step(actions[i])
        np.testing.assert_array_equal(info["final_obs"][i], final)  # the landed scene
    assert next_images.dtype == np.uint8 and not np.array_equal(next_images, info["final_obs"])


def test_a_bad_pixel_setting_names_the_argument():
    with pytest.raises(ValueError, match="observation_mode"):
        gym.make("BoxToss-v0", observation_mode="rgb")
    with pytest.raises(ValueError, match=r"pixel_size\[1\]"):
        gym.make("BoxToss-v0", observation_mode="pixels", pixel_size=(64, 8))
    with pytest.raises(TypeError, match="pixel_size must be a"):
        gym.make("BoxToss-v0", observation_mode="pixels", pixel_size=64)
