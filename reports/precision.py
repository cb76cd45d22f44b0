"""Error against run time (work-precision) of the seed scheme, the robust default and other engines.

    python -m reports.precision --write-docs   # the full report: docs/precision.md, docs/figures/precision_*.png
    python -m reports.precision                # the full report into build/reports/ (ignored by git), or --out DIR
    python -m reports.precision --quick        # a few points of each part, into build/reports/ (the tests run this)

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

Its parts: ``precision_exact`` (the constants and stage 1), ``precision_throws`` (stage 2 and the
report's results, ``PrecisionReport``), ``precision_writer`` (the page and the README block),
``precision_figures`` (the figures); this module runs them (``run``, ``main``) and keeps every name
importable from ``reports.precision``.
"""

from __future__ import annotations

from pathlib import Path

from benchmarks.other_engines import ENGINES, missing_engines
from box_toss_env.files import write_atomic

from . import document
from .cases import seeded_throws
from .precision_exact import (
    ACCEPT_FLOOR,
    ANGLE_ERROR_MAX,
    BLOW_UP_ENERGY_GAIN,
    COLORS,
    ERROR_FLOOR,
    EXPONENTS,
    FACE_AGREEMENT_MIN,
    MIN_JUDGED_SHARE,
    N_THROWS,
    ORDER_FLOOR,
    ORDER_FLOOR_FACTOR,
    ORDER_GOAL,
    ORDER_GOAL_SHARE,
    POSITION_ERROR_MAX,
    QUICK_EXPONENTS,
    QUICK_N_THROWS,
    QUICK_THROW_EXPONENTS,
    REFERENCE_FACTOR_EXPONENT,
    RESOLVE_SHARE,
    SOLVERS,
    THROW_SEED,
    Point,
    failure_of,
    fit_order,
    measure_engine_case,
    measure_exact_cases,
    measure_other_case,
)
from .precision_figures import AXIS_LABELS, plot_faces, plot_orders, plot_work_precision
from .precision_throws import (
    QUICK_TIPPING_EXPONENTS,
    TIPPING_EXPONENTS,
    TIPPING_MATERIALS,
    TIPPING_TIME,
    OrderSummary,
    PrecisionReport,
    Reference,
    Setting,
    all_throws,
    compare,
    fill_errors,
    landing_differences,
    make_reference,
    measure_setting,
    measure_throws,
    measure_tipping,
    order_summaries,
    recommend,
    throw_orders,
)
from .precision_writer import (
    THROW_HEADER,
    convergence_text,
    describe,
    error_cell,
    findings,
    markdown,
    order_text,
    readme_block,
    recommendation_text,
    summary_rows,
    throw_rows,
    tipping_spread,
    tipping_table,
)
from .timing import Stopwatch

__all__ = [
    "ACCEPT_FLOOR",
    "ANGLE_ERROR_MAX",
    "AXIS_LABELS",
    "BLOW_UP_ENERGY_GAIN",
    "COLORS",
    "ERROR_FLOOR",
    "EXPONENTS",
    "FACE_AGREEMENT_MIN",
    "MIN_JUDGED_SHARE",
    "N_THROWS",
    "ORDER_FLOOR",
    "ORDER_FLOOR_FACTOR",
    "ORDER_GOAL",
    "ORDER_GOAL_SHARE",
    "OrderSummary",
    "POSITION_ERROR_MAX",
    "Point",
    "PrecisionReport",
    "QUICK_EXPONENTS",
    "QUICK_N_THROWS",
    "QUICK_THROW_EXPONENTS",
    "QUICK_TIPPING_EXPONENTS",
    "REFERENCE_FACTOR_EXPONENT",
    "RESOLVE_SHARE",
    "Reference",
    "SOLVERS",
    "Setting",
    "THROW_HEADER",
    "THROW_SEED",
    "TIPPING_EXPONENTS",
    "TIPPING_MATERIALS",
    "TIPPING_TIME",
    "all_throws",
    "compare",
    "convergence_text",
    "describe",
    "error_cell",
    "failure_of",
    "fill_errors",
    "findings",
    "fit_order",
    "landing_differences",
    "main",
    "make_reference",
    "markdown",
    "measure_engine_case",
    "measure_exact_cases",
    "measure_other_case",
    "measure_setting",
    "measure_throws",
    "measure_tipping",
    "order_summaries",
    "order_text",
    "plot_faces",
    "plot_orders",
    "plot_work_precision",
    "readme_block",
    "recommend",
    "recommendation_text",
    "run",
    "summary_rows",
    "throw_orders",
    "throw_rows",
    "tipping_spread",
    "tipping_table",
    "write_report",
]


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
    return PrecisionReport(
        quick, exponents, throw_exponents, engines, missing, points, throws, throw_results, tipping, watch.seconds
    )


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


def main(argv=None) -> int:
    return document.report_command("precision", __doc__, run, write_report, argv)


if __name__ == "__main__":
    raise SystemExit(main())
