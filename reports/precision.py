"""Error against run time (work-precision) of the seed scheme, the robust default and other engines.

    python -m reports.precision            # the full report: docs/precision.md, docs/figures/precision_*.png
    python -m reports.precision --quick    # a few points of each part, into build/reports/ (the tests run this)

Three stages, each a function:

1. ``measure_exact_cases``: the five cases with closed-form answers (``cases.exact_cases``), for each
   method at dt = 2^-k: the error of the state reached, and the wall time of the run;
2. ``measure_throws``: 256 seeded BoxToss throws, simulated until rest as the env does, for the seed
   and the robust solver at each dt: time per throw, and the landing pose (position, angle, face)
   against each solver's converged reference (``make_reference``);
3. ``write_report``: tables, fitted orders, the recommended env setting and three figures.

Timing is single-thread (``parallel=False``), a warm-up run then the minimum of repeats
(``timing``). A run that goes non-finite, or gains energy it cannot have, is marked failed and
kept in the tables and plots (never dropped).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmarks.other_engines import ENGINES, INSTALL_HINT, missing_engines
from box_toss_env.envs import task
from box_toss_env.files import write_atomic
from box_toss_env.physics import Simulator, layout, make_settings

from . import document
from .cases import ENV_DEFAULTS, STIFFNESS, ExactCase, Throws, dt_of, energy, exact_cases, seeded_throws, wrap
from .document import dt_label, percent, sci, seconds, table
from .timing import Stopwatch, best_of, best_time

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
COLORS = {"seed": "tab:red", "robust": "tab:blue", "pymunk": "tab:green", "box2d": "tab:orange",
          "mujoco": "tab:purple"}


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
        return (not self.failed.any() and self.judged_face_agreement >= FACE_AGREEMENT_MIN
                and self.judged("position") <= POSITION_ERROR_MAX and self.judged("angle") <= ANGLE_ERROR_MAX)


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
    return Setting(solver, exponent, wall / throws.n, state.copy(), throws.blown_up(state, stats),
                   ~np.isnan(stats[:, layout.REST_TIME]))


def make_reference(throws: Throws, solver: str, exponent: int, parallel: bool = True) -> Reference:
    """The reference runs use every core (``parallel``): they are not timing figures."""
    with Stopwatch() as watch:
        states, stats = throws.run(solver, dt_of(exponent), parallel=parallel)
        check, check_stats = throws.run(solver, dt_of(exponent + 1), parallel=parallel)
    position, angle, same_face = landing_differences(check, states)
    valid = same_face & ~throws.blown_up(states, stats) & ~throws.blown_up(check, check_stats)
    return Reference(solver, exponent, states, check, np.where(valid, position, np.inf),
                     np.where(valid, angle, np.inf), valid, valid.copy(), {}, valid.copy(), watch.seconds)


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
    reference.accepted = (reference.valid & (reference.position_change < reference.tolerance["position"])
                          & (reference.angle_change < reference.tolerance["angle"]))
    reference.judged = (reference.valid & (reference.position_change < RESOLVE_SHARE * POSITION_ERROR_MAX)
                        & (reference.angle_change < RESOLVE_SHARE * ANGLE_ERROR_MAX))
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
        return (f"{self.label}: median {self.median:.2f}, >= 1 on {percent(self.share_at_least(1.0))}, >= 0.9 on "
                f"{percent(self.share_at_least(0.9))} of the {self.measured.size} throws with >= 3 resolved errors")


def order_summaries(settings: list[Setting], reference: Reference) -> list[OrderSummary]:
    """Per-throw orders over every step, the coarse half and the fine half of the steps."""
    half = len(settings) // 2
    parts = [("every step", settings), ("coarse half", settings[:half]), ("fine half", settings[half:])]
    return [OrderSummary(f"{label} ({dt_label(part[0].exponent)} to {dt_label(part[-1].exponent)} s)",
                         throw_orders(part, reference)) for label, part in parts if len(part) >= 3]


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

    return {(e, mu): [(k, simulate(tipping_box(e, mu, dt=dt_of(k)), duration=TIPPING_TIME).final_state[0])
                      for k in exponents] for e, mu in TIPPING_MATERIALS}


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
        return {(case.name, method): fit_order(self.points_of(case.name, method))
                for case in exact_cases() for method in self.methods}

    def throw_order(self, solver: str) -> float:
        """Fitted order of the median landing position error over every throw on the reference face."""
        settings, _ = self.throw_results[solver]
        points = [Point("throws", solver, s.exponent, all_throws(s, 50), s.seconds_per_throw,
                        "failed" if s.failed.any() else "") for s in settings]
        return fit_order(points)

    def env_default(self) -> Setting | None:
        exponent = -math.log2(ENV_DEFAULTS["dt"])
        settings, _ = self.throw_results[ENV_DEFAULTS["solver"]]
        return next((s for s in settings if s.exponent == exponent), None)


def run(quick: bool = False, log=print) -> PrecisionReport:
    """Measure everything the report shows."""
    with Stopwatch() as watch:
        exponents = QUICK_EXPONENTS if quick else EXPONENTS
        throw_exponents = QUICK_THROW_EXPONENTS if quick else EXPONENTS
        repeats, budget = (1, 0.5) if quick else (3, 4.0)
        missing = tuple(missing_engines())
        engines = tuple(name for name in ENGINES if name not in missing)
        log("exact-answer cases")
        points = measure_exact_cases(exponents, engines, repeats, budget, log)
        log("seeded throws")
        throws = seeded_throws(QUICK_N_THROWS if quick else N_THROWS, THROW_SEED)
        throw_results = measure_throws(throws, throw_exponents, repeats, budget, parallel=not quick, log=log)
        tipping = measure_tipping(QUICK_TIPPING_EXPONENTS if quick else TIPPING_EXPONENTS)
    return PrecisionReport(quick, exponents, throw_exponents, engines, missing, points, throws, throw_results,
                           tipping, watch.seconds)


def error_cell(point: Point) -> str:
    if point.failed:
        return f"FAIL: {point.failure}" + ("" if math.isnan(point.error) else f" ({sci(point.error)})")
    return sci(point.error)


THROW_HEADER = ["dt [s]", "time per throw", "failed", "at rest", "face agreement", "position error p95 [m]",
                "angle error p95 [deg]", "meets criterion", "face agr. (accepted)",
                "position error [m] p50 / p95 / max (accepted)", "angle error [deg] p50 / p95 / max (accepted)"]


def throw_rows(settings: list[Setting]) -> list[list[str]]:
    rows = []
    for s in settings:
        p50, p95, pmax = s.percentiles("position")
        a50, a95, amax = s.percentiles("angle")
        rows.append([dt_label(s.exponent), seconds(s.seconds_per_throw), str(int(s.failed.sum())),
                     percent(s.at_rest.mean()), percent(s.judged_face_agreement), sci(s.judged("position")),
                     sci(s.judged("angle")), s.verdict(), percent(s.face_agreement),
                     f"{sci(p50)} / {sci(p95)} / {sci(pmax)}", f"{sci(a50)} / {sci(a95)} / {sci(amax)}"])
    return rows


def describe(setting: Setting | None) -> str:
    if setting is None:
        return "none"
    return f"{setting.solver} at dt = {dt_label(setting.exponent)} s"


def summary_rows(report: PrecisionReport) -> list[list[str]]:
    """The short table of docs/reports.md: per solver, the env's dt and the finest dt."""
    rows = []
    default = report.env_default()
    best = recommend(report.throw_results)
    picks = []
    for solver in SOLVERS:
        settings, _ = report.throw_results[solver]
        exponents = {s.exponent for s in settings}
        for exponent in sorted({-int(math.log2(ENV_DEFAULTS["dt"])), max(exponents)} & exponents):
            picks.append(next(s for s in settings if s.exponent == exponent))
    if best is not None and all(best is not s for s in picks):
        picks.append(best)
    for s in picks:
        note = []
        if s is default:
            note.append("env default")
        if s is best:
            note.append("recommended")
        rows.append([f"{s.solver}, dt = {dt_label(s.exponent)} s" + (f" ({', '.join(note)})" if note else ""),
                     seconds(s.seconds_per_throw), str(int(s.failed.sum())), percent(s.judged_face_agreement),
                     sci(s.judged("position", 50)), sci(s.judged("position")), sci(s.judged("angle")),
                     f"{s.judged_share:.0%}", s.verdict()])
    return rows


