"""The parts of a BoxToss frame drawn with pygame-ce (``SceneDrawing``, which ``SceneRenderer`` is made of),
and where the floor's ticks go."""

from __future__ import annotations

from collections.abc import Sequence
from types import ModuleType
from typing import Any

import numpy as np

from box_toss_env.rendering.box_corners import box_vertices
from box_toss_env.rendering.camera import Camera
from box_toss_env.rendering.palette import (
    FACE_STRIPE_WIDTH_PX,
    FLOOR_LABEL_GAP_PX,
    FLOOR_LINE_WIDTH_PX,
    FLOOR_TICK_LENGTH_PX,
    MARKED_STRIPE_WIDTH_PX,
    MAX_STRIPE_FRACTION,
    MIN_PX_PER_FLOOR_TICK,
    PIXEL_LIMIT,
    RESULT_PADDING_PX,
    TEXT_MARGIN_PX,
    TRACE_WIDTH_PX,
    Palette,
)


class SceneDrawing:
    """The parts of a frame, each drawn onto a pygame surface: sky and ground with the floor's ticks, the
    target, a box with its coloured faces, text, the result and a trace. ``SceneRenderer`` draws with them."""

    palette: Palette
    width_px: int
    height_px: int
    _headline_font: Any
    drawn_text: dict[str, list[str]]

    def _get_font(self, pygame: ModuleType) -> Any:  # ``SceneRenderer._get_font``
        raise NotImplementedError

    def _is_out_of_view(self, corners_px: np.ndarray) -> bool:
        columns, rows = corners_px[:, 0], corners_px[:, 1]
        return bool(columns.max() < 0 or columns.min() > self.width_px or rows.max() < 0 or rows.min() > self.height_px)

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

    def _draw_result(self, pygame: ModuleType, surface: Any, result_lines: Sequence[str], success: bool | None) -> None:
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
