"""World-to-pixel mapping: world y points up [m], pixel rows grow downwards [px]."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Camera:
    """A view of the world with one scale for both axes, so boxes keep their shape.

    Pixel coordinates are ``(column, row)`` floats; the pixel ``frame[row, column]`` covers
    ``[column, column + 1) x [row, row + 1)``. The world point ``center`` [m] is at the image centre::

        column = width_px / 2 + (x - center_x) * pixels_per_metre
        row    = height_px / 2 - (y - center_y) * pixels_per_metre
    """

    center_x: float
    """World x at the image centre [m]."""
    center_y: float
    """World y at the image centre [m]."""
    pixels_per_metre: float
    """Scale [px/m], the same horizontally and vertically."""
    width_px: int
    height_px: int

    def __post_init__(self) -> None:
        if not self.pixels_per_metre > 0:
            raise ValueError(f"pixels_per_metre must be positive, got {self.pixels_per_metre}")
        if self.width_px < 1 or self.height_px < 1:
            raise ValueError(f"image size must be at least 1x1 px, got {self.width_px}x{self.height_px}")

    @classmethod
    def from_view(
        cls,
        x_min: float,
        x_max: float,
        y_min: float,
        y_max: float,
        width_px: int,
        height_px: int,
        *,
        padding_px: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0),
    ) -> Camera:
        """The largest-scale camera whose image contains ``[x_min, x_max] x [y_min, y_max]`` [m].

        ``padding_px`` = (left, right, top, bottom) keeps bands of the image free (for text, floor labels):
        the rectangle is fitted into the image less those bands, centred there; the image shows more than
        the rectangle along one axis when the aspect ratios differ.
        """
        if not (x_max > x_min and y_max > y_min):
            raise ValueError(f"empty view rectangle x [{x_min}, {x_max}], y [{y_min}, {y_max}]")
        left, right, top, bottom = (float(p) for p in padding_px)
        inner_width_px, inner_height_px = width_px - left - right, height_px - top - bottom
        if not (inner_width_px > 0 and inner_height_px > 0):
            raise ValueError(f"padding {padding_px} px leaves no room in a {width_px}x{height_px} px image")
        pixels_per_metre = min(inner_width_px / (x_max - x_min), inner_height_px / (y_max - y_min))
        # the rectangle's centre goes to the centre of the padded region, which is off the image centre
        # by ((left - right) / 2, (top - bottom) / 2) px
        return cls(
            center_x=0.5 * (x_min + x_max) - 0.5 * (left - right) / pixels_per_metre,
            center_y=0.5 * (y_min + y_max) + 0.5 * (top - bottom) / pixels_per_metre,
            pixels_per_metre=float(pixels_per_metre),
            width_px=int(width_px),
            height_px=int(height_px),
        )

    @classmethod
    def fit_points(
        cls,
        points: np.ndarray,
        width_px: int,
        height_px: int,
        *,
        margin_m: float = 0.5,
        min_span_m: float = 1.0,
        include_floor: bool = True,
    ) -> Camera:
        """A camera that shows all ``points`` (k, 2) [m] with ``margin_m`` around them.

        ``include_floor`` also keeps the floor line y = 0 in view; each axis spans at least ``min_span_m``
        so that a single point does not zoom in without bound. Pass box corners (``box_vertices``) to
        frame whole boxes.
        """
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if include_floor:
            points = np.concatenate([points, [[points[:, 0].mean() if len(points) else 0.0, 0.0]]])
        if len(points) == 0:
            raise ValueError("fit_points needs at least one point (or include_floor=True)")
        low, high = points.min(axis=0), points.max(axis=0)
        half_span = np.maximum(0.5 * (high - low), 0.5 * min_span_m) + margin_m
        center = 0.5 * (low + high)
        return cls.from_view(
            center[0] - half_span[0],
            center[0] + half_span[0],
            center[1] - half_span[1],
            center[1] + half_span[1],
            width_px,
            height_px,
        )

    @property
    def view_bounds(self) -> tuple[float, float, float, float]:
        """The visible rectangle ``(x_min, x_max, y_min, y_max)`` [m]."""
        half_width_m = 0.5 * self.width_px / self.pixels_per_metre
        half_height_m = 0.5 * self.height_px / self.pixels_per_metre
        return (
            self.center_x - half_width_m,
            self.center_x + half_width_m,
            self.center_y - half_height_m,
            self.center_y + half_height_m,
        )

    def world_to_pixel(self, points: np.ndarray) -> np.ndarray:
        """Pixel coordinates ``(column, row)`` [px] of world points ``(..., 2)`` [m], as floats."""
        points = np.asarray(points, dtype=np.float64)
        pixels = np.empty_like(points)
        pixels[..., 0] = 0.5 * self.width_px + (points[..., 0] - self.center_x) * self.pixels_per_metre
        pixels[..., 1] = 0.5 * self.height_px - (points[..., 1] - self.center_y) * self.pixels_per_metre
        return pixels

    def pixel_to_world(self, pixels: np.ndarray) -> np.ndarray:
        """World points [m] of pixel coordinates ``(..., 2)`` given as ``(column, row)`` [px]."""
        pixels = np.asarray(pixels, dtype=np.float64)
        points = np.empty_like(pixels)
        points[..., 0] = self.center_x + (pixels[..., 0] - 0.5 * self.width_px) / self.pixels_per_metre
        points[..., 1] = self.center_y - (pixels[..., 1] - 0.5 * self.height_px) / self.pixels_per_metre
        return points

    def pixel_index(self, point: np.ndarray) -> tuple[int, int]:
        """``(row, column)`` of the pixel containing a world point [m], for indexing ``frame[row, column]``.

        The index may lie outside the image when the point is out of view.
        """
        column, row = np.floor(self.world_to_pixel(np.asarray(point, dtype=np.float64).reshape(2)))
        return int(row), int(column)


def bounds_of_boxes(corners: np.ndarray) -> np.ndarray:
    """(..., 4) bounds ``(x_min, x_max, y_min, y_max)`` [m] of box corners (..., 4, 2) [m]."""
    corners = np.asarray(corners, dtype=np.float64)
    return np.stack(
        [corners[..., 0].min(-1), corners[..., 0].max(-1), corners[..., 1].min(-1), corners[..., 1].max(-1)],
        axis=-1,
    )


def union_bounds(*bounds: np.ndarray) -> np.ndarray:
    """The smallest bounds containing all of the given ones; each is (..., 4) ``(x_min, x_max, y_min, y_max)``
    and they broadcast (e.g. per-frame bounds with one fixed rectangle)."""
    stacked = np.broadcast_arrays(*(np.asarray(b, dtype=np.float64) for b in bounds))
    lows, highs = np.minimum.reduce(stacked), np.maximum.reduce(stacked)
    return np.stack([lows[..., 0], highs[..., 1], lows[..., 2], highs[..., 3]], axis=-1)


def follow_bounds(bounds: np.ndarray, radius: int) -> np.ndarray:
    """Smoothly moving view bounds (n, 4) that contain per-frame bounds (n, 4), for a camera following them.

    Two sliding windows of ``radius`` frames either side (shortened at the ends):

        held[k]   = union of bounds[j]  for |j - k| <= radius   (looks ahead: the view opens before it is needed)
        result[k] = mean of held[j]     for |j - k| <= radius   (eases every edge in and out)

    Every ``held[j]`` averaged into ``result[k]`` contains ``bounds[k]`` (|j - k| <= radius), and an edge-wise
    mean of rectangles that all contain a rectangle contains it too: the box is in view in every frame by
    construction, while each edge moves at most ``1 / (2 radius + 1)`` of its total travel per frame.
    """
    bounds = np.asarray(bounds, dtype=np.float64).reshape(-1, 4)
    n_frames, radius = len(bounds), int(radius)
    if radius <= 0 or n_frames <= 1:
        return bounds.copy()
    padded = np.pad(bounds, ((radius, radius), (0, 0)), mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * radius + 1, axis=0)  # (n, 4, window)
    held = np.stack(
        [windows[:, 0].min(-1), windows[:, 1].max(-1), windows[:, 2].min(-1), windows[:, 3].max(-1)], axis=-1
    )
    # repeating the end frames (edge padding) leaves each union as it was; the mean is over frames that exist
    cumulative = np.concatenate([np.zeros((1, 4)), np.cumsum(held, axis=0)])
    frames = np.arange(n_frames)
    low, high = np.maximum(frames - radius, 0), np.minimum(frames + radius, n_frames - 1) + 1
    return (cumulative[high] - cumulative[low]) / (high - low)[:, None]
