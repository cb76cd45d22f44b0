"""The viewer's pygame front end: events become controller calls, frames are drawn by ``SceneRenderer``
plus a text panel on the right. The same drawing serves the window and the headless PNG frames.

pygame is imported when a window or a frame surface is made (``rendering.import_pygame``), so a
missing ``render`` extra raises ``DependencyNotInstalled`` naming ``box_toss_env[render]``.

The windows show their first frame before any kernel runs: with a ``KernelLoader`` the kernels load
or compile on a background thread started after that frame, and a notice is drawn over the scene
(``Canvas.notice``) until they are ready.

This module holds the scene viewer's window (``ViewerWindow``); ``canvas`` holds the surface and the
panel both windows draw on, ``play_window`` play mode's window (``PlayWindow``); their names stay
importable from here.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from box_toss_env.physics import layout
from box_toss_env.rendering import SceneRenderer
from box_toss_env.viewer.canvas import (
    AIM_ARROW,
    AIM_PATH,
    AIM_RAW,
    DRAG_LINE,
    FONT_SIZE_PX,
    FRAME_RATE,
    LANE_DIVIDER,
    NOTICE_BACKGROUND,
    NOTICE_BORDER,
    NOTICE_TEXT,
    NOTICE_TOP_PX,
    PANEL_ALERT,
    PANEL_BACKGROUND,
    PANEL_BUTTON,
    PANEL_DIM,
    PANEL_GOOD,
    PANEL_MARGIN_PX,
    PANEL_SELECTED,
    PANEL_TEXT,
    PANEL_WIDTH_PX,
    WRAP_CHARS,
    Canvas,
    Panel,
    notice_lines,
    output_paths,
)
from box_toss_env.viewer.controller import PARAMETER_BY_NAME, ROW_LABELS, ROWS, ZOOM_STEP, ViewerController
from box_toss_env.viewer.play_window import PLAY_KEYS, PlayWindow, throw_kernel_call

__all__ = [
    "AIM_ARROW",
    "AIM_PATH",
    "AIM_RAW",
    "Canvas",
    "DRAG_LINE",
    "FONT_SIZE_PX",
    "FRAME_RATE",
    "LANE_DIVIDER",
    "NOTICE_BACKGROUND",
    "NOTICE_BORDER",
    "NOTICE_TEXT",
    "NOTICE_TOP_PX",
    "PANEL_ALERT",
    "PANEL_BACKGROUND",
    "PANEL_BUTTON",
    "PANEL_DIM",
    "PANEL_GOOD",
    "PANEL_MARGIN_PX",
    "PANEL_SELECTED",
    "PANEL_TEXT",
    "PANEL_WIDTH_PX",
    "PLAY_KEYS",
    "Panel",
    "PlayWindow",
    "VIEWER_BUTTONS",
    "VIEWER_KEYS",
    "ViewerWindow",
    "WRAP_CHARS",
    "notice_lines",
    "output_paths",
    "scene_subtitle",
    "throw_kernel_call",
]


VIEWER_KEYS = (
    ("Space", "pause / run"),
    (".", "one frame's steps"),
    ("R", "restart"),
    ("S", "solver: seed <-> robust"),
    ("C", "compare seed | robust"),
    ("I / P", "impulses / penalty on-off"),
    ("B", "boxes collide on-off"),
    ("Up / Down", "select a panel row"),
    ("Left / Right", "change it (next value)"),
    ("Enter or digits", "type a value; Enter sets it"),
    ("drag a box", "pull it with the mouse"),
    ("wheel, + / -", "zoom at the cursor"),
    ("right-drag", "pan;  F: fit the view"),
    ("H", "hide / show this help"),
    ("Q or Esc", "quit"),
)
"""Key bindings of the viewer, as shown in its panel (and the README)."""

VIEWER_BUTTONS = (("restart", "Restart"), ("pause", "Pause"), ("step", "Step"), ("compare", "Compare"))


def scene_subtitle(boxes_collide: bool, steps_per_frame: int) -> str:
    """The viewer panel's second line: what the boxes meet and how many steps each frame draws."""
    against = "the floor and one another" if boxes_collide else "the floor"
    return f"boxes against {against}, {steps_per_frame} step{'s' * (steps_per_frame != 1)} a frame"


