"""Every engine side by side in one run, from one box to 5,000: cost per body-step and per body per
simulated second, awake, settling and asleep, with the quality bought (penetration, the top box's drift).
Prints one table; asserts nothing.

    python -m benchmarks.engine_scale [--quick] [--budget SECONDS] [--write-docs]

Cases: piles of 1, 10 and 100 boxes (``scenes.pile(n)``), of 1,000 and 5,000 boxes laid out wide
(``wide_pile``: ``WIDE_LAYERS`` layers, so the pile is not a 10 m column), the 210-box pyramid
(``scenes.pyramid(rows=20)``), and the OnBox throw (ours only: the engine kernel per throw of
``BoxToss-OnBox-v0`` beside ``BoxToss-v0``).

Method. A pile is first settled for ``SETTLE`` s (untimed) by our engine at its scene defaults and ``SETTLE_DT``, up
to ``OUR_SETTLE_MAX`` boxes (it leaves almost no overlap, which every engine accepts; starting ours from another
engine's pile, with its millimetre overlaps, makes ours work harder; 1,000 boxes take under a second) and above
that by the first available of Box2D v3, pymunk, Box2D 2.3; every engine then starts from that same state
(the pyramid from its exact initial state) and is timed over ``WINDOW`` s of simulated time, its stepping loop
alone, best of ``REPEATS`` runs as far as the budget allows:

- **awake**: nobody may sleep (ours ``sleep_time`` 1e6 s; Box2D sleeping off on the world and on every
  body; pymunk never sleeps), so every step solves every contact; timed after ``LEAD_IN`` s untimed in the
  same world, so that every engine's contacts are warm;
- **settled**: each engine's own sleeping allowed (ours ``until_rest=True``: the run stops once every box
  has lain still ``sleep_time``, and its figures divide by the whole window, the steps skipped at rest
  included, as a sleeping Box2D island's steps are; Box2D's islands sleep after 0.5 s; pymunk does not
  sleep by default), from a fresh start: what falling asleep costs;
- **asleep**: the same, once the scene has fallen asleep: each engine first runs ``LEAD_IN`` s untimed
  (Box2D's world stepped on, ours a run until rest with a warm start, ``warm_start_memory``, which carries
  the islands' sleep into the timed run, as one long run would), then the window is timed: what a pile
  that lies still costs while a scene goes on.

Figures: ns per body-step = wall / (steps n); us per body per simulated second = wall / (n T), T the
simulated time covered, which puts engines with different steps on one scale. Each engine runs at its
own default step (``DEFAULT_DT``: 60 Hz for the others, Box2D v3 with 4 substeps), ours at ``OUR_DT`` with
the Gauss-Seidel stop ``OUR_SOLVER``.
Per-case budget: an engine whose window would take longer than ``--budget`` s is timed over fewer steps
(at least ``MIN_STEPS``; the table's ``steps`` column says how many, and the text which runs were cut).
Quality, at the end of the awake run: max penetration (deepest box corner below the floor or inside another
box, m) and how far the top box (the highest at the start) moved (m) since the start, lead-in included.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from benchmarks.engine import load_text
from benchmarks.other_scenes import (
    DEFAULT_DT,
    UnsupportedScene,
    available_scene_engines,
    simulate_scene,
)
from box_toss_env.files import save_figure
from box_toss_env.physics import Box, Scene, Simulator, layout, make_settings, scenes, simulate, warm_start_memory

OUR_DT: dict[str, float] = {"pile": 1 / 60, "wide pile": 1 / 60, "pyramid": 1 / 60}
"""[s] our engine's step per kind of scene: the one place to edit when the engine picks its own. The cheapest of
1/60, 1/90 and 1/120 at which the awake scene's deepest penetration stays under 1 mm throughout (the bound the
engine issue sets); a user who wants every contact under 0.5 mm takes 1/90. The measurements that chose it are on
docs/engine_scale.md ("How our settings were chosen")."""
OUR_SOLVER = {"solver_tolerance": 1e-4, "solver_iterations": 32, "penetration_slop": 5e-5}
"""Our solver settings for these scenes: the Gauss-Seidel stop (``Scene.solver_tolerance``, ``solver_iterations``;
sweeps stop once they change the impulses by less than 1e-4 of their sum, after 32 at most) and
``penetration_slop`` 50 um (the penalty starts once a contact is twice that deep and leaves up to that alone;
Box2D's slop is 5 mm). The stop spares the sweeps that do not converge on a column of boxes, the slop lets the
penalty rest instead of running at every step; a looser stop lets more contacts sink into the penalty's band,
and a settled pile kept awake creeps at this stop, which the settled runs' sleeping ends. What each setting costs
and buys, measured: docs/engine_scale.md ("How our settings were chosen"); ``benchmarks.pile_pareto`` turns the
tolerance and the slop."""


OURS = "ours"
ENGINE_ORDER = (OURS, "box2d3", "box2d", "pymunk")
SETTLER_ORDER = ("box2d3", "pymunk", "box2d")  # who settles a pile for everyone (ours if none is installed)
PILE_SIZES = (1, 10, 100, 1000, 5000)
QUICK_SIZES = (1, 10, 100, 1000)
WIDE_FROM = 1000  # piles of this many boxes or more are laid out wide
WIDE_LAYERS = 8
PYRAMID_ROWS = 20  # 210 boxes
SETTLE = 2.0  # [s] untimed settling of a pile
SETTLE_DT = 1 / 90
"""[s] the step of our settling of a pile, whatever step the pile is timed at (``OUR_DT``), so that every engine and
every timed step start from one state; at 1/60 the wide piles keep boxes awake after the asleep runs' lead-in."""
WINDOW, QUICK_WINDOW = 2.0, 1.0  # [s] simulated time timed per case
MIN_STEPS = 4
REPEATS = 3  # best of this many timed runs, as far as the budget allows
OUR_SETTLE_MAX = 10_000  # piles up to this many boxes are settled by our engine
BUDGET, QUICK_BUDGET = 5.0, 1.5  # [s] of wall time per (case, engine, mode)
NEVER_SLEEP = 1e6  # [s] our sleep_time in awake runs
MODES = ("awake", "settled", "asleep")
LEAD_IN = {"awake": 0.5, "settled": 0.0, "asleep": 2.0}
"""[s] simulated untimed before the window, per mode, in the same world (ours: a run whose warm start carries its
contacts' impulses and its sleep into the timed one): awake, so that every engine is timed with its contacts warm,
as a scene that goes on is (ours pays its cold start once, in the lead-in: docs/engine_scale.md says what it
costs); asleep, so that Box2D's islands (0.5 s still) and ours have fallen asleep; settled from a fresh start: what
falling asleep costs."""
ONBOX_THROWS, QUICK_ONBOX_THROWS = 400, 100
BATCH, BATCHES, QUICK_BATCHES = 256, 3, 1  # make_vec(BATCH, threads=1), batch steps timed

DOCS = Path(__file__).resolve().parents[1] / "docs"
DOCS_PAGE = DOCS / "engine_scale.md"
FIGURE = DOCS / "figures" / "engine_scale.png"
MARKER = "engine-scale"
README_MARKER = "engine-scale-summary"  # the README's few lines of it (agents.doc_sections.SECTION_PAGES)
README_CASES = ("pile 100", "pile 1000", "pyramid 210")  # the cases of the awake goals, in the README


def wide_pile(n: int, layers: int = WIDE_LAYERS, seed: int = 0) -> Scene:
    """``scenes.pile(n)`` laid out ``layers`` rows high and ceil(n / layers) columns wide (the same 40 x 20 cm
    boxes, 0.6 m and 0.3 m apart, shifted and tilted at random), so that a big pile stays low."""
    template = scenes.pile(1)
    rng = np.random.default_rng(seed)
    columns = math.ceil(n / layers)
    boxes = []
    for k in range(n):
        row, column = divmod(k, columns)
        boxes.append(
            Box(
                length=0.4,
                width=0.2,
                mass=2.0,
                position=(0.6 * (column - 0.5 * (columns - 1)) + float(rng.uniform(-0.08, 0.08)), 0.15 + 0.3 * row),
                angle=float(rng.uniform(-0.2, 0.2)),
            )
        )
    return template.replace(boxes=tuple(boxes))


def pile_case(n: int) -> tuple[str, Scene]:
    """(kind, scene) of the pile of ``n`` boxes, at our step for that kind."""
    kind = "wide pile" if n >= WIDE_FROM else "pile"
    scene = wide_pile(n) if kind == "wide pile" else scenes.pile(n)
    return kind, scene.replace(dt=OUR_DT[kind], **OUR_SOLVER)


def pyramid_case() -> Scene:
    return scenes.pyramid(rows=PYRAMID_ROWS).replace(dt=OUR_DT["pyramid"], **OUR_SOLVER)


# -- quality -------------------------------------------------------------------------------------
def corners(scene: Scene, state: np.ndarray) -> np.ndarray:
    """(n, 4, 2) world corners of every box."""
    half = np.array([[0.5 * b.length, 0.5 * b.width] for b in scene.boxes])
    signs = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    local = signs[None] * half[:, None]
    c, s = np.cos(state[:, 2]), np.sin(state[:, 2])
    x = c[:, None] * local[..., 0] - s[:, None] * local[..., 1] + state[:, None, 0]
    y = s[:, None] * local[..., 0] + c[:, None] * local[..., 1] + state[:, None, 1]
    return np.stack([x, y], axis=-1)


def max_penetration(scene: Scene, state: np.ndarray) -> float:
    """Deepest penetration [m]: a corner below the floor (-y), or a corner of one box inside another
    (its distance to the nearest face of that box). Pairs come from overlapping bounding boxes."""
    points = corners(scene, state)
    depth = max(0.0, float(-points[..., 1].min()))
    if not scene.boxes_collide or scene.n_bodies < 2:
        return depth
    low, high = points.min(axis=1), points.max(axis=1)
    order = np.argsort(low[:, 0])
    half = np.array([[0.5 * b.length, 0.5 * b.width] for b in scene.boxes])
    for a_rank, i in enumerate(order):
        for j in order[a_rank + 1 :]:
            if low[j, 0] > high[i, 0]:
                break
            if low[j, 1] > high[i, 1] or low[i, 1] > high[j, 1]:
                continue
            for inner, outer in ((i, j), (j, i)):
                c, s = math.cos(state[outer, 2]), math.sin(state[outer, 2])
                d = points[inner] - state[outer, :2]
                local = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=1)
                inside = half[outer] - np.abs(local)  # > 0 on both axes: the corner is inside
                depth = max(depth, float(np.max(np.where((inside > 0).all(axis=1), inside.min(axis=1), 0.0))))
    return depth


