"""One running simulation of the viewer (a ``Lane``): its scene, its ``Simulator`` and kernel, the box
held by the mouse (``Grab``), and the ms-per-step read-out (``StepTimer``)."""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from box_toss_env.physics import (
    NonFiniteStateError,
    Scene,
    Simulator,
    check_finite_stats,
    layout,
    make_settings,
    warm_start_memory,
)
from box_toss_env.viewer.kernel_loader import KernelJob, KernelLoader, zero_step_args

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
    warm_start: np.ndarray | None = field(init=False, default=None)  # the contacts' impulses between frames
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
            args = zero_step_args(
                scene.initial_state(),
                scene.body_params(),
                make_settings(scene, 0, until_rest=False),
                np.zeros((scene.n_bodies, layout.STATS_SIZE)),
                warm_start=simulator.carries_warm_start,
            )
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
            self.warm_start = warm_start_memory(scene.n_bodies) if simulator.carries_warm_start else None
        self.scene = scene
        self.params = scene.body_params()
        self.settings = make_settings(scene, self.steps_per_frame, until_rest=False)

    def restart(self) -> None:
        """Back to the scene's initial state (with the current parameters)."""
        self.state = self.scene.initial_state()
        self.stats = np.zeros((self.scene.n_bodies, layout.STATS_SIZE))
        # the contacts' impulses carried from frame to frame, so that a pile stepped a frame at a time does not creep
        self.warm_start = warm_start_memory(self.scene.n_bodies) if self.simulator.carries_warm_start else None
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
        self.simulator.run(self.state, self.params, self.settings, self.stats, warm_start=self.warm_start)
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
        inside = (np.abs(local_x) <= self.params[:, layout.HALF_LENGTH]) & (
            np.abs(local_y) <= self.params[:, layout.HALF_WIDTH]
        )
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
        self.state[grab.body, layout.VX : layout.VY + 1] = velocity
        self.state[grab.body, layout.SPIN] *= DRAG_SPIN_DAMPING