def write_report(report: PrecisionReport, out: Path, readme: Path | None = None) -> Path:
    """Write ``precision.md`` and its figures into ``out`` (figures in ``out/figures``); with ``readme``,
    rewrite the report's block of docs/reports.md."""
    out.mkdir(parents=True, exist_ok=True)
    figures = out / "figures"
    names = {"work": "precision_work.png", "order": "precision_order.png", "faces": "precision_faces.png"}
    plot_work_precision(report, figures / names["work"])
    plot_orders(report, figures / names["order"])
    plot_faces(report, figures / names["faces"])
    path = out / "precision.md"
    write_atomic(path, markdown(report, names))
    if readme is not None:
        document.update_readme("precision", readme_block(report), readme)
    return path


def recommendation_text(report: PrecisionReport) -> str:
    default, best = report.env_default(), recommend(report.throw_results)
    criteria = (f"the cheapest setting (wall time per throw) with no failed throw, landing-face agreement "
                f">= {FACE_AGREEMENT_MIN:.0%} with the reference, and 95th-percentile landing errors (over the "
                f"throws on the reference face) <= {POSITION_ERROR_MAX * 100:g} cm and <= {ANGLE_ERROR_MAX:g} degree")
    lines = [f"BoxToss-v0 simulates with `solver={ENV_DEFAULTS['solver']!r}`, `dt={ENV_DEFAULTS['dt']!r}` "
             f"(= {dt_label(round(-math.log2(ENV_DEFAULTS['dt'])))} s) by default. The criterion is {criteria}."]
    undecided = [s for settings, _ in report.throw_results.values() for s in settings if not s.decidable]
    if best is None and any(s.solver == "robust" for s in undecided):
        shares = sorted({f"{s.solver} {s.judged_share:.0%}" for s in undecided})
        lines.append(f"**No setting can be certified**: judging the criterion needs a reference that moves by less "
                     f"than a tenth of its thresholds ({RESOLVE_SHARE * POSITION_ERROR_MAX * 1000:g} mm, "
                     f"{RESOLVE_SHARE * ANGLE_ERROR_MAX:g} degree) when its step is halved, for at least "
                     f"{MIN_JUDGED_SHARE:.0%} of the throws; it does so for only {', '.join(shares)} of them. "
                     "The solver's landings do not converge with dt (see Findings).")
    elif best is None:
        lines.append("**No measured setting meets the criterion** (see the throw tables below for how close each "
                     "comes).")
    else:
        lines.append(f"The cheapest setting that meets it is **{describe(best)}** "
                     f"({seconds(best.seconds_per_throw)} per throw; face agreement "
                     f"{percent(best.judged_face_agreement)}, landing errors {sci(best.judged('position'))} m and "
                     f"{sci(best.judged('angle'))} degree at the 95th percentile).")
    if default is not None:
        verdict = ("cannot be judged against" if not default.decidable else
                   "meets" if default.meets_criteria() else "does not meet")
        lines.append(f"The env default {verdict} it: {seconds(default.seconds_per_throw)} per throw; over the "
                     f"{int(round(default.judged_share * report.throws.n))} judged throws, face agreement "
                     f"{percent(default.judged_face_agreement)} and landing position error "
                     f"{sci(default.judged('position', 50))} m median, {sci(default.judged('position'))} m at the "
                     f"95th percentile; over all throws, face agreement {percent(default.face_agreement_all)} and "
                     f"{sci(all_throws(default, 95))} m at the 95th percentile.")
        if best is not None and best is not default:
            cheaper = best.seconds_per_throw < default.seconds_per_throw
            lines.append(f"**Recommendation: switch the env default to {describe(best)}** "
                         + ("(cheaper, and it meets the criterion)." if cheaper else
                            "(the env default does not meet the criterion; this is the cheapest setting that does)."))
        elif best is default:
            lines.append("That is why the env uses it: it is the cheapest setting whose landings can be trusted.")
    return "\n\n".join(lines)