# -- timing --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Row:
    case: str
    n: int
    engine: str
    dt: float  # [s] the engine's step
    mode: str  # one of MODES
    steps: int  # steps timed
    wall: float  # [s]
    penetration: float = math.nan  # [m]
    drift: float = math.nan  # [m]
    note: str = ""

    @property
    def ns_per_body_step(self) -> float:
        return 1e9 * self.wall / (self.steps * self.n) if self.steps else math.nan

    @property
    def us_per_body_second(self) -> float:
        """wall / (n T), T = steps dt the simulated time covered [us per body per simulated second]."""
        return 1e6 * self.wall / (self.n * self.steps * self.dt) if self.steps else math.nan


def budget_steps(step_seconds: float, dt: float, window: float, budget: float) -> int:
    """Steps to time: the window's, or fewer (at least MIN_STEPS) if they would take over ``budget`` s."""
    full = max(1, round(window / dt))
    return int(min(full, max(MIN_STEPS, budget / max(step_seconds, 1e-9))))


def run_ours(scene: Scene, start: np.ndarray, steps: int, mode: str) -> tuple[float, np.ndarray, str]:
    """(wall s, final state, note) of our engine from ``start``, single thread, in ``mode`` (MODES): awake runs
    never sleep, the others stop once every box is at rest (``until_rest``); the timed run follows an untimed one
    of LEAD_IN[mode] s whose warm start it carries (the note says how many boxes were asleep when an asleep
    run's timing began, if not all)."""
    scene = scene.replace(sleep_time=NEVER_SLEEP) if mode == "awake" else scene
    simulator = Simulator.for_scene(scene, parallel=False)
    params = scene.body_params()
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    simulator.run(start.copy(), params, make_settings(scene, 1, False), stats)  # compile / load, untimed
    state, warm, note = start.copy(), warm_start_memory(scene.n_bodies), ""
    until_rest = mode != "awake"
    lead_in = round(LEAD_IN[mode] / scene.dt)
    if lead_in:
        simulator.run(state, params, make_settings(scene, lead_in, until_rest), stats, warm_start=warm)
    if mode == "asleep":
        asleep = int(np.count_nonzero(~np.isnan(stats[:, layout.REST_TIME])))
        note = "" if asleep == scene.n_bodies else f"{asleep:,} of {scene.n_bodies:,} boxes asleep when timing began"
    settings = make_settings(scene, steps, until_rest)
    begin = time.perf_counter()
    simulator.run(state, params, settings, stats, warm_start=warm)
    return time.perf_counter() - begin, state, note


