"""Draws the box-toss scene (floor, target, boxes with coloured faces, text) with pygame-ce.

``SceneRenderer`` holds the window, the surface and the font and draws a frame from the parts in
``drawing`` (``SceneDrawing``), in the look of ``palette``; their names stay importable from here.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from types import ModuleType
from typing import Any

import numpy as np

from box_toss_env.rendering.box_corners import box_vertices
from box_toss_env.rendering.camera import Camera
from box_toss_env.rendering.dependency import import_pygame
from box_toss_env.rendering.drawing import FLOOR_TICK_STEPS_M, SceneDrawing, floor_label, floor_tick_step, floor_ticks
from box_toss_env.rendering.palette import (
    FACE_COLOUR_NAMES,
    FACE_STRIPE_WIDTH_PX,
    FLOOR_LABEL_GAP_PX,
    FLOOR_LINE_WIDTH_PX,
    FLOOR_TICK_LENGTH_PX,
    HEADLINE_SCALE,
    MARKED_STRIPE_WIDTH_PX,
    MAX_STRIPE_FRACTION,
    MIN_PX_PER_FLOOR_TICK,
    PIXEL_LIMIT,
    RESULT_PADDING_PX,
    RGB,
    TEXT_MARGIN_PX,
    TRACE_WIDTH_PX,
    Palette,
)

__all__ = [
    "FACE_COLOUR_NAMES",
    "FACE_STRIPE_WIDTH_PX",
    "FLOOR_LABEL_GAP_PX",
    "FLOOR_LINE_WIDTH_PX",
    "FLOOR_TICK_LENGTH_PX",
    "FLOOR_TICK_STEPS_M",
    "HEADLINE_SCALE",
    "MARKED_STRIPE_WIDTH_PX",
    "MAX_STRIPE_FRACTION",
    "MIN_PX_PER_FLOOR_TICK",
    "PIXEL_LIMIT",
    "Palette",
    "RESULT_PADDING_PX",
    "RGB",
    "SceneRenderer",
    "TEXT_MARGIN_PX",
    "TRACE_WIDTH_PX",
    "as_box_arrays",
    "floor_label",
    "floor_tick_step",
    "floor_ticks",
]


class SceneRenderer(SceneDrawing):
    """Draws boxes on the floor y = 0 into RGB frames (``render_rgb``) or a window (``show``).

    The scene is given as plain arrays:

    - ``position`` (n, 2) [m], ``angle`` (n,) [rad, counter-clockwise], ``half_extents`` (n, 2) [m]
      (half length along local x, half width along local y). A single box may be given as (2,), scalar,
      (2,); ``angle`` and ``half_extents`` broadcast over the boxes.
    - ``target_x`` [m]: a flag and a bracket on the floor; ``target_tolerance_m`` [m] sets the bracket's
      half-width. ``target_face`` (0..3 or None for any face) adds an icon of the box resting on that face
      and a label.
    - ``text_lines``: strings drawn top-left (skipped with a warning if ``pygame.font`` is unavailable).
    - ``result_lines``: a box of text top-right, its first line a headline coloured by ``result_success``
      (green True, red False, plain None): how a throw ended.
    - ``trace``: (k, 2) points [m] joined by a thin line under the boxes, e.g. the path a box's centre took.

    The floor has ticks labelled in metres, every 1, 2, 5, 10, ... m, the first step whose labels do not
    crowd. ``drawn_text`` holds the text of the last frame drawn, by where it went (``"lines"``,
    ``"result"``, ``"floor"``, ``"target"``), so callers and tests can read what a frame says.

    Faces are numbered by outward normal in the body frame (0: -y, 1: +x, 2: +y, 3: -x, see
    ``box_corners``). Each face has a coloured stripe inside the box (``Palette.face_colours``: red, blue,
    yellow, purple); face 0's stripe is twice as thick, so at angle 0 the red stripe is at the bottom and at
    angle pi it is on top.

    pygame is imported on the first draw; the drawing surface is created once and reused, the window only
    when ``show`` is first called.
    """

    def __init__(
        self,
        width_px: int = 600,
        height_px: int = 400,
        camera: Camera | None = None,
        palette: Palette | None = None,
        font_size_px: int = 18,
        window_title: str = "BoxToss",
    ) -> None:
        self.width_px = int(width_px)
        self.height_px = int(height_px)
        self.camera = camera if camera is not None else Camera.from_view(-1.0, 7.0, -1.0, 4.0, width_px, height_px)
        self._check_camera_size(self.camera)
        self.palette = palette if palette is not None else Palette()
        self.font_size_px = int(font_size_px)
        self.window_title = window_title
        self._surface: Any = None
        self._font: Any = None
        self._headline_font: Any = None
        self._font_loaded = False
        self.drawn_text: dict[str, list[str]] = {}
        """The text of the last frame drawn, by where it went: "lines", "result", "floor", "target"."""
        self._window: Any = None
        self._clock: Any = None

    # ----- public drawing API -----

    def render_rgb(
        self,
        position: np.ndarray,
        angle: np.ndarray,
        half_extents: np.ndarray,
        *,
        target_x: float | None = None,
        target_face: int | None = None,
        target_tolerance_m: float | None = None,
        target_label: str | None = None,
        text_lines: Sequence[str] = (),
        result_lines: Sequence[str] = (),
        result_success: bool | None = None,
        trace: np.ndarray | None = None,
        camera: Camera | None = None,
    ) -> np.ndarray:
        """Draw the scene and return it as a new (height_px, width_px, 3) uint8 array.

        ``camera`` overrides ``self.camera`` for this frame and must have the renderer's image size.
        """
        pygame = import_pygame()
        surface = self._draw_scene(
            position,
            angle,
            half_extents,
            target_x=target_x,
            target_face=target_face,
            target_tolerance_m=target_tolerance_m,
            target_label=target_label,
            text_lines=text_lines,
            result_lines=result_lines,
            result_success=result_success,
            trace=trace,
            camera=camera,
        )
        rgb_bytes = pygame.image.tobytes(surface, "RGB")
        return np.frombuffer(rgb_bytes, dtype=np.uint8).reshape(self.height_px, self.width_px, 3).copy()

    def show(
        self,
        position: np.ndarray,
        angle: np.ndarray,
        half_extents: np.ndarray,
        *,
        fps: float | None = None,
        **scene: Any,
    ) -> bool:
        """Draw the scene into the window (opened on first call), waiting to hold ``fps`` if given.

        ``scene``: ``render_rgb``'s keyword arguments (``target_x``, ``target_face``, ``target_tolerance_m``,
        ``target_label``, ``text_lines``, ``result_lines``, ``result_success``, ``trace``, ``camera``); another
        name is a TypeError. Returns False once the user has asked to close the
        window (the QUIT event is left in pygame's queue); the caller then calls ``close``.
        """
        pygame = import_pygame()
        surface = self._draw_scene(position, angle, half_extents, **scene)
        return self._present(pygame, surface, fps)

    def show_frame(self, frame: np.ndarray, fps: float | None = None) -> bool:
        """Show a (height_px, width_px, 3) uint8 frame, e.g. a recorded one, in the window; see ``show``."""
        pygame = import_pygame()
        frame = np.ascontiguousarray(frame)
        if frame.shape != (self.height_px, self.width_px, 3) or frame.dtype != np.uint8:
            raise ValueError(
                f"frame must be ({self.height_px}, {self.width_px}, 3) uint8, got {frame.shape} {frame.dtype}"
            )
        surface = pygame.image.frombuffer(frame, (self.width_px, self.height_px), "RGB")
        return self._present(pygame, surface, fps)

    def close(self) -> None:
        """Close the window if one is open. Safe to call more than once; ``render_rgb`` still works after."""
        if self._window is None:
            return
        pygame = import_pygame()
        pygame.display.quit()
        self._window = None
        self._clock = None

    def __enter__(self) -> SceneRenderer:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # ----- the drawing script -----

    def _draw_scene(
        self,
        position: np.ndarray,
        angle: np.ndarray,
        half_extents: np.ndarray,
        *,
        target_x: float | None = None,
        target_face: int | None = None,
        target_tolerance_m: float | None = None,
        target_label: str | None = None,
        text_lines: Sequence[str] = (),
        result_lines: Sequence[str] = (),
        result_success: bool | None = None,
        trace: np.ndarray | None = None,
        camera: Camera | None = None,
    ) -> Any:
        """Draw the whole scene onto the reused surface and return the surface."""
        pygame = import_pygame()
        camera = self.camera if camera is None else camera
        self._check_camera_size(camera)
        position, angle, half_extents = as_box_arrays(position, angle, half_extents)
        if target_face is not None and target_face not in (0, 1, 2, 3):
            raise ValueError(f"target_face must be 0, 1, 2, 3 or None, got {target_face!r}")
        if self._surface is None:
            self._surface = pygame.Surface((self.width_px, self.height_px))
        surface = self._surface
        self.drawn_text = {"lines": [], "result": [], "floor": [], "target": []}

        self._draw_sky_and_ground(pygame, surface, camera)
        if target_x is not None:
            self._draw_target(
                pygame, surface, camera, float(target_x), target_face, target_tolerance_m, target_label, half_extents
            )
        if trace is not None:
            self._draw_trace(pygame, surface, camera, trace)
        corners_px = camera.world_to_pixel(box_vertices(position, angle, half_extents))
        for box_corners_px, box_half_extents in zip(corners_px, half_extents, strict=True):
            self._draw_box(pygame, surface, box_corners_px, 2.0 * box_half_extents * camera.pixels_per_metre)
        if text_lines:
            self._draw_text(pygame, surface, text_lines)
        if result_lines:
            self._draw_result(pygame, surface, result_lines, result_success)
        return surface

    # ----- helpers -----

    def _present(self, pygame: ModuleType, surface: Any, fps: float | None) -> bool:
        """Blit ``surface`` to the window (opened lazily), pump events, hold the frame rate."""
        if self._window is None or not pygame.display.get_init():
            pygame.display.init()
            pygame.display.set_caption(self.window_title)
            self._window = pygame.display.set_mode((self.width_px, self.height_px))
            self._clock = pygame.time.Clock()
        self._window.blit(surface, (0, 0))
        pygame.event.pump()
        pygame.display.flip()
        if fps:
            self._clock.tick(fps)
        return not pygame.event.peek(pygame.QUIT)

    def _get_font(self, pygame: ModuleType) -> Any:
        """The text font, loaded once; None (with one warning) if this pygame build has no font module."""
        if not self._font_loaded:
            self._font_loaded = True
            try:
                pygame.font.init()
                self._font = pygame.font.Font(None, self.font_size_px)
                self._headline_font = pygame.font.Font(None, round(HEADLINE_SCALE * self.font_size_px))
                self._headline_font.set_bold(True)
            except (ImportError, NotImplementedError, OSError, pygame.error) as error:
                warnings.warn(f"pygame.font is unavailable ({error}); text is not drawn", RuntimeWarning, stacklevel=2)
                self._font = self._headline_font = None
        return self._font

    def _check_camera_size(self, camera: Camera) -> None:
        if (camera.width_px, camera.height_px) != (self.width_px, self.height_px):
            raise ValueError(
                f"camera is {camera.width_px}x{camera.height_px} px but the renderer draws "
                f"{self.width_px}x{self.height_px} px"
            )


def as_box_arrays(
    position: np.ndarray, angle: np.ndarray, half_extents: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Box state as float arrays ``position (n, 2)``, ``angle (n,)``, ``half_extents (n, 2)``.

    A single box may be given as ``(2,)``, scalar, ``(2,)``; ``angle`` and ``half_extents`` broadcast over
    the boxes.
    """
    position = np.atleast_2d(np.asarray(position, dtype=np.float64))
    if position.ndim != 2 or position.shape[1] != 2:
        raise ValueError(f"position must have shape (n, 2) or (2,), got {np.shape(position)}")
    n_boxes = len(position)
    try:
        angle = np.broadcast_to(np.asarray(angle, dtype=np.float64), (n_boxes,))
        half_extents = np.broadcast_to(np.asarray(half_extents, dtype=np.float64), (n_boxes, 2))
    except ValueError as error:
        raise ValueError(
            f"angle {np.shape(angle)} and half_extents {np.shape(half_extents)} do not match "
            f"{n_boxes} boxes (expected (n,) and (n, 2))"
        ) from error
    return position, angle, half_extents
