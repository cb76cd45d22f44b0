"""The precision report's constants and its first stage: the cases with closed-form answers
(``cases.exact_cases``), each method's error and wall time at dt = 2^-k, and the fitted order."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from benchmarks.other_engines import ENGINES
from box_toss_env.physics import Simulator, layout, make_settings

from .cases import ExactCase, dt_of, energy, exact_cases
from .timing import best_of, best_time

SOLVERS = ("seed", "robust")
EXPONENTS = tuple(range(5, 17))  # dt = 2^-k s
QUICK_EXPONENTS = (5, 8, 11)
QUICK_THROW_EXPONENTS = (6, 8, 10)
N_THROWS, QUICK_N_THROWS = 256, 16
THROW_SEED = 2024
REFERENCE_FACTOR_EXPONENT = 4  # the reference step is 2^4 = 16 times smaller than the finest measured
BLOW_UP_ENERGY_GAIN = 0.1  # a run ending with 10% more energy than it started with has blown up
ERROR_FLOOR = 1e-13  # errors below this are rounding; not used to fit orders
ACCEPT_FLOOR = {"position": 1e-12, "angle": 1e-10}  # [m], [deg]: reference changes below these are rounding
# what the env's default must achieve: landing face as the reference for >= 99% of throws, and (95th
# percentile over the throws that land on that face) within 1 cm and 1 degree of the reference pose
FACE_AGREEMENT_MIN, POSITION_ERROR_MAX, ANGLE_ERROR_MAX = 0.99, 0.01, 1.0
MIN_JUDGED_SHARE = 0.9  # the criterion is judged only if the reference resolves it for this share of the throws
RESOLVE_SHARE = 0.1  # a reference resolves the criterion where halving its step moves the landing < 10% of a threshold
ORDER_GOAL, ORDER_GOAL_SHARE = 1.0, 0.95  # landings converge: per-throw order of landing x >= 1 on >= 95% of throws
ORDER_FLOOR_FACTOR = 10.0  # a landing error below 10 times the reference's own half-step change is not fitted
ORDER_FLOOR = 1e-9  # [m] nor one below this
COLORS = {"seed": "tab:red", "robust": "tab:blue", "pymunk": "tab:green", "box2d": "tab:orange", "mujoco": "tab:purple"}


# -- 1. exact-answer cases ---------------------------------------------------------------------------
@dataclass
class Point:
    """One method at one dt on one case."""

    case: str
    method: str
    exponent: int
    error: float  # nan when the run went non-finite
    seconds: float  # wall time of the run [s]
    failure: str = ""  # "" when the run is valid, else why it failed

    @property
    def failed(self) -> bool:
        return bool(self.failure)


def failure_of(case: ExactCase, state: np.ndarray, finite: bool) -> str:
    """Why a final state counts as failed, or ""."""
    if not finite or not np.isfinite(state).all():
        return "non-finite"
    start = case.initial_energy()
    end = float(energy(case.box, case.base.gravity, state))
    if end > start + BLOW_UP_ENERGY_GAIN * abs(start):
        return f"blow-up (energy x{end / start:.3g})" if start > 0 else "blow-up (energy gain)"
    return ""


def measure_engine_case(case: ExactCase, solver: str, exponent: int, repeats: int, budget: float) -> Point:
    """Our engine on one case: a ``Simulator`` on raw arrays, single thread, timed."""
    dt = dt_of(exponent)
    scene = case.scene(solver, dt)
    simulator = Simulator.for_scene(scene, parallel=False)
    initial, params = scene.initial_state(), scene.body_params()
    settings = make_settings(scene, case.steps(dt), until_rest=False)
    state = initial.copy()
    stats = np.zeros((1, layout.STATS_SIZE))

    def run():
        state[:] = initial
        simulator.run(state, params, settings, stats)

    wall = best_time(run, repeats, budget)
    finite = stats[0, layout.STATUS] == layout.STATUS_OK
    failure = failure_of(case, state[0], finite)
    error = case.error(state[0], dt) if np.isfinite(state).all() else math.nan
    return Point(case.name, solver, exponent, error, wall, failure)


def measure_other_case(case: ExactCase, engine: str, exponent: int, repeats: int, budget: float) -> Point:
    """Another engine on one case through its adapter (``benchmarks.other_engines``); the time is that
    of its stepping loop alone."""
    dt = dt_of(exponent)
    results = []

    def measure():
        results.append(ENGINES[engine].simulate_toss(case.toss, dt, case.steps(dt)))
        return results[-1].wall_seconds

    try:
        wall = best_of(measure, repeats, budget)
    except Exception as error:  # an engine that raises on a case fails it, visibly
        return Point(case.name, engine, exponent, math.nan, math.nan, f"error: {type(error).__name__}")
    state = results[-1].final_state
    error = case.error(state, dt) if np.isfinite(state).all() else math.nan
    return Point(case.name, engine, exponent, error, wall, failure_of(case, state, True))


def measure_exact_cases(exponents, engines, repeats: int, budget: float, log=print) -> list[Point]:
    points = []
    for case in exact_cases():
        for method in (*SOLVERS, *engines):
            for exponent in exponents:
                if method in SOLVERS:
                    point = measure_engine_case(case, method, exponent, repeats, budget)
                else:
                    point = measure_other_case(case, method, exponent, repeats, budget)
                points.append(point)
            log(f"  {case.name:14} {method:7} done")
    return points


def fit_order(points: list[Point]) -> float:
    """Least-squares slope of log(error) against log(dt) over the valid points above rounding
    (nan with fewer than 3 such points)."""
    valid = [(dt_of(p.exponent), p.error) for p in points if not p.failed and p.error > ERROR_FLOOR]
    if len(valid) < 3:
        return math.nan
    dts, errors = np.array(valid).T
    return float(np.polyfit(np.log(dts), np.log(errors), 1)[0])