def best_of(run: Callable[[], tuple[float, np.ndarray]], budget: float) -> tuple[float, np.ndarray]:
    """(least wall time, final state) of up to REPEATS calls of ``run``, fewer if they would exceed ``budget``."""
    wall, state = run()
    spent, best = wall, wall
    for _ in range(REPEATS - 1):
        if spent + wall > budget:
            break
        wall, state = run()
        spent, best = spent + wall, min(best, wall)
    return best, state


def time_ours(case: str, scene: Scene, start: np.ndarray, mode: str, window: float, budget: float) -> Row:
    probe, _, _ = run_ours(scene, start, MIN_STEPS, "awake")
    steps = budget_steps(probe / MIN_STEPS, scene.dt, window, budget)
    notes = []

    def run() -> tuple[float, np.ndarray]:
        wall, state, note = run_ours(scene, start, steps, mode)
        notes.append(note)
        return wall, state

    wall, state = best_of(run, budget)
    # until_rest stops early: the rest of the window is simulated for free, so the figure is per ``steps``
    return Row(case, scene.n_bodies, OURS, scene.dt, mode, steps, wall, *quality(scene, start, state), note=notes[-1])


def time_other(engine: str, case: str, scene: Scene, start: np.ndarray, mode: str, window: float, budget: float) -> Row:
    dt = DEFAULT_DT[engine]
    sleep = mode != "awake"
    untimed = round(LEAD_IN[mode] / dt)
    try:
        probe = simulate_scene(engine, scene, MIN_STEPS, record=False, sleep=False, state=start, dt=dt)
    except UnsupportedScene as error:
        return Row(case, scene.n_bodies, engine, dt, mode, 0, math.nan, note=str(error))
    steps = budget_steps(probe.wall_seconds / MIN_STEPS, dt, window, budget)

    def run() -> tuple[float, np.ndarray]:
        done = simulate_scene(engine, scene, steps, record=False, sleep=sleep, state=start, dt=dt, untimed=untimed)
        return done.wall_seconds, done.final_state

    wall, state = best_of(run, budget)
    return Row(case, scene.n_bodies, engine, dt, mode, steps, wall, *quality(scene, start, state))


