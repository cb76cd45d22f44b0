"""Play mode's pygame front end: ``PlayWindow`` draws a ``PlayController`` (the env's own frames, the aim
over them, a panel with the reward and its terms) and turns mouse and keys into throws."""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from box_toss_env.files import atomic_path
from box_toss_env.physics import Simulator, layout
from box_toss_env.viewer.canvas import (
    AIM_ARROW,
    AIM_PATH,
    AIM_RAW,
    FRAME_RATE,
    PANEL_ALERT,
    PANEL_DIM,
    PANEL_GOOD,
    PANEL_WIDTH_PX,
    Canvas,
    Panel,
    notice_lines,
    output_paths,
)
from box_toss_env.viewer.kernel_loader import KernelLoader, zero_step_args
from box_toss_env.viewer.play import THROW_GAIN, PlayController

PLAY_KEYS = (
    ("drag, release", "aim (velocity), throw"),
    ("wheel, Q / E", "spin + / - (0: none)"),
    ("Space", "replay the last throw"),
    ("R / N", "retry / new target"),
    ("right-click", "cancel the drag"),
    ("Esc", "quit"),
)
"""Key bindings of play mode."""


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
            radius = (
                0.45
                * self.camera.pixels_per_metre
                * math.hypot(controller.config.half_length, controller.config.half_width)
                + 10
            )
            sweep = 1.5 * math.pi * controller.spin / max(controller.config.max_spin, 1e-9)
            start, stop = (
                (0.25 * math.pi, 0.25 * math.pi + sweep) if sweep > 0 else (0.25 * math.pi + sweep, 0.25 * math.pi)
            )
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
    args = zero_step_args(
        np.zeros((n, layout.STATE_SIZE)),
        np.zeros((n, layout.PARAM_SIZE)),
        env.engine_settings,
        np.zeros((n, layout.STATS_SIZE)),
        warm_start=Simulator(flags).carries_warm_start,
    )
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
