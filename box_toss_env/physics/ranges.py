"""The values the engine accepts: what it can honour in float64, checked where a scene is built.

docs/ranges.md is the one table of these ranges and the env's (``envs.task.TASK_RANGES``); a test
keeps it equal to the code. They are generous on purpose: the robust solver's tested range
(docs/stability.md) is narrower, and every value in here gives a finite, simulated result:
masses and sizes keep m, I, 1/m and 1/I and the impulses between them far from overflow, dt keeps
a run's step count an exact integer below ``MAX_STEPS``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .validation import check_range, fmt, interval


@dataclass(frozen=True)
class Range:
    """An allowed interval of one argument, with its unit."""

    low: float
    high: float
    unit: str = ""
    low_open: bool = False

    def check(self, name: str, value) -> float:
        """``value`` as a float; TypeError if it is not a real number, ValueError naming ``name`` and
        this interval if it lies outside."""
        return check_range(name, value, self.low, self.high, low_open=self.low_open, unit=self.unit)

    def __str__(self) -> str:
        return interval(self.low, self.high, self.low_open, False, self.unit)


MAX_STEPS = 10**8
"""The most time steps one run may take (``steps``, ``duration / dt``, the env's ``max_sim_time / dt``)."""


def check_step_count(duration_name: str, duration: float, dt: float) -> int:
    """The whole steps ``ceil(duration / dt)`` of a run, or a ValueError if there are more than MAX_STEPS."""
    count = math.ceil(duration / dt - 1e-9)
    if count > MAX_STEPS:
        raise ValueError(
            f"{duration_name} / dt must be at most {fmt(MAX_STEPS)} steps, got {duration:g} s / "
            f"{dt:g} s = {count:.3g} steps (a larger dt or a shorter {duration_name})"
        )
    return int(count)


ENGINE_RANGES = {
    "length": Range(1e-4, 1e3, "m"),  # Box, each side
    "width": Range(1e-4, 1e3, "m"),
    "mass": Range(1e-6, 1e6, "kg"),
    "dt": Range(1e-7, 1.0, "s"),
    "gravity": Range(-1e4, 1e4, "m/s^2"),
    "restitution": Range(0.0, 1.0),
    "friction": Range(0.0, 10.0),
    "penalty_stiffness": Range(0.0, math.inf, "N/m"),
    "restitution_threshold": Range(0.0, math.inf, "m/s"),
    "sleep_speed": Range(0.0, math.inf, "m/s"),
    "sleep_time": Range(0.0, math.inf, "s"),
    "penetration_slop": Range(0.0, math.inf, "m"),
    "solver_tolerance": Range(0.0, 1.0),
    "solver_iterations": Range(1, 10_000),
}
"""Scene and Box arguments. ``inf`` means any finite value: a stiffness too high for the seed scheme's
explicit spring is its documented fault (reported as ``NonFiniteStateError``), not a bad input."""