def quality(scene: Scene, start: np.ndarray, final: np.ndarray) -> tuple[float, float]:
    """(max penetration [m], drift of the top box [m]: the one highest at the start)."""
    top = int(np.argmax(start[:, 1]))
    return max_penetration(scene, final), float(np.hypot(*(final[top, :2] - start[top, :2])))


def settle(scene: Scene, engines: list[str], our_max: int = OUR_SETTLE_MAX) -> tuple[np.ndarray, str]:
    """(the pile after SETTLE s, who settled it): ours up to ``our_max`` boxes, at the scene defaults of the
    settings in OUR_SOLVER (the most exact: every setting measured starts from the same pile), else the first
    available of SETTLER_ORDER (ours if none is)."""
    for engine in SETTLER_ORDER if scene.n_bodies > our_max else ():
        if engine in engines:
            steps = round(SETTLE / DEFAULT_DT[engine])
            return simulate_scene(engine, scene, steps, record=False, dt=DEFAULT_DT[engine]).final_state, engine
    defaults = Scene()
    exact = scene.replace(**{name: getattr(defaults, name) for name in OUR_SOLVER})
    return simulate(exact.replace(dt=SETTLE_DT), duration=SETTLE).final_state, OURS


def scale_rows(
    sizes=PILE_SIZES,
    engines: list[str] | None = None,
    window: float = WINDOW,
    budget: float = BUDGET,
    log: Callable[[str], None] = lambda _: None,
    our_settle_max: int = OUR_SETTLE_MAX,
    pyramid: bool = True,
) -> tuple[list[Row], dict[str, str]]:
    """Every case in every engine, in every mode (MODES): (rows, who settled each case)."""
    engines = [OURS, *available_scene_engines()] if engines is None else engines
    others = [e for e in engines if e != OURS]
    cases = [(f"pile {n}", *pile_case(n)[1:], True) for n in sizes]
    cases += [(f"pyramid {pyramid_case().n_bodies}", pyramid_case(), False)] if pyramid else []
    rows, settlers = [], {}
    for name, scene, needs_settling in cases:
        if needs_settling:
            log(f"{name}: settling")
            start, settlers[name] = settle(scene, others, our_settle_max)
        else:
            start = scene.initial_state()
        for engine in engines:
            for mode in MODES:
                log(f"{name}: {engine}, {mode}")
                timer = time_ours if engine == OURS else partial(time_other, engine)
                rows.append(timer(name, scene, start, mode, window, budget))
    return rows, settlers


