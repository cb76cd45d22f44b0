"""Running the scene suite (``benchmarks.scene_suite``) in every engine: one observed run per engine and plan that
measures what the scene did, step by step, and decides how many steps fit the budget, then timed repeats of each
window, interleaved across engines (ABAB, not AAA BBB), in thread CPU time, the stepping loop alone.

Ours runs as a user gets it: ``Simulator.for_scene(scene)`` on the scene as ``scenes`` builds it, one thread, the
settings of ``make_settings`` and ``sleep`` and ``until_rest`` at ``simulate``'s defaults (read from its signature,
so a new default is measured as soon as it lands), the warm start (``warm_start_memory``) carried from run to run,
as one long run. "Sleeping off" is ``sleep_time`` 1e6 s, ``sleep=False`` and ``until_rest=False``. ``ours, tuned``
(``OUR_TUNED``) is ours at settings a user can pick, shown beside the defaults, never instead of them.
"""

from __future__ import annotations

import inspect
import math
import statistics
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from benchmarks.other_scenes import STATE_SIZE, UnsupportedScene, World, available_scene_engines, make_world
from benchmarks.scene_quality import Quality, Track
from benchmarks.scene_suite import Case, Plan
from box_toss_env.physics import Scene, Simulator, layout, make_settings, simulate, warm_start_memory

OURS, OURS_TUNED = "ours", "ours, tuned"
OUR_TUNED = {"dt": 1 / 60, "solver_tolerance": 1e-4, "solver_iterations": 32, "penetration_slop": 5e-5}
"""Settings a user can pick (``Scene`` fields) for ``ours, tuned``, with ``until_rest=True`` where sleeping is on:
the settings the earlier comparison used for every case (a 60 Hz step, a loose Gauss-Seidel stop, a 50 um slop)."""
NEVER_SLEEP = 1e6  # [s] our sleep_time where sleeping is off
REPEATS, QUICK_REPEATS = 3, 2
BUDGET, QUICK_BUDGET = 30.0, 2.0  # [s] of CPU per window (and per untimed stretch) in the observed run
CHUNK = 64  # steps a call in untimed stretches (ours), between budget checks
SHARED_CPU = 0.05
"""A timed run whose process CPU time passes its thread's by more than this share (plus 1 ms) had other threads at
work in the process: its row says so."""


def until_rest_default() -> bool:
    """``simulate``'s default for ``until_rest`` (whether a plain ``simulate(scene, ...)`` ends once all sleep)."""
    return bool(inspect.signature(simulate).parameters["until_rest"].default)


def sleep_default() -> bool:
    """``simulate``'s default for ``sleep`` (whether a plain ``simulate(scene, ...)`` lets islands at rest sleep)."""
    return bool(inspect.signature(simulate).parameters["sleep"].default)


class OurWorld:
    """Our engine on one scene, stepped on in runs that carry the warm start, with the interface of ``World``."""

    def __init__(self, scene: Scene, sleep: bool, until_rest: bool | None = None, **settings):
        changes = {**settings, **({} if sleep else {"sleep_time": NEVER_SLEEP})}
        self.scene = scene.replace(**changes) if changes else scene
        self.until_rest = (until_rest_default() if until_rest is None else until_rest) and sleep
        self.sleep = sleep and (sleep_default() or self.until_rest)
        self.dt = self.scene.dt
        self.simulator = Simulator.for_scene(self.scene, parallel=False, threads=1)
        self.params = self.scene.body_params()
        self.state = self.scene.initial_state()
        self.stats = np.zeros((self.scene.n_bodies, layout.STATS_SIZE))
        self.warm = warm_start_memory(self.scene.n_bodies)
        self.settings: dict[int, np.ndarray] = {}
        self.run_settings(1)  # compile or load the kernel, untimed, on copies
        scratch = (self.state.copy(), self.stats.copy(), self.warm.copy())
        self.simulator.run(scratch[0], self.params, self.run_settings(1), scratch[1], warm_start=scratch[2])

    def run_settings(self, steps: int) -> np.ndarray:
        if steps not in self.settings:
            self.settings[steps] = make_settings(self.scene, steps, self.until_rest, self.sleep)
        return self.settings[steps]

    def advance(self, steps: int) -> float:
        settings = self.run_settings(steps)
        began = time.thread_time()
        self.simulator.run(self.state, self.params, settings, self.stats, warm_start=self.warm)
        return time.thread_time() - began

    def read_states(self, out: np.ndarray) -> None:
        out[:] = self.state

    def asleep(self) -> np.ndarray:
        """Bodies asleep at the end of the last run (its stats' rest time is set)."""
        return ~np.isnan(self.stats[:, layout.REST_TIME])

    def place(self, body: int, row: Sequence[float]) -> None:
        self.state[body] = row

    def reset(self) -> None:
        """Back to the scene's start, nothing carried."""
        self.restore((self.scene.initial_state(), np.zeros_like(self.stats), np.zeros_like(self.warm)))

    def snapshot(self) -> tuple[np.ndarray, ...]:
        return self.state.copy(), self.stats.copy(), self.warm.copy()

    def restore(self, snapshot: tuple[np.ndarray, ...]) -> None:
        for target, saved in zip((self.state, self.stats, self.warm), snapshot, strict=True):
            target[:] = saved


