"""The precision report's second stage: seeded BoxToss throws against each solver's converged reference
(``Setting``, ``Reference``, ``measure_throws``), the tipping box, the recommended setting, and the
report's results (``PrecisionReport``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from box_toss_env.envs import task
from box_toss_env.physics import layout

from .cases import ENV_DEFAULTS, Throws, dt_of, exact_cases, wrap
from .document import dt_label, percent, seconds
from .precision_exact import (
    ACCEPT_FLOOR,
    ANGLE_ERROR_MAX,
    FACE_AGREEMENT_MIN,
    MIN_JUDGED_SHARE,
    ORDER_FLOOR,
    ORDER_FLOOR_FACTOR,
    POSITION_ERROR_MAX,
    REFERENCE_FACTOR_EXPONENT,
    RESOLVE_SHARE,
    SOLVERS,
    Point,
    fit_order,
)
from .timing import Stopwatch, best_time


# -- 2. seeded throws against a converged reference --------------------------------------------------------
def landing_differences(states: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per throw: |position difference| [m], |angle difference| [deg] and whether the face down agrees."""
    position = np.hypot(states[:, 0] - reference[:, 0], states[:, 1] - reference[:, 1])
    angle = np.degrees(np.abs(wrap(states[:, 2] - reference[:, 2])))
    with np.errstate(invalid="ignore"):
        same_face = task.faces_down(np.nan_to_num(states[:, 2])) == task.faces_down(reference[:, 2])
    same_face &= np.isfinite(states).all(axis=1)
    return position, angle, same_face


@dataclass
class Setting:
    """One solver at one dt on the throws."""

    solver: str
    exponent: int
    seconds_per_throw: float
    states: np.ndarray  # (n, 6) final states
    failed: np.ndarray  # (n,) non-finite or blown up
    at_rest: np.ndarray  # (n,) came to rest before max_sim_time
    # against the reference, filled by ``compare``
    face_agreement: float = math.nan  # over the accepted throws
    face_agreement_all: float = math.nan  # over every throw
    position_errors: np.ndarray = field(default_factory=lambda: np.zeros(0))  # accepted throws on the reference face
    angle_errors: np.ndarray = field(default_factory=lambda: np.zeros(0))
    position_errors_all: np.ndarray = field(default_factory=lambda: np.zeros(0))  # every throw on the reference face
    accepted_share: float = 1.0  # of the throws, those whose reference is accepted
    # over the throws whose reference resolves the criterion (``Reference.judged``), filled by ``compare``
    judged_share: float = 1.0
    judged_face_agreement: float = math.nan
    judged_position_errors: np.ndarray = field(default_factory=lambda: np.zeros(0))  # those on the reference face
    judged_angle_errors: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def percentiles(self, quantity: str) -> tuple[float, float, float]:
        values = self.position_errors if quantity == "position" else self.angle_errors
        if values.size == 0:
            return math.nan, math.nan, math.nan
        return tuple(float(v) for v in np.percentile(values, [50, 95, 100]))

    def judged(self, quantity: str, quantile: float = 95) -> float:
        """A percentile of the landing error over the judged throws on the reference face (nan if none)."""
        values = self.judged_position_errors if quantity == "position" else self.judged_angle_errors
        return float(np.percentile(values, quantile)) if values.size else math.nan

    @property
    def decidable(self) -> bool:
        """Whether the reference resolves the criterion for enough throws to judge it."""
        return self.judged_share >= MIN_JUDGED_SHARE

    def verdict(self) -> str:
        if not self.decidable:
            return "undecided"
        return "yes" if self.meets_criteria() else "no"

    def meets_criteria(self) -> bool:
        """No failed throw; over the judged throws, face agreement >= 99% and (on the reference face) 95th
        percentile landing errors <= 1 cm and <= 1 degree."""
        if not self.decidable:
            return False
        return (
            not self.failed.any()
            and self.judged_face_agreement >= FACE_AGREEMENT_MIN
            and self.judged("position") <= POSITION_ERROR_MAX
            and self.judged("angle") <= ANGLE_ERROR_MAX
        )


@dataclass
class Reference:
    """A solver's converged reference: the same solver at ``exponent`` (16 times smaller than the finest
    step measured), accepted per throw where halving its step changes the landing by less than a tenth
    of the smallest error reported for that throw (``compare``)."""

    solver: str
    exponent: int
    states: np.ndarray
    check_states: np.ndarray  # at half the reference step
    position_change: np.ndarray  # (n,) [m] between the two
    angle_change: np.ndarray  # (n,) [deg]
    valid: np.ndarray  # (n,) both finite, inside the bounds and on the same face
    accepted: np.ndarray  # (n,) bool, set by ``compare``
    tolerance: dict  # {"position": (n,) m, "angle": (n,) deg}, set by ``compare``
    judged: np.ndarray  # (n,) bool: moves less than a tenth of the criterion's thresholds, set by ``compare``
    seconds: float  # wall time of the two reference runs (parallel, not a timing figure)


