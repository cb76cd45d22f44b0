"""Pixel observations: a small RGB image of each throw's scene, drawn for a whole batch in one compiled call.

``observation_mode="pixels"`` (``BoxTossEnv``, its batched form and the ``BoxToss-*-Pixels-v0`` ids) observes this
image instead of the state vector. Each channel holds one kind of thing, so that a convolutional policy need not
tell colours apart:

- red (channel 0): the thrown box, at its pose (in the hand before the throw, where it ended after it);
- green (channel 1): the target, a band of full height whose edges are the target x -+ ``position_tolerance``
  (where the box's centre must rest), and on the thrown box a strip along each face that may end down (all four
  for ``target_face="any"``: an outline; one for a "this side up" target);
- blue (channel 2): every other box of the scene (the base box of ``base_box=True``).

Shapes are antialiased: a pixel's value is 255 times the share of its ``SUPERSAMPLE`` x ``SUPERSAMPLE`` sample
points inside the shape (the band's share is exact), so positions are kept to a fraction of a pixel. The view
(``PixelView``) is fixed per task from its ranges, square pixels: from the release points (less a corner radius)
to the farthest target (plus the tolerance), from the floor (the image's bottom edge) to the highest release
point (plus a corner radius); the same for every episode, so a pixel is a place. A box outside the view (a throw
that rolled far) is drawn as far as it is inside.

``draw_scenes`` is the kernel (numba, no Python per box or per pixel); ``PixelRenderer`` feeds it a ``ThrowBatch``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from box_toss_env.envs.task_config import TaskConfig
from box_toss_env.physics import layout
from box_toss_env.physics.compile.compilation import ensure_compiled, jit_kernel

SUPERSAMPLE = 4
"""Sample points per pixel along each axis for the boxes' antialiasing (16 per pixel)."""
FACE_STRIP = 0.4
"""Width of a target face's strip on the thrown box, as a share of the box's half width."""
VIEW_MARGIN_M = 0.1
"""Free space around the release points and targets in the view [m]."""
OBSERVATION_MODES = ("state", "pixels")
DEFAULT_PIXEL_SIZE = (96, 40)
"""(width, height) [px] of a pixel observation: about 5 cm a pixel over the default task's view."""
CHANNELS = 3
THROWN, TARGET, OTHER = 0, 1, 2  # the channels


@dataclass(frozen=True)
class PixelView:
    """Where the image looks: world x of its left edge [m], world y of its bottom edge [m] and pixels per metre."""

    x0: float
    y0: float
    scale: float

    @classmethod
    def for_task(cls, config: TaskConfig, width: int, height: int) -> PixelView:
        """The view of a task's home scene (module docstring), centred in a ``width`` x ``height`` image."""
        radius = config.max_corner_radius
        reach = config.position_tolerance
        if config.base_box:
            reach = max(reach, 0.5 * config.base_length_range[1])
        x_low = min(config.release_x_range[0] - radius, config.target_x_range[0] - reach) - VIEW_MARGIN_M
        x_high = max(config.release_x_range[1] + radius, config.target_x_range[1] + reach) + VIEW_MARGIN_M
        y_high = config.release_height_range[1] + radius + VIEW_MARGIN_M
        scale = min(width / (x_high - x_low), height / y_high)
        return cls(x0=0.5 * (x_low + x_high) - 0.5 * width / scale, y0=0.0, scale=scale)

    def as_array(self) -> np.ndarray:
        return np.array([self.x0, self.y0, self.scale])


