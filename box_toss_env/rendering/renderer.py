"""Draws the box-toss scene (floor, target, boxes with coloured faces, text) with pygame-ce."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np

from box_toss_env.rendering.camera import Camera
from box_toss_env.rendering.dependency import import_pygame
from box_toss_env.rendering.geometry import box_vertices

RGB = tuple[int, int, int]


@dataclass(frozen=True)
class Palette:
    """Colours of the scene, as (r, g, b) in 0..255."""

    background: RGB = (236, 241, 246)
    ground: RGB = (122, 108, 92)
    floor_line: RGB = (60, 52, 44)
    box_fill: RGB = (170, 180, 190)
    box_outline: RGB = (30, 30, 30)
    face_colours: tuple[RGB, RGB, RGB, RGB] = (
        (214, 39, 40),  # face 0, local -y: red, the thick stripe
        (31, 119, 180),  # face 1, local +x: blue
        (255, 187, 0),  # face 2, local +y: yellow
        (148, 103, 189),  # face 3, local -x: purple
    )
    target: RGB = (0, 158, 115)
    target_pole: RGB = (70, 70, 70)
    text: RGB = (20, 20, 20)
    floor_label: RGB = (246, 240, 230)
    trace: RGB = (110, 130, 165)
    result_background: RGB = (255, 255, 255)
    success: RGB = (0, 135, 90)
    failure: RGB = (200, 40, 40)


FACE_COLOUR_NAMES = ("red", "blue", "yellow", "purple")
"""Names of ``Palette().face_colours``, for text that refers to a face by its colour."""


MARKED_STRIPE_WIDTH_PX = 6.0
"""Width of the coloured stripe inside the marked face (face 0 on boxes) [px]."""
FACE_STRIPE_WIDTH_PX = 3.0
"""Width of the coloured stripe inside each other face [px]."""
MAX_STRIPE_FRACTION = 0.3
"""A stripe covers at most this fraction of the box's thickness across its face."""
PIXEL_LIMIT = 1.0e5
"""Pixel coordinates handed to pygame are clipped to +-PIXEL_LIMIT (pygame needs them to fit in C ints)."""
TEXT_MARGIN_PX = 6
FLOOR_LINE_WIDTH_PX = 2
FLOOR_TICK_LENGTH_PX = 5
MIN_PX_PER_FLOOR_TICK = 30.0
"""Floor ticks are at least this far apart [px]: every 1, 2, 5, 10, 20, ... m, the first step that fits."""
FLOOR_LABEL_GAP_PX = 10
"""Floor tick labels ("3 m") are at least this far apart [px]."""
RESULT_PADDING_PX = 6
HEADLINE_SCALE = 1.4
"""The result's first line (its headline) is drawn this much larger than other text."""
TRACE_WIDTH_PX = 2


