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
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from box_toss_env.physics import (
    SOLVERS,
    NonFiniteStateError,
    Scene,
    Simulator,
    check_finite_stats,
    layout,
    make_settings,
)
from box_toss_env.rendering import Camera, box_vertices
from box_toss_env.viewer.kernels import KernelJob, KernelLoader, zero_step_args

STEPS_PER_FRAME = 8
"""Simulation steps per drawn frame, as in the seed demo."""
TIMING_WINDOW_STEPS = 50
"""The ms-per-step read-out is the mean over this many of the latest steps, as in the seed demo."""
DRAG_FOLLOW_FRAMES = 1.0
"""A dragged box's grab point is given the velocity that closes the gap to the cursor in this many frames."""
DRAG_SPIN_DAMPING = 0.5
"""A dragged box's spin is multiplied by this before each frame (it would swing wildly otherwise)."""
MAX_DRAG_SPEED = 50.0
"""Cap on the speed a drag gives a box [m/s]."""
ZOOM_STEP = 1.15
"""Zoom factor of one wheel click or key press."""
MIN_PIXELS_PER_METRE, MAX_PIXELS_PER_METRE = 0.5, 20000.0


# -- the panel's parameters ----------------------------------------------------------------------
@dataclass(frozen=True)
class Parameter:
    """A numeric field of ``Scene`` shown in the panel. The arrow keys move it along ``ladder``
    (to the nearest ladder value above or below the current one); any value can also be typed."""

    name: str  # the Scene field
    label: str
    unit: str
    ladder: tuple[float, ...]

    def next_value(self, current: float, direction: int) -> float:
        """The nearest ladder value above (``direction > 0``) or below ``current``; ``current``
        itself when the ladder ends there."""
        tolerance = 1e-9 * max(1.0, abs(current))
        if direction > 0:
            above = [v for v in self.ladder if v > current + tolerance]
            return min(above) if above else current
        below = [v for v in self.ladder if v < current - tolerance]
        return max(below) if below else current

    def format(self, value: float) -> str:
        return f"{value:.6g} {self.unit}".rstrip()


def _one_two_five(low_exponent: int, high_exponent: int) -> tuple[float, ...]:
    return tuple(m * 10.0**e for e in range(low_exponent, high_exponent + 1) for m in (1.0, 2.0, 5.0))


PARAMETERS = (
    Parameter("dt", "time step size", "s",
              (0.0002, 0.0005, 0.001, 0.002, 0.0025, 0.004, 0.005, 0.0075, 0.01, 0.015, 0.02, 0.03, 0.05)),
    Parameter("gravity", "gravity", "m/s^2", tuple(sorted({*range(-30, 1), -9.81}))),
    Parameter("penalty_stiffness", "penalty stiffness", "N/m", (0.0, *_one_two_five(0, 6))),
    Parameter("restitution", "restitution coefficient", "", tuple(round(0.05 * k, 2) for k in range(21))),
    Parameter("friction", "friction coefficient", "",
              (0.0, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.5, 2.0)),
)
TOGGLES = (("use_impulses", "use impulses"), ("use_penalty", "use penalty force"), ("boxes_collide", "boxes collide"))
PARAMETER_BY_NAME = {parameter.name: parameter for parameter in PARAMETERS}
ROWS = (*(parameter.name for parameter in PARAMETERS), *(name for name, _ in TOGGLES), "solver")
"""The panel's selectable rows, top to bottom: the five parameters, the three toggles, the solver."""
ROW_LABELS = {**{p.name: p.label for p in PARAMETERS}, **dict(TOGGLES), "solver": "solver"}
COMPARE_SOLVERS = ("seed", "robust")
"""The lanes of compare mode, left to right."""


# -- timing ----------------------------------------------------------------------------------------
class StepTimer:
    """Mean wall time per simulation step over the latest ``window`` steps.

    A run of k steps that took s seconds counts as k steps of s / k each."""

    def __init__(self, window: int = TIMING_WINDOW_STEPS):
        self.step_seconds: deque[float] = deque(maxlen=window)

    def record(self, seconds: float, steps: int) -> None:
        self.step_seconds.extend([seconds / steps] * min(steps, self.step_seconds.maxlen))

    @property
    def mean_ms(self) -> float:
        """Mean [ms] per step; nan before the first step."""
        if not self.step_seconds:
            return math.nan
        return 1e3 * sum(self.step_seconds) / len(self.step_seconds)

    def reset(self) -> None:
        self.step_seconds.clear()


