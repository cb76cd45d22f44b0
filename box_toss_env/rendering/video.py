"""Write lists of (H, W, 3) uint8 frames to GIF (Pillow) or MP4 (imageio with imageio-ffmpeg), each file
written whole or not at all (``box_toss_env.files.atomic_path``)."""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from gymnasium.error import DependencyNotInstalled

from box_toss_env.files import atomic_path
from box_toss_env.rendering.dependency import RENDER_INSTALL_HINT

GIF_MIN_DELAY_CS = 2
"""Browsers play GIF frame delays below 2 cs (50 fps) as 10 cs, so such GIFs run slow."""


def write_gif(frames: Iterable[np.ndarray], path: str | Path, fps: float) -> Path:
    """Write frames (each (H, W, 3) uint8) to an endlessly looping GIF and return its path.

    GIF delays are whole centiseconds; they are rounded so that the total duration stays ``n / fps``.
    Pillow merges identical consecutive frames into one longer frame, so a still scene gives fewer frames.
    Above 50 fps browsers play GIFs slowly: pass every k-th frame at ``fps / k`` instead.
    """
    frames = _checked_frames(frames)
    fps = _checked_fps(fps)
    image_module = _import_render_dependency("PIL.Image", "Pillow")
    frame_end_cs = np.round(100.0 * np.arange(len(frames) + 1) / fps).astype(np.int64)
    delays_cs = np.maximum(np.diff(frame_end_cs), 1)
    if len(frames) > 1 and delays_cs.min() < GIF_MIN_DELAY_CS:
        warnings.warn(
            f"GIF at {fps:g} fps has delays below {GIF_MIN_DELAY_CS} cs, which browsers play slowly; "
            "write every k-th frame at fps / k instead",
            RuntimeWarning,
            stacklevel=2,
        )
    path = Path(path)
    images = [image_module.fromarray(frame) for frame in frames]
    with atomic_path(path) as temp:  # written whole or not at all
        images[0].save(
            temp,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=[int(delay) * 10 for delay in delays_cs],  # [ms]
            loop=0,
        )
    return path


def write_video(frames: Iterable[np.ndarray], path: str | Path, fps: float) -> Path:
    """Write frames (each (H, W, 3) uint8) to a video chosen by the file suffix and return its path.

    ``.gif`` goes to ``write_gif``. Other suffixes (``.mp4``, ...) are encoded with H.264 through imageio's
    ffmpeg writer, which needs the ``imageio-ffmpeg`` package; without it this raises
    ``DependencyNotInstalled`` suggesting a ``.gif``. Odd frame sizes are padded by one edge pixel, since
    H.264 needs even sizes.
    """
    path = Path(path)
    if path.suffix.lower() == ".gif":
        return write_gif(frames, path, fps)
    frames = _checked_frames(frames)
    fps = _checked_fps(fps)
    imageio = _import_ffmpeg_writer(path)
    height, width = frames[0].shape[:2]
    padding = ((0, height % 2), (0, width % 2), (0, 0))
    with atomic_path(path) as temp:  # written whole or not at all
        writer = imageio.get_writer(
            temp, format="FFMPEG", mode="I", fps=fps, codec="libx264", pixelformat="yuv420p", macro_block_size=1
        )
        try:
            for frame in frames:
                writer.append_data(np.pad(frame, padding, mode="edge"))
        finally:  # imageio's writer closes only on success: ffmpeg would go on writing after an error
            writer.close()
    return path


def _checked_frames(frames: Iterable[np.ndarray]) -> list[np.ndarray]:
    """The frames as a list of (H, W, 3) uint8 arrays of one size; raises ValueError otherwise."""
    frames = [np.asarray(frame) for frame in frames]
    if not frames:
        raise ValueError("no frames to write")
    expected_shape = frames[0].shape
    if len(expected_shape) != 3 or expected_shape[2] != 3:
        raise ValueError(f"frames must be (H, W, 3) arrays, got {expected_shape}")
    for index, frame in enumerate(frames):
        if frame.shape != expected_shape or frame.dtype != np.uint8:
            raise ValueError(f"frame {index} is {frame.shape} {frame.dtype}; all frames must be {expected_shape} uint8")
    return frames


def _checked_fps(fps: float) -> float:
    fps = float(fps)
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be positive, got {fps}")
    return fps


def _import_render_dependency(module_name: str, package_name: str):
    try:
        return importlib.import_module(module_name)
    except ImportError as error:
        raise DependencyNotInstalled(
            f"Writing videos needs {package_name}, which is not installed. Install it with: {RENDER_INSTALL_HINT}"
        ) from error


def _import_ffmpeg_writer(path: Path):
    """imageio's v2 API, once an ffmpeg binary is known to be available through imageio-ffmpeg."""
    imageio = _import_render_dependency("imageio.v2", "imageio")
    try:
        imageio_ffmpeg = importlib.import_module("imageio_ffmpeg")
        imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError) as error:
        raise DependencyNotInstalled(
            f'Writing "{path.name}" needs an ffmpeg writer for imageio, which is not available ({error}). '
            f"Install it with: pip install imageio-ffmpeg, or write a GIF instead: write_gif(frames, "
            f'"{path.with_suffix(".gif").name}", fps).'
        ) from error
    return imageio