def markdown(report: PrecisionReport, figures: dict) -> str:
    cases = exact_cases()
    orders = report.orders()
    parts = [
        "# Precision: error against run time",
        "",
        f"Generated by `python -m reports.precision{' --quick' if report.quick else ''}` in "
        f"{report.run_seconds / 60:.1f} min on {document.machine()}. Every number and figure below comes from "
        "that command; edit the code in `reports/`, not this file.",
        "",
        "## What is measured",
        "",
        f"- **Methods**: the seed scheme (`solver=\"seed\"`) and the robust default (`solver=\"robust\"`) of "
        f"`box_toss_env.physics` at dt = 2^-k s for k = {report.exponents[0]}..{report.exponents[-1]}; "
        + (f"{', '.join(report.engines)} (through `benchmarks/other_engines.py`, with its documented settings) "
           "on the exact-answer cases at the same dt grid." if report.engines else "no other engine installed.")
        + (f" Not installed, so not shown: {', '.join(report.missing)} ({INSTALL_HINT})." if report.missing else ""),
        "- Neither solver has a substep setting: n substeps of an outer step h would be the grid step h / n, "
        "which the dt sweep covers (the robust solver splits a contact step by itself only where the box turns "
        "more than 0.05 rad in it). The env takes one outer step per throw.",
        f"- **Material**: the env's penalty stiffness k = {STIFFNESS:g} N/m in every case (the seed scheme's "
        "explicit spring is unstable at the coarse steps for it, which is part of what it costs).",
        "- **Timing**: wall time of one run of a case (or per throw, for the throws: 256 throws in one "
        "single-thread engine call, divided by 256), a warm-up run then the minimum of up to 3 repeats. "
        "Our engine runs compiled kernels on raw arrays (`Simulator`); the other engines are stepped from "
        "Python as their users would, so their times include that per-step call.",
        f"- **Failures**: a run whose state goes non-finite, or that ends with more than "
        f"{BLOW_UP_ENERGY_GAIN:.0%} more energy than it started with (a throw: lands where its energy cannot take it, "
        "outside the env's observation bounds) is marked FAIL; it stays in the tables and is drawn as a cross.",
        "",
        "## The env's default setting",
        "",
        recommendation_text(report),
        "",
        "## 256 seeded BoxToss throws" if not report.quick else f"## {report.throws.n} seeded BoxToss throws",
        "",
        f"BoxToss-v0 with its default arguments: release poses, targets and dynamics from the env's own sampling "
        f"(`task.sample_episodes`) and one fixed action per throw, uniform in [-1, 1]^3, all from "
        f"`numpy.random.default_rng({report.throws.seed})`. Each throw is simulated until the box rests (at most "
        f"{report.throws.config.max_sim_time:g} s), as the env does; the landing pose is the final state.",
        "",
        "Each solver is compared with its own converged reference: the same solver at a step 16 times smaller "
        "than the finest measured, accepted for a throw only where halving the reference step keeps the face "
        "and changes the landing position and angle by less than a tenth of the smallest error reported for "
        f"that throw (over the measured settings; floors {ACCEPT_FLOOR['position']:g} m and "
        f"{ACCEPT_FLOOR['angle']:g} deg for rounding), so every error reported for it is resolved to 10%: the "
        "'(accepted)' columns. The criterion for the env's setting is judged on the throws whose reference moves by "
        f"less than a tenth of the criterion's thresholds ({RESOLVE_SHARE * POSITION_ERROR_MAX * 1000:g} mm, "
        f"{RESOLVE_SHARE * ANGLE_ERROR_MAX:g} degree, same face) when its step is halved, which resolves every "
        f"verdict to 10%, and only if they are at least {MIN_JUDGED_SHARE:.0%} of the throws: the first columns "
        "(face agreement over those throws; errors over those of them landing on the reference's face).",
        "",
    ]
    for solver in SOLVERS:
        settings, reference = report.throw_results[solver]
        change = reference.position_change[reference.valid]
        p50, p95 = (np.percentile(change, [50, 95]) if change.size else (math.nan, math.nan))
        parts += [
            f"### {solver}",
            "",
            f"Reference dt = {dt_label(reference.exponent)} s, checked at {dt_label(reference.exponent + 1)} s "
            f"({reference.seconds:.0f} s for both{'' if report.quick else ', on all cores'}): judged for "
            f"**{int(reference.judged.sum())}**, accepted for **{int(reference.accepted.sum())} of "
            f"{report.throws.n}** throws. Halving the reference step changes the face (or fails) for "
            f"{int((~reference.valid).sum())} throws, and moves the landing position of the others by "
            f"{sci(p50)} m median, {sci(p95)} m at the 95th percentile. Fitted order of the median position "
            f"error over all throws on the reference face: {order_text(report.throw_order(solver))}.",
            "",
            "Per-throw order of convergence of the landing x (slope of log |x - x_ref| against log dt, fitted over the "
            f"steps whose error is above {ORDER_FLOOR_FACTOR:g} times the reference's own half-step change and "
            f"{ORDER_FLOOR:g} m): " + "; ".join(summary.text() for summary in order_summaries(settings, reference))
            + ".",
            "",
            table(THROW_HEADER, throw_rows(settings)),
            "",
        ]
    parts += [
        f"![landing-face agreement against cost](figures/{figures['faces']})",
        "",
        "## Cases with exact answers",
        "",
        f"Each error is measured on the state reached at the end of the run; wall time is per run. A robust "
        f"error of 0 means exact to the last bit; errors below {ERROR_FLOOR:g} are rounding and are drawn at that "
        "floor.",
        "",
    ]
    for case in cases:
        header = ["dt [s]"] + [f"{m} error" for m in report.methods] + [f"{m} time" for m in report.methods]
        rows = []
        for exponent in report.exponents:
            cells = [next(p for p in report.points_of(case.name, m) if p.exponent == exponent) for m in report.methods]
            rows.append([dt_label(exponent)] + [error_cell(p) for p in cells] + [seconds(p.seconds) for p in cells])
        parts += [
            f"### {case.title}",
            "",
            f"Exact answer: {case.answer}. Error: {case.error_name}. Simulated: {case.duration:.3g} s "
            f"(`reports/cases.py`, `{case.name}`).",
            "",
            table(header, rows),
            "",
        ]
    order_rows = [[case.title] + [order_text(orders[(case.name, m)], report.points_of(case.name, m))
                                  for m in report.methods] for case in cases]
    parts += [
        "### Fitted order (slope of log error against log dt)",
        "",
        "Over the valid points above rounding; 'exact' where every valid error is at rounding level.",
        "",
        table(["case"] + list(report.methods), order_rows),
        "",
        f"![error against run time](figures/{figures['work']})",
        "",
        f"![error against dt with fitted orders](figures/{figures['order']})",
        "",
        "## Findings",
        "",
        findings(report),
        "",
        "### A contact-mode impact against dt (robust solver)",
        "",
        f"`cases.tipping_box`: the 40 x 20 cm, 2 kg toss box standing on one corner at 0.3 rad and sliding at 1 m/s "
        f"tips over; its other corner hits the floor while the first is held. State at t = {TIPPING_TIME:g} s:",
        "",
        tipping_table(report),
        "",
    ]
    return "\n".join(parts)


