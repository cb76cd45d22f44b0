"""Videos of whole throws: Gymnasium's RecordVideo keeps two frames a throw, RecordThrowVideo every frame."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.wrappers import RecordVideo

import box_toss_env  # noqa: F401  (registers the envs)
from box_toss_env.wrappers import RecordThrowVideo

pytest.importorskip("pygame")
imageio = pytest.importorskip("imageio.v3")
pytest.importorskip("moviepy")

SIZE = {"render_width": 96, "render_height": 64, "render_fps": 20}  # small frames: a fast test


def video_frames(folder) -> list[np.ndarray]:
    (path,) = sorted(folder.glob("*.mp4"))
    return list(imageio.imiter(path))


def throw_frames(seed: int, action) -> list[np.ndarray]:
    """Every frame an "rgb_array_list" env draws for one throw, asked for after the reset and after the step (as a
    recorder asks): the box in the hand, then the throw and its result."""
    env = gym.make("BoxToss-v0", render_mode="rgb_array_list", **SIZE)
    env.reset(seed=seed)
    frames = env.render()
    env.step(action)
    frames += env.render()
    env.close()
    return frames


ACTION = np.array([0.2, 0.3, -0.4], dtype=np.float32)


def test_record_throw_video_records_every_frame_of_a_throw(tmp_path):
    expected = throw_frames(3, ACTION)
    env = RecordThrowVideo(
        gym.make("BoxToss-v0", render_mode="rgb_array_list", **SIZE),
        str(tmp_path / "videos"),
        episode_trigger=lambda _: True,
    )
    env.reset(seed=3)
    env.step(ACTION)
    assert len(expected) > 20  # a throw of about a second at 20 fps, and its result held for one
    assert len(env.recorded_frames) == len(expected)  # the box in the hand, the throw, the result: in order
    for recorded, drawn in zip(env.recorded_frames, expected, strict=True):
        np.testing.assert_array_equal(recorded, drawn)
    env.close()
    frames = video_frames(tmp_path / "videos")
    # moviepy's writer may drop the very last frame (one of the held result's) where n / fps rounds down
    assert len(expected) - 1 <= len(frames) <= len(expected)
    assert frames[0].shape == expected[0].shape
    # H.264 changes pixels a little: the mean colour of each frame, in order
    np.testing.assert_allclose([f.mean() for f in frames], [f.mean() for f in expected[: len(frames)]], atol=4.0)


def test_gymnasium_record_video_keeps_two_frames_a_throw(tmp_path):
    """What the wrapper is for: the plain RecordVideo holds the box in the hand and the last frame."""
    env = RecordVideo(
        gym.make("BoxToss-v0", render_mode="rgb_array_list", **SIZE),
        str(tmp_path / "videos"),
        episode_trigger=lambda _: True,
    )
    env.reset(seed=3)
    env.step(ACTION)
    env.close()
    assert len(video_frames(tmp_path / "videos")) == 2


def test_episodes_go_to_their_own_videos_and_render_still_returns_the_frames(tmp_path):
    env = RecordThrowVideo(
        gym.make("BoxToss-v0", render_mode="rgb_array_list", **SIZE),
        str(tmp_path / "videos"),
        episode_trigger=lambda k: k == 1,
    )
    for seed in (0, 1, 2):
        env.reset(seed=seed)
        env.step(ACTION)
        if seed == 1:
            assert len(env.render()) == len(throw_frames(1, ACTION))  # the frames the wrapper took, handed on
    env.close()
    assert [path.name for path in (tmp_path / "videos").glob("*.mp4")] == ["rl-video-episode-1.mp4"]


def test_record_throw_video_refuses_other_render_modes(tmp_path):
    with pytest.raises(ValueError, match="rgb_array_list"):
        RecordThrowVideo(gym.make("BoxToss-v0", render_mode="rgb_array"), str(tmp_path))