# -- one running simulation --------------------------------------------------------------------------
@dataclass
class Grab:
    """A box held by the mouse: ``local`` is the held point in the box's frame [m], ``target`` the
    cursor in the world [m]."""

    body: int
    local: np.ndarray
    target: np.ndarray


@dataclass(eq=False)
class Lane:
    """One simulation as the demo runs it: the scene, its compiled ``Simulator`` and the arrays it
    steps. ``state`` is edited in place between runs (dragging); ``sim_time`` and ``steps`` count
    from the last restart."""

    scene: Scene
    steps_per_frame: int = STEPS_PER_FRAME
    clock: Callable[[], float] = time.perf_counter
    loader: KernelLoader | None = None
    simulator: Simulator = field(init=False)
    job: KernelJob | None = field(init=False, default=None)  # the kernel's load, while it is queued or running
    state: np.ndarray = field(init=False)
    params: np.ndarray = field(init=False)
    settings: np.ndarray = field(init=False)
    stats: np.ndarray = field(init=False)
    timer: StepTimer = field(init=False, default_factory=StepTimer)
    sim_time: float = field(init=False, default=0.0)
    steps: int = field(init=False, default=0)
    diverged: NonFiniteStateError | None = field(init=False, default=None)
    grab: Grab | None = field(init=False, default=None)

    def __post_init__(self):
        self._use_simulator(self._make_simulator(self.scene), self.scene)
        self.set_scene(self.scene)
        self.restart()

    @staticmethod
    def _make_simulator(scene: Scene) -> Simulator:
        # a handful of boxes: numba's threads would cost more than they save
        return Simulator.for_scene(scene, parallel=False)

    def _use_simulator(self, simulator: Simulator, scene: Scene) -> None:
        """Take ``simulator``; with a loader, queue its kernel's first call (nothing if compiled already)."""
        self.simulator = simulator
        if self.loader is not None:
            args = zero_step_args(scene.initial_state(), scene.body_params(),
                                  make_settings(scene, 0, until_rest=False),
                                  np.zeros((scene.n_bodies, layout.STATS_SIZE)))
            self.job = self.loader.prepare(simulator.kernel, args, scene.solver)

    @property
    def ready(self) -> bool:
        """The kernel can run now (always, without a loader: the first run compiles it)."""
        return self.job is None or self.job.ready

    @property
    def notice(self) -> str | None:
        """What the lane waits for ("compiling the seed kernel... (first use only)"), or None."""
        return None if self.ready else self.job.notice

    @property
    def solver(self) -> str:
        return self.scene.solver

    def set_scene(self, scene: Scene) -> None:
        """Take new parameters; the state goes on from where it is. The simulator is rebuilt only
        when the compile-time flags change (solver, impulses, penalty, friction, boxes colliding on or off)."""
        simulator = self._make_simulator(scene)
        if simulator.flags != self.simulator.flags:
            self._use_simulator(simulator, scene)
        self.scene = scene
        self.params = scene.body_params()
        self.settings = make_settings(scene, self.steps_per_frame, until_rest=False)

    def restart(self) -> None:
        """Back to the scene's initial state (with the current parameters)."""
        self.state = self.scene.initial_state()
        self.stats = np.zeros((self.scene.n_bodies, layout.STATS_SIZE))
        self.timer.reset()
        self.sim_time = 0.0
        self.steps = 0
        self.diverged = None
        self.grab = None

    def step_frame(self) -> None:
        """Run one frame's steps (applying the drag first); a divergence stops the lane."""
        if self.diverged is not None or not self.ready:
            return
        if self.grab is not None:
            self._pull_grabbed_box()
        start = self.clock()
        self.simulator.run(self.state, self.params, self.settings, self.stats)
        elapsed = self.clock() - start
        try:
            check_finite_stats(self.stats, self.solver)
        except NonFiniteStateError as error:  # the kernel counts steps from the start of this run
            self.sim_time += error.step * self.scene.dt
            self.steps += error.step
            self.diverged = NonFiniteStateError(error.body, self.steps, self.solver)
            self.grab = None
            return
        self.timer.record(elapsed, self.steps_per_frame)
        self.steps += self.steps_per_frame
        self.sim_time += self.steps_per_frame * self.scene.dt

    # -- dragging -----------------------------------------------------------------------------------
    def body_at(self, point: np.ndarray) -> int | None:
        """The topmost box (the last drawn) containing the world point [m], or None."""
        x, y, angle = self.state[:, layout.X], self.state[:, layout.Y], self.state[:, layout.ANGLE]
        dx, dy = point[0] - x, point[1] - y
        local_x = np.cos(angle) * dx + np.sin(angle) * dy
        local_y = -np.sin(angle) * dx + np.cos(angle) * dy
        inside = ((np.abs(local_x) <= self.params[:, layout.HALF_LENGTH])
                  & (np.abs(local_y) <= self.params[:, layout.HALF_WIDTH]))
        hits = np.flatnonzero(inside)
        return int(hits[-1]) if hits.size else None

    def grab_at(self, point: np.ndarray) -> bool:
        """Hold the box under the world point, if any; returns whether one was grabbed."""
        point = np.asarray(point, dtype=np.float64)
        body = self.body_at(point) if self.diverged is None else None
        if body is None:
            return False
        x, y, angle = self.state[body, :3]
        cos, sin = math.cos(angle), math.sin(angle)
        dx, dy = point[0] - x, point[1] - y
        self.grab = Grab(body, np.array([cos * dx + sin * dy, -sin * dx + cos * dy]), point.copy())
        return True

    def grab_point(self) -> np.ndarray | None:
        """World position of the held point [m]."""
        if self.grab is None:
            return None
        x, y, angle = self.state[self.grab.body, :3]
        cos, sin = math.cos(angle), math.sin(angle)
        lx, ly = self.grab.local
        return np.array([x + cos * lx - sin * ly, y + sin * lx + cos * ly])

    def _pull_grabbed_box(self) -> None:
        """v = (cursor - held point) / (frames * steps * dt): the held point reaches the cursor in
        ``DRAG_FOLLOW_FRAMES`` frames if nothing else acts; the spin is damped."""
        grab = self.grab
        gap = grab.target - self.grab_point()
        velocity = gap / (DRAG_FOLLOW_FRAMES * self.steps_per_frame * self.scene.dt)
        speed = float(np.hypot(*velocity))
        if speed > MAX_DRAG_SPEED:
            velocity *= MAX_DRAG_SPEED / speed
        self.state[grab.body, layout.VX:layout.VY + 1] = velocity
        self.state[grab.body, layout.SPIN] *= DRAG_SPIN_DAMPING