def order_text(order: float, points: list[Point] | None = None) -> str:
    if not math.isnan(order):
        return f"{order:.2f}"
    if points and all(not p.failed and p.error <= ERROR_FLOOR for p in points):
        return "exact"
    return "-"


def findings(report: PrecisionReport) -> str:
    """The closing notes, every number read from the measurements."""
    lines = []
    for solver in SOLVERS:
        settings, reference = report.throw_results[solver]
        finest = settings[-1]
        ok = [s for s in settings if not s.failed.any()]
        coarsest_ok = min(ok, key=lambda s: s.exponent) if ok else None
        lines.append(
            f"- **{solver}**: on the throws, failures (non-finite or blown up) at "
            f"{', '.join(dt_label(s.exponent) for s in settings if s.failed.any()) or 'no dt'}; "
            f"the coarsest dt without one is {dt_label(coarsest_ok.exponent) if coarsest_ok else 'none'}. "
            f"At the finest dt ({dt_label(finest.exponent)}) it lands on the reference face for "
            f"{percent(finest.face_agreement_all)} of all throws, with landing position errors "
            f"{sci(all_throws(finest, 50))} m median and {sci(all_throws(finest, 95))} m at the 95th percentile (over "
            f"all throws on the reference face); its reference is converged (accepted) for "
            f"{int(reference.accepted.sum())}/{report.throws.n} throws.")
    orders = report.orders()
    for solver in SOLVERS:
        texts = [f"{case.title.lower()} {order_text(orders[(case.name, solver)], report.points_of(case.name, solver))}"
                 for case in exact_cases()]
        lines.append(f"- Fitted orders of the {solver} solver on the exact-answer cases: {'; '.join(texts)}.")
    _, robust_reference = report.throw_results["robust"]
    change = robust_reference.position_change
    moved, flipped = int((change > 1e-3).sum()), int((~robust_reference.valid).sum())
    lines.append(f"- Halving the robust solver's reference step ({dt_label(robust_reference.exponent)} s) moves the "
                 f"landing by more than 1 mm for {moved} of {report.throws.n} throws and changes the face of "
                 f"{flipped}.")
    lines.append("- " + convergence_text(report))
    spread = tipping_spread(report)
    coupled, others = spread[TIPPING_MATERIALS[0]], max(spread[TIPPING_MATERIALS[1]], spread[TIPPING_MATERIALS[2]])
    verdict = ("does not converge with dt" if coupled > max(10.0 * others, RESOLVE_SHARE * POSITION_ERROR_MAX)
               else "settles with dt")
    lines.append(
        f"- A contact-mode impact with both restitution and friction (the tipping-box table: a corner slams down "
        f"while the box is held by its other corner) {verdict}: its state at {TIPPING_TIME:g} s varies by "
        f"{sci(coupled)} over the three finest steps, against {sci(spread[TIPPING_MATERIALS[2]])} with e = 0 and "
        f"{sci(spread[TIPPING_MATERIALS[1]])} with mu = 0.")
    return "\n".join(lines)


