"""The precision report written: its tables, findings and recommendation, ``docs/precision.md`` and the
README block."""

from __future__ import annotations

import math

import numpy as np

from benchmarks.other_engines import INSTALL_HINT

from . import document
from .cases import ENV_DEFAULTS, STIFFNESS, exact_cases
from .document import dt_label, percent, sci, seconds, table
from .precision_exact import (
    ACCEPT_FLOOR,
    ANGLE_ERROR_MAX,
    BLOW_UP_ENERGY_GAIN,
    ERROR_FLOOR,
    FACE_AGREEMENT_MIN,
    MIN_JUDGED_SHARE,
    ORDER_FLOOR,
    ORDER_FLOOR_FACTOR,
    ORDER_GOAL,
    ORDER_GOAL_SHARE,
    POSITION_ERROR_MAX,
    RESOLVE_SHARE,
    SOLVERS,
    Point,
)
from .precision_throws import (
    TIPPING_MATERIALS,
    TIPPING_TIME,
    PrecisionReport,
    Setting,
    all_throws,
    order_summaries,
    recommend,
)


def error_cell(point: Point) -> str:
    if point.failed:
        return f"FAIL: {point.failure}" + ("" if math.isnan(point.error) else f" ({sci(point.error)})")
    return sci(point.error)


THROW_HEADER = [
    "dt [s]",
    "time per throw",
    "failed",
    "at rest",
    "face agreement",
    "position error p95 [m]",
    "angle error p95 [deg]",
    "meets criterion",
    "face agr. (accepted)",
    "position error [m] p50 / p95 / max (accepted)",
    "angle error [deg] p50 / p95 / max (accepted)",
]


def throw_rows(settings: list[Setting]) -> list[list[str]]:
    rows = []
    for s in settings:
        p50, p95, pmax = s.percentiles("position")
        a50, a95, amax = s.percentiles("angle")
        rows.append(
            [
                dt_label(s.exponent),
                seconds(s.seconds_per_throw),
                str(int(s.failed.sum())),
                percent(s.at_rest.mean()),
                percent(s.judged_face_agreement),
                sci(s.judged("position")),
                sci(s.judged("angle")),
                s.verdict(),
                percent(s.face_agreement),
                f"{sci(p50)} / {sci(p95)} / {sci(pmax)}",
                f"{sci(a50)} / {sci(a95)} / {sci(amax)}",
            ]
        )
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
        rows.append(
            [
                f"{s.solver}, dt = {dt_label(s.exponent)} s" + (f" ({', '.join(note)})" if note else ""),
                seconds(s.seconds_per_throw),
                str(int(s.failed.sum())),
                percent(s.judged_face_agreement),
                sci(s.judged("position", 50)),
                sci(s.judged("position")),
                sci(s.judged("angle")),
                f"{s.judged_share:.0%}",
                s.verdict(),
            ]
        )
    return rows


