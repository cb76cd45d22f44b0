"""The viewer panel's rows: the numeric ``Scene`` fields it shows (``Parameter``, stepped along a ladder or
typed), the toggles, the solver row, and the lanes of compare mode."""

from __future__ import annotations

from dataclasses import dataclass


# -- the panel's parameters ----------------------------------------------------------------------
@dataclass(frozen=True)
class Parameter:
    """A numeric field of ``Scene`` shown in the panel. The arrow keys move it along ``ladder``
    (to the nearest ladder value above or below the current one); any value can also be typed."""

    name: str  # the Scene field
    label: str
    unit: str
    ladder: tuple[float, ...]

    def next_value(self, current: float, direction: int) -> float:
        """The nearest ladder value above (``direction > 0``) or below ``current``; ``current``
        itself when the ladder ends there."""
        tolerance = 1e-9 * max(1.0, abs(current))
        if direction > 0:
            above = [v for v in self.ladder if v > current + tolerance]
            return min(above) if above else current
        below = [v for v in self.ladder if v < current - tolerance]
        return max(below) if below else current

    def format(self, value: float) -> str:
        return f"{value:.6g} {self.unit}".rstrip()


def _one_two_five(low_exponent: int, high_exponent: int) -> tuple[float, ...]:
    return tuple(m * 10.0**e for e in range(low_exponent, high_exponent + 1) for m in (1.0, 2.0, 5.0))


PARAMETERS = (
    Parameter(
        "dt",
        "time step size",
        "s",
        (0.0002, 0.0005, 0.001, 0.002, 0.0025, 0.004, 0.005, 0.0075, 0.01, 0.015, 0.02, 0.03, 0.05),
    ),
    Parameter("gravity", "gravity", "m/s^2", tuple(sorted({*range(-30, 1), -9.81}))),
    Parameter("penalty_stiffness", "penalty stiffness", "N/m", (0.0, *_one_two_five(0, 6))),
    Parameter("restitution", "restitution coefficient", "", tuple(round(0.05 * k, 2) for k in range(21))),
    Parameter(
        "friction",
        "friction coefficient",
        "",
        (0.0, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.5, 2.0),
    ),
)
TOGGLES = (("use_impulses", "use impulses"), ("use_penalty", "use penalty force"), ("boxes_collide", "boxes collide"))
PARAMETER_BY_NAME = {parameter.name: parameter for parameter in PARAMETERS}
ROWS = (*(parameter.name for parameter in PARAMETERS), *(name for name, _ in TOGGLES), "solver")
"""The panel's selectable rows, top to bottom: the five parameters, the three toggles, the solver."""
ROW_LABELS = {**{p.name: p.label for p in PARAMETERS}, **dict(TOGGLES), "solver": "solver"}
COMPARE_SOLVERS = ("seed", "robust")
"""The lanes of compare mode, left to right."""