# -- the scene viewer ------------------------------------------------------------------------------------
class ViewerWindow:
    """Draws a ``ViewerController`` (lanes of boxes + the panel) and feeds it pygame events."""

    def __init__(self, controller: ViewerController, scene_name: str, *, headless: bool = False):
        self.controller = controller
        self.scene_name = scene_name
        self.canvas = Canvas(
            (controller.width_px + PANEL_WIDTH_PX, controller.height_px),
            headless=headless,
            title=f"BoxToss viewer: {scene_name}",
        )
        self.pygame = self.canvas.pygame
        self.renderers: dict[tuple[int, int], SceneRenderer] = {}
        self.row_rects: dict[str, Any] = {}
        self.button_rects: dict[str, Any] = {}
        self.show_help = True
        self.panning = False
        self.mouse = (0, 0)  # the last cursor position seen, for the wheel

    # -- drawing ----------------------------------------------------------------------------------------
    def draw(self) -> None:
        controller = self.controller
        for index, lane in enumerate(controller.lanes):
            camera = controller.lane_camera(index)
            size = (camera.width_px, camera.height_px)
            if size not in self.renderers:
                self.renderers[size] = SceneRenderer(*size, camera=camera)
            frame = self.renderers[size].render_rgb(
                lane.state[:, layout.X : layout.Y + 1],
                lane.state[:, layout.ANGLE],
                lane.params[:, layout.HALF_LENGTH : layout.HALF_WIDTH + 1],
                text_lines=controller.readouts(index),
                camera=camera,
            )
            left = index * controller.lane_width_px
            self.canvas.blit_rgb(frame, left)
            if index > 0:
                self.pygame.draw.line(self.canvas.surface, LANE_DIVIDER, (left, 0), (left, controller.height_px), 2)
            held = lane.grab_point()
            if held is not None:
                start = camera.world_to_pixel(held) + (left, 0)
                end = camera.world_to_pixel(lane.grab.target) + (left, 0)
                self.pygame.draw.line(self.canvas.surface, DRAG_LINE, start, end, 2)
                self.pygame.draw.circle(self.canvas.surface, DRAG_LINE, end, 4)
            if lane.notice is not None:
                self.canvas.notice(
                    notice_lines(lane.job, "the boxes move when it is ready"), left, controller.lane_width_px
                )
        self._draw_panel()

    def _draw_panel(self) -> None:
        controller = self.controller
        panel = Panel(self.canvas, controller.width_px)
        panel.line(f"Rigid body collisions: {self.scene_name}")
        panel.line(scene_subtitle(controller.scene.boxes_collide, controller.steps_per_frame), PANEL_DIM)
        panel.gap()
        self.button_rects = panel.buttons(
            [(name, "Run" if name == "pause" and controller.paused else label) for name, label in VIEWER_BUTTONS]
        )
        self.row_rects = {}
        for index, row in enumerate(ROWS):
            selected = index == controller.selected
            value = controller.row_value(row)
            if selected and controller.entry is not None:
                value = controller.entry + "_"
            self.row_rects[row] = panel.line(
                ROW_LABELS[row], background=PANEL_SELECTED if selected else None, value=value
            )
        panel.gap()
        status = "paused" if controller.paused else "running"
        if controller.loading:
            status = "held until the kernel" + ("s are" if len(controller.lanes) > 1 else " is") + " ready"
        if controller.compare:
            status += ", comparing seed | robust"
        panel.wrapped(status, PANEL_DIM)
        if controller.message:
            panel.wrapped(controller.message, PANEL_ALERT)
        if self.show_help:
            panel.gap()
            panel.keys(VIEWER_KEYS)

    # -- events -------------------------------------------------------------------------------------------
    def handle(self, event) -> bool:
        """Apply one pygame event; False when the user asks to quit."""
        pygame, controller = self.pygame, self.controller
        if event.type == pygame.QUIT:
            return False
        if event.type == pygame.KEYDOWN:
            return self._key(event)
        if event.type == pygame.MOUSEBUTTONDOWN:
            self.mouse = event.pos
            if event.button == 1:
                if not self._click_panel(event.pos):
                    controller.grab(event.pos)
            elif event.button in (2, 3):
                self.panning = True
        elif event.type == pygame.MOUSEBUTTONUP:
            if event.button == 1:
                controller.release()
            elif event.button in (2, 3):
                self.panning = False
        elif event.type == pygame.MOUSEMOTION:
            self.mouse = event.pos
            if controller.grab_lane is not None:
                controller.drag_to(event.pos)
            if self.panning:
                controller.pan(*event.rel)
        elif event.type == pygame.MOUSEWHEEL:
            if controller.lane_at(self.mouse[0]) is not None:
                controller.zoom(ZOOM_STEP**event.y, self.mouse)
        return True

    def _click_panel(self, position) -> bool:
        controller = self.controller
        for name, rect in self.button_rects.items():
            if rect.collidepoint(position):
                {
                    "restart": controller.restart,
                    "pause": controller.toggle_pause,
                    "step": lambda: controller.advance_frame(force=True),
                    "compare": controller.toggle_compare,
                }[name]()
                return True
        for row, rect in self.row_rects.items():
            if rect.collidepoint(position):
                controller.select_row(row)
                if row not in PARAMETER_BY_NAME:
                    controller.adjust(+1)
                return True
        return position[0] >= controller.width_px

    def _key(self, event) -> bool:
        pygame, controller = self.pygame, self.controller
        key = event.key
        if controller.entry is not None:
            if key in (pygame.K_RETURN, pygame.K_KP_ENTER):
                controller.commit_entry()
            elif key == pygame.K_ESCAPE:
                controller.cancel_entry()
            elif key == pygame.K_BACKSPACE:
                controller.backspace()
            else:
                controller.type_text(event.unicode)
            return True
        if key in (pygame.K_ESCAPE, pygame.K_q):
            return False
        actions: dict[int, Callable[[], Any]] = {
            pygame.K_SPACE: controller.toggle_pause,
            pygame.K_PERIOD: lambda: controller.advance_frame(force=True),
            pygame.K_r: controller.restart,
            pygame.K_s: controller.switch_solver,
            pygame.K_c: controller.toggle_compare,
            pygame.K_i: lambda: controller.toggle("use_impulses"),
            pygame.K_p: lambda: controller.toggle("use_penalty"),
            pygame.K_b: lambda: controller.toggle("boxes_collide"),
            pygame.K_UP: lambda: controller.select(-1),
            pygame.K_DOWN: lambda: controller.select(+1),
            pygame.K_TAB: lambda: controller.select(+1),
            pygame.K_LEFT: lambda: controller.adjust(-1),
            pygame.K_RIGHT: lambda: controller.adjust(+1),
            pygame.K_RETURN: controller.begin_entry,
            pygame.K_KP_ENTER: controller.begin_entry,
            pygame.K_f: controller.fit,
            pygame.K_h: self._toggle_help,
            pygame.K_EQUALS: lambda: controller.zoom(ZOOM_STEP),
            pygame.K_PLUS: lambda: controller.zoom(ZOOM_STEP),
            pygame.K_KP_PLUS: lambda: controller.zoom(ZOOM_STEP),
            pygame.K_MINUS: lambda: controller.zoom(1.0 / ZOOM_STEP),
            pygame.K_KP_MINUS: lambda: controller.zoom(1.0 / ZOOM_STEP),
        }
        if key in actions:
            actions[key]()
        elif event.unicode and event.unicode in "0123456789" and controller.selected_row in PARAMETER_BY_NAME:
            controller.begin_entry()
            controller.type_text(event.unicode)
        return True

    def _toggle_help(self) -> None:
        self.show_help = not self.show_help

    # -- loops ----------------------------------------------------------------------------------------------
    def run(self, max_frames: int | None = None) -> None:
        """The interactive loop: events, one frame of steps, draw, at ``FRAME_RATE``. The scene at its
        start is shown first, then the controller's kernel loader (if any) starts."""
        clock = self.pygame.time.Clock()
        frame = 0
        try:
            self.draw()
            self.canvas.present()
            if self.controller.loader is not None:
                self.controller.loader.start()
            while max_frames is None or frame < max_frames:
                if not all(self.handle(event) for event in self.pygame.event.get()):
                    break
                self.controller.advance_frame()
                self.draw()
                self.canvas.present()
                clock.tick(FRAME_RATE)
                frame += 1
        finally:
            self.canvas.close()

    def write_frames(self, n_frames: int, out: str | Path, skip: int = 0) -> tuple[list[Path], np.ndarray]:
        """Headless: step ``skip`` frames, then draw and save ``n_frames`` frames, stepping one frame
        between them (once the kernels are ready). Returns the paths and the states drawn,
        (n_frames, lanes, bodies, 6)."""
        self.controller.wait_for_kernels()
        for _ in range(skip):
            self.controller.advance_frame()
        paths = output_paths(out, n_frames)
        states = []
        for index, path in enumerate(paths):
            if index > 0:
                self.controller.advance_frame()
            self.draw()
            self.canvas.save(path)
            states.append(np.stack([lane.state.copy() for lane in self.controller.lanes]))
        return paths, np.stack(states)