@jit_kernel
def draw_scenes(boxes, bands, faces, view, out):
    """Draw ``out`` (n, H, W, 3) uint8, one scene per image.

    ``boxes`` (n, m, 6): each scene's boxes, x [m], y [m], angle [rad], half length, half width [m] and channel
    (box 0 is the thrown one; a negative channel skips the row). ``bands`` (n, 2): each target band's centre x and
    half width [m]. ``faces`` (n, 4): 1.0 where face f of box 0 is drawn into the target channel (faces by outward
    normal in the box's frame: 0 -y, 1 +x, 2 +y, 3 -x). ``view``: x0, y0 and pixels per metre (``PixelView``)."""
    n, height, width = out.shape[0], out.shape[1], out.shape[2]
    x0, y0, scale = view[0], view[1], view[2]
    step = 1.0 / SUPERSAMPLE
    for i in range(n):
        out[i] = 0
        # the target band: exact horizontal coverage of [centre - half, centre + half] per column, every row
        left = (bands[i, 0] - bands[i, 1] - x0) * scale
        right = (bands[i, 0] + bands[i, 1] - x0) * scale
        for col in range(max(int(math.floor(left)), 0), min(int(math.ceil(right)), width)):
            cover = min(right, col + 1.0) - max(left, float(col))
            value = np.uint8(min(255.0, 255.0 * cover + 0.5))
            for row in range(height):
                out[i, row, col, TARGET] = value
        for b in range(boxes.shape[1]):
            channel = int(boxes[i, b, 5])
            if channel < 0:
                continue
            cx, cy, angle, hl, hw = boxes[i, b, 0], boxes[i, b, 1], boxes[i, b, 2], boxes[i, b, 3], boxes[i, b, 4]
            cos, sin = math.cos(angle), math.sin(angle)
            extent_x = abs(hl * cos) + abs(hw * sin)
            extent_y = abs(hl * sin) + abs(hw * cos)
            col_low = max(int(math.floor((cx - extent_x - x0) * scale)), 0)
            col_high = min(int(math.ceil((cx + extent_x - x0) * scale)), width)
            row_low = max(int(math.floor(height - (cy + extent_y - y0) * scale)), 0)
            row_high = min(int(math.ceil(height - (cy - extent_y - y0) * scale)), height)
            strip = FACE_STRIP * hw
            for row in range(row_low, row_high):
                for col in range(col_low, col_high):
                    inside = 0
                    marked = 0
                    for sy in range(SUPERSAMPLE):
                        wy = y0 + (height - row - (sy + 0.5) * step) / scale - cy
                        for sx in range(SUPERSAMPLE):
                            wx = x0 + (col + (sx + 0.5) * step) / scale - cx
                            lx = cos * wx + sin * wy  # the sample in the box's frame
                            ly = -sin * wx + cos * wy
                            if abs(lx) <= hl and abs(ly) <= hw:
                                inside += 1
                                if b == 0 and (
                                    (faces[i, 0] > 0.5 and ly < strip - hw)
                                    or (faces[i, 1] > 0.5 and lx > hl - strip)
                                    or (faces[i, 2] > 0.5 and ly > hw - strip)
                                    or (faces[i, 3] > 0.5 and lx < strip - hl)
                                ):
                                    marked += 1
                    if inside:
                        value = (255 * inside + SUPERSAMPLE * SUPERSAMPLE // 2) // (SUPERSAMPLE * SUPERSAMPLE)
                        out[i, row, col, channel] = max(out[i, row, col, channel], np.uint8(value))
                    if marked:
                        value = (255 * marked + SUPERSAMPLE * SUPERSAMPLE // 2) // (SUPERSAMPLE * SUPERSAMPLE)
                        out[i, row, col, TARGET] = max(out[i, row, col, TARGET], np.uint8(value))
    return out


class PixelRenderer:
    """Pixel observations of a task's throws (module docstring): ``draw(batch)`` returns a new (n, H, W, 3) uint8
    array of a ``ThrowBatch``'s current scenes."""

    def __init__(self, config: TaskConfig, width: int, height: int):
        self.config, self.width, self.height = config, width, height
        self.view = PixelView.for_task(config, width, height)
        self._view = self.view.as_array()

    @property
    def shape(self) -> tuple[int, int, int]:
        """(height, width, channels) of one observation."""
        return (self.height, self.width, CHANNELS)

    def scene_arrays(self, state: np.ndarray, params: np.ndarray, target_x: np.ndarray, target_faces: np.ndarray):
        """The kernel's inputs for n scenes of ``bodies = len(state) // n`` boxes each (engine rows, the thrown box
        first): ``boxes``, ``bands``, ``faces``."""
        n = len(target_x)
        bodies = len(state) // n
        boxes = np.empty((n, bodies, 6))
        boxes[:, :, :3] = state[:, layout.X : layout.ANGLE + 1].reshape(n, bodies, 3)
        boxes[:, :, 3] = params[:, layout.HALF_LENGTH].reshape(n, bodies)
        boxes[:, :, 4] = params[:, layout.HALF_WIDTH].reshape(n, bodies)
        boxes[:, :, 5] = OTHER
        boxes[:, 0, 5] = THROWN
        bands = np.empty((n, 2))
        bands[:, 0] = target_x
        bands[:, 1] = self.config.position_tolerance
        return boxes, bands, np.ascontiguousarray(target_faces, dtype=np.float64)

    def draw_arrays(self, state, params, target_x, target_faces) -> np.ndarray:
        """A new (n, H, W, 3) uint8 array of the scenes (``scene_arrays``'s arguments)."""
        boxes, bands, faces = self.scene_arrays(state, params, target_x, target_faces)
        out = np.empty((len(bands), self.height, self.width, CHANNELS), dtype=np.uint8)
        args = (boxes, bands, faces, self._view, out)
        ensure_compiled(draw_scenes, args)
        return draw_scenes(*args)

    def draw(self, batch) -> np.ndarray:
        """The scenes of a ``functional.ThrowBatch`` as they are now."""
        episodes = batch.episodes
        return self.draw_arrays(batch.state, batch.params, episodes.target_x, episodes.target_faces)