EngineWorld = OurWorld | World

LOOP_STEPS = 100_000  # calls per repeat of ``loop_overhead``


def loop_overhead(steps: int = LOOP_STEPS, repeats: int = REPEATS) -> dict[str, float]:
    """Thread CPU us per step of the Python loop that steps the other engines (``World.advance``, one call a step,
    as their users step them): around a call that does nothing (``"loop"``), and around an empty Box2D v3 world's
    whole step at its defaults, 60 Hz and 4 substeps (``"box2d3 empty"``, where pyb2d3 is installed): the most the
    loop and Box2D's fixed cost a step can add to a small scene's figure. Best of ``repeats``."""

    def idle(*_) -> None:
        return None

    calls: dict[str, Callable[[], object]] = {"loop": idle}
    if "box2d3" in available_scene_engines():
        import pyb2d3

        world = pyb2d3.World(gravity=(0.0, -9.81))
        calls["box2d3 empty"] = lambda: world.step(1 / 60, 4)
    out = {}
    for name, call in calls.items():
        stepper = World(name, 1 / 60, call, idle, lambda: np.zeros(0, bool), idle)
        out[name] = 1e6 * min(stepper.advance(steps) for _ in range(repeats)) / steps
    return out


Builder = Callable[[Case, bool], "EngineWorld"]


def default_builder(engine: str) -> Builder:
    """How ``engine`` (OURS, OURS_TUNED or an engine of ``other_scenes``) builds its world of a case."""
    if engine == OURS:
        return lambda case, sleep: OurWorld(case.scene, sleep)
    if engine == OURS_TUNED:
        return lambda case, sleep: OurWorld(case.scene, sleep, until_rest=True, **OUR_TUNED)
    return lambda case, sleep: make_world(engine, case.scene, sleep, case.layout)


def build_world(
    engine: str, case: Case, sleep: bool, ours: dict | None = None, builders: dict[str, Builder] | None = None
) -> EngineWorld:
    """``engine``'s world of ``case`` (UnsupportedScene where the engine cannot build it), by ``builders[engine]`` if
    given. Our worlds are kept in ``ours`` by (engine, sleep) and given again (the timed runs restore a snapshot into
    them): a new one would check the scene again, comparing every pair of boxes."""
    ours = {} if ours is None else ours
    if (engine, sleep) in ours:
        return ours[engine, sleep]
    world = ((builders or {}).get(engine) or default_builder(engine))(case, sleep)
    if isinstance(world, OurWorld):
        ours[engine, sleep] = world
    return world


@dataclass
class Window:
    """One timed window of one engine: what the observed run measured and the timed repeats' CPU seconds."""

    case: str
    engine: str
    label: str
    n: int
    dt: float  # [s] the engine's step
    wanted: int  # steps of the window
    steps: int = 0  # steps run (fewer than wanted where the budget cut the run)
    observed: float = 0.0  # [s] CPU of the observed run's steps, one call a step
    seconds: list[float] = field(default_factory=list)  # thread CPU of each timed repeat
    quality: Quality = field(default_factory=Quality)
    stands: bool = False
    note: str = ""
    snapshot: tuple | None = field(default=None, repr=False)  # ours: the world at the window's start

    @property
    def cpu(self) -> float:
        """Median thread CPU seconds of the timed repeats."""
        return statistics.median(self.seconds) if self.seconds else math.nan

    @property
    def us_per_body_second(self) -> float:
        """Thread CPU per body per simulated second, cpu / (n steps dt) [us]."""
        return 1e6 * self.cpu / (self.n * self.steps * self.dt) if self.steps and self.seconds else math.nan

    @property
    def spread(self) -> float:
        """(slowest - fastest) / median of the repeats."""
        return (max(self.seconds) - min(self.seconds)) / self.cpu if len(self.seconds) > 1 else 0.0

    @property
    def cut(self) -> bool:
        return 0 < self.steps < self.wanted


def window_steps(seconds: float, dt: float) -> int:
    return max(1, round(seconds / dt))


