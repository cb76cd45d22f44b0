"""Running scenes: ``simulate`` for one scene, ``Simulator`` for repeated runs on raw arrays
(the environments), both over the same compiled kernels."""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba
import numpy as np

from . import layout
from .colliding.parallel import reaches_threads
from .compile import background_compile
from .compile.compilation import ensure_compiled
from .kernels import KernelFlags, make_kernel
from .ranges import MAX_STEPS, check_step_count
from .scene import Scene
from .validation import check_bool, check_integer, check_range


class NonFiniteStateError(FloatingPointError):
    """A body's state stopped being finite: the simulation diverged. Nothing is clipped."""

    def __init__(self, body: int, step: int, solver: str):
        self.body = body
        self.step = step
        self.solver = solver
        super().__init__(
            f"body {body} went non-finite at step {step} with solver={solver!r}. Nothing was "
            f"clipped: {DIVERGENCE_CAUSES.get(solver, DIVERGENCE_CAUSES['robust'])}"
        )


DIVERGENCE_CAUSES = {
    "seed": "the explicit seed scheme gains energy where dt * sqrt(penalty_stiffness / effective mass) > 2 "
    "(reduce dt or the stiffness, or use solver='robust')",
    "robust": "the robust solver overflowed on this scene's values, which it should not do inside the ranges "
    "of docs/ranges.md: please report the scene",
}
"""What makes each solver's state non-finite, as its ``NonFiniteStateError`` says."""


@dataclass
class Trajectory:
    """States on the time grid t_n = n dt: ``state[n, body] = (x, y, angle, vx, vy, spin)``.
    A body that fell asleep before the end keeps its resting state in the later rows."""

    time: np.ndarray  # (T,) [s]
    state: np.ndarray  # (T, n_bodies, 6)

    @property
    def position(self) -> np.ndarray:  # (T, n, 2) [m]
        return self.state[:, :, layout.X : layout.Y + 1]

    @property
    def angle(self) -> np.ndarray:  # (T, n) [rad]
        return self.state[:, :, layout.ANGLE]

    @property
    def velocity(self) -> np.ndarray:  # (T, n, 2) [m/s]
        return self.state[:, :, layout.VX : layout.VY + 1]

    @property
    def spin(self) -> np.ndarray:  # (T, n) [rad/s]
        return self.state[:, :, layout.SPIN]


@dataclass
class SimulationResult:
    """What a run produced, per body. Times in seconds; nan where a thing did not happen."""

    final_state: np.ndarray  # (n, 6)
    first_contact_time: np.ndarray  # (n,) flight time before the first floor contact
    n_impacts: np.ndarray  # (n,) int
    n_steps: np.ndarray  # (n,) int, time steps actually integrated
    max_penetration: np.ndarray  # (n,) [m]
    rest_time: np.ndarray  # (n,) when the body fell asleep
    end_time: np.ndarray  # (n,) simulated time reached
    trajectory: Trajectory | None = None
    impacts: list[np.ndarray] | None = None  # per body: (k, 3) time, approach speed, corners

    @property
    def at_rest(self) -> np.ndarray:
        return ~np.isnan(self.rest_time)


