"""What a second thread buys a large scene whose boxes collide: wall time of the same run on 1 and on N threads
(``simulate``'s and ``Simulator``'s ``threads``), and whether the results are the same bit for bit. Prints one
table; ``--write-docs`` also puts it in docs/engine_scale.md (its ``thread-scaling`` section).

    python -m benchmarks.thread_scaling [--cases NAMES] [--threads N] [--repeats R] [--seconds S] [--write-docs]

Cases (``CASES``), each at the scene's defaults as ``benchmarks.scene_suite`` builds it:

- ``large_pyramid``: Box2D's benchmark scene (5,050 boxes, sleeping off), one step of 1/60 s untimed, then the
  published 499 steps' time (8.3 s) timed, or ``--seconds``;
- ``pile 1000 drop``: the wide pile of 1,000 dropped from its built state, the suite's 2 s window (``simulate``'s
  default: islands at rest sleep);
- ``pile 1000 awake``: the same pile settled for the suite's 3 s (untimed, once), then 2 s kept awake.

Method. Each timed run starts from the same state and warm start (``warm_start_memory``) and is timed in wall time
(``time.perf_counter``: threads are what is measured, so CPU time would not show them); the thread counts
alternate within each repeat, their order swapped from one repeat to the next; the load average
(``os.getloadavg``, 1 min) is read before each run and printed with the times, since other work on the machine
takes a thread's core. The speedup is the ratio of the medians. Every run's final state is compared with the
first's: ``identical`` says whether all were equal bit for bit.

Control. Before each timed run the same thread count runs a plain parallel loop (``control_run``: CONTROL_REGIONS
parallel regions one after another, each the same arithmetic cut into N equal shares, about as short as the solver's
regions): on N threads it is nearly N times faster when the host gives the process N whole cores (each region's
start costs the rest), so its speedup, printed beside the case's, says what the machine gave the threads around the
case's runs (on a virtual machine the host decides: two runs of the same build a few minutes apart measured 0.88x
and 1.60x on the pile of 1,000 kept awake).
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from agents.doc_sections import DOCS, replace_section
from benchmarks.scene_suite import (
    BOX2D_HZ,
    LARGE_PYRAMID_STEPS,
    SETTLE,
    WINDOW,
    large_pyramid,
    wide_pile,
)
from benchmarks.suite_runs import NEVER_SLEEP, sleep_default
from box_toss_env.physics import Scene, Simulator, layout, make_settings, warm_start_memory

REPEATS = 3
CONTROL_REGIONS = 2_000  # parallel regions a control run starts, one after another
CONTROL_WORK = 5_000  # square roots in each share of a region (some 10 us on one thread)
DOCS_PAGE = DOCS / "engine_scale.md"
MARKER = "thread-scaling"


@dataclass(frozen=True)
class Start:
    """A run to time: the scene, its state and warm start at the start, its steps and whether islands sleep."""

    scene: Scene
    state: np.ndarray
    warm: np.ndarray
    steps: int
    sleep: bool


def advance(scene: Scene, state: np.ndarray, warm: np.ndarray, steps: int, sleep: bool, threads: int) -> None:
    """``steps`` steps of ``scene`` from ``state`` and ``warm`` (both advanced in place) on ``threads`` threads."""
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    settings = make_settings(scene, steps, until_rest=False, sleep=sleep)
    Simulator.for_scene(scene, threads=threads).run(state, scene.body_params(), settings, stats, warm_start=warm)


def prepared(scene: Scene, lead_in: float, timed: float, sleep: bool) -> Start:
    """The start of a timed run of ``timed`` s after ``lead_in`` s run untimed (on every thread)."""
    state, warm = scene.initial_state(), warm_start_memory(scene.n_bodies)
    lead_steps = round(lead_in / scene.dt)
    if lead_steps:
        advance(scene, state, warm, lead_steps, sleep, numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]  # numba sets its config at import
    return Start(scene, state, warm, max(round(timed / scene.dt), 1), sleep)


def pyramid_start(seconds: float | None) -> Start:
    scene = large_pyramid()[0].replace(sleep_time=NEVER_SLEEP)
    timed = (LARGE_PYRAMID_STEPS - 1) / BOX2D_HZ if seconds is None else seconds
    return prepared(scene, 1 / BOX2D_HZ, timed, False)


def drop_start(seconds: float | None) -> Start:
    return prepared(wide_pile(1000), 0.0, WINDOW if seconds is None else seconds, sleep_default())


def awake_start(seconds: float | None) -> Start:
    scene = wide_pile(1000)
    start = prepared(scene, SETTLE, WINDOW if seconds is None else seconds, True)
    return Start(scene.replace(sleep_time=NEVER_SLEEP), start.state, start.warm, start.steps, False)


CASES: dict[str, Callable[[float | None], Start]] = {
    "large_pyramid": pyramid_start,
    "pile 1000 drop": drop_start,
    "pile 1000 awake": awake_start,
}


@numba.njit(parallel=True, nogil=True)
def control_region(out: np.ndarray, work: int) -> None:
    """One parallel region: ``out.size`` equal shares of ``work`` square roots each, one share per thread."""
    for share in numba.prange(out.shape[0]):
        total = 0.0
        for i in range(work):
            total += math.sqrt(i + share)
        out[share] = total


@numba.njit(nogil=True)
def control_regions(out: np.ndarray, regions: int, work: int) -> None:
    for _ in range(regions):
        control_region(out, work)


def control_run(threads: int, shares: int) -> float:
    """Wall seconds of CONTROL_REGIONS regions of ``shares`` shares on ``threads`` threads (the same work on any
    number: on ``shares`` threads ideally ``shares`` times faster than on one)."""
    before = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        out = np.zeros(shares)
        began = time.perf_counter()
        control_regions(out, CONTROL_REGIONS, CONTROL_WORK)
        return time.perf_counter() - began
    finally:
        numba.set_num_threads(before)


@dataclass
class Timings:
    """A case's runs: wall seconds per thread count, the control's (``control_run``) beside each, the loads read
    before each run, and whether every run ended in the same state bit for bit."""

    times: dict[int, list[float]]
    control: dict[int, list[float]]
    loads: list[float]
    identical: bool


def timed_run(start: Start, threads: int) -> tuple[float, float, np.ndarray]:
    """(wall seconds, load average before, final state) of one run of ``start`` on ``threads`` threads."""
    state, warm = start.state.copy(), start.warm.copy()
    load = os.getloadavg()[0]
    began = time.perf_counter()
    advance(start.scene, state, warm, start.steps, start.sleep, threads)
    return time.perf_counter() - began, load, state


def measure(start: Start, counts: tuple[int, ...], repeats: int) -> Timings:
    """Wall times per thread count over ``repeats`` interleaved repeats, each run after a control run on as many
    threads (``control_run``, ``max(counts)`` shares), the loads read, and whether every run ended in the same
    state bit for bit."""
    timings = Timings({count: [] for count in counts}, {count: [] for count in counts}, [], True)
    control_run(max(counts), max(counts))  # compile the control, untimed
    first: np.ndarray | None = None
    for repeat in range(repeats):
        for count in counts if repeat % 2 == 0 else counts[::-1]:
            timings.control[count].append(control_run(count, max(counts)))
            seconds, load, state = timed_run(start, count)
            timings.times[count].append(seconds)
            timings.loads.append(load)
            if first is None:
                first = state
            timings.identical = timings.identical and np.array_equal(first, state)
    return timings


def table(rows: list[tuple[str, int, Timings]], threads: int) -> str:
    header = (
        f"| case | bodies x steps | 1 thread, wall [s] | {threads} threads, wall [s] | speedup | control's speedup "
        "| load (1 min) | identical |\n|---|---:|---:|---:|---:|---:|---:|---|"
    )
    lines = [header]
    for name, size, run in rows:
        one, many = statistics.median(run.times[1]), statistics.median(run.times[threads])
        spread = ", ".join(f"{a:.2f}/{b:.2f}" for a, b in zip(run.times[1], run.times[threads], strict=True))
        control = statistics.median(run.control[1]) / statistics.median(run.control[threads])
        each = ", ".join(f"{a / b:.2f}" for a, b in zip(run.control[1], run.control[threads], strict=True))
        lines.append(
            f"| {name} | {size:,} | {one:.2f} | {many:.2f} | {one / many:.2f}x ({spread}) | {control:.2f}x ({each}) | "
            f"{min(run.loads):.2f}-{max(run.loads):.2f} | {'yes' if run.identical else 'NO'} |"
        )
    return "\n".join(lines)


def parse(argv) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=lambda t: t.split(","), default=list(CASES), help=f"of {list(CASES)}")
    most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # numba sets its config at import
    parser.add_argument("--threads", type=int, default=min(2, most), help=f"threads against 1, in [2, {most}]")
    parser.add_argument("--repeats", type=int, default=REPEATS, help="interleaved repeats, in [1, 100]")
    parser.add_argument("--seconds", type=float, help="simulated seconds timed (default: each case's own)")
    parser.add_argument("--write-docs", action="store_true", help="put the table in docs/engine_scale.md")
    args = parser.parse_args(argv)
    unknown = [name for name in args.cases if name not in CASES]
    if unknown:
        parser.error(f"--cases: unknown {unknown}, choose from {list(CASES)}")
    if not 2 <= args.threads <= most:
        parser.error(f"--threads must be in [2, {most}], got {args.threads}")
    if not 1 <= args.repeats <= 100:
        parser.error(f"--repeats must be in [1, 100], got {args.repeats}")
    if args.seconds is not None and not 0.0 < args.seconds <= 3600.0:
        parser.error(f"--seconds must be in (0, 3600], got {args.seconds}")
    if args.write_docs and (args.seconds is not None or args.cases != list(CASES)):
        parser.error("--write-docs writes the whole table: it takes no --cases nor --seconds")
    return args


def docs_section(text: str, threads: int, repeats: int, load: float) -> str:
    """The page's section: how the table was made, then the table."""
    return (
        f"`python -m benchmarks.thread_scaling`: wall time on 1 and on {threads} threads, {repeats} interleaved "
        f"repeats, their medians; {os.cpu_count()} cores, load {load:.2f} at the start. The control's speedup: a plain "
        f"parallel loop's of short regions, timed before each run (the ratio of the medians, then each repeat's); "
        f"under {threads}x by its regions' start alone, lower still when the host does not give the process "
        f"{threads} whole cores.\n\n{text}"
    )


def main(argv=None) -> None:
    args = parse(argv)
    load = os.getloadavg()[0]
    rows = []
    for name in args.cases:
        start = CASES[name](args.seconds)
        rows.append((name, start.scene.n_bodies * start.steps, measure(start, (1, args.threads), args.repeats)))
        print(f"{name}: done, load {os.getloadavg()[0]:.2f}", flush=True)
    text = table(rows, args.threads)
    print(text)
    if args.write_docs:
        replace_section(MARKER, docs_section(text, args.threads, args.repeats, load), readme=DOCS_PAGE)


if __name__ == "__main__":
    main()
