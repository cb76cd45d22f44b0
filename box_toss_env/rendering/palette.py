"""How a BoxToss frame looks: its colours (``Palette``) and the sizes of its strokes, stripes and text [px]."""

from __future__ import annotations

from dataclasses import dataclass

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
