"""The viewer's pygame front end: events become controller calls, frames are drawn by ``SceneRenderer``
plus a text panel on the right. The same drawing serves the window and the headless PNG frames.

pygame is imported when a window or a frame surface is made (``rendering.import_pygame``), so a
missing ``render`` extra raises ``DependencyNotInstalled`` naming ``box_toss_env[render]``.

The windows show their first frame before any kernel runs: with a ``KernelLoader`` the kernels load
or compile on a background thread started after that frame, and a notice is drawn over the scene
(``Canvas.notice``) until they are ready.
"""

from __future__ import annotations

import dataclasses
import math
import textwrap
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from box_toss_env.files import atomic_path
from box_toss_env.physics import Simulator, layout
from box_toss_env.rendering import SceneRenderer, import_pygame
from box_toss_env.viewer.controller import PARAMETER_BY_NAME, ROW_LABELS, ROWS, ZOOM_STEP, ViewerController
from box_toss_env.viewer.kernels import KernelJob, KernelLoader, zero_step_args
from box_toss_env.viewer.play import THROW_GAIN, PlayController

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

PLAY_KEYS = (
    ("drag, release", "aim (velocity), throw"),
    ("wheel, Q / E", "spin + / - (0: none)"),
    ("Space", "replay the last throw"),
    ("R / N", "retry / new target"),
    ("right-click", "cancel the drag"),
    ("Esc", "quit"),
)
"""Key bindings of play mode."""

VIEWER_BUTTONS = (("restart", "Restart"), ("pause", "Pause"), ("step", "Step"), ("compare", "Compare"))


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
            self.text(line, (rect.left + pad, rect.top + pad + index * line_height),
                      NOTICE_TEXT if index == 0 else PANEL_DIM)
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


def scene_subtitle(boxes_collide: bool, steps_per_frame: int) -> str:
    """The viewer panel's second line: what the boxes meet and how many steps each frame draws."""
    against = "the floor and one another" if boxes_collide else "the floor"
    return f"boxes against {against}, {steps_per_frame} step{'s' * (steps_per_frame != 1)} a frame"


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


# -- the scene viewer ------------------------------------------------------------------------------------
class ViewerWindow:
    """Draws a ``ViewerController`` (lanes of boxes + the panel) and feeds it pygame events."""

    def __init__(self, controller: ViewerController, scene_name: str, *, headless: bool = False):
        self.controller = controller
        self.scene_name = scene_name
        self.canvas = Canvas((controller.width_px + PANEL_WIDTH_PX, controller.height_px), headless=headless,
                             title=f"BoxToss viewer: {scene_name}")
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
                lane.state[:, layout.X:layout.Y + 1], lane.state[:, layout.ANGLE],
                lane.params[:, layout.HALF_LENGTH:layout.HALF_WIDTH + 1],
                text_lines=controller.readouts(index), camera=camera)
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
                self.canvas.notice(notice_lines(lane.job, "the boxes move when it is ready"), left,
                                   controller.lane_width_px)
        self._draw_panel()

    def _draw_panel(self) -> None:
        controller = self.controller
        panel = Panel(self.canvas, controller.width_px)
        panel.line(f"Rigid body collisions: {self.scene_name}")
        panel.line(scene_subtitle(controller.scene.boxes_collide, controller.steps_per_frame), PANEL_DIM)
        panel.gap()
        self.button_rects = panel.buttons(
            [(name, "Run" if name == "pause" and controller.paused else label) for name, label in VIEWER_BUTTONS])
        self.row_rects = {}
        for index, row in enumerate(ROWS):
            selected = index == controller.selected
            value = controller.row_value(row)
            if selected and controller.entry is not None:
                value = controller.entry + "_"
            self.row_rects[row] = panel.line(ROW_LABELS[row], background=PANEL_SELECTED if selected else None,
                                             value=value)
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
                controller.zoom(ZOOM_STEP ** event.y, self.mouse)
        return True

    def _click_panel(self, position) -> bool:
        controller = self.controller
        for name, rect in self.button_rects.items():
            if rect.collidepoint(position):
                {"restart": controller.restart, "pause": controller.toggle_pause,
                 "step": lambda: controller.advance_frame(force=True),
                 "compare": controller.toggle_compare}[name]()
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