def convergence_text(report: PrecisionReport) -> str:
    """Whether the robust solver's landings converge at first order: the per-throw order of landing x over every
    step measured, against the goal (>= 1 on >= 95% of the throws), as measured."""
    settings, reference = report.throw_results["robust"]
    summaries = order_summaries(settings, reference)
    every, fine = summaries[0], summaries[-1]
    share = every.share_at_least(ORDER_GOAL)
    met = share >= ORDER_GOAL_SHARE
    change = reference.position_change[reference.valid]
    settles = float(np.percentile(change, 95)) if change.size else math.nan
    return (f"Convergence of the robust solver's landings: its reference settles (halving its step moves the landing "
            f"by {sci(settles)} m at the 95th percentile), and the per-throw order of landing x is >= {ORDER_GOAL:g} "
            f"on {percent(share)} of the throws ({every.label}; median {every.median:.2f}; >= 0.9 on "
            f"{percent(every.share_at_least(0.9))}; {fine.label}: median {fine.median:.2f}, >= {ORDER_GOAL:g} on "
            f"{percent(fine.share_at_least(ORDER_GOAL))}). The goal of order >= {ORDER_GOAL:g} on "
            f">= {ORDER_GOAL_SHARE:.0%} of the throws is {'met' if met else 'not met'}: the solver is first order "
            "in dt in the sense of these figures, no more.")