class Simulator:
    """A kernel compiled for one combination of stages, run on arrays many times.

    ``run`` takes the state (n, 6) and the body parameters (n, 7) (see ``layout``) and advances
    the state in place; it allocates nothing per step. With ``flags.parallel`` the run uses ``threads`` threads
    (in [1, numba.config.NUMBA_NUM_THREADS], default: all of them, the cores available, and one where boxes
    collide: ``python -m benchmarks.thread_scaling`` measures what a second buys there; without it, one whatever
    numba's thread count), and its results do not depend on how many: without box-box contact the bodies are split
    into that many contiguous shares run at once (the kernel releases the GIL, so the shares run on a thread pool,
    and each body's result does not depend on the split); a scene whose boxes collide is one call whose large stages
    run on that many of numba's threads (``colliding.parallel``: from hundreds of boxes up; the kernel sets numba's
    count for the call, ``colliding.threads``), bit for bit as on one.
    One body and a batch run the same compiled kernel (``kernels``); its first run compiles it or loads it from
    numba's cache (``compilation.ensure_compiled``). With ``start_interpreted`` (the envs), a kernel that is not in the
    cache yet is compiled by a worker process while runs of up to ``MAX_INTERPRETED_BODIES`` bodies use its
    interpreted copy, which gives the same results (``background_compile``).
    """

    def __init__(self, flags: KernelFlags, threads: int | None = None, start_interpreted: bool = False):
        self.flags = flags
        self.threads = None if threads is None else check_threads(threads)
        self.kernel = make_kernel(flags)
        self._no_trajectory = np.zeros((0, 0, layout.STATE_SIZE))
        self._no_events = np.zeros((0, 0, layout.EVENT_SIZE))
        self._no_warm_start = np.zeros((0, layout.WARM_START_SIZE))
        self._ready = False  # compiled or loaded for the arrays of the first run
        self._start = (
            background_compile.InterpretedStart(self.kernel, background_compile.kernel_recipe(flags))
            if start_interpreted
            else None
        )
        self.interpreted = False  # whether the last run used the kernel's interpreted copy

    @classmethod
    def for_scene(
        cls, scene: Scene, *, record: bool = False, parallel: bool | None = None, threads: int | None = None
    ) -> Simulator:
        if parallel is None:
            parallel = scene.n_bodies > 1
        flags = KernelFlags(
            solver=scene.solver,
            use_impulses=scene.use_impulses,
            use_penalty=scene.has_penalty,
            use_friction=scene.has_friction,
            record=record,
            parallel=parallel,
            boxes_collide=scene.boxes_collide,
        )
        return cls(flags, threads)

    @property
    def shares(self) -> int:
        """How many threads a parallel run uses at most (1 without ``flags.parallel``)."""
        if not self.flags.parallel:
            return 1
        if self.threads is None and self.flags.boxes_collide:
            return 1  # unless told: a second thread pays only where its core is free (docs/engine_scale.md#threads)
        return self.threads if self.threads is not None else numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # numba sets its config at import

    @property
    def carries_warm_start(self) -> bool:
        """Whether ``run`` takes a ``warm_start``: the colliding kernels. The robust one keeps each contact's
        impulses from one substep to the next and so from one run to the next; the seed scheme keeps none
        and leaves the array as it is. The floor-only kernels have no contacts to keep."""
        return self.flags.boxes_collide

    def run(
        self,
        state: np.ndarray,
        params: np.ndarray,
        settings: np.ndarray,
        stats: np.ndarray,
        trajectory: np.ndarray | None = None,
        events: np.ndarray | None = None,
        warm_start: np.ndarray | None = None,
    ) -> None:
        """Advance ``state`` in place and fill ``stats`` (n, STATS_SIZE); with ``record`` also
        ``trajectory`` (max_steps + 1, n, 6) and ``events`` (n, MAX_EVENTS, 3).

        ``warm_start`` (from ``warm_start_memory``, kernels that ``carries_warm_start``): what the last run that
        was given this array ended with (each contact's impulses, each body's sleep: ``islands``), the start of
        this one's, and its end written back. A scene advanced in several runs with one such array steps as in
        one run: its contacts keep their load (without it each run starts them from zero, and a pile settles a
        little anew at each) and, with ``until_rest``, an island that fell asleep stays asleep, at no cost,
        until something reaches it or the caller moves, pushes or changes one of its bodies. Give each scene or episode
        its own, zeroed when it starts."""
        if self.flags.record and (trajectory is None or events is None):
            raise ValueError("trajectory and events arrays are required when recording")
        trajectory = self._no_trajectory if trajectory is None else trajectory
        events = self._no_events if events is None else events
        if warm_start is not None and not self.carries_warm_start:
            raise ValueError(
                "warm_start is for scenes whose boxes collide (Simulator.carries_warm_start); "
                f"this kernel is {self.flags}"
            )
        if self.flags.boxes_collide and reaches_threads(state.shape[0]):  # the kernel sets numba's count (``threads``)
            settings = with_threads(settings, self.shares)
        if self.carries_warm_start:
            warm = self._no_warm_start if warm_start is None else check_warm_start(warm_start)
            args: tuple = (state, params, settings, stats, trajectory, events, warm)
        else:
            args = (state, params, settings, stats, trajectory, events)
        if not self._ready:
            outputs = (state, stats, trajectory, events, *args[6:])  # and the warm start, which the kernel writes
            self.interpreted = self._start is not None and self._start.run(args, outputs)
            if self.interpreted:
                return
            ensure_compiled(self.kernel, args)
            self._ready = True
        if self.flags.boxes_collide:  # one scene, stepped together: its large stages on numba's threads
            self.kernel(*args)
            return
        shares = min(self.shares, state.shape[0])
        if shares <= 1 or self.flags.record:  # a recording's (T, n, 6) trajectory does not split into contiguous shares
            self.kernel(*args)
        else:
            run_in_shares(self.kernel, shares, state, params, settings, stats, trajectory, events)


