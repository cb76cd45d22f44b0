"""The viewer's model: live scenes, their parameters and the view, with no window (pure numpy).

``ViewerController`` holds what the seed demo's page holds: the scene's parameters (time step,
gravity, penalty stiffness, restitution, friction, the two toggles), one running simulation per
shown solver (a ``Lane``: one in the normal view, the seed scheme and the robust solver side by
side in compare mode), the pause switch, the box held by the mouse and the camera. The pygame
front end (``window``) only turns events into calls here and draws what it reads back.

Stepping follows the demo: each drawn frame runs ``STEPS_PER_FRAME`` (8) time steps through a
``Simulator`` built for the scene's compile-time flags (rebuilt only when those change), and the
wall time per step is averaged over the last ``TIMING_WINDOW_STEPS`` (50) steps.

With a ``KernelLoader`` (the window's), a lane's kernel is loaded or compiled on a background thread:
until every lane's kernel is ready the scene holds still and ``notices`` says which one is compiling.
Without one, the first step compiles it where it runs.

Its parts: ``parameters`` (the panel's rows), ``lane`` (one running simulation), ``view`` (the camera);
their names stay importable from here.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence

import numpy as np

from box_toss_env.physics import (
    SOLVERS,
    Scene,
    layout,
)
from box_toss_env.rendering import Camera
from box_toss_env.viewer.kernel_loader import KernelLoader
from box_toss_env.viewer.lane import (
    DRAG_FOLLOW_FRAMES,
    DRAG_SPIN_DAMPING,
    MAX_DRAG_SPEED,
    STEPS_PER_FRAME,
    TIMING_WINDOW_STEPS,
    Grab,
    Lane,
    StepTimer,
)
from box_toss_env.viewer.parameters import (
    COMPARE_SOLVERS,
    PARAMETER_BY_NAME,
    PARAMETERS,
    ROW_LABELS,
    ROWS,
    TOGGLES,
    Parameter,
)
from box_toss_env.viewer.view import MAX_PIXELS_PER_METRE, MIN_PIXELS_PER_METRE, ZOOM_STEP, View, fit_view, view_points

__all__ = [
    "COMPARE_SOLVERS",
    "DRAG_FOLLOW_FRAMES",
    "DRAG_SPIN_DAMPING",
    "Grab",
    "Lane",
    "MAX_DRAG_SPEED",
    "MAX_PIXELS_PER_METRE",
    "MIN_PIXELS_PER_METRE",
    "PARAMETERS",
    "PARAMETER_BY_NAME",
    "Parameter",
    "ROWS",
    "ROW_LABELS",
    "STEPS_PER_FRAME",
    "StepTimer",
    "TIMING_WINDOW_STEPS",
    "TOGGLES",
    "View",
    "ViewerController",
    "ZOOM_STEP",
    "fit_view",
    "view_points",
]


# -- the controller ------------------------------------------------------------------------------------
class ViewerController:
    """The viewer's state and every action the user can take, without a window.

    ``width_px`` and ``height_px`` are the size of the scene area (the panel is extra); in compare
    mode it is split into two lanes side by side. Parameter changes build a new ``Scene`` through
    ``Scene.replace`` (which validates); a rejected change leaves everything as it was and puts the
    reason in ``message``. With a ``loader`` kernels are loaded off the caller's thread (see ``loading``).
    """

    def __init__(
        self,
        scene: Scene,
        *,
        width_px: int = 900,
        height_px: int = 560,
        steps_per_frame: int = STEPS_PER_FRAME,
        clock: Callable[[], float] = time.perf_counter,
        loader: KernelLoader | None = None,
    ):
        if steps_per_frame < 1:
            raise ValueError(f"steps_per_frame must be >= 1, got {steps_per_frame}")
        self.scene = scene
        self.width_px = int(width_px)
        self.height_px = int(height_px)
        self.steps_per_frame = int(steps_per_frame)
        self.clock = clock
        self.loader = loader
        self.lanes = [self._make_lane(scene)]
        self.compare = False
        self.paused = False
        self.selected = 0  # index into ROWS
        self.entry: str | None = None  # text typed into the selected parameter, while typing
        self.message = ""
        self.grab_lane: int | None = None
        self.view = fit_view(scene, self.lane_width_px, self.height_px)

    def _make_lane(self, scene: Scene) -> Lane:
        return Lane(scene, self.steps_per_frame, self.clock, self.loader)

    # -- kernels ------------------------------------------------------------------------------------------
    @property
    def loading(self) -> bool:
        """A lane's kernel is still loading or compiling: nothing steps until all are ready."""
        return not all(lane.ready for lane in self.lanes)

    def notices(self) -> list[str | None]:
        """Per lane, what it waits for ("compiling the seed kernel... (first use only)"), or None."""
        return [lane.notice for lane in self.lanes]

    def wait_for_kernels(self, timeout: float | None = None) -> bool:
        """Block until every lane's kernel is ready (starting the loader); False on timeout."""
        return True if self.loader is None else self.loader.wait(timeout)

    # -- stepping -------------------------------------------------------------------------------------
    def advance_frame(self, *, force: bool = False) -> None:
        """One drawn frame: ``steps_per_frame`` steps in every lane, unless paused (``force``
        steps anyway: the single-step key). A lane that diverges stops; with one lane, so does
        the viewer (paused, "diverged" in the panel) until a restart. While a kernel loads
        (``loading``) nothing steps, so that the lanes start together."""
        if (self.paused and not force) or self.loading:
            return
        for index, lane in enumerate(self.lanes):
            was_fine = lane.diverged is None
            lane.step_frame()
            if was_fine and lane.diverged is not None:
                self.message = str(lane.diverged)
                if index == self.grab_lane:
                    self.grab_lane = None
        if all(lane.diverged is not None for lane in self.lanes):
            self.paused = True

    def toggle_pause(self) -> None:
        self.paused = not self.paused

    def restart(self) -> None:
        """Every lane back to the scene's initial state, running."""
        for lane in self.lanes:
            lane.restart()
        self.grab_lane = None
        self.paused = False
        self.message = ""

    # -- parameters -------------------------------------------------------------------------------------
    def _apply(self, **changes) -> bool:
        """Change scene fields in every lane (each keeping its solver); False and ``message`` set if
        the engine rejects the new scene."""
        try:
            scene = self.scene.replace(**changes)
            lane_scenes = [scene.replace(solver=lane.solver) if self.compare else scene for lane in self.lanes]
        except ValueError as error:
            self.message = f"rejected: {error}"
            return False
        self.scene = scene
        for lane, lane_scene in zip(self.lanes, lane_scenes, strict=True):
            lane.set_scene(lane_scene)
        self.message = ""
        return True

    def set_parameter(self, name: str, value) -> bool:
        """Set a parameter (a number, or the text the user typed)."""
        if name not in PARAMETER_BY_NAME:
            raise KeyError(f"unknown parameter {name!r}; the parameters are {tuple(PARAMETER_BY_NAME)}")
        try:
            number = float(value)
        except (TypeError, ValueError):
            self.message = f"rejected: {name} must be a number, got {value!r}"
            return False
        return self._apply(**{name: number})

    def step_parameter(self, name: str, direction: int) -> bool:
        """Move a parameter to the next value of its ladder up (+1) or down (-1)."""
        parameter = PARAMETER_BY_NAME[name]
        return self.set_parameter(name, parameter.next_value(getattr(self.scene, name), direction))

    def toggle(self, name: str) -> bool:
        """Switch ``use_impulses``, ``use_penalty`` or ``boxes_collide`` (the boxes collide with one another:
        a box dragged into another pushes it; the state goes on from where it is)."""
        if name not in dict(TOGGLES):
            raise KeyError(f"unknown toggle {name!r}; the toggles are {tuple(dict(TOGGLES))}")
        return self._apply(**{name: not getattr(self.scene, name)})

    def switch_solver(self) -> bool:
        """The seed scheme <-> the robust solver; the state goes on from where it is. In compare mode
        both are shown already, so nothing changes."""
        if self.compare:
            self.message = "compare mode shows both solvers (C leaves it)"
            return False
        other = SOLVERS[(SOLVERS.index(self.scene.solver) + 1) % len(SOLVERS)]
        return self._apply(solver=other)

    def toggle_compare(self) -> bool:
        """Compare mode: the seed scheme (left) and the robust solver (right) on the same scene, both
        restarted. Leaving it keeps the lane of the scene's solver, where it is."""
        if self.compare:
            self.lanes = [lane for lane in self.lanes if lane.solver == self.scene.solver]
            self.compare = False
        else:
            try:
                scenes = [self.scene.replace(solver=solver) for solver in COMPARE_SOLVERS]
            except ValueError as error:
                self.message = f"compare needs both solvers: {error}"
                return False
            self.lanes = [self._make_lane(scene) for scene in scenes]
            self.compare = True
            self.paused = False
        self.grab_lane = None
        self.message = ""
        self.fit()
        return True

    # -- the panel: selection, arrow keys, typing ------------------------------------------------------
    @property
    def selected_row(self) -> str:
        return ROWS[self.selected]

    def select(self, delta: int) -> None:
        self.cancel_entry()
        self.selected = (self.selected + delta) % len(ROWS)

    def select_row(self, row: str) -> None:
        self.cancel_entry()
        self.selected = ROWS.index(row)

    def adjust(self, direction: int) -> bool:
        """Left/right on the selected row: a parameter moves along its ladder, a toggle or the solver
        flips."""
        row = self.selected_row
        if row in PARAMETER_BY_NAME:
            return self.step_parameter(row, direction)
        if row == "solver":
            return self.switch_solver()
        return self.toggle(row)

    def begin_entry(self) -> None:
        """Start typing a value into the selected parameter (Enter); toggles and the solver flip."""
        if self.selected_row in PARAMETER_BY_NAME:
            self.entry = ""
        else:
            self.adjust(+1)

    def type_text(self, text: str) -> None:
        if self.entry is not None:
            self.entry += "".join(c for c in text if c in "0123456789.-+eE")

    def backspace(self) -> None:
        if self.entry:
            self.entry = self.entry[:-1]

    def commit_entry(self) -> bool:
        if self.entry is None:
            return False
        text, self.entry = self.entry, None
        return self.set_parameter(self.selected_row, text) if text else False

    def cancel_entry(self) -> None:
        self.entry = None

    def row_value(self, row: str) -> str:
        """The value shown in the panel for a row."""
        if row in PARAMETER_BY_NAME:
            return PARAMETER_BY_NAME[row].format(getattr(self.scene, row))
        if row == "solver":
            return " | ".join(COMPARE_SOLVERS) if self.compare else self.scene.solver
        return "on" if getattr(self.scene, row) else "off"

    # -- read-outs ------------------------------------------------------------------------------------------
    def readouts(self, lane_index: int) -> list[str]:
        """The demo's read-outs for one lane: simulated time, mean ms per step, number of bodies,
        and the solver and status."""
        lane = self.lanes[lane_index]
        mean_ms = lane.timer.mean_ms
        lines = [
            f"{lane.solver} solver",
            f"{lane.sim_time:.2f} s",
            "-- ms / step" if math.isnan(mean_ms) else f"{mean_ms:.3g} ms / step",
            f"{lane.scene.n_bodies} bodies",
        ]
        x_min, x_max, y_min, y_max = self.lane_camera(lane_index).view_bounds
        x, y = lane.state[:, layout.X], lane.state[:, layout.Y]
        out_of_view = ~((x >= x_min) & (x <= x_max) & (y >= y_min) & (y <= y_max))
        if lane.diverged is None and out_of_view.any():
            lines.append(f"{int(out_of_view.sum())} out of view (highest y = {y.max():.3g} m): zoom out")
        if lane.diverged is not None:
            lines.append(f"DIVERGED at step {lane.diverged.step} (body {lane.diverged.body}): R restarts")
        elif self.paused:
            lines.append("paused")
        return lines

    # -- cameras, zoom and pan -----------------------------------------------------------------------------
    @property
    def lane_width_px(self) -> int:
        return self.width_px // len(self.lanes)

    def lane_camera(self, lane_index: int) -> Camera:
        return Camera(
            self.view.center_x, self.view.center_y, self.view.pixels_per_metre, self.lane_width_px, self.height_px
        )

    def lane_at(self, column: float) -> int | None:
        """The lane under a window column [px] (None over the panel)."""
        if not 0 <= column < self.lane_width_px * len(self.lanes):
            return None
        return int(column // self.lane_width_px)

    def to_world(self, pixel: Sequence[float], lane_index: int | None = None) -> np.ndarray:
        """World point [m] under a window pixel (column, row); in the given lane, or the one under it."""
        lane_index = self.lane_at(pixel[0]) if lane_index is None else lane_index
        lane_index = 0 if lane_index is None else lane_index
        local = np.array([pixel[0] - lane_index * self.lane_width_px, pixel[1]], dtype=np.float64)
        return self.lane_camera(lane_index).pixel_to_world(local)

    def zoom(self, factor: float, pixel: Sequence[float] | None = None) -> None:
        """Scale by ``factor`` (> 1 zooms in), keeping the world point under ``pixel`` (window
        column, row) where it is; about the lane's centre without a pixel."""
        lane_index = 0 if pixel is None else (self.lane_at(pixel[0]) or 0)
        camera = self.lane_camera(lane_index)
        if pixel is None:
            local = np.array([0.5 * camera.width_px, 0.5 * camera.height_px])
        else:
            local = np.array([pixel[0] - lane_index * self.lane_width_px, pixel[1]], dtype=np.float64)
        fixed = camera.pixel_to_world(local)
        scale = float(np.clip(self.view.pixels_per_metre * factor, MIN_PIXELS_PER_METRE, MAX_PIXELS_PER_METRE))
        self.view = View(
            fixed[0] - (local[0] - 0.5 * camera.width_px) / scale,
            fixed[1] + (local[1] - 0.5 * camera.height_px) / scale,
            scale,
        )

    def pan(self, d_column: float, d_row: float) -> None:
        """Move the view with the mouse by (columns, rows) [px]: the world follows the cursor."""
        scale = self.view.pixels_per_metre
        self.view = View(self.view.center_x - d_column / scale, self.view.center_y + d_row / scale, scale)

    def fit(self) -> None:
        """The first view of the scene: every box, and the arcs of the moving ones."""
        self.view = fit_view(self.scene, self.lane_width_px, self.height_px)

    # -- dragging boxes --------------------------------------------------------------------------------------
    def grab(self, pixel: Sequence[float]) -> bool:
        """Hold the box under a window pixel; False if there is none."""
        lane_index = self.lane_at(pixel[0])
        if lane_index is None:
            return False
        if self.lanes[lane_index].grab_at(self.to_world(pixel, lane_index)):
            self.grab_lane = lane_index
            return True
        return False

    def drag_to(self, pixel: Sequence[float]) -> None:
        """Move the cursor target of the held box (in the lane it was grabbed in)."""
        if self.grab_lane is None:
            return
        lane = self.lanes[self.grab_lane]
        if lane.grab is None:
            self.grab_lane = None
            return
        lane.grab.target = self.to_world(pixel, self.grab_lane)

    def release(self) -> None:
        """Let go: the box keeps the velocity the drag gave it."""
        if self.grab_lane is not None:
            self.lanes[self.grab_lane].grab = None
        self.grab_lane = None