class SceneRenderer:
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
    ``geometry``). Each face has a coloured stripe inside the box (``Palette.face_colours``: red, blue,
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
        self.camera = (
            camera if camera is not None else Camera.from_view(-1.0, 7.0, -1.0, 4.0, width_px, height_px)
        )
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
            pygame,
            position,
            angle,
            half_extents,
            target_x,
            target_face,
            target_tolerance_m,
            target_label,
            text_lines,
            camera,
            result_lines=result_lines,
            result_success=result_success,
            trace=trace,
        )
        rgb_bytes = pygame.image.tobytes(surface, "RGB")
        return np.frombuffer(rgb_bytes, dtype=np.uint8).reshape(self.height_px, self.width_px, 3).copy()

    def show(
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
        fps: float | None = None,
    ) -> bool:
        """Draw the scene into the window (opened on first call), waiting to hold ``fps`` if given.

        Takes the same scene arguments as ``render_rgb``. Returns False once the user has asked to close the
        window (the QUIT event is left in pygame's queue); the caller then calls ``close``.
        """
        pygame = import_pygame()
        surface = self._draw_scene(
            pygame,
            position,
            angle,
            half_extents,
            target_x,
            target_face,
            target_tolerance_m,
            target_label,
            text_lines,
            camera,
            result_lines=result_lines,
            result_success=result_success,
            trace=trace,
        )
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
        pygame: ModuleType,
        position: np.ndarray,
        angle: np.ndarray,
        half_extents: np.ndarray,
        target_x: float | None,
        target_face: int | None,
        target_tolerance_m: float | None,
        target_label: str | None,
        text_lines: Sequence[str],
        camera: Camera | None,
        *,
        result_lines: Sequence[str] = (),
        result_success: bool | None = None,
        trace: np.ndarray | None = None,
    ) -> Any:
        """Draw the whole scene onto the reused surface and return the surface."""
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

    def _draw_sky_and_ground(self, pygame: ModuleType, surface: Any, camera: Camera) -> None:
        """Background, the ground region below y = 0, the floor line, and ticks labelled in metres."""
        palette = self.palette
        surface.fill(palette.background)
        floor_row = camera.world_to_pixel(np.zeros(2))[1]
        # rows whose pixel centre lies below y = 0 are ground
        ground_top = int(np.clip(np.ceil(floor_row - 0.5), 0, self.height_px))
        if ground_top >= self.height_px:
            return
        surface.fill(palette.ground, (0, ground_top, self.width_px, self.height_px - ground_top))
        surface.fill(palette.floor_line, (0, ground_top - 1, self.width_px, FLOOR_LINE_WIDTH_PX))
        if ground_top <= 0:
            return
        x_min, x_max, _, _ = camera.view_bounds
        font = self._get_font(pygame)
        step_m = floor_tick_step(camera.pixels_per_metre, x_min, x_max, font)
        label_top = ground_top + FLOOR_TICK_LENGTH_PX + 1
        for tick_x in floor_ticks(x_min, x_max, step_m):
            column = camera.world_to_pixel(np.array([tick_x, 0.0]))[0]
            pygame.draw.line(
                surface, palette.floor_line, (column, ground_top), (column, ground_top + FLOOR_TICK_LENGTH_PX)
            )
            if font is None:
                continue
            label = floor_label(tick_x)
            width, height = font.size(label)
            left = int(round(column - 0.5 * width))
            if left < 0 or left + width > self.width_px or label_top + height > self.height_px:
                continue  # a label cut by the image's edge reads as another number
            surface.blit(font.render(label, True, palette.floor_label), (left, label_top))
            self.drawn_text["floor"].append(label)

    def _draw_target(
        self,
        pygame: ModuleType,
        surface: Any,
        camera: Camera,
        target_x: float,
        target_face: int | None,
        target_tolerance_m: float | None,
        target_label: str | None,
        half_extents: np.ndarray,
    ) -> None:
        """A bracket on the floor at ``target_x``, a flag, and an icon and label for the face to land on
        (``target_label`` replaces the label's text, e.g. "a long side down")."""
        palette = self.palette
        column, floor_row = _clip_px(camera.world_to_pixel(np.array([target_x, 0.0])))
        if target_tolerance_m is None:
            bracket_half_width = 10.0
        else:
            bracket_half_width = max(4.0, float(target_tolerance_m) * camera.pixels_per_metre)
        bracket_half_width = min(bracket_half_width, PIXEL_LIMIT)
        bracket_height = 8.0
        bracket = [
            (column - bracket_half_width, floor_row - bracket_height),
            (column - bracket_half_width, floor_row),
            (column + bracket_half_width, floor_row),
            (column + bracket_half_width, floor_row - bracket_height),
        ]
        pygame.draw.lines(surface, palette.target, False, bracket, 3)

        pole_height = float(np.clip(self.height_px / 6, 20, 48))
        pole_top = floor_row - pole_height
        flag_width, flag_height = 0.6 * pole_height, 0.35 * pole_height
        pygame.draw.line(surface, palette.target_pole, (column, floor_row), (column, pole_top), 2)
        flag = [
            (column, pole_top),
            (column + flag_width, pole_top + 0.5 * flag_height),
            (column, pole_top + flag_height),
        ]
        pygame.draw.polygon(surface, palette.target, flag)

        label_left = column + flag_width + 4
        if target_face is not None:
            icon_size = 0.7 * pole_height
            icon_centre = np.array([label_left + 0.5 * icon_size, pole_top + 0.5 * flag_height])
            self._draw_face_icon(pygame, surface, icon_centre, target_face, half_extents, icon_size)
            label_left += icon_size + 6
        font = self._get_font(pygame)
        if font is not None:
            label = target_label or ("any face" if target_face is None else f"face {target_face} down")
            label_width = font.size(label)[0]
            if label_left + label_width > self.width_px and column - 4 - label_width >= 0:
                label_left = column - 4 - label_width  # no room right of the flag: write it on the left
            surface.blit(font.render(label, True, palette.target), (label_left, pole_top))
            self.drawn_text["target"].append(label)

    def _draw_face_icon(
        self,
        pygame: ModuleType,
        surface: Any,
        centre_px: np.ndarray,
        face: int,
        half_extents: np.ndarray,
        size_px: float,
    ) -> None:
        """A small box like the first one, resting on ``face``, whose stripe is drawn thick at the bottom."""
        length_over_width = half_extents[0, 0] / half_extents[0, 1] if len(half_extents) else 2.0
        aspect = float(np.clip(length_over_width, 1 / 3, 3))
        icon_half_extents = 0.5 * size_px * np.array([[min(1.0, aspect), min(1.0, 1.0 / aspect)]])
        angle_face_down = np.array([-0.5 * np.pi * face])  # rotates face k's outward normal onto -y
        corners = box_vertices(np.zeros((1, 2)), angle_face_down, icon_half_extents)[0]
        corners_px = np.column_stack([centre_px[0] + corners[:, 0], centre_px[1] - corners[:, 1]])
        self._draw_box(pygame, surface, corners_px, 2.0 * icon_half_extents[0], marked_face=face)

    def _draw_box(
        self,
        pygame: ModuleType,
        surface: Any,
        corners_px: np.ndarray,
        size_px: np.ndarray,
        marked_face: int = 0,
    ) -> None:
        """Fill one box, stripe each face in its colour (``marked_face`` last and thickest), outline it.

        ``corners_px`` (4, 2) are the box corners in pixels, counter-clockwise in the world (so clockwise on
        screen); ``size_px`` (2,) is the box's full length and width in pixels.
        """
        if not np.all(np.isfinite(corners_px)) or self._is_out_of_view(corners_px):
            return
        palette = self.palette
        corners_px = _clip_px(corners_px)
        pygame.draw.polygon(surface, palette.box_fill, corners_px.tolist())
        edges = np.roll(corners_px, -1, axis=0) - corners_px
        edge_lengths = np.hypot(edges[:, 0], edges[:, 1])
        # world counter-clockwise is screen clockwise, so (ey, -ex) points into the box
        inward = np.column_stack([edges[:, 1], -edges[:, 0]]) / np.maximum(edge_lengths, 1e-12)[:, None]
        thickness_across_face = (size_px[1], size_px[0], size_px[1], size_px[0])
        faces_in_drawing_order = [face for face in range(4) if face != marked_face] + [marked_face]
        for face in faces_in_drawing_order:
            if edge_lengths[face] < 1e-9:
                continue
            width = MARKED_STRIPE_WIDTH_PX if face == marked_face else FACE_STRIPE_WIDTH_PX
            width = max(min(width, MAX_STRIPE_FRACTION * thickness_across_face[face]), 1.0)
            start, end = corners_px[face], corners_px[(face + 1) % 4]
            stripe = np.array([start, end, end + width * inward[face], start + width * inward[face]])
            pygame.draw.polygon(surface, palette.face_colours[face], stripe.tolist())
        pygame.draw.polygon(surface, palette.box_outline, corners_px.tolist(), width=1)

    def _draw_text(self, pygame: ModuleType, surface: Any, text_lines: Sequence[str]) -> None:
        """Text lines top-left, one per row."""
        font = self._get_font(pygame)
        if font is None:
            return
        line_height = font.get_linesize()
        for index, line in enumerate(text_lines):
            surface.blit(
                font.render(str(line), True, self.palette.text),
                (TEXT_MARGIN_PX, TEXT_MARGIN_PX + index * line_height),
            )
            self.drawn_text["lines"].append(str(line))

    def _draw_result(
        self, pygame: ModuleType, surface: Any, result_lines: Sequence[str], success: bool | None
    ) -> None:
        """A box top-right: the first line large, in green (success) or red (not), the others below it."""
        font = self._get_font(pygame)
        if font is None:
            return
        palette = self.palette
        colour = palette.text if success is None else (palette.success if success else palette.failure)
        lines = [str(line) for line in result_lines]
        rendered = [self._headline_font.render(lines[0], True, colour)]
        rendered += [font.render(line, True, palette.text) for line in lines[1:]]
        width = max(image.get_width() for image in rendered) + 2 * RESULT_PADDING_PX
        height = sum(image.get_height() for image in rendered) + 2 * RESULT_PADDING_PX
        left = max(self.width_px - TEXT_MARGIN_PX - width, 0)
        box = pygame.Rect(left, TEXT_MARGIN_PX, width, height)
        surface.fill(palette.result_background, box)
        pygame.draw.rect(surface, colour, box, 2)
        top = TEXT_MARGIN_PX + RESULT_PADDING_PX
        for image in rendered:
            surface.blit(image, (left + RESULT_PADDING_PX, top))
            top += image.get_height()
        self.drawn_text["result"] = lines

    def _draw_trace(self, pygame: ModuleType, surface: Any, camera: Camera, trace: np.ndarray) -> None:
        """The points of ``trace`` (k, 2) [m] joined by a thin line."""
        points = np.asarray(trace, dtype=np.float64).reshape(-1, 2)
        points = points[np.all(np.isfinite(points), axis=1)]
        if len(points) < 2:
            return
        pixels = _clip_px(camera.world_to_pixel(points))
        pygame.draw.lines(surface, self.palette.trace, False, pixels.tolist(), TRACE_WIDTH_PX)

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
                warnings.warn(
                    f"pygame.font is unavailable ({error}); text is not drawn", RuntimeWarning, stacklevel=2
                )
                self._font = self._headline_font = None
        return self._font

    def _is_out_of_view(self, corners_px: np.ndarray) -> bool:
        columns, rows = corners_px[:, 0], corners_px[:, 1]
        return bool(
            columns.max() < 0
            or columns.min() > self.width_px
            or rows.max() < 0
            or rows.min() > self.height_px
        )

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