def run_untimed(world: EngineWorld, steps: int, budget: float) -> int:
    """Advance ``steps`` untimed (in CHUNK-step runs); stop once ``budget`` CPU s are spent: the steps run."""
    done, spent = 0, 0.0
    while done < steps and spent <= budget:
        chunk = min(CHUNK, steps - done)
        spent += world.advance(chunk)
        done += chunk
    return done


def observe_window(world: EngineWorld, case: Case, window: Window, thrown: int | None, budget: float) -> None:
    """Step ``world`` through ``window`` one step a call, sampling every step, until done or ``budget`` is spent."""
    state = np.empty((case.scene.n_bodies, STATE_SIZE))
    world.read_states(state)
    track = Track(case.scene, state.copy(), case.scale, thrown)
    while window.steps < window.wanted and window.observed <= budget:
        window.observed += world.advance(1)
        window.steps += 1
        world.read_states(state)
        track.add(state, world.asleep(), window.steps * world.dt)
    window.quality, window.stands = track.quality, track.stands


def observe_plan(engine: str, case: Case, plan: Plan, budget: float, ours: dict, builders=None) -> list[Window]:
    """The observed run of one plan: its windows, measured (a window after a stretch the budget cut is left out,
    with a note)."""
    world = build_world(engine, case, plan.sleep, ours, builders)
    if isinstance(world, OurWorld):
        world.reset()
    windows, blocked = [], ""
    for segment in plan.segments:
        steps = window_steps(segment.seconds, world.dt)
        if blocked:
            if segment.label:
                windows.append(
                    Window(case.name, engine, segment.label, case.scene.n_bodies, world.dt, steps, note=blocked)
                )
            continue
        if segment.throw is not None:
            world.place(*segment.throw)
        if not segment.label:
            done = run_untimed(world, steps, budget)
            if done < steps:
                blocked = f"not run: the budget cut the {segment.seconds:g} s before it at {done * world.dt:.3g} s"
            continue
        window = Window(case.name, engine, segment.label, case.scene.n_bodies, world.dt, steps)
        window.snapshot = world.snapshot() if isinstance(world, OurWorld) else None
        observe_window(world, case, window, None if segment.throw is None else segment.throw[0], budget)
        if window.cut:
            blocked = f"not run: the budget cut the window before it at {window.steps * world.dt:.3g} s"
        windows.append(window)
    return windows


def timed_run(engine: str, case: Case, plan: Plan, window: Window, ours: dict, builders=None) -> tuple[float, float]:
    """(thread CPU s, process CPU s) of ``window.steps`` steps from the window's start, in one call (ours, from the
    observed run's snapshot) or one loop (a fresh world that replays the plan up to the window, untimed)."""
    world = build_world(engine, case, plan.sleep, ours, builders)
    if isinstance(world, OurWorld):
        world.restore(window.snapshot)
    else:
        for segment in plan.segments:
            if segment.throw is not None:
                world.place(*segment.throw)
            if segment.label == window.label:
                break
            world.advance(window_steps(segment.seconds, world.dt))
    began = time.process_time()
    seconds = world.advance(window.steps)
    return seconds, time.process_time() - began


def run_case(
    case: Case,
    engines: Sequence[str],
    repeats: int,
    budget: float,
    log: Callable[[str], None] = lambda _: None,
    builders: dict[str, Builder] | None = None,
) -> tuple[list[Window], list[tuple[str, str]]]:
    """Every window of ``case`` in every engine (each built by ``builders[engine]`` if given, else
    ``default_builder``): (windows, the order the timed runs ran in, (engine, label))."""
    observed: list[tuple[str, Plan, Window]] = []
    windows: list[Window] = []
    ours: dict = {}
    for engine in engines:
        for plan in case.plans:
            log(f"{case.name}: {engine}, observing {'/'.join(plan.labels)}")
            try:
                found = observe_plan(engine, case, plan, budget, ours, builders)
            except UnsupportedScene as error:
                found = [
                    Window(case.name, engine, label, case.scene.n_bodies, math.nan, 0, note=str(error))
                    for label in plan.labels
                ]
            windows += found
            observed += [(engine, plan, w) for w in found if w.steps]
    order = []
    for repeat in range(repeats):
        log(f"{case.name}: timed repeat {repeat + 1} of {repeats}")
        for engine, plan, window in observed:
            seconds, process = timed_run(engine, case, plan, window, ours, builders)
            window.seconds.append(seconds)
            order.append((engine, window.label))
            if process > seconds * (1 + SHARED_CPU) + 1e-3 and "threads" not in window.note:
                window.note = f"other threads of the process ran during a timed run ({process:.3g} s process CPU)"
    for window in windows:
        window.snapshot = None
    return windows, order
