"""What the stability report measures with: its constants, a ``Check`` per point and solver, a ``Row``
per case, a single box's run (``Run``) and the report (``StabilityReport``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from box_toss_env.physics import NonFiniteStateError, Scene, simulate

from . import fuzz
from .cases import energy, lowest_corner

SOLVERS = ("robust", "seed")
DECLARED_RANGE = {
    "time step dt": "2^-14 to 2^-5 s",
    "penalty stiffness k": "1e2 to 1e9 N/m",
    "impact speed": "up to 200 m/s",
    "spin": "up to 600 rad/s",
    "aspect ratio": "up to 1:200",
    "mass": "1e-3 to 1e3 kg (material unchanged)",
    "restitution, friction": "e in [0, 1], mu in [0, 1.5]",
    "distance from the origin": "up to 1e5 m",
    "boxes that collide": "stacks of up to 10 boxes, mass ratio up to 1:1000, box-box impacts up to 200 m/s",
}
"""Where the robust default is meant to hold. Every point of every row is inside it."""

FULL_DTS = (5, 8, 11, 14)  # dt = 2^-k of the rows other than the map
QUICK_DTS = (5, 11)
MAP_STIFFNESS = tuple(10.0**e for e in range(2, 10))
MAP_DTS = tuple(range(5, 15))
QUICK_MAP_STIFFNESS = (1e2, 1e5, 1e8)
QUICK_MAP_DTS = (5, 9, 13)
ENERGY_ROUNDING = 1e-9  # relative energy change allowed for rounding
MAX_LISTED = 200  # a row with more points lists only some of them under "Every point"


@dataclass
class Check:
    """One solver on one parameter point of a row."""

    point: dict  # parameter name -> value, as shown
    solver: str
    passed: bool
    measured: str  # what was measured, as shown
    values: dict = field(default_factory=dict)


@dataclass
class Row:
    name: str
    title: str
    criterion: str
    declared: str  # the robust solver's declared range for this row
    checks: list[Check]
    smallest_failure: tuple | None = None  # random scenes: hypothesis's smallest robust failure

    def of(self, solver: str) -> list[Check]:
        return [c for c in self.checks if c.solver == solver]

    def passed(self, solver: str) -> bool:
        return all(c.passed for c in self.of(solver))

    def verdict(self, solver: str, limit: int = 4) -> str:
        checks = self.of(solver)
        failed = [c for c in checks if not c.passed]
        if not failed:
            return f"PASS {len(checks)}/{len(checks)}"
        where = "; ".join(point_text(c.point) for c in failed[:limit]) + ("; ..." if len(failed) > limit else "")
        return f"**FAIL** {len(checks) - len(failed)}/{len(checks)} (fails at {where})"


def point_text(point: dict) -> str:
    return ", ".join(f"{name} {value}" for name, value in point.items())


def k_text(k: float) -> str:
    return f"1e{round(math.log10(k))}"


# -- running a scene ------------------------------------------------------------------------------------
@dataclass
class Run:
    """A recorded run: states on the grid, or the reason there are none."""

    scene: Scene
    states: np.ndarray | None  # (T, 6)
    result: object | None
    error: str = ""

    @property
    def finite(self) -> bool:
        return self.states is not None and bool(np.isfinite(self.states).all())

    @property
    def box(self):
        return self.scene.boxes[0]

    def energy(self) -> np.ndarray:
        return energy(self.box, self.scene.gravity, self.states)

    def max_penetration(self) -> float:
        """Deepest any corner went below the floor, on the grid or inside the solver's substeps [m]."""
        return max(float(-lowest_corner(self.box, self.states).min()), float(self.result.max_penetration[0]), 0.0)

    def energy_gain(self) -> tuple[float, float]:
        """(largest rise of the total energy above its start [J], what is allowed for it [J]): rounding, plus
        m |g| times the deepest penetration, the potential energy a position correction may return when it
        pushes the box out (the robust solver moves positions, not velocities, to undo a penetration)."""
        e = self.energy()
        allowed = ENERGY_ROUNDING * abs(e[0]) + self.box.mass * abs(self.scene.gravity) * self.max_penetration()
        return float(e.max() - e[0]), allowed


def run_scene(scene: Scene, duration: float, until_rest: bool = False) -> Run:
    try:
        result = simulate(scene, duration=duration, until_rest=until_rest, record=True)
    except NonFiniteStateError as error:
        return Run(scene, None, None, f"non-finite at step {error.step}")
    return Run(scene, result.trajectory.state[:, 0], result)


def not_finite(run: Run, point: dict, solver: str) -> Check:
    return Check(point, solver, False, run.error or "non-finite")


# -- the report ---------------------------------------------------------------------------------------------------
@dataclass
class StabilityReport:
    quick: bool
    rows: list[Row]
    run_seconds: float = math.nan
    fuzz: list[fuzz.FuzzResult] = field(default_factory=list)  # the property-based fuzz (reports.fuzz)
    load: str = ""  # the machine's load when the report ran (``document.load``)

    def row(self, name: str) -> Row:
        return next(r for r in self.rows if r.name == name)

    def seed_beyond_line(self) -> tuple[int, int]:
        """(seed failures, seed points) beyond omega dt = 2 in the map."""
        beyond = [c for c in self.row("stiffness_map").of("seed") if c.values["omega_dt"] > 2.0]
        return sum(not c.passed for c in beyond), len(beyond)
