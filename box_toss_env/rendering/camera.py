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
        cls, x_min: float, x_max: float, y_min: float, y_max: float, width_px: int, height_px: int
    ) -> Camera:
        """The largest-scale camera whose image contains ``[x_min, x_max] x [y_min, y_max]`` [m].

        The rectangle is centred; the image shows more than it along one axis when the aspect ratios differ.
        """
        if not (x_max > x_min and y_max > y_min):
            raise ValueError(f"empty view rectangle x [{x_min}, {x_max}], y [{y_min}, {y_max}]")
        pixels_per_metre = min(width_px / (x_max - x_min), height_px / (y_max - y_min))
        return cls(
            center_x=0.5 * (x_min + x_max),
            center_y=0.5 * (y_min + y_max),
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
