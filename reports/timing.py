"""Wall-clock timing for the reports: a warm-up call, then the minimum of repeated calls.

Single thread throughout (the engine's kernels are built with ``parallel=False`` for timed runs),
so the figures compare methods, not core counts. The minimum of repeats is the least disturbed
measurement on a shared machine; calls too short for the clock are batched (as ``timeit`` does).
"""

from __future__ import annotations

import time
from collections.abc import Callable

MIN_BATCH_SECONDS = 2e-3
"""A timed batch lasts at least this long; shorter calls are repeated inside it [s]."""


def best_time(function: Callable[[], object], repeats: int = 3, budget: float = 5.0) -> float:
    """Seconds per call of ``function``: one warm-up call, then the minimum over up to ``repeats``
    timed batches (each at least ``MIN_BATCH_SECONDS`` long), stopping early once ``budget``
    seconds have been spent on timed batches (at least one batch is always timed)."""
    start = time.perf_counter()
    function()
    once = time.perf_counter() - start
    number = 1 if once >= MIN_BATCH_SECONDS else max(1, int(MIN_BATCH_SECONDS / max(once, 1e-7)))
    best = float("inf")
    spent = 0.0
    for _ in range(max(1, repeats)):
        start = time.perf_counter()
        for _ in range(number):
            function()
        elapsed = time.perf_counter() - start
        spent += elapsed
        best = min(best, elapsed / number)
        if spent >= budget:
            break
    return best


def best_of(measure: Callable[[], float], repeats: int = 3, budget: float = 5.0) -> float:
    """The minimum of ``measure()`` (a function that times itself and returns seconds) over up to
    ``repeats`` calls after one warm-up call, stopping once ``budget`` seconds have been measured."""
    measure()
    best = float("inf")
    spent = 0.0
    for _ in range(max(1, repeats)):
        seconds = measure()
        best = min(best, seconds)
        spent += seconds
        if spent >= budget:
            break
    return best


class Stopwatch:
    """Measures the wall time of a whole report run: ``with Stopwatch() as watch: ...; watch.seconds``."""

    def __enter__(self) -> Stopwatch:
        self.start = time.perf_counter()
        self.seconds = 0.0
        return self

    def __exit__(self, *exc) -> None:
        self.seconds = time.perf_counter() - self.start