def onbox_rows(throws: int, batches: int) -> list[tuple[str, float, float, float, float]]:
    """(env id, bodies, engine kernel us per throw, us per body per simulated second, us per throw of a
    ``make_vec(256, threads=1)`` batch, env included) for BoxToss-v0 and BoxToss-OnBox-v0 at their defaults,
    random actions, until rest (``env_throughput.kernel_seconds_per_throw``, the best of REPEATS runs over the same
    throws, as the scenes' timings; ``batches`` batch steps timed)."""
    import gymnasium as gym

    from benchmarks.env_throughput import kernel_seconds_per_throw

    out = []
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, (max(throws, BATCH * (batches + 1)), 3)).astype(np.float32)
    for env_id in ("BoxToss-v0", "BoxToss-OnBox-v0"):
        env = gym.make(env_id)
        env.reset(seed=0)
        kernel_seconds_per_throw(env, actions[:20])  # compile / load, untimed
        seconds = min(kernel_seconds_per_throw(env, actions[:throws]) for _ in range(REPEATS))
        simulated = simulated_seconds_per_throw(env, actions[:throws])
        bodies = env.unwrapped._state.shape[0]
        env.close()
        envs = gym.make_vec(env_id, num_envs=BATCH, vectorization_mode="vector_entry_point", threads=1)
        envs.reset(seed=0)
        batch_actions = actions[: BATCH * (batches + 1)].reshape(-1, BATCH, 3)
        envs.step(batch_actions[0])  # warm-up
        begin = time.perf_counter()
        for step_actions in batch_actions[1:]:
            envs.step(step_actions)
        batched = (time.perf_counter() - begin) / (batches * BATCH)
        envs.close()
        out.append((env_id, bodies, 1e6 * seconds, 1e6 * seconds / (bodies * simulated), 1e6 * batched))
    return out


def simulated_seconds_per_throw(env, actions: np.ndarray) -> float:
    """Mean simulated time of a throw until rest [s] (steps integrated x dt, from the step's stats)."""
    total = 0.0
    for action in actions:
        env.reset()
        env.step(action)
        unwrapped = env.unwrapped
        total += float(unwrapped._stats[:, layout.N_STEPS].max()) * unwrapped.engine_settings[layout.DT]
    return total / len(actions)


# -- output --------------------------------------------------------------------------------------
def fmt(value: float, spec: str) -> str:
    return "-" if not math.isfinite(value) else format(value, spec)