# -- play mode -------------------------------------------------------------------------------------------
class PlayWindow:
    """Draws a ``PlayController``: the env's own frames (target, box, throw), the aim drawn over them,
    and a panel with the aim, the reward and its terms."""

    def __init__(self, controller: PlayController, *, headless: bool = False, loader: KernelLoader | None = None):
        from box_toss_env.envs.render import ThrowRenderer

        self.controller = controller
        env = controller.env.unwrapped
        width, height = env.render_size
        self.fps = float(env.metadata["render_fps"])
        # the env draws with a ThrowRenderer for its config and frame size: the same camera maps the mouse
        self.camera = ThrowRenderer(controller.config, width, height, self.fps).home_camera
        self.width_px, self.height_px = width, height
        self.canvas = Canvas((width + PANEL_WIDTH_PX, height), headless=headless, title="BoxToss: play")
        self.pygame = self.canvas.pygame
        self.playback_start: float | None = None
        self.loader = loader
        self.job = None if loader is None else loader.prepare(*throw_kernel_call(controller.env), env.solver)
        self.throw_pending = False  # released before the kernel was ready: thrown when it is

    @property
    def ready(self) -> bool:
        """The env's kernel can throw now (always, without a loader: the first throw compiles it)."""
        return self.job is None or self.job.ready

    def release_throw(self) -> None:
        """Throw the aimed drag now, or as soon as the kernel is ready."""
        if self.ready:
            self.throw_pending = False
            if self.controller.end_drag() is not None:
                self.start_playback()
        else:
            self.throw_pending = True

    def start_playback(self) -> None:
        self.playback_start = time.perf_counter()

    def playback_index(self) -> int | None:
        """Which frame of the last throw to show now (None: the throw is over, show its end)."""
        result = self.controller.result
        if result is None or self.playback_start is None or not result.frames:
            return None
        index = int((time.perf_counter() - self.playback_start) * self.fps)
        if index >= len(result.frames):
            self.playback_start = None
            return None
        return index

    # -- drawing ----------------------------------------------------------------------------------------
    def draw(self, playback_index: int | None = None) -> None:
        controller = self.controller
        result = controller.result
        if result is not None and result.frames:
            frame = result.frames[-1 if playback_index is None else playback_index]
        elif controller.hand_frames:
            frame = controller.hand_frames[-1]
        else:
            frame = np.full((self.height_px, self.width_px, 3), 255, dtype=np.uint8)
        self.canvas.blit_rgb(frame, 0)
        if result is None:
            self._draw_aim()
        if not self.ready:
            self.canvas.notice(notice_lines(self.job, "throws wait until it is ready"), 0, self.width_px)
        self._draw_panel(done=result is not None and playback_index is None)

    def _px(self, point) -> tuple[float, float]:
        column, row = self.camera.world_to_pixel(np.asarray(point, dtype=np.float64))
        return float(column), float(row)

    def _draw_aim(self) -> None:
        pygame, surface, controller = self.pygame, self.canvas.surface, self.controller
        centre = controller.release[:2]
        if controller.aiming:
            _, (speed, theta, _), clipped = controller.aimed()
            if clipped:
                raw_end = centre + controller.velocity / THROW_GAIN
                pygame.draw.line(surface, AIM_RAW, self._px(centre), self._px(raw_end), 1)
            for point in controller.preview_path()[1::2]:
                pygame.draw.circle(surface, AIM_PATH, self._px(point), 2)
            end = centre + speed / THROW_GAIN * np.array([math.cos(theta), math.sin(theta)])
            _arrow(pygame, surface, self._px(centre), self._px(end), AIM_ARROW)
        if controller.spin:
            radius = 0.45 * self.camera.pixels_per_metre * math.hypot(controller.config.half_length,
                                                                      controller.config.half_width) + 10
            sweep = 1.5 * math.pi * controller.spin / max(controller.config.max_spin, 1e-9)
            start, stop = (0.25 * math.pi, 0.25 * math.pi + sweep) if sweep > 0 else (0.25 * math.pi + sweep,
                                                                                     0.25 * math.pi)
            column, row = self._px(centre)
            rect = pygame.Rect(0, 0, 2 * radius, 2 * radius)
            rect.center = (int(column), int(row))
            pygame.draw.arc(surface, AIM_ARROW, rect, start, stop, 2)
            tip_angle = 0.25 * math.pi + sweep
            tip = (column + radius * math.cos(tip_angle), row - radius * math.sin(tip_angle))
            pygame.draw.circle(surface, AIM_ARROW, tip, 4)

    def _draw_panel(self, *, done: bool) -> None:
        controller = self.controller
        panel = Panel(self.canvas, self.width_px)
        panel.line("BoxToss: throw it yourself")
        panel.line(f"land on {controller.target_label} at x = {controller.target_x:.2f} m", PANEL_DIM)
        panel.gap()
        result = controller.result
        if result is None:
            action, (speed, theta, spin), clipped = controller.aimed()
        else:  # the throw just made
            action, (speed, theta, spin), clipped = result.action, result.throw, result.clipped
        panel.line("speed", value=f"{speed:.2f} m/s")
        panel.line("direction", value=f"{math.degrees(theta):.0f} deg")
        panel.line("spin", value=f"{spin:+.1f} rad/s")
        panel.line("action", value="[" + ", ".join(f"{a:+.2f}" for a in action) + "]")
        if clipped:
            panel.line("(clipped into the action space)", PANEL_ALERT)
        panel.gap()
        if result is not None and done:
            info = result.info
            panel.line("success!" if info["success"] else "no success", PANEL_GOOD if info["success"] else PANEL_ALERT)
            panel.line("reward", value=f"{result.reward:+.3f}")
            for name, value in result.terms.items():
                panel.line("  " + name.removeprefix("reward_"), value=f"{value:+.3f}")
            panel.line("distance", value=f"{info['distance']:.3f} m")
            panel.line("orientation error", value=f"{math.degrees(info['orientation_error']):.1f} deg")
            panel.line("face down", value=f"{info['face_down']}")
            panel.line("at rest", value="yes" if info["at_rest"] else "no")
            panel.line("flight, impacts", value=f"{info['flight_time']:.2f} s, {info['n_impacts']}")
        elif self.throw_pending:
            panel.line("throwing when the kernel is ready ...", PANEL_DIM)
        elif result is not None:
            panel.line("throwing ...", PANEL_DIM)
        else:
            panel.line("drag to aim, release to throw", PANEL_DIM)
        panel.gap()
        panel.keys(PLAY_KEYS)

    # -- events -------------------------------------------------------------------------------------------
    def handle(self, event) -> bool:
        pygame, controller = self.pygame, self.controller
        if event.type == pygame.QUIT:
            return False
        if self.throw_pending:  # released, waiting for the kernel: only Esc (quit) is taken until it is thrown
            return not (event.type == pygame.KEYDOWN and event.key == pygame.K_ESCAPE)
        if event.type == pygame.KEYDOWN:
            key = event.key
            if key == pygame.K_ESCAPE:
                if not controller.aiming:
                    return False
                controller.cancel_drag()
            elif key == pygame.K_e:
                controller.change_spin(-1)
            elif key == pygame.K_q:
                controller.change_spin(+1)
            elif key in (pygame.K_0, pygame.K_KP0):
                controller.reset_spin()
            elif key == pygame.K_r:
                controller.retry()
            elif key == pygame.K_n:
                controller.new_target()
            elif key == pygame.K_SPACE and controller.result is not None:
                self.start_playback()
        elif event.type == pygame.MOUSEBUTTONDOWN and event.pos[0] < self.width_px:
            if event.button == 1:
                controller.begin_drag(self.camera.pixel_to_world(np.asarray(event.pos, dtype=np.float64)))
            elif event.button == 3:
                controller.cancel_drag()
        elif event.type == pygame.MOUSEMOTION and controller.aiming:
            controller.drag_to(self.camera.pixel_to_world(np.asarray(event.pos, dtype=np.float64)))
        elif event.type == pygame.MOUSEBUTTONUP and event.button == 1 and controller.aiming:
            controller.drag_to(self.camera.pixel_to_world(np.asarray(event.pos, dtype=np.float64)))
            self.release_throw()
        elif event.type == pygame.MOUSEWHEEL:
            controller.change_spin(int(event.y))
        return True

    def run(self, max_frames: int | None = None) -> None:
        clock = self.pygame.time.Clock()
        frame = 0
        try:
            self.draw()
            self.canvas.present()
            if self.loader is not None:
                self.loader.start()
            while max_frames is None or frame < max_frames:
                if not all(self.handle(event) for event in self.pygame.event.get()):
                    break
                if self.throw_pending and self.ready:
                    self.release_throw()
                self.draw(self.playback_index())
                self.canvas.present()
                clock.tick(FRAME_RATE)
                frame += 1
        finally:
            self.canvas.close()

    def write_frames(self, n_frames: int, out: str | Path, throw: Sequence[float] | None = None) -> list[Path]:
        """Headless: the aim (a scripted drag giving ``throw`` = (vx, vy, spin), if given), then the
        throw's frames with the result on the last; ``n_frames`` of them, evenly spread from the aim to
        the result (a single frame is the result)."""
        controller = self.controller
        if self.loader is not None:
            self.loader.wait()
        if throw is None:
            self.draw()
            shots: list[Callable[[], Any]] = [self.canvas.surface.copy]
        else:
            vx, vy, spin = (float(v) for v in throw)
            centre = controller.release[:2]
            controller.begin_drag(centre)
            controller.drag_to(centre + np.array([vx, vy]) / THROW_GAIN)
            controller.spin = spin
            self.draw()
            aim = self.canvas.surface.copy()
            result = controller.end_drag()
            shots = [lambda: aim]
            shots += [lambda k=k: self._drawn(k) for k in range(len(result.frames) - 1)]
            shots.append(lambda: self._drawn(None))
        if n_frames == 1:
            shots = shots[-1:]
        elif n_frames < len(shots):
            shots = [shots[k] for k in np.unique(np.rint(np.linspace(0, len(shots) - 1, n_frames)).astype(int))]
        paths = output_paths(out, len(shots))
        for shot, path in zip(shots, paths, strict=True):
            surface = shot()
            with atomic_path(path) as temp:
                self.pygame.image.save(surface, str(temp))
        return paths

    def _drawn(self, playback_index: int | None) -> Any:
        self.draw(playback_index)
        return self.canvas.surface


def throw_kernel_call(env) -> tuple[Any, tuple]:
    """(kernel, zero-step arguments) of the kernel ``env`` (a BoxToss env) throws with: the kernel of
    the env's flags, recording when the env draws (kernels are cached per flags, so it is the env's)."""
    env = env.unwrapped
    flags = dataclasses.replace(env.flags, record=env.render_mode in ("human", "rgb_array_list"))
    n = 1
    args = zero_step_args(np.zeros((n, layout.STATE_SIZE)), np.zeros((n, layout.PARAM_SIZE)), env.engine_settings,
                          np.zeros((n, layout.STATS_SIZE)))
    return Simulator(flags).kernel, args


def _arrow(pygame, surface, start, end, colour) -> None:
    pygame.draw.line(surface, colour, start, end, 3)
    direction = np.subtract(end, start)
    length = float(np.hypot(*direction))
    if length < 1.0:
        return
    unit = direction / length
    normal = np.array([-unit[1], unit[0]])
    head = [end, np.add(end, -10 * unit + 5 * normal), np.add(end, -10 * unit - 5 * normal)]
    pygame.draw.polygon(surface, colour, [tuple(p) for p in head])