def measure_setting(throws: Throws, solver: str, exponent: int, repeats: int, budget: float) -> Setting:
    run, state, stats = throws.runner(solver, dt_of(exponent), parallel=False)
    wall = best_time(run, repeats, budget)
    return Setting(
        solver,
        exponent,
        wall / throws.n,
        state.copy(),
        throws.blown_up(state, stats),
        ~np.isnan(stats[:, layout.REST_TIME]),
    )


def make_reference(throws: Throws, solver: str, exponent: int, parallel: bool = True) -> Reference:
    """The reference runs use every core (``parallel``): they are not timing figures."""
    with Stopwatch() as watch:
        states, stats = throws.run(solver, dt_of(exponent), parallel=parallel)
        check, check_stats = throws.run(solver, dt_of(exponent + 1), parallel=parallel)
    position, angle, same_face = landing_differences(check, states)
    valid = same_face & ~throws.blown_up(states, stats) & ~throws.blown_up(check, check_stats)
    return Reference(
        solver,
        exponent,
        states,
        check,
        np.where(valid, position, np.inf),
        np.where(valid, angle, np.inf),
        valid,
        valid.copy(),
        {},
        valid.copy(),
        watch.seconds,
    )


def compare(settings: list[Setting], reference: Reference) -> None:
    """Settle which throws the reference is accepted for, then fill each setting's landing errors.

    A throw is accepted where halving the reference step changes its landing position and angle by less
    than a tenth of the smallest error reported for it (over the measured settings; errors below the
    rounding floors count as those floors), so every error reported for it is resolved to 10%."""
    smallest = {}
    for quantity, index in (("position", 0), ("angle", 1)):
        errors = np.array([landing_differences(s.states, reference.states)[index] for s in settings])
        errors[np.array([s.failed for s in settings]) | ~np.isfinite(errors)] = np.inf
        smallest[quantity] = np.maximum(errors.min(axis=0), ACCEPT_FLOOR[quantity])
    reference.tolerance = {quantity: 0.1 * values for quantity, values in smallest.items()}
    reference.accepted = (
        reference.valid
        & (reference.position_change < reference.tolerance["position"])
        & (reference.angle_change < reference.tolerance["angle"])
    )
    reference.judged = (
        reference.valid
        & (reference.position_change < RESOLVE_SHARE * POSITION_ERROR_MAX)
        & (reference.angle_change < RESOLVE_SHARE * ANGLE_ERROR_MAX)
    )
    for setting in settings:
        fill_errors(setting, reference, reference.accepted)
        position, angle, same_face = landing_differences(setting.states, reference.states)
        same_face &= ~setting.failed
        judged = reference.judged
        setting.judged_share = float(judged.mean())
        setting.judged_face_agreement = float(same_face[judged].mean()) if judged.any() else math.nan
        setting.judged_position_errors = position[judged & same_face]
        setting.judged_angle_errors = angle[judged & same_face]


def fill_errors(setting: Setting, reference: Reference, accepted: np.ndarray) -> None:
    position, angle, same_face = landing_differences(setting.states, reference.states)
    same_face &= ~setting.failed
    setting.face_agreement_all = float(same_face.mean())
    setting.accepted_share = float(accepted.mean())
    setting.face_agreement = float(same_face[accepted].mean()) if accepted.any() else math.nan
    keep = accepted & same_face
    setting.position_errors_all = position[same_face]
    setting.position_errors = position[keep]
    setting.angle_errors = angle[keep]


def throw_orders(settings: list[Setting], reference: Reference) -> np.ndarray:
    """Per throw, the order of convergence of the landing x: the least-squares slope of log |x - x_ref|
    against log dt over the settings whose error is resolved (above ``ORDER_FLOOR_FACTOR`` times the
    reference's own change when its step is halved, and above ``ORDER_FLOOR``); nan where fewer than 3
    settings are (the landing is within the reference's resolution at nearly every dt) or any failed."""
    log_dt = np.log([dt_of(s.exponent) for s in settings])
    errors = np.array([np.abs(s.states[:, 0] - reference.states[:, 0]) for s in settings])  # (settings, throws)
    failed = np.array([s.failed for s in settings]).any(axis=0)
    change = np.abs(reference.check_states[:, 0] - reference.states[:, 0])
    orders = np.full(errors.shape[1], math.nan)
    for j in range(errors.shape[1]):
        resolved = np.isfinite(errors[:, j]) & (errors[:, j] > max(ORDER_FLOOR_FACTOR * change[j], ORDER_FLOOR))
        if not failed[j] and resolved.sum() >= 3:
            orders[j] = np.polyfit(log_dt[resolved], np.log(errors[resolved, j]), 1)[0]
    return orders