def table(rows: list[Row]) -> list[str]:
    """One markdown table: a line per (case, engine), the modes side by side."""
    by = {(r.case, r.engine, r.mode): r for r in rows}
    keys = list(dict.fromkeys((r.case, r.engine) for r in rows))
    lines = [
        "| case | boxes | engine | dt [s] | awake ns/body-step | awake us/body/sim-s | steps | "
        "settled us/body/sim-s | asleep us/body/sim-s | max penetration [m] | top drift [m] |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for case, engine in keys:
        awake, rest, asleep = (by[(case, engine, mode)] for mode in MODES)
        drift = fmt(awake.drift, ".2e")
        lines.append(
            f"| {case} | {awake.n} | {engine} | {dt_text(awake.dt)} | "
            f"{fmt(awake.ns_per_body_step, ',.0f')} | {fmt(awake.us_per_body_second, ',.1f')} | "
            f"{awake.steps} | {fmt(rest.us_per_body_second, ',.1f')} | {fmt(asleep.us_per_body_second, ',.2f')} | "
            f"{fmt(awake.penetration, '.2e')} | {drift} |"
        )
    notes = [r for r in rows if r.note and (r.mode == "awake" or r.engine == OURS)]
    return lines + [f"- {r.engine}, {r.case}, {r.mode}: {r.note}" for r in notes]


def dt_text(dt: float) -> str:
    return f"1/{round(1 / dt)}" if abs(1 / dt - round(1 / dt)) < 1e-9 else f"{dt:g}"


def plot(rows: list[Row], path: Path = FIGURE) -> None:
    """Log-log: us per body per simulated second against boxes, one line per engine and mode (solid awake,
    dashed settled, dotted asleep), piles only."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    piles = [r for r in rows if r.case.startswith("pile") and r.steps]
    for k, engine in enumerate(dict.fromkeys(r.engine for r in piles)):
        for mode, style in zip(MODES, ("-", "--", ":"), strict=True):
            points = sorted((r.n, r.us_per_body_second) for r in piles if r.engine == engine and r.mode == mode)
            if points:
                ax.loglog(*zip(*points, strict=True), style, marker="o", color=f"C{k}", label=f"{engine}, {mode}")
    ax.set_xlabel("boxes in the pile")
    ax.set_ylabel("wall time per body per simulated second [us]")
    ax.set_title("Cost of a settled pile, one thread, each engine at its own step")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    plt.close(fig)


def write_docs(text: str, page: Path = DOCS_PAGE, marker: str = MARKER) -> None:
    """Put ``text`` between the page's ``marker`` markers."""
    from agents.doc_sections import replace_section

    replace_section(marker, text, readme=page)


def report(args: argparse.Namespace, log: Callable[[str], None]) -> tuple[str, str]:
    """(the page's generated text, the README's summary of it)."""
    import numba

    quick = args.quick
    sizes = QUICK_SIZES if quick else PILE_SIZES
    window = QUICK_WINDOW if quick else WINDOW
    budget = args.budget if args.budget is not None else (QUICK_BUDGET if quick else BUDGET)
    engines = [e for e in ENGINE_ORDER if e == OURS or e in available_scene_engines()]
    rows, settlers = scale_rows(sizes, engines, window, budget, log)
    log("OnBox throws")
    onbox = onbox_rows(QUICK_ONBOX_THROWS if quick else ONBOX_THROWS, QUICK_BATCHES if quick else BATCHES)
    lines = [
        f"`python -m benchmarks.engine_scale{' --quick' if quick else ''}`: numba {numba.__version__}, "
        f"one thread for every engine; {load_text()}.",
        "",
        f"Window {window:g} s of simulated time per case, per-case budget {budget:g} s of wall time: "
        f"where the window would take longer, fewer steps are timed (`steps`, at least {MIN_STEPS}): "
        f"{shortened_text(rows, window)}. "
        "Settled: sleeping allowed, from a fresh start (ours until rest, so fewer steps when everyone sleeps). "
        f"Asleep: the same after {LEAD_IN['asleep']:g} s untimed; awake after {LEAD_IN['awake']:g} s untimed, every "
        "engine in its own world (ours carrying its contacts and sleep in a warm start). Piles settled "
        f"{SETTLE:g} s first by " + ", ".join(f"{case}: {who}" for case, who in settlers.items()) + ".",
        "",
    ]
    lines += table(rows)
    lines += [
        "",
        "Our engine per throw (until rest, random actions): the kernel alone, one env, and a batch of "
        f"`make_vec({BATCH}, threads=1)` with the env's own work included:",
        "",
        "| env | bodies | kernel us per throw | kernel us/body/sim-s | batched us per throw |",
        "|---|---:|---:|---:|---:|",
    ]
    lines += [
        f"| {env_id} | {bodies} | {micros:,.0f} | {per:,.1f} | {batched:,.0f} |"
        for env_id, bodies, micros, per, batched in onbox
    ]
    if quick:
        lines += ["", "(quick run: shorter window, smaller budget, no 5,000-box pile)"]
    if getattr(args, "write_docs", False):  # the figure is the docs' (a tracked file): written only when asked
        plot(rows)
    return "\n".join(lines), readme_summary(rows, onbox, lines[0])


def readme_summary(rows: list[Row], onbox, header: str) -> str:
    """Ours beside Box2D v3 awake on the README_CASES, and the throw onto a box beside a floor throw: the README's
    lines, from the same run as the page."""
    awake = {(row.case, row.engine): row for row in rows if row.mode == "awake"}
    lines = [
        "| awake, us per box per simulated second | ours | Box2D v3 | ours / Box2D v3 | penetration [m]: ours "
        "| Box2D v3 | top drift [m]: ours | Box2D v3 |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for case in README_CASES:
        ours, other = awake.get((case, OURS)), awake.get((case, "box2d3"))
        if ours is None or other is None:
            continue
        ratio = ours.us_per_body_second / other.us_per_body_second
        drifts = [fmt(row.drift, ".1e") for row in (ours, other)]
        lines.append(
            f"| {case} | {ours.us_per_body_second:,.1f} | {other.us_per_body_second:,.1f} | {ratio:.1f} | "
            f"{fmt(ours.penetration, '.1e')} | {fmt(other.penetration, '.1e')} | {drifts[0]} | {drifts[1]} |"
        )
    kernel = {env_id: micros for env_id, _, micros, _, _ in onbox}
    throw = ""
    if {"BoxToss-v0", "BoxToss-OnBox-v0"} <= set(kernel):
        throw = (
            f" A throw onto a box (`BoxToss-OnBox-v0`) costs the engine {kernel['BoxToss-OnBox-v0']:,.0f} us, "
            f"{kernel['BoxToss-OnBox-v0'] / kernel['BoxToss-v0']:.1f} times a floor throw's "
            f"{kernel['BoxToss-v0']:,.0f} us."
        )
    rest = {(row.case, row.engine, row.mode): row for row in rows if row.mode != "awake"}
    still = [
        f"{case}: ours {rest[(case, OURS, 'settled')].us_per_body_second:,.1f} and "
        f"{rest[(case, OURS, 'asleep')].us_per_body_second:,.2f}, Box2D v3 "
        f"{rest[(case, 'box2d3', 'settled')].us_per_body_second:,.1f} and "
        f"{rest[(case, 'box2d3', 'asleep')].us_per_body_second:,.2f}"
        for case in README_CASES
        if all((case, engine, mode) in rest for engine in (OURS, "box2d3") for mode in ("settled", "asleep"))
    ]
    sleeping = (
        f" Falling asleep from a fresh start, and asleep, us per box per simulated second: {'; '.join(still)}."
        if still
        else ""
    )
    return "\n".join([*lines, "", f"{header}{sleeping} Every engine: [the page](docs/engine_scale.md).{throw}"])


def shortened_text(rows: list[Row], window: float) -> str:
    """Which awake runs the budget cut short, for the generated text."""
    cut = [
        f"{row.engine} on {row.case}"
        for row in rows
        if row.mode == "awake" and row.steps and row.steps < round(window / row.dt)
    ]
    return "so were " + ", ".join(cut) if cut else "no run was cut short"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="1 s window, 1.5 s budget, piles up to 1,000 boxes")
    parser.add_argument(
        "--budget", type=budget_seconds, default=None, help="wall seconds per (case, engine, mode), in [0.1, 600]"
    )
    parser.add_argument(
        "--write-docs",
        action="store_true",
        help=f"write the table into {DOCS_PAGE.name} and its summary into README.md",
    )
    args = parser.parse_args(argv)
    began = time.perf_counter()
    text, summary = report(args, log=lambda line: print(f"[{time.perf_counter() - began:6.1f} s] {line}", flush=True))
    print(text)
    if args.write_docs:
        from agents.doc_sections import README

        write_docs(text)
        write_docs(summary, page=README, marker=README_MARKER)


def budget_seconds(text: str) -> float:
    """--budget's type: seconds in [0.1, 600] (argparse prints the message with the option's name)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0.1 <= value <= 600:
        raise argparse.ArgumentTypeError(f"must be in [0.1, 600] s, got {text}")
    return value


if __name__ == "__main__":
    main()
