"""What the viewer's windows draw on: the pygame surface (``Canvas``, a window or a headless frame), the
text panel on the right (``Panel``), their colours and sizes, the kernel notice and where headless frames go."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from box_toss_env.files import atomic_path
from box_toss_env.rendering import import_pygame
from box_toss_env.viewer.kernel_loader import KernelJob

PANEL_WIDTH_PX = 340
FRAME_RATE = 60
"""Frames drawn per second in the window; the viewer steps the simulation once per frame."""
FONT_SIZE_PX = 20
PANEL_MARGIN_PX = 10
WRAP_CHARS = 44

PANEL_BACKGROUND = (248, 248, 250)
PANEL_SELECTED = (208, 224, 246)
PANEL_BUTTON = (226, 230, 236)
PANEL_TEXT = (20, 20, 20)
PANEL_DIM = (95, 95, 105)
PANEL_ALERT = (180, 30, 30)
PANEL_GOOD = (0, 120, 80)
LANE_DIVIDER = (40, 40, 40)
DRAG_LINE = (200, 40, 40)
AIM_ARROW = (200, 40, 40)
AIM_RAW = (150, 150, 150)
AIM_PATH = (90, 90, 90)
NOTICE_BACKGROUND = (255, 244, 200)
NOTICE_BORDER = (200, 150, 30)
NOTICE_TEXT = (60, 40, 0)
NOTICE_TOP_PX = 96
"""The notice's top edge [px]: below a lane's read-outs."""


def output_paths(out: str | Path, n_frames: int) -> list[Path]:
    """Where headless frames go: ``out`` ending in ``.png`` names the file (numbered ``_0000`` ... when
    there are several), otherwise it is a folder of ``frame_0000.png`` ... Parent folders are made."""
    out = Path(out)
    if out.suffix.lower() == ".png":
        out.parent.mkdir(parents=True, exist_ok=True)
        if n_frames == 1:
            return [out]
        return [out.with_name(f"{out.stem}_{index:04d}.png") for index in range(n_frames)]
    out.mkdir(parents=True, exist_ok=True)
    return [out / f"frame_{index:04d}.png" for index in range(n_frames)]


class Canvas:
    """A pygame surface to draw on: the window's, or an off-screen one (headless: no display at all)."""

    def __init__(self, size: tuple[int, int], *, headless: bool, title: str):
        self.pygame = pygame = import_pygame()
        pygame.font.init()
        self.font = pygame.font.Font(None, FONT_SIZE_PX)
        self.headless = headless
        if headless:
            self.surface = pygame.Surface(size)
        else:
            pygame.display.init()
            pygame.display.set_caption(title)
            self.surface = pygame.display.set_mode(size)
        self.size = size

    def blit_rgb(self, frame: np.ndarray, left: int) -> None:
        frame = np.ascontiguousarray(frame)
        height, width = frame.shape[:2]
        self.surface.blit(self.pygame.image.frombuffer(frame, (width, height), "RGB"), (left, 0))

    def text(self, line: str, position: tuple[int, int], colour=PANEL_TEXT) -> Any:
        """Draw one line; returns its rect."""
        return self.surface.blit(self.font.render(line, True, colour), position)

    def notice(self, lines: Sequence[str], left: int, width: int) -> Any:
        """A boxed notice centred near the top of the columns [left, left + width); returns its rect."""
        pygame = self.pygame
        pad = 8
        line_height = self.font.get_linesize() + 2
        text_width = max(self.font.size(line)[0] for line in lines)
        rect = pygame.Rect(0, 0, min(text_width + 2 * pad, width - 8), len(lines) * line_height + 2 * pad)
        rect.midtop = (left + width // 2, NOTICE_TOP_PX)
        self.surface.fill(NOTICE_BACKGROUND, rect)
        pygame.draw.rect(self.surface, NOTICE_BORDER, rect, 2)
        for index, line in enumerate(lines):
            self.text(
                line, (rect.left + pad, rect.top + pad + index * line_height), NOTICE_TEXT if index == 0 else PANEL_DIM
            )
        return rect

    def save(self, path: Path) -> None:
        with atomic_path(path) as temp:  # the format follows the suffix, which the temporary name keeps
            self.pygame.image.save(self.surface, str(temp))

    def present(self) -> None:
        if not self.headless:
            self.pygame.display.flip()

    def close(self) -> None:
        if not self.headless:
            self.pygame.display.quit()


def notice_lines(job: KernelJob, then: str) -> list[str]:
    """The notice for a kernel being loaded or compiled: what, how long so far, and what follows."""
    return [job.notice, f"{job.elapsed():.1f} s; {then}"]


class Panel:
    """Writes lines top-down into the panel column, remembering clickable rects."""

    def __init__(self, canvas: Canvas, left: int):
        self.canvas = canvas
        self.left = left + PANEL_MARGIN_PX
        self.top = PANEL_MARGIN_PX
        self.line_height = canvas.font.get_linesize() + 2
        self.width = PANEL_WIDTH_PX - 2 * PANEL_MARGIN_PX
        canvas.surface.fill(PANEL_BACKGROUND, (left, 0, PANEL_WIDTH_PX, canvas.size[1]))

    def line(self, text: str = "", colour=PANEL_TEXT, *, background=None, value: str | None = None) -> Any:
        pygame = self.canvas.pygame
        rect = pygame.Rect(self.left - 4, self.top - 1, self.width + 8, self.line_height)
        if background is not None:
            self.canvas.surface.fill(background, rect)
        self.canvas.text(text, (self.left, self.top), colour)
        if value is not None:
            self.canvas.text(value, (self.left + int(0.58 * self.width), self.top), colour)
        self.top += self.line_height
        return rect

    def wrapped(self, text: str, colour=PANEL_TEXT) -> None:
        for part in textwrap.wrap(text, WRAP_CHARS):
            self.line(part, colour)

    def gap(self, fraction: float = 0.5) -> None:
        self.top += int(fraction * self.line_height)

    def keys(self, bindings: Sequence[tuple[str, str]]) -> None:
        for key, action in bindings:
            self.canvas.text(key, (self.left, self.top), PANEL_DIM)
            self.canvas.text(action, (self.left + 110, self.top), PANEL_DIM)
            self.top += self.line_height

    def buttons(self, labels: Sequence[tuple[str, str]]) -> dict[str, Any]:
        pygame = self.canvas.pygame
        rects, left = {}, self.left
        for name, label in labels:
            width = self.canvas.font.size(label)[0] + 12
            rect = pygame.Rect(left, self.top, width, self.line_height + 4)
            self.canvas.surface.fill(PANEL_BUTTON, rect)
            pygame.draw.rect(self.canvas.surface, PANEL_DIM, rect, 1)
            self.canvas.text(label, (left + 6, self.top + 3))
            rects[name] = rect
            left += width + 6
        self.top += self.line_height + 10
        return rects
