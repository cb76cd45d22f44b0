"""The precision report's figures: error against run time, the fitted orders, landing-face agreement."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from . import document
from .cases import dt_of, exact_cases
from .precision_exact import COLORS, ERROR_FLOOR, FACE_AGREEMENT_MIN, POSITION_ERROR_MAX, SOLVERS
from .precision_throws import PrecisionReport, all_throws, recommend
from .precision_writer import describe, order_text

# -- figures ------------------------------------------------------------------------------------------------------
AXIS_LABELS = {
    "free_flight": "pose error at t = 1 s [m]",
    "corner_impact": "velocity error at t = 0.25 s [m/s]",
    "flat_drop": "apex error [m]",
    "slide": "stopping distance error [m]",
    "resting": "drift at t = 10 s [m]",
}


def _panels(n: int):
    import matplotlib.pyplot as plt

    columns = 3
    rows = math.ceil(n / columns)
    figure, axes = plt.subplots(rows, columns, figsize=(5.2 * columns, 4.4 * rows), squeeze=False, layout="constrained")
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


def plot_work_precision(report: PrecisionReport, path: Path) -> None:
    cases = exact_cases()
    figure, axes = _panels(len(cases) + 1)
    for ax, case in zip(axes, cases, strict=False):
        for method in report.methods:
            points = report.points_of(case.name, method)
            _draw_curve(
                ax,
                [p.seconds for p in points],
                [p.error for p in points],
                [p.failed for p in points],
                [str(p.exponent) for p in points],
                COLORS[method],
                method,
            )
        ax.set(
            xscale="log", yscale="log", title=case.title, xlabel="wall time per run [s]", ylabel=AXIS_LABELS[case.name]
        )
    ax = axes[-1]
    for solver in SOLVERS:
        settings, _ = report.throw_results[solver]
        _draw_curve(
            ax,
            [s.seconds_per_throw for s in settings],
            [all_throws(s, 95) for s in settings],
            [s.failed.any() for s in settings],
            [str(s.exponent) for s in settings],
            COLORS[solver],
            solver,
        )
    ax.axhline(POSITION_ERROR_MAX, color="gray", ls=":", lw=1)
    ax.set(
        xscale="log",
        yscale="log",
        title=f"{report.throws.n} BoxToss throws (all, on the reference face)",
        xlabel="wall time per throw [s]",
        ylabel="95th percentile landing position error [m]",
    )
    for ax in axes:
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    figure.suptitle(
        "Error against wall time (labels: k of dt = 2^-k s; crosses: failed runs; "
        f"errors below {ERROR_FLOOR:g} drawn at it)"
    )
    document.save_figure(figure, path)


def plot_orders(report: PrecisionReport, path: Path) -> None:
    cases = exact_cases()
    figure, axes = _panels(len(cases) + 1)
    orders = report.orders()
    for ax, case in zip(axes, cases, strict=False):
        for method in report.methods:
            points = report.points_of(case.name, method)
            order = orders[(case.name, method)]
            _draw_curve(
                ax,
                [dt_of(p.exponent) for p in points],
                [p.error for p in points],
                [p.failed for p in points],
                [""] * len(points),
                COLORS[method],
                f"{method} (order {order_text(order, points)})",
            )
            _draw_fit(
                ax,
                [(dt_of(p.exponent), p.error) for p in points if not p.failed and p.error > ERROR_FLOOR],
                order,
                COLORS[method],
            )
        ax.set(xscale="log", yscale="log", title=case.title, xlabel="dt [s]", ylabel=AXIS_LABELS[case.name])
    ax = axes[-1]
    for solver in SOLVERS:
        settings, _ = report.throw_results[solver]
        medians = [all_throws(s, 50) for s in settings]
        order = report.throw_order(solver)
        _draw_curve(
            ax,
            [dt_of(s.exponent) for s in settings],
            medians,
            [s.failed.any() for s in settings],
            [""] * len(settings),
            COLORS[solver],
            f"{solver} (order {order_text(order)})",
        )
        _draw_fit(
            ax,
            [
                (dt_of(s.exponent), m)
                for s, m in zip(settings, medians, strict=True)
                if not s.failed.any() and m > ERROR_FLOOR
            ],
            order,
            COLORS[solver],
        )
    ax.set(
        xscale="log",
        yscale="log",
        title="BoxToss throws (all, on the reference face)",
        xlabel="dt [s]",
        ylabel="median landing position error [m]",
    )
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
        ax.plot(
            xs,
            [100 * s.judged_face_agreement for s in settings],
            "o-",
            color=COLORS[solver],
            label=f"{solver}: judged throws (reference resolved)",
        )
        ax.plot(
            xs,
            [100 * s.face_agreement_all for s in settings],
            "s--",
            color=COLORS[solver],
            alpha=0.5,
            ms=3,
            label=f"{solver}: all throws",
        )
        for s, x in zip(settings, xs, strict=True):
            ax.annotate(
                str(s.exponent),
                (x, 100 * s.judged_face_agreement),
                textcoords="offset points",
                xytext=(3, 3),
                fontsize=7,
                color=COLORS[solver],
            )
    ax.axhline(100 * FACE_AGREEMENT_MIN, color="gray", ls=":", lw=1, label=f"{FACE_AGREEMENT_MIN:.0%}")
    best = recommend(report.throw_results)
    if best is not None:
        ax.plot(
            [best.seconds_per_throw],
            [100 * best.judged_face_agreement],
            "*",
            ms=14,
            color="gold",
            mec="k",
            label=f"recommended: {describe(best)}",
        )
    ax.set(
        xscale="log",
        xlabel="wall time per throw [s]",
        ylabel="landing on the reference's face [%]",
        title="Landing-face agreement against cost (labels: k of dt = 2^-k s)",
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    document.save_figure(figure, path)
