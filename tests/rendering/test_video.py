"""GIF and MP4 writers."""

import importlib.util
import sys

import numpy as np
import pytest
from gymnasium.error import DependencyNotInstalled
from PIL import Image

from box_toss_env.rendering import write_gif, write_video

HEIGHT_PX, WIDTH_PX = 24, 32


def make_frames(n_frames: int) -> list[np.ndarray]:
    """Frames that differ from each other (Pillow merges identical consecutive GIF frames)."""
    frames = []
    for index in range(n_frames):
        frame = np.full((HEIGHT_PX, WIDTH_PX, 3), 240, dtype=np.uint8)
        frame[4:12, 2 + 4 * index : 10 + 4 * index] = (200, 30, 40)
        frames.append(frame)
    return frames


def read_gif(path) -> tuple[list[np.ndarray], list[int]]:
    """The frames of a GIF as RGB arrays, and each frame's delay [ms]."""
    frames, delays_ms = [], []
    with Image.open(path) as image:
        for index in range(image.n_frames):
            image.seek(index)
            frames.append(np.asarray(image.convert("RGB")))
            delays_ms.append(image.info["duration"])
    return frames, delays_ms


def test_write_gif_round_trips_frames_and_frame_count(tmp_path):
    frames = make_frames(5)
    path = write_gif(frames, tmp_path / "toss.gif", fps=20)
    read_frames, delays_ms = read_gif(path)
    assert len(read_frames) == 5
    for written, read in zip(frames, read_frames, strict=True):
        np.testing.assert_array_equal(read, written)  # few flat colours survive the palette exactly
    assert delays_ms == [50] * 5


def test_gif_delays_keep_total_duration(tmp_path):
    _, delays_ms = read_gif(write_gif(make_frames(3), tmp_path / "toss.gif", fps=30))
    assert sum(delays_ms) == 100  # 3 frames at 30 fps: 30 + 40 + 30 ms, not 3 x 30 ms


def test_write_video_with_gif_suffix_writes_gif(tmp_path):
    path = write_video(np.stack(make_frames(4)), tmp_path / "toss.GIF", fps=10)
    assert len(read_gif(path)[0]) == 4


def test_gif_faster_than_browsers_play_warns(tmp_path):
    with pytest.warns(RuntimeWarning, match="browsers"):
        write_gif(make_frames(3), tmp_path / "fast.gif", fps=100)


@pytest.mark.parametrize(
    "frames",
    [
        [],
        [np.zeros((4, 4), dtype=np.uint8)],
        [np.zeros((4, 4, 3), dtype=np.float32)],
        [np.zeros((4, 4, 3), dtype=np.uint8), np.zeros((4, 5, 3), dtype=np.uint8)],
    ],
)
def test_invalid_frames_raise(tmp_path, frames):
    with pytest.raises(ValueError):
        write_gif(frames, tmp_path / "bad.gif", fps=10)


def test_bad_fps_raises(tmp_path):
    with pytest.raises(ValueError, match="fps"):
        write_gif(make_frames(2), tmp_path / "bad.gif", fps=0)


def test_mp4_without_ffmpeg_suggests_gif(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # makes `import imageio_ffmpeg` fail
    with pytest.raises(DependencyNotInstalled, match=r"imageio-ffmpeg.*\.gif"):
        write_video(make_frames(2), tmp_path / "toss.mp4", fps=10)
    assert not (tmp_path / "toss.mp4").exists()


@pytest.mark.skipif(importlib.util.find_spec("imageio_ffmpeg") is None, reason="imageio-ffmpeg not installed")
def test_write_mp4_with_ffmpeg(tmp_path):
    import imageio_ffmpeg

    odd_frames = [frame[:-1, :-1] for frame in make_frames(6)]  # H.264 fails on odd sizes unless padded
    path = write_video(odd_frames, tmp_path / "toss.mp4", fps=12)
    n_frames, duration_s = imageio_ffmpeg.count_frames_and_secs(str(path))
    assert n_frames == 6
    assert duration_s == pytest.approx(0.5, abs=0.05)