@dataclass
class OrderSummary:
    """The per-throw orders of landing x over some of the settings."""

    label: str  # which steps
    orders: np.ndarray  # (n,) nan where not measurable

    @property
    def measured(self) -> np.ndarray:
        return self.orders[np.isfinite(self.orders)]

    def share_at_least(self, order: float) -> float:
        return float((self.measured >= order).mean()) if self.measured.size else math.nan

    @property
    def median(self) -> float:
        return float(np.median(self.measured)) if self.measured.size else math.nan

    def text(self) -> str:
        if not self.measured.size:
            return f"{self.label}: not measurable"
        return (
            f"{self.label}: median {self.median:.2f}, >= 1 on {percent(self.share_at_least(1.0))}, >= 0.9 on "
            f"{percent(self.share_at_least(0.9))} of the {self.measured.size} throws with >= 3 resolved errors"
        )


def order_summaries(settings: list[Setting], reference: Reference) -> list[OrderSummary]:
    """Per-throw orders over every step, the coarse half and the fine half of the steps."""
    half = len(settings) // 2
    parts = [("every step", settings), ("coarse half", settings[:half]), ("fine half", settings[half:])]
    return [
        OrderSummary(
            f"{label} ({dt_label(part[0].exponent)} to {dt_label(part[-1].exponent)} s)", throw_orders(part, reference)
        )
        for label, part in parts
        if len(part) >= 3
    ]


def measure_throws(throws: Throws, exponents, repeats: int, budget: float, parallel: bool = True, log=print):
    """Per solver: the settings measured and the reference they are compared with."""
    results = {}
    for solver in SOLVERS:
        settings = []
        for exponent in exponents:
            settings.append(measure_setting(throws, solver, exponent, repeats, budget))
            log(f"  throws {solver:6} dt {dt_label(exponent):6} {seconds(settings[-1].seconds_per_throw)} per throw")
        reference = make_reference(throws, solver, max(exponents) + REFERENCE_FACTOR_EXPONENT, parallel)
        log(f"  throws {solver:6} reference dt {dt_label(reference.exponent)} and its half: {reference.seconds:.0f} s")
        compare(settings, reference)
        results[solver] = (settings, reference)
    return results


TIPPING_MATERIALS = ((0.5, 0.5), (0.5, 0.0), (0.0, 0.5))  # (e, mu)
TIPPING_EXPONENTS, QUICK_TIPPING_EXPONENTS = tuple(range(8, 21, 2)), (8, 12, 16)
TIPPING_TIME = 0.25  # [s]


def measure_tipping(exponents) -> dict:
    """{(e, mu): [(k, state at TIPPING_TIME)]} of the robust solver on ``cases.tipping_box``: a contact-mode impact."""
    from box_toss_env.physics import simulate

    from .cases import tipping_box

    return {
        (e, mu): [
            (k, simulate(tipping_box(e, mu, dt=dt_of(k)), duration=TIPPING_TIME).final_state[0]) for k in exponents
        ]
        for e, mu in TIPPING_MATERIALS
    }


def recommend(results) -> Setting | None:
    """The cheapest setting (time per throw) that meets the criteria, or None."""
    meeting = [s for settings, _ in results.values() for s in settings if s.meets_criteria()]
    return min(meeting, key=lambda s: s.seconds_per_throw) if meeting else None


# -- 3. the report ---------------------------------------------------------------------------------------
@dataclass
class PrecisionReport:
    quick: bool
    exponents: tuple
    throw_exponents: tuple
    engines: tuple
    missing: tuple
    points: list[Point]
    throws: Throws
    throw_results: dict
    tipping: dict
    run_seconds: float = math.nan

    def points_of(self, case: str, method: str) -> list[Point]:
        return [p for p in self.points if p.case == case and p.method == method]

    @property
    def methods(self) -> tuple:
        return (*SOLVERS, *self.engines)

    def orders(self) -> dict:
        return {
            (case.name, method): fit_order(self.points_of(case.name, method))
            for case in exact_cases()
            for method in self.methods
        }

    def throw_order(self, solver: str) -> float:
        """Fitted order of the median landing position error over every throw on the reference face."""
        settings, _ = self.throw_results[solver]
        points = [
            Point(
                "throws", solver, s.exponent, all_throws(s, 50), s.seconds_per_throw, "failed" if s.failed.any() else ""
            )
            for s in settings
        ]
        return fit_order(points)

    def env_default(self) -> Setting | None:
        exponent = -math.log2(ENV_DEFAULTS["dt"])
        settings, _ = self.throw_results[ENV_DEFAULTS["solver"]]
        return next((s for s in settings if s.exponent == exponent), None)


def all_throws(setting: Setting, quantile: float) -> float:
    """A percentile of the landing position error over every throw on the reference face (nan if none)."""
    values = setting.position_errors_all
    return float(np.percentile(values, quantile)) if values.size else math.nan