# -- the view ----------------------------------------------------------------------------------------
@dataclass
class View:
    """What the camera looks at: the world point at the centre of each lane [m] and the scale [px/m]."""

    center_x: float
    center_y: float
    pixels_per_metre: float


def view_points(scene: Scene) -> np.ndarray:
    """Points a first view of ``scene`` should show [m]: every box corner, and for a moving box
    the top of its ballistic arc and where that arc meets the floor."""
    state = scene.initial_state()
    params = scene.body_params()
    corners = box_vertices(state[:, :2], state[:, layout.ANGLE], params[:, :2]).reshape(-1, 2)
    points = [corners]
    g = -scene.gravity
    for x, y, _, vx, vy, _ in state:
        if g > 0 and (vx or vy):
            apex_time = max(vy / g, 0.0)
            landing_time = (vy + math.sqrt(vy * vy + 2.0 * g * max(y, 0.0))) / g
            points.append([[x + vx * apex_time, y + vy * apex_time - 0.5 * g * apex_time**2],
                           [x + vx * landing_time, 0.0]])
    return np.concatenate([np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in points])


def fit_view(scene: Scene, width_px: int, height_px: int) -> View:
    points = view_points(scene)
    span = float(np.ptp(points, axis=0).max())
    camera = Camera.fit_points(points, width_px, height_px, margin_m=0.2 + 0.12 * span, min_span_m=2.0)
    return View(camera.center_x, camera.center_y, camera.pixels_per_metre)


# -- the controller ------------------------------------------------------------------------------------
class ViewerController:
    """The viewer's state and every action the user can take, without a window.

    ``width_px`` and ``height_px`` are the size of the scene area (the panel is extra); in compare
    mode it is split into two lanes side by side. Parameter changes build a new ``Scene`` through
    ``Scene.replace`` (which validates); a rejected change leaves everything as it was and puts the
    reason in ``message``. With a ``loader`` kernels are loaded off the caller's thread (see ``loading``).
    """

    def __init__(self, scene: Scene, *, width_px: int = 900, height_px: int = 560,
                 steps_per_frame: int = STEPS_PER_FRAME, clock: Callable[[], float] = time.perf_counter,
                 loader: KernelLoader | None = None):
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
        return Camera(self.view.center_x, self.view.center_y, self.view.pixels_per_metre,
                      self.lane_width_px, self.height_px)

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
        self.view = View(fixed[0] - (local[0] - 0.5 * camera.width_px) / scale,
                         fixed[1] + (local[1] - 0.5 * camera.height_px) / scale, scale)

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
