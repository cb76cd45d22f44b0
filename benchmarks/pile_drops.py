"""Dropped piles over many seeds at the engine's defaults: how deep any box goes into another or into the floor while
its pile drops, what the drop costs and when the pile sleeps. Prints one table; writes nothing.

    python -m benchmarks.pile_drops                                  # piles of 16 and 100, seeds 0-9, 3 s each
    python -m benchmarks.pile_drops --sizes 100 --seeds 3 --duration 2
    python -m benchmarks.pile_drops --sizes 1000 --layers 8 --seeds 3 --duration 2   # the engine benchmark's piles

Method. Each pile is ``scenes.pile(n, seed=s)`` as a user builds it (with ``--layers``, the engine benchmark's wide
pile of that many rows, ``scene_suite.wide_pile``), run by ``simulate`` at its defaults (islands at
rest sleep). The cost is one unrecorded run in thread CPU time (``time.thread_time``), per body per simulated second;
a recorded run of the same pile gives the measures (bit for bit the same run): the deepest penetration over every
step, box into box (separating-axis depth) or into the floor (``scene_quality.overlaps``), and when the last box fell
asleep. A size's row gives the mean and the largest over its seeds; the kernels are compiled before anything is
timed.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.scene_quality import box_arrays, overlaps
from benchmarks.scene_suite import wide_pile
from box_toss_env.physics import scenes, simulate

SIZES = (16, 100)
SEEDS = 10
DURATION = 3.0  # [s] the piles land and sleep within it (a pile of 100: by 1.6 s at most over 10 seeds)


def drop(n: int, seed: int, duration: float, layers: int | None = None) -> tuple[float, float, float]:
    """(us per body per simulated second, deepest penetration [m], the time the last box fell asleep [s], nan if
    one is awake at the end) of the pile of n boxes of ``seed`` dropped for ``duration`` (``layers``: the wide pile
    of that many rows)."""
    scene = scenes.pile(n, seed=seed) if layers is None else wide_pile(n, layers, seed)
    start = time.thread_time()
    simulate(scene, duration=duration)
    cost = 1e6 * (time.thread_time() - start) / (n * duration)
    result = simulate(scene, duration=duration, record=True)
    half = box_arrays(scene)[0]
    deepest = max(max(overlaps(state, half, np.zeros(n, np.bool_))) for state in result.trajectory.state)
    asleep = float(np.max(result.rest_time)) if np.all(result.at_rest) else float("nan")
    return cost, deepest, asleep


def table(rows: list[tuple[int, np.ndarray]], duration: float, layers: int | None = None) -> str:
    """A markdown table, a row per size: its seeds' mean and largest of each measure."""
    shape = "" if layers is None else f", {layers} rows wide"
    command = "python -m benchmarks.pile_drops" + ("" if layers is None else f" --layers {layers}")
    lines = [
        f"Dropped piles at the defaults{shape}, {duration:g} s each (`{command}`):",
        "",
        "| boxes | seeds | deepest penetration, mean / max [mm] | us per body per simulated second, mean / max "
        "| all asleep at, mean / max [s] |",
        "|---:|---:|---|---|---|",
    ]
    for n, runs in rows:
        cost, deepest, asleep = runs.T
        lines.append(
            f"| {n:,} | {len(runs)} | {1e3 * deepest.mean():.2f} / {1e3 * deepest.max():.2f} "
            f"| {cost.mean():.1f} / {cost.max():.1f} | {asleep.mean():.2f} / {asleep.max():.2f} |"
        )
    return "\n".join(lines)


def parse(argv) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=lambda t: [int(x) for x in t.split(",")], default=list(SIZES))
    parser.add_argument("--seeds", type=int, default=SEEDS, help="seeds 0 to N - 1 of each size, N in [1, 1000]")
    parser.add_argument("--duration", type=float, default=DURATION, help="simulated seconds, in (0, 60]")
    parser.add_argument("--layers", type=int, default=None, help="the engine benchmark's wide piles, rows in [1, 100]")
    args = parser.parse_args(argv)
    if not all(1 <= n <= 10_000 for n in args.sizes):
        parser.error(f"--sizes must each be in [1, 10000], got {args.sizes}")
    if not 1 <= args.seeds <= 1000:
        parser.error(f"--seeds must be in [1, 1000], got {args.seeds}")
    if not 0.0 < args.duration <= 60.0:
        parser.error(f"--duration must be in (0, 60], got {args.duration}")
    if args.layers is not None and not 1 <= args.layers <= 100:
        parser.error(f"--layers must be in [1, 100], got {args.layers}")
    return args


def main(argv=None) -> None:
    args = parse(argv)
    for n in args.sizes:  # compile (or load) the kernels before anything is timed
        drop(n, 0, 0.01, args.layers)
    rows = [
        (n, np.array([drop(n, seed, args.duration, args.layers) for seed in range(args.seeds)])) for n in args.sizes
    ]
    print(table(rows, args.duration, args.layers))


if __name__ == "__main__":
    main()
