"""Every engine side by side on a suite of named scenes (``benchmarks.scene_suite``): piles of 16 to 5,000 boxes
dropped, at rest and kept awake, structures, thin, tiny and huge boxes, throws into a pile, and Box2D's own
benchmark scenes; each engine at its own defaults, from its own start; cost per body per simulated second in thread
CPU time and what each engine did (penetration, energy, tunnelling, sleep, jitter, standing). Prints the tables;
writes nothing unless asked.

    python -m benchmarks.engine_scale [--quick] [--cases NAMES] [--engines NAMES] [--budget S] [--repeats N]
                                      [--json PATH] [--write-docs]

``--write-docs`` writes the page (docs/engine_scale.md: its method and tables), the figure
(docs/figures/engine_scale.png) and the README's summary; without it no file changes (``--json`` writes the
measured windows where told). The method is written by the command with the page (``method``).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable
from dataclasses import asdict
from importlib import metadata
from pathlib import Path

import numpy as np

from benchmarks import scale_report
from benchmarks.engine import load_text
from benchmarks.other_scenes import (
    BOX2D3_CONTACT,
    BOX2D3_SUBSTEPS,
    BOX2D_ITERATIONS,
    DEFAULT_DT,
    PYMUNK_COLLISION_SLOP,
    PYMUNK_ITERATIONS,
    available_scene_engines,
)
from benchmarks.scene_quality import DEEP, ENERGY_SHARE, JITTER_SPEED, STAND_DRIFT
from benchmarks.scene_suite import AWAKE_LEAD_IN, SETTLE, WINDOW, Case, suite, wide_pile
from benchmarks.suite_runs import (
    BUDGET,
    NEVER_SLEEP,
    OUR_TUNED,
    OURS,
    OURS_TUNED,
    QUICK_BUDGET,
    QUICK_REPEATS,
    REPEATS,
    Window,
    loop_overhead,
    run_case,
    sleep_default,
    until_rest_default,
)
from box_toss_env.files import write_atomic
from box_toss_env.physics import layout, scenes

ENGINE_ORDER = (OURS, OURS_TUNED, "box2d3", "box2d", "pymunk")
QUICK_WINDOW, QUICK_SETTLE = 0.5, 1.0  # [s]
ONBOX_THROWS, QUICK_ONBOX_THROWS = 400, 100
BATCH, BATCHES, QUICK_BATCHES = 256, 3, 1  # make_vec(BATCH, threads=1), batch steps timed
ONBOX_REPEATS = 3

DOCS = Path(__file__).resolve().parents[1] / "docs"
DOCS_PAGE = DOCS / "engine_scale.md"
FIGURE = DOCS / "figures" / "engine_scale.png"
MARKER = "engine-scale"
README_MARKER = "engine-scale-summary"  # the README's few lines of it (agents.doc_sections.SECTION_PAGES)

__all__ = ["NEVER_SLEEP", "pile_case", "wide_pile"]


def pile_case(n: int):
    """(kind, scene) of the pile of ``n`` boxes as the suite builds it, every setting at the scene defaults
    (``benchmarks.substep_groups`` starts from it)."""
    return ("wide pile", wide_pile(n)) if n >= 1000 else ("pile", scenes.pile(n))


def select(cases: list[Case], names: list[str] | None) -> list[Case]:
    """The cases named (all if None); a ValueError names the unknown ones and the choices."""
    if names is None:
        return cases
    known = {case.name: case for case in cases}
    unknown = [name for name in names if name not in known]
    if unknown:
        raise ValueError(f"--cases: unknown {unknown}; choose from {list(known)}")
    return [known[name] for name in names]


def run_suite(
    cases: list[Case], engines: list[str], repeats: int, budget: float, log: Callable[[str], None]
) -> tuple[list[Window], list[tuple[str, str, str]]]:
    """Every window of every case in every engine, and the order the timed runs ran in (case, engine, window)."""
    windows, order = [], []
    for case in cases:
        found, ran = run_case(case, engines, repeats, budget, log)
        windows += found
        order += [(case.name, engine, label) for engine, label in ran]
    return windows, order


# -- ours per throw (the env path) ---------------------------------------------------------------
ONBOX_ENVS = ("BoxToss-v0", "BoxToss-OnBox-v0")


def onbox_rows(throws: int, batches: int) -> list[tuple[str, float, float, float, float]]:
    """(env id, bodies, engine kernel us per throw, us per body per simulated second, us per throw of a
    ``make_vec(256, threads=1)`` batch, env included) for BoxToss-v0 and BoxToss-OnBox-v0 at their defaults,
    random actions, until rest: ``env_throughput.kernel_seconds_per_throw`` in thread CPU time, the best of
    ONBOX_REPEATS runs over the same throws, the two envs' runs interleaved; ``batches`` batch steps timed, thread
    CPU time (``threads=1``: the calling thread steps the batch)."""
    import gymnasium as gym

    from benchmarks.env_throughput import kernel_seconds_per_throw

    actions = np.random.default_rng(0).uniform(-1.0, 1.0, (max(throws, BATCH * (batches + 1)), 3)).astype(np.float32)
    envs = {env_id: gym.make(env_id) for env_id in ONBOX_ENVS}
    for env in envs.values():
        env.reset(seed=0)
        kernel_seconds_per_throw(env, actions[:20])  # compile / load, untimed
    best = dict.fromkeys(ONBOX_ENVS, math.inf)
    for _ in range(ONBOX_REPEATS):
        for env_id, env in envs.items():
            best[env_id] = min(best[env_id], kernel_seconds_per_throw(env, actions[:throws], time.thread_time))
    out = []
    for env_id, env in envs.items():
        simulated = simulated_seconds_per_throw(env, actions[:throws])
        bodies = env.unwrapped._state.shape[0]
        env.close()
        seconds = best[env_id]
        batched = batch_seconds_per_throw(env_id, actions, batches)
        out.append((env_id, bodies, 1e6 * seconds, 1e6 * seconds / (bodies * simulated), 1e6 * batched))
    return out


def batch_seconds_per_throw(env_id: str, actions: np.ndarray, batches: int) -> float:
    """Thread CPU seconds per throw of ``make_vec(BATCH, threads=1)`` over ``batches`` batch steps after one."""
    import gymnasium as gym

    envs = gym.make_vec(env_id, num_envs=BATCH, vectorization_mode="vector_entry_point", threads=1)
    envs.reset(seed=0)
    batch_actions = actions[: BATCH * (batches + 1)].reshape(-1, BATCH, 3)
    envs.step(batch_actions[0])  # warm-up
    begin = time.thread_time()
    for step_actions in batch_actions[1:]:
        envs.step(step_actions)
    seconds = (time.thread_time() - begin) / (batches * BATCH)
    envs.close()
    return seconds


def simulated_seconds_per_throw(env, actions: np.ndarray) -> float:
    """Mean simulated time of a throw until rest [s] (steps integrated x dt, from the step's stats)."""
    total = 0.0
    for action in actions:
        env.reset()
        env.step(action)
        unwrapped = env.unwrapped
        total += float(unwrapped._stats[:, layout.N_STEPS].max()) * unwrapped.engine_settings[layout.DT]
    return total / len(actions)


def onbox_lines(onbox) -> tuple[list[str], str]:
    """(the page's table of ours per throw, the README's sentence about it)."""
    lines = [
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
    kernel = {env_id: micros for env_id, _, micros, _, _ in onbox}
    if {"BoxToss-v0", "BoxToss-OnBox-v0"} > set(kernel):
        return lines, ""
    sentence = (
        f" A throw onto a box (`BoxToss-OnBox-v0`) costs the engine {kernel['BoxToss-OnBox-v0']:,.0f} us, "
        f"{kernel['BoxToss-OnBox-v0'] / kernel['BoxToss-v0']:.1f} times a floor throw's {kernel['BoxToss-v0']:,.0f} us."
    )
    return lines, sentence


# -- the page ------------------------------------------------------------------------------------
def version(package: str) -> str:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "not installed"


def our_settings_text(case: Case) -> str:
    scene = case.scene
    names = ("dt", "solver_tolerance", "solver_iterations", "penetration_slop", "sleep_speed", "sleep_time")
    return ", ".join(f"{name} {getattr(scene, name):g}" for name in names)


def method(cases: list[Case], window: float, settle: float, repeats: int, budget: float) -> list[str]:
    """The method, written with the figures by the command (every constant from the code that used it)."""
    b2_hz, b2_damping, b2_push = BOX2D3_CONTACT.values()
    tuned = ", ".join(f"{k} {v:g}" for k, v in OUR_TUNED.items())
    return [
        "### Method (written by the command)",
        "",
        f"- **Engines**, each at its own defaults, one thread. Ours (box_toss_env {version('box_toss_env')}, numba "
        f"{version('numba')}): each scene exactly as `scenes.*` builds it (for the pile of 16: "
        f"{our_settings_text(cases[0])}), run by `Simulator.for_scene` with `sleep` and `until_rest` at "
        f"`simulate`'s defaults ({sleep_default()}, {until_rest_default()}), its warm start (`warm_start_memory`) "
        f"carried from run to run. Box2D v3 (pyb2d3 "
        f"{version('pyb2d3')}): {1 / DEFAULT_DT['box2d3']:g} Hz, {BOX2D3_SUBSTEPS} substeps, contact hertz "
        f"{b2_hz:g}, damping ratio {b2_damping:g}, push {b2_push:g} m/s, sleeping and continuous collision on. "
        f"Box2D 2.3 (box2d {version('box2d')}): {1 / DEFAULT_DT['box2d']:g} Hz, {BOX2D_ITERATIONS[0]} velocity and "
        f"{BOX2D_ITERATIONS[1]} position iterations, sleeping on. pymunk ({version('pymunk')}): "
        f"{1 / DEFAULT_DT['pymunk']:g} Hz, {PYMUNK_ITERATIONS} iterations, collision slop "
        f"{PYMUNK_COLLISION_SLOP * 1e3:g} mm (its default 0.1 is meant for pixels), no sleeping (its default). "
        f"`ours, tuned` is ours at settings a user can pick ({tuned}, `until_rest=True`): its column stands beside "
        "the defaults', never instead.",
        "- **Scenes** (`benchmarks/scene_suite.py`): "
        + "; ".join(f"{c.name} ({c.scene.n_bodies:,} boxes{', ' + c.note if c.note else ''})" for c in cases)
        + ". Every engine starts from the scene's own start (boxes apart, or a structure built at rest) and "
        "settles its own pile.",
        f"- **Windows**, {window:g} s of simulated time each: *dropped*, from the start, each engine's default "
        f"sleeping; *at rest*, the same world after {settle:g} s; *kept awake*, sleeping off (ours `sleep_time` "
        f"{NEVER_SLEEP:g} s), after {settle:g} s; *standing*, a built structure from its start, and kept awake after "
        f"{AWAKE_LEAD_IN:g} s; *thrown in*, a box thrown level into the pile that settled {settle:g} s; *as "
        "published*, Box2D's benchmark: sleeping off, the first 60 Hz step untimed, the rest timed.",
        "- **Timing**: a first, observed run steps each world one step a call and reads its states after every step "
        "(the measures below); it also fixes how many steps each window runs: a window whose steps pass the budget "
        f"of {budget:g} s of CPU stops there (the window's `steps`, and the notes). Then {repeats} timed repeats, "
        "interleaved across engines and windows (ABAB, not AAA BBB), time the stepping loop alone in thread CPU "
        "time (`time.thread_time`), reading states only at the end: ours in one call from the observed run's state "
        "and warm start at the window's start; the others in a fresh world stepped, untimed, up to the window. "
        "Cost: the median of the repeats, per body per simulated second (CPU / (bodies x steps x dt)), which "
        "puts engines with different steps on one scale; a window of sleeping bodies counts its whole span.",
        f"- **Measures**, every step of the observed window: penetration, box into box (separating-axis depth) or "
        "into the floor, deepest over the window and at its end; energy gain, the total's highest rise above its "
        f"start (gained: above {ENERGY_SHARE:g} of the energy above the lowest pose); max rise, the most a box rose "
        f"above its start; tunnelled, boxes found more than {DEEP:g} of the thinner box's thickness inside another or "
        "with their centre below the floor (and a thrown box that passed the pile's far side below its top); all "
        "asleep at, from the window's start; moving at the end, awake boxes faster than "
        f"{JITTER_SPEED * 100:g} cm/s (centre or corner); drift, the most a box moved, and a structure holds (stands) "
        f"while every box stays within {STAND_DRIFT * 100:g} cm of where it was built. Lengths scale with the boxes "
        "(tiny: 1/400, huge: 250), speeds with the square root.",
        f"- **Goals** (the engine issue's): cost <= Box2D v3's; penetration <= {scale_report.PENETRATION_LIMIT * 1e3:g}"
        f" mm throughout and <= {scale_report.REST_PENETRATION_LIMIT * 1e3:g} mm at the end of a window at rest; "
        "every structure standing; nothing tunnelling, gaining energy or jittering; every box asleep by the end of a "
        "window with sleeping at the defaults.",
        "- pyb2d3 binds Box2D 3.1; Box2D's later releases publish faster steps, so the ratios against Box2D v3 here "
        "flatter ours.",
    ]


def page_text(args, cases, windows, onbox, header: str, window: float, settle: float, overhead=None) -> str:
    cases_by = {c.name: c for c in cases}
    lines = [header, ""]
    lines += method(cases, window, settle, args.repeats, args.budget)
    lines += scale_report.loop_note(overhead or {}, windows)
    lines += ["", "### Cost at the defaults: us per body per simulated second, one thread", ""]
    lines += scale_report.cost_table(windows)
    lines += ["", "### Ours at the defaults against the engine goals", ""]
    lines += scale_report.goals_table(windows, cases_by)
    lines += ["", "### What each engine did", ""]
    lines += scale_report.quality_table(windows, cases_by)
    notes = scale_report.notes(windows)
    lines += ["", "Notes:", "", *notes] if notes else []
    if onbox:
        lines += ["", *onbox_lines(onbox)[0]]
    return "\n".join(lines)


def write_docs(text: str, page: Path = DOCS_PAGE, marker: str = MARKER) -> None:
    """Put ``text`` between the page's ``marker`` markers."""
    from agents.doc_sections import replace_section

    replace_section(marker, text, readme=page)


def write_json(path: Path, windows: list[Window], order) -> None:
    rows = []
    for w in windows:
        row = asdict(w)
        row.pop("snapshot", None)
        row["us_per_body_second"] = w.us_per_body_second
        rows.append(row)
    text = json.dumps({"windows": rows, "order": order}, indent=1, default=float)
    write_atomic(path, text.replace("NaN", "null"))


# -- the command ---------------------------------------------------------------------------------
def positive(low: float, high: float, kind=float):
    def check(text: str):
        try:
            value = kind(text)
        except ValueError:
            value = math.nan
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be in [{low:g}, {high:g}], got {text}")
        return value

    return check


def parse(argv) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small scenes, 0.5 s windows, 2 s budget")
    parser.add_argument("--cases", type=lambda t: t.split(","), help="comma-separated case names (default: all)")
    parser.add_argument("--engines", type=lambda t: t.split(","), help=f"comma-separated, of {list(ENGINE_ORDER)}")
    parser.add_argument("--budget", type=positive(0.01, 3600), help="CPU seconds per window, in [0.01, 3600]")
    parser.add_argument("--repeats", type=positive(1, 100, int), help="timed repeats, in [1, 100]")
    parser.add_argument("--no-onbox", action="store_true", help="leave out ours per throw of the envs")
    parser.add_argument("--json", type=Path, help="also write the measured windows to this file")
    parser.add_argument("--write-docs", action="store_true", help="write docs/engine_scale.md, its figure, README")
    args = parser.parse_args(argv)
    args.budget = args.budget if args.budget is not None else (QUICK_BUDGET if args.quick else BUDGET)
    args.repeats = args.repeats if args.repeats is not None else (QUICK_REPEATS if args.quick else REPEATS)
    available = [e for e in ENGINE_ORDER if e in (OURS, OURS_TUNED) or e in available_scene_engines()]
    engines = args.engines if args.engines is not None else available
    wrong = [e for e in engines if e not in available]
    if wrong:
        parser.error(f"--engines: {wrong} not available; choose from {available}")
    args.engines = [e for e in ENGINE_ORDER if e in engines]
    window, settle = (QUICK_WINDOW, QUICK_SETTLE) if args.quick else (WINDOW, SETTLE)
    try:
        args.suite = select(suite(args.quick, window, settle), args.cases)
    except ValueError as error:
        parser.error(str(error))
    args.window, args.settle = window, settle
    return args


def main(argv=None) -> None:
    args = parse(argv)
    import numba

    numba.set_num_threads(1)
    began = time.perf_counter()

    def log(line: str) -> None:
        print(f"[{time.perf_counter() - began:7.1f} s] {line}", flush=True)

    header = (
        f"`python -m benchmarks.engine_scale{' --quick' if args.quick else ''}`: one thread for every engine; "
        f"{load_text()}."
    )
    windows, order = run_suite(args.suite, args.engines, args.repeats, args.budget, log)
    log("the Python loop that steps the other engines")
    overhead = loop_overhead()
    onbox = []
    if not args.no_onbox and OURS in args.engines:
        log("ours per throw of BoxToss-v0 and BoxToss-OnBox-v0")
        onbox = onbox_rows(*((QUICK_ONBOX_THROWS, QUICK_BATCHES) if args.quick else (ONBOX_THROWS, BATCHES)))
    text = page_text(args, args.suite, windows, onbox, header, args.window, args.settle, overhead)
    text += (
        f"\n\nThe run took {(time.perf_counter() - began) / 60:.1f} min of wall time, "
        f"{time.process_time() / 60:.1f} min of this process's CPU."
    )
    print(text)
    if args.json is not None:
        write_json(args.json, windows, order)
    if args.write_docs:
        from agents.doc_sections import README

        write_docs(text, DOCS_PAGE)
        write_docs(scale_report.readme_summary(windows, header, onbox_lines(onbox)[1]), README, README_MARKER)
        scale_report.plot(windows, FIGURE)


if __name__ == "__main__":
    main()