def tipping_spread(report: PrecisionReport) -> dict:
    """{(e, mu): largest spread of x [m], vx or vy [m/s] over the three finest steps}."""
    return {key: float(np.ptp(np.array([state[[0, 3, 4]] for _, state in runs[-3:]]), axis=0).max())
            for key, runs in report.tipping.items()}


def tipping_table(report: PrecisionReport) -> str:
    header = ["dt [s]"] + [f"e {e:g}, mu {mu:g}: x [m], (vx, vy) [m/s]" for e, mu in TIPPING_MATERIALS]
    exponents = [k for k, _ in report.tipping[TIPPING_MATERIALS[0]]]
    rows = [[dt_label(k)] + [f"{runs[i][1][0]:.5f}, ({runs[i][1][3]:+.5f}, {runs[i][1][4]:+.5f})"
                             for runs in report.tipping.values()] for i, k in enumerate(exponents)]
    spread = tipping_spread(report)
    rows.append(["spread over the 3 finest"] + [sci(spread[key]) for key in TIPPING_MATERIALS])
    return table(header, rows)


def readme_block(report: PrecisionReport) -> str:
    default, best = report.env_default(), recommend(report.throw_results)
    return "\n".join([
        f"**Error against run time** (`docs/precision.md`): `python -m reports.precision` "
        f"({report.run_seconds / 60:.1f} min on {document.machine().split(',')[1].strip()}; "
        "`--quick` for the reduced version the tests run; both need the `reports` extra, "
        "`pip install -e '.[reports]'`: matplotlib, hypothesis and the other engines). Landing pose of "
        f"{report.throws.n} seeded BoxToss-v0 throws against each solver's reference 16 times finer, over the throws "
        "whose reference moves less than a tenth of the criterion's thresholds when its step is halved (errors: "
        "those landing on the reference's face):",
        "",
        table(["setting", "time per throw", "failed", "face agreement", "position error p50 [m]",
               "position error p95 [m]", "angle error p95 [deg]", "throws judged", "meets criterion"],
              summary_rows(report)),
        "",
        f"Env default: {describe(default)}; cheapest setting with >= 99% face agreement and <= 1 cm, <= 1 degree: "
        + (describe(best) if best is not None else "none can be certified (see the report)") + ".",
        "",
        convergence_text(report),
    ])


