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
"""

from __future__ import annotations

import argparse
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


def timed_run(start: Start, threads: int) -> tuple[float, float, np.ndarray]:
    """(wall seconds, load average before, final state) of one run of ``start`` on ``threads`` threads."""
    state, warm = start.state.copy(), start.warm.copy()
    load = os.getloadavg()[0]
    began = time.perf_counter()
    advance(start.scene, state, warm, start.steps, start.sleep, threads)
    return time.perf_counter() - began, load, state


def measure(start: Start, counts: tuple[int, ...], repeats: int) -> tuple[dict[int, list[float]], list[float], bool]:
    """Wall times per thread count over ``repeats`` interleaved repeats, the loads read, and whether every run
    ended in the same state bit for bit."""
    times: dict[int, list[float]] = {count: [] for count in counts}
    loads: list[float] = []
    first: np.ndarray | None = None
    identical = True
    for repeat in range(repeats):
        for count in counts if repeat % 2 == 0 else counts[::-1]:
            seconds, load, state = timed_run(start, count)
            times[count].append(seconds)
            loads.append(load)
            if first is None:
                first = state
            identical = identical and np.array_equal(first, state)
    return times, loads, identical


def table(rows: list[tuple[str, int, dict[int, list[float]], list[float], bool]], threads: int) -> str:
    header = (
        f"| case | bodies x steps | 1 thread, wall [s] | {threads} threads, wall [s] | speedup | load (1 min) "
        "| identical |\n|---|---:|---:|---:|---:|---:|---|"
    )
    lines = [header]
    for name, size, times, loads, identical in rows:
        one, many = statistics.median(times[1]), statistics.median(times[threads])
        spread = ", ".join(f"{a:.2f}/{b:.2f}" for a, b in zip(times[1], times[threads], strict=True))
        lines.append(
            f"| {name} | {size:,} | {one:.2f} | {many:.2f} | {one / many:.2f}x ({spread}) | "
            f"{min(loads):.2f}-{max(loads):.2f} | {'yes' if identical else 'NO'} |"
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
        f"repeats, their medians; {os.cpu_count()} cores, load {load:.2f} at the start.\n\n{text}"
    )


def main(argv=None) -> None:
    args = parse(argv)
    load = os.getloadavg()[0]
    rows = []
    for name in args.cases:
        start = CASES[name](args.seconds)
        times, loads, identical = measure(start, (1, args.threads), args.repeats)
        rows.append((name, start.scene.n_bodies * start.steps, times, loads, identical))
        print(f"{name}: done, load {os.getloadavg()[0]:.2f}", flush=True)
    text = table(rows, args.threads)
    print(text)
    if args.write_docs:
        replace_section(MARKER, docs_section(text, args.threads, args.repeats, load), readme=DOCS_PAGE)


if __name__ == "__main__":
    main()