def recommendation_text(report: PrecisionReport) -> str:
    default, best = report.env_default(), recommend(report.throw_results)
    criteria = (
        f"the cheapest setting (wall time per throw) with no failed throw, landing-face agreement "
        f">= {FACE_AGREEMENT_MIN:.0%} with the reference, and 95th-percentile landing errors (over the "
        f"throws on the reference face) <= {POSITION_ERROR_MAX * 100:g} cm and <= {ANGLE_ERROR_MAX:g} degree"
    )
    lines = [
        f"BoxToss-v0 simulates with `solver={ENV_DEFAULTS['solver']!r}`, `dt={ENV_DEFAULTS['dt']!r}` "
        f"(= {dt_label(round(-math.log2(ENV_DEFAULTS['dt'])))} s) by default. The criterion is {criteria}."
    ]
    undecided = [s for settings, _ in report.throw_results.values() for s in settings if not s.decidable]
    if best is None and any(s.solver == "robust" for s in undecided):
        shares = sorted({f"{s.solver} {s.judged_share:.0%}" for s in undecided})
        lines.append(
            f"**No setting can be certified**: judging the criterion needs a reference that moves by less "
            f"than a tenth of its thresholds ({RESOLVE_SHARE * POSITION_ERROR_MAX * 1000:g} mm, "
            f"{RESOLVE_SHARE * ANGLE_ERROR_MAX:g} degree) when its step is halved, for at least "
            f"{MIN_JUDGED_SHARE:.0%} of the throws; it does so for only {', '.join(shares)} of them. "
            "The solver's landings do not converge with dt (see Findings)."
        )
    elif best is None:
        lines.append(
            "**No measured setting meets the criterion** (see the throw tables below for how close each comes)."
        )
    else:
        lines.append(
            f"The cheapest setting that meets it is **{describe(best)}** "
            f"({seconds(best.seconds_per_throw)} per throw; face agreement "
            f"{percent(best.judged_face_agreement)}, landing errors {sci(best.judged('position'))} m and "
            f"{sci(best.judged('angle'))} degree at the 95th percentile)."
        )
    if default is not None:
        verdict = (
            "cannot be judged against"
            if not default.decidable
            else "meets"
            if default.meets_criteria()
            else "does not meet"
        )
        lines.append(
            f"The env default {verdict} it: {seconds(default.seconds_per_throw)} per throw; over the "
            f"{int(round(default.judged_share * report.throws.n))} judged throws, face agreement "
            f"{percent(default.judged_face_agreement)} and landing position error "
            f"{sci(default.judged('position', 50))} m median, {sci(default.judged('position'))} m at the "
            f"95th percentile; over all throws, face agreement {percent(default.face_agreement_all)} and "
            f"{sci(all_throws(default, 95))} m at the 95th percentile."
        )
        if best is not None and best is not default:
            cheaper = best.seconds_per_throw < default.seconds_per_throw
            lines.append(
                f"**Recommendation: switch the env default to {describe(best)}** "
                + (
                    "(cheaper, and it meets the criterion)."
                    if cheaper
                    else "(the env default does not meet the criterion; this is the cheapest setting that does)."
                )
            )
        elif best is default:
            lines.append("That is why the env uses it: it is the cheapest setting whose landings can be trusted.")
    return "\n\n".join(lines)


def markdown(report: PrecisionReport, figures: dict) -> str:
    return "\n".join([*method_lines(report), *throw_lines(report), *exact_lines(report, figures)])


def method_lines(report: PrecisionReport) -> list[str]:
    """The page's head: what is measured and the env's default setting."""
    return [
        "# Precision: error against run time",
        "",
        f"Generated by `python -m reports.precision{' --quick' if report.quick else ' --write-docs'}` in "
        f"{report.run_seconds / 60:.1f} min on {document.machine()}. Every number and figure below comes from "
        "that command; edit the code in `reports/`, not this file.",
        "",
        "## What is measured",
        "",
        f'- **Methods**: the seed scheme (`solver="seed"`) and the robust default (`solver="robust"`) of '
        f"`box_toss_env.physics` at dt = 2^-k s for k = {report.exponents[0]}..{report.exponents[-1]}; "
        + (
            f"{', '.join(report.engines)} (through `benchmarks/other_engines.py`, with its documented settings) "
            "on the exact-answer cases at the same dt grid."
            if report.engines
            else "no other engine installed."
        )
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
    ]


def throw_lines(report: PrecisionReport) -> list[str]:
    """The seeded throws: how they are compared, and a table per solver."""
    parts = [
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
        p50, p95 = np.percentile(change, [50, 95]) if change.size else (math.nan, math.nan)
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
            f"{ORDER_FLOOR:g} m): "
            + "; ".join(summary.text() for summary in order_summaries(settings, reference))
            + ".",
            "",
            table(THROW_HEADER, throw_rows(settings)),
            "",
        ]
    return parts