# -- figures ------------------------------------------------------------------------------------------------------
AXIS_LABELS = {"free_flight": "pose error at t = 1 s [m]", "corner_impact": "velocity error at t = 0.25 s [m/s]",
               "flat_drop": "apex error [m]", "slide": "stopping distance error [m]",
               "resting": "drift at t = 10 s [m]"}


def _panels(n: int):
    import matplotlib.pyplot as plt

    columns = 3
    rows = math.ceil(n / columns)
    figure, axes = plt.subplots(rows, columns, figsize=(5.2 * columns, 4.4 * rows), squeeze=False,
                                layout="constrained")
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    return figure, list(axes.flat[:n])


def _draw_curve(ax, xs, errors, failed, labels, color, label, style="-"):
    """One method's points: valid ones as dots, failed ones as crosses (drawn a decade above the largest
    error when they have none), points without a value (nothing to compare) left out."""
    xs = np.array(xs, dtype=float)
    errors = np.array(errors, dtype=float)
    failed = np.array(failed, dtype=bool)
    finite = errors[np.isfinite(errors)]
    ceiling = (finite.max() if finite.size else 1.0) * 10
    shown = np.where(np.isfinite(errors), np.maximum(errors, ERROR_FLOOR), np.where(failed, ceiling, np.nan))
    drawn = np.isfinite(shown)
    ax.plot(xs[drawn], shown[drawn], style, color=color, alpha=0.5)
    ax.plot(xs[drawn & ~failed], shown[drawn & ~failed], "o", color=color, ms=4, label=label)
    if (drawn & failed).any():
        ax.plot(xs[drawn & failed], shown[drawn & failed], "x", color=color, ms=7, mew=2)
    for x, y, text in zip(xs[drawn], shown[drawn], np.array(labels, dtype=object)[drawn], strict=True):
        ax.annotate(text, (x, y), textcoords="offset points", xytext=(3, 3), fontsize=6, color=color)


def all_throws(setting: Setting, quantile: float) -> float:
    """A percentile of the landing position error over every throw on the reference face (nan if none)."""
    values = setting.position_errors_all
    return float(np.percentile(values, quantile)) if values.size else math.nan


def plot_work_precision(report: PrecisionReport, path: Path) -> None:
    cases = exact_cases()
    figure, axes = _panels(len(cases) + 1)
    for ax, case in zip(axes, cases, strict=False):
        for method in report.methods:
            points = report.points_of(case.name, method)
            _draw_curve(ax, [p.seconds for p in points], [p.error for p in points], [p.failed for p in points],
                        [str(p.exponent) for p in points], COLORS[method], method)
        ax.set(xscale="log", yscale="log", title=case.title, xlabel="wall time per run [s]",
               ylabel=AXIS_LABELS[case.name])
    ax = axes[-1]
    for solver in SOLVERS:
        settings, _ = report.throw_results[solver]
        _draw_curve(ax, [s.seconds_per_throw for s in settings], [all_throws(s, 95) for s in settings],
                    [s.failed.any() for s in settings], [str(s.exponent) for s in settings], COLORS[solver], solver)
    ax.axhline(POSITION_ERROR_MAX, color="gray", ls=":", lw=1)
    ax.set(xscale="log", yscale="log", title=f"{report.throws.n} BoxToss throws (all, on the reference face)",
           xlabel="wall time per throw [s]", ylabel="95th percentile landing position error [m]")
    for ax in axes:
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    figure.suptitle("Error against wall time (labels: k of dt = 2^-k s; crosses: failed runs; "
                    f"errors below {ERROR_FLOOR:g} drawn at it)")
    document.save_figure(figure, path)