def warm_start_memory(n_bodies: int) -> np.ndarray:
    """A zeroed warm start for ``Simulator.run`` on a colliding scene of up to ``n_bodies`` bodies
    (``layout.WARM_START_SIZE`` columns): WARM_BODY_ROWS a body for its sleep, room for 8 contacts a body, what the
    kernel starts with; more are kept as far as it goes."""
    n_bodies = check_integer("n_bodies", n_bodies, 1)
    return np.zeros((1 + layout.WARM_BODY_ROWS * n_bodies + max(8 * n_bodies, 16), layout.WARM_START_SIZE))


def check_warm_start(warm_start) -> np.ndarray:
    """``warm_start`` if it is a C-contiguous float64 array (rows, WARM_START_SIZE) with at least one row
    (``warm_start_memory``), else a ValueError naming it."""
    if (
        not isinstance(warm_start, np.ndarray)
        or warm_start.dtype != np.float64
        or warm_start.ndim != 2
        or warm_start.shape[0] < 1
        or warm_start.shape[1] != layout.WARM_START_SIZE
        or not warm_start.flags.c_contiguous
    ):
        shape = getattr(warm_start, "shape", None)
        raise ValueError(
            f"warm_start must be a C-contiguous float64 array of shape (rows >= 1, "
            f"{layout.WARM_START_SIZE}) from warm_start_memory, got {type(warm_start).__name__} {shape}"
        )
    return warm_start


def with_threads(settings: np.ndarray, threads: int) -> np.ndarray:
    """A copy of ``settings`` with THREADS at ``threads``: the colliding kernel runs its large stages on that many of
    numba's threads (1: off threads), whatever numba's count is, and sets the count back after
    (``colliding.threads``). A copy, not the caller's array, nor one kept here: calls from several threads at once
    each read their own."""
    settings = np.array(settings, dtype=np.float64)
    settings[layout.THREADS] = threads
    return settings


def run_in_shares(kernel, shares: int, state, params, settings, stats, trajectory, events) -> None:
    """Run ``kernel`` on ``shares`` contiguous row ranges of the body arrays at once: all but the last
    on the thread pool, the last on the calling thread (the kernel releases the GIL)."""
    n = state.shape[0]
    edges = [n * k // shares for k in range(shares + 1)]
    pool = thread_pool(shares - 1)
    futures = [
        pool.submit(kernel, state[a:b], params[a:b], settings, stats[a:b], trajectory, events)
        for a, b in zip(edges[:-2], edges[1:-1], strict=True)
    ]
    a = edges[-2]
    try:
        kernel(state[a:], params[a:], settings, stats[a:], trajectory, events)
    finally:
        for future in futures:
            future.result()


_thread_pools: dict[int, ThreadPoolExecutor] = {}


def thread_pool(workers: int) -> ThreadPoolExecutor:
    """A pool of ``workers`` threads shared by every simulator (created at first use)."""
    pool = _thread_pools.get(workers)
    if pool is None:
        pool = _thread_pools[workers] = ThreadPoolExecutor(workers, thread_name_prefix="box-toss-engine")
    return pool


def _forget_thread_pools() -> None:
    """In a forked child the pools' threads do not exist: start new ones when needed."""
    _thread_pools.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_thread_pools)


def check_threads(threads) -> int:
    """``threads`` as an int in [1, numba's thread count] (``numba.config.NUMBA_NUM_THREADS``, the
    most numba can run), else a TypeError or ValueError naming it."""
    return check_integer("threads", threads, 1, numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]  # numba sets its config at import


def make_settings(scene: Scene, max_steps: int, until_rest: bool, sleep: bool = True) -> np.ndarray:
    """The scene-wide settings array the kernels read (see ``layout``): ``until_rest`` ends the run once every body
    sleeps; ``sleep`` (colliding scenes; implied by ``until_rest``) lets islands at rest sleep, the run going on."""
    settings = np.empty(layout.SETTINGS_SIZE)
    settings[layout.DT] = scene.dt
    settings[layout.GRAVITY] = scene.gravity
    settings[layout.MAX_STEPS] = max_steps
    settings[layout.UNTIL_REST] = 1.0 if until_rest else 0.0
    settings[layout.RESTITUTION_THRESHOLD] = scene.restitution_threshold
    settings[layout.SLEEP_SPEED] = scene.sleep_speed
    settings[layout.SLEEP_TIME] = scene.sleep_time
    settings[layout.PENETRATION_SLOP] = scene.penetration_slop
    settings[layout.SOLVER_TOLERANCE] = scene.solver_tolerance
    settings[layout.SOLVER_ITERATIONS] = scene.solver_iterations
    settings[layout.SLEEP] = 1.0 if sleep or until_rest else 0.0
    settings[layout.QUIET_STEPS] = 1.0 if scene.quiet_steps else 0.0
    settings[layout.THREADS] = 0.0  # numba's count as it is (``Simulator.run`` gives a colliding run its own)
    return settings