def _clip_px(pixels: np.ndarray) -> np.ndarray:
    return np.clip(pixels, -PIXEL_LIMIT, PIXEL_LIMIT)


FLOOR_TICK_STEPS_M = tuple(m * 10.0**e for e in range(0, 6) for m in (1.0, 2.0, 5.0))
"""Distances between floor ticks to choose from [m]."""


def floor_label(tick_x: float) -> str:
    """The label of the floor tick at ``tick_x`` [m]: "0", "2 m", "-1 m"."""
    return "0" if tick_x == 0 else f"{tick_x:g} m"


def floor_tick_step(pixels_per_metre: float, x_min: float, x_max: float, font: Any = None) -> float:
    """The first of 1, 2, 5, 10, 20, ... m whose ticks are ``MIN_PX_PER_FLOOR_TICK`` apart and, with a
    ``font``, whose widest label fits between neighbours with ``FLOOR_LABEL_GAP_PX`` to spare."""
    for step_m in FLOOR_TICK_STEPS_M:
        spacing_px = step_m * pixels_per_metre
        if spacing_px < MIN_PX_PER_FLOOR_TICK:
            continue
        if font is None:
            return step_m
        ticks = floor_ticks(x_min, x_max, step_m)
        widest = max((font.size(floor_label(x))[0] for x in ticks[[0, -1]]), default=0) if len(ticks) else 0
        if spacing_px >= widest + FLOOR_LABEL_GAP_PX:
            return step_m
    return FLOOR_TICK_STEPS_M[-1]


def floor_ticks(x_min: float, x_max: float, step_m: float) -> np.ndarray:
    """Multiples of ``step_m`` in [x_min, x_max] [m]."""
    return step_m * np.arange(np.ceil(x_min / step_m), np.floor(x_max / step_m) + 1)