def plot_orders(report: PrecisionReport, path: Path) -> None:
    cases = exact_cases()
    figure, axes = _panels(len(cases) + 1)
    orders = report.orders()
    for ax, case in zip(axes, cases, strict=False):
        for method in report.methods:
            points = report.points_of(case.name, method)
            order = orders[(case.name, method)]
            _draw_curve(ax, [dt_of(p.exponent) for p in points], [p.error for p in points],
                        [p.failed for p in points], [""] * len(points), COLORS[method],
                        f"{method} (order {order_text(order, points)})")
            _draw_fit(ax, [(dt_of(p.exponent), p.error) for p in points if not p.failed and p.error > ERROR_FLOOR],
                      order, COLORS[method])
        ax.set(xscale="log", yscale="log", title=case.title, xlabel="dt [s]", ylabel=AXIS_LABELS[case.name])
    ax = axes[-1]
    for solver in SOLVERS:
        settings, _ = report.throw_results[solver]
        medians = [all_throws(s, 50) for s in settings]
        order = report.throw_order(solver)
        _draw_curve(ax, [dt_of(s.exponent) for s in settings], medians, [s.failed.any() for s in settings],
                    [""] * len(settings), COLORS[solver], f"{solver} (order {order_text(order)})")
        _draw_fit(ax, [(dt_of(s.exponent), m) for s, m in zip(settings, medians, strict=True)
                       if not s.failed.any() and m > ERROR_FLOOR], order, COLORS[solver])
    ax.set(xscale="log", yscale="log", title="BoxToss throws (all, on the reference face)", xlabel="dt [s]",
           ylabel="median landing position error [m]")
    for ax in axes:
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    figure.suptitle("Error against dt, with the fitted order (dashed)")
    document.save_figure(figure, path)


def _draw_fit(ax, valid, order, color):
    if math.isnan(order) or not valid:
        return
    x, y = np.array(valid).T
    intercept = np.mean(np.log(y) - order * np.log(x))
    ax.plot(x, np.exp(intercept) * x**order, "--", lw=0.8, color=color)


def plot_faces(report: PrecisionReport, path: Path) -> None:
    import matplotlib.pyplot as plt

    figure, ax = plt.subplots(figsize=(7.5, 4.5), layout="constrained")
    for solver in SOLVERS:
        settings, _ = report.throw_results[solver]
        xs = [s.seconds_per_throw for s in settings]
        ax.plot(xs, [100 * s.judged_face_agreement for s in settings], "o-", color=COLORS[solver],
                label=f"{solver}: judged throws (reference resolved)")
        ax.plot(xs, [100 * s.face_agreement_all for s in settings], "s--", color=COLORS[solver], alpha=0.5, ms=3,
                label=f"{solver}: all throws")
        for s, x in zip(settings, xs, strict=True):
            ax.annotate(str(s.exponent), (x, 100 * s.judged_face_agreement), textcoords="offset points",
                        xytext=(3, 3), fontsize=7, color=COLORS[solver])
    ax.axhline(100 * FACE_AGREEMENT_MIN, color="gray", ls=":", lw=1, label=f"{FACE_AGREEMENT_MIN:.0%}")
    best = recommend(report.throw_results)
    if best is not None:
        ax.plot([best.seconds_per_throw], [100 * best.judged_face_agreement], "*", ms=14, color="gold", mec="k",
                label=f"recommended: {describe(best)}")
    ax.set(xscale="log", xlabel="wall time per throw [s]", ylabel="landing on the reference's face [%]",
           title="Landing-face agreement against cost (labels: k of dt = 2^-k s)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    document.save_figure(figure, path)


def main(argv=None) -> int:
    return document.report_command("precision", __doc__, run, write_report, argv)


if __name__ == "__main__":
    raise SystemExit(main())