def exact_lines(report: PrecisionReport, figures: dict) -> list[str]:
    """The cases with exact answers, their fitted orders, the findings and the tipping box."""
    cases = exact_cases()
    orders = report.orders()
    parts = [
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
    order_rows = [
        [case.title] + [order_text(orders[(case.name, m)], report.points_of(case.name, m)) for m in report.methods]
        for case in cases
    ]
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
    return parts


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
            f"{int(reference.accepted.sum())}/{report.throws.n} throws."
        )
    orders = report.orders()
    for solver in SOLVERS:
        texts = [
            f"{case.title.lower()} {order_text(orders[(case.name, solver)], report.points_of(case.name, solver))}"
            for case in exact_cases()
        ]
        lines.append(f"- Fitted orders of the {solver} solver on the exact-answer cases: {'; '.join(texts)}.")
    _, robust_reference = report.throw_results["robust"]
    change = robust_reference.position_change
    moved, flipped = int((change > 1e-3).sum()), int((~robust_reference.valid).sum())
    lines.append(
        f"- Halving the robust solver's reference step ({dt_label(robust_reference.exponent)} s) moves the "
        f"landing by more than 1 mm for {moved} of {report.throws.n} throws and changes the face of "
        f"{flipped}."
    )
    lines.append("- " + convergence_text(report))
    spread = tipping_spread(report)
    coupled, others = spread[TIPPING_MATERIALS[0]], max(spread[TIPPING_MATERIALS[1]], spread[TIPPING_MATERIALS[2]])
    verdict = (
        "does not converge with dt"
        if coupled > max(10.0 * others, RESOLVE_SHARE * POSITION_ERROR_MAX)
        else "settles with dt"
    )
    lines.append(
        f"- A contact-mode impact with both restitution and friction (the tipping-box table: a corner slams down "
        f"while the box is held by its other corner) {verdict}: its state at {TIPPING_TIME:g} s varies by "
        f"{sci(coupled)} over the three finest steps, against {sci(spread[TIPPING_MATERIALS[2]])} with e = 0 and "
        f"{sci(spread[TIPPING_MATERIALS[1]])} with mu = 0."
    )
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
    return (
        f"Convergence of the robust solver's landings: its reference settles (halving its step moves the landing "
        f"by {sci(settles)} m at the 95th percentile), and the per-throw order of landing x is >= {ORDER_GOAL:g} "
        f"on {percent(share)} of the throws ({every.label}; median {every.median:.2f}; >= 0.9 on "
        f"{percent(every.share_at_least(0.9))}; {fine.label}: median {fine.median:.2f}, >= {ORDER_GOAL:g} on "
        f"{percent(fine.share_at_least(ORDER_GOAL))}). The goal of order >= {ORDER_GOAL:g} on "
        f">= {ORDER_GOAL_SHARE:.0%} of the throws is {'met' if met else 'not met'}: the solver is first order "
        "in dt in the sense of these figures, no more."
    )


def tipping_spread(report: PrecisionReport) -> dict:
    """{(e, mu): largest spread of x [m], vx or vy [m/s] over the three finest steps}."""
    return {
        key: float(np.ptp(np.array([state[[0, 3, 4]] for _, state in runs[-3:]]), axis=0).max())
        for key, runs in report.tipping.items()
    }


def tipping_table(report: PrecisionReport) -> str:
    header = ["dt [s]"] + [f"e {e:g}, mu {mu:g}: x [m], (vx, vy) [m/s]" for e, mu in TIPPING_MATERIALS]
    exponents = [k for k, _ in report.tipping[TIPPING_MATERIALS[0]]]
    rows = [
        [dt_label(k)]
        + [f"{runs[i][1][0]:.5f}, ({runs[i][1][3]:+.5f}, {runs[i][1][4]:+.5f})" for runs in report.tipping.values()]
        for i, k in enumerate(exponents)
    ]
    spread = tipping_spread(report)
    rows.append(["spread over the 3 finest"] + [sci(spread[key]) for key in TIPPING_MATERIALS])
    return table(header, rows)


def readme_block(report: PrecisionReport) -> str:
    default, best = report.env_default(), recommend(report.throw_results)
    return "\n".join(
        [
            f"**Error against run time** (`docs/precision.md`): `python -m reports.precision --write-docs` "
            f"({report.run_seconds / 60:.1f} min on {document.machine().split(',')[1].strip()}; "
            "`--quick` for the reduced version the tests run; both need the `reports` extra, "
            "`pip install -e '.[reports]'`: matplotlib, hypothesis and the other engines). Landing pose of "
            f"{report.throws.n} seeded BoxToss-v0 throws against each solver's reference 16 times finer, "
            "over the throws "
            "whose reference moves less than a tenth of the criterion's thresholds when its step is halved (errors: "
            "those landing on the reference's face):",
            "",
            table(
                [
                    "setting",
                    "time per throw",
                    "failed",
                    "face agreement",
                    "position error p50 [m]",
                    "position error p95 [m]",
                    "angle error p95 [deg]",
                    "throws judged",
                    "meets criterion",
                ],
                summary_rows(report),
            ),
            "",
            f"Env default: {describe(default)}; cheapest setting with >= 99% face agreement and <= 1 cm, <= 1 degree: "
            + (describe(best) if best is not None else "none can be certified (see the report)")
            + ".",
            "",
            convergence_text(report),
        ]
    )