def steps_for(scene: Scene, steps: int | None, duration: float | None) -> int:
    """Number of grid steps from exactly one of ``steps`` or ``duration`` [s]."""
    if (steps is None) == (duration is None):
        raise ValueError("give exactly one of steps (an int >= 0) or duration (seconds >= 0)")
    if steps is not None:
        return check_integer("steps", steps, 0, MAX_STEPS)
    duration = check_range("duration", duration, 0.0, unit="s")
    return check_step_count("duration", duration, scene.dt)


def simulate(
    scene: Scene,
    *,
    steps: int | None = None,
    duration: float | None = None,
    until_rest: bool = False,
    record: bool = False,
    threads: int | None = None,
    sleep: bool = True,
) -> SimulationResult:
    """Run ``scene`` for ``steps`` time steps (or ``duration`` seconds, rounded up to whole steps).

    ``sleep`` (colliding scenes): an island of touching boxes that has lain still for ``scene.sleep_time`` (every
    point slower than ``scene.sleep_speed``) sleeps, at no cost, at rest, until an awake body reaches it; the run
    goes on to its end. Off, every body is stepped at every step (a resting pile costs as a moving one).
    ``until_rest`` also ends the run once every body sleeps (each body's ``end_time``; the floor-only solver ends
    each body once it has lain still on a face for ``scene.sleep_time``, and lets none sleep without it).
    ``record`` keeps the states on the time grid and the impacts; without it nothing per step
    is stored. Raises ``NonFiniteStateError`` naming the body and step if a state diverges.
    """
    max_steps = steps_for(scene, steps, duration)
    sleep = check_bool("sleep", sleep)
    simulator = Simulator.for_scene(scene, record=record, threads=threads)
    state = scene.initial_state()
    params = scene.body_params()
    settings = make_settings(scene, max_steps, until_rest, sleep)
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    trajectory = events = None
    if record:
        trajectory = np.empty((max_steps + 1, scene.n_bodies, layout.STATE_SIZE))
        events = np.zeros((scene.n_bodies, layout.MAX_EVENTS, layout.EVENT_SIZE))
    simulator.run(state, params, settings, stats, trajectory, events)
    return collect_result(scene, state, stats, trajectory, events)


def check_finite_stats(stats: np.ndarray, solver: str) -> None:
    """Raise NonFiniteStateError for the first body whose status says it diverged."""
    failed = np.flatnonzero(stats[:, layout.STATUS] != layout.STATUS_OK)
    if failed.size:
        body = int(failed[0])
        raise NonFiniteStateError(body, int(stats[body, layout.FAIL_STEP]), solver)


def collect_result(scene: Scene, state, stats, trajectory, events) -> SimulationResult:
    check_finite_stats(stats, scene.solver)
    result = SimulationResult(
        final_state=state,
        first_contact_time=stats[:, layout.FIRST_CONTACT_TIME].copy(),
        n_impacts=stats[:, layout.N_IMPACTS].astype(np.int64),
        n_steps=stats[:, layout.N_STEPS].astype(np.int64),
        max_penetration=stats[:, layout.MAX_PENETRATION].copy(),
        rest_time=stats[:, layout.REST_TIME].copy(),
        end_time=stats[:, layout.END_TIME].copy(),
    )
    if trajectory is not None:
        recorded = stats[:, layout.N_RECORDED].astype(np.int64)
        rows = int(recorded.max())
        for body, count in enumerate(recorded):  # a body asleep early keeps its final state
            trajectory[count:rows, body] = state[body]
        result.trajectory = Trajectory(time=np.arange(rows) * scene.dt, state=trajectory[:rows])
        result.impacts = [events[body, : min(n, layout.MAX_EVENTS)].copy() for body, n in enumerate(result.n_impacts)]
    return result
