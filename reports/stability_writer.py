"""The stability report written: the map's figure, the findings, ``docs/stability.md`` and the README block."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from box_toss_env.files import write_atomic
from box_toss_env.physics import scenes

from . import document, fuzz
from .cases import STIFFNESS, dt_of
from .document import table
from .stability_checks import DECLARED_RANGE, MAX_LISTED, SOLVERS, StabilityReport, point_text
from .stability_random import RANDOM_FIELDS, random_check
from .stability_rows import contact_omega


def plot_map(report: StabilityReport, path: Path) -> None:
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    row = report.row("stiffness_map")
    ks = sorted({c.values["k"] for c in row.checks})
    exponents = sorted({c.values["exponent"] for c in row.checks}, reverse=True)  # dt increasing
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True, layout="constrained")
    scene = scenes.resting()
    for ax, solver in zip(axes, SOLVERS, strict=True):
        grid = np.zeros((len(ks), len(exponents)))
        for c in row.of(solver):
            grid[ks.index(c.values["k"]), exponents.index(c.values["exponent"])] = 1.0 if c.passed else 0.0
        log_dt = [math.log10(dt_of(e)) for e in exponents]
        log_k = [math.log10(k) for k in ks]
        ax.pcolormesh(
            _edges(log_dt),
            _edges(log_k),
            grid,
            cmap=ListedColormap(["#e45756", "#54a24b"]),
            vmin=0,
            vmax=1,
            edgecolors="white",
            linewidth=0.5,
        )
        line_k = np.logspace(log_k[0] - 0.5, log_k[-1] + 0.5, 50)
        omega = np.array([contact_omega(scene.replace(penalty_stiffness=k)) for k in line_k])
        ax.plot(np.log10(2.0 / omega), np.log10(line_k), "k--", lw=1.5, label="omega dt = 2")
        ax.set(
            xlim=(_edges(log_dt)[0], _edges(log_dt)[-1]),
            ylim=(_edges(log_k)[0], _edges(log_k)[-1]),
            xlabel="log10 dt [s]",
            title=f"{solver}: green pass, red fail",
        )
        ax.legend(loc="upper right", fontsize=8)
    axes[0].set_ylabel("log10 penalty stiffness k [N/m]")
    figure.suptitle("Resting 2 x 1 m box, 2 s: omega = sqrt(k / m_eff), m_eff of the stiffest contact mode")
    document.save_figure(figure, path)


def _edges(centres):
    centres = np.asarray(centres, dtype=float)
    step = np.diff(centres).mean() if centres.size > 1 else 1.0
    return np.concatenate([centres - step / 2, [centres[-1] + step / 2]])


def map_findings(report: StabilityReport) -> str:
    row = report.row("stiffness_map")
    failed, total = report.seed_beyond_line()
    seed = row.of("seed")
    inside_failed = [c.values["omega_dt"] for c in seed if not c.passed and c.values["omega_dt"] <= 2.0]
    passed = [c.values["omega_dt"] for c in seed if c.passed]
    text = (
        f"The seed scheme fails at {failed} of the {total} map points beyond omega dt = 2, as the explicit "
        "spring's stability limit says"
    )
    if inside_failed:
        text += (
            f", and also at {len(inside_failed)} points below it, from omega dt = {min(inside_failed):.2f} up: "
            "there the explicit spring is stable, but the seed's impulses, applied with restitution to corners "
            "that are still inside the floor, feed the contact's oscillation until the box is thrown off"
        )
    if passed:
        text += f". The largest omega dt at which it passed is {max(passed):.2f}"
    robust = row.of("robust")
    return text + f". The robust default passes {sum(c.passed for c in robust)} of {len(robust)} map points."


def findings(report: StabilityReport) -> str:
    """The closing notes, every number read from the checks."""
    lines = []
    for solver in SOLVERS:
        checks = [c for row in report.rows for c in row.of(solver)]
        passed_rows = [row for row in report.rows if row.passed(solver)]
        lines.append(
            f"- **{solver}**: passes {len(passed_rows)} of {len(report.rows)} rows "
            f"({sum(c.passed for c in checks)} of {len(checks)} points)."
        )
    for row in report.rows:
        failed = [c for c in row.of("robust") if not c.passed]
        for c in failed[:4]:
            lines.append(f"- The robust default fails *{row.title}* at {point_text(c.point)}: {c.measured}.")
        if len(failed) > 4:
            lines.append(f"- ... and at {len(failed) - 4} more points of that row.")
    failed, total = report.seed_beyond_line()
    lines.append(f"- The seed scheme fails at {failed} of the {total} map points beyond omega dt = 2.")
    return "\n".join(lines)


def every_point_lines(rows) -> list[str]:
    """The "Every point" section: each row's points with both solvers' verdicts (the random scenes: the first 10
    and every failure of the robust default)."""
    parts = ["## Every point", ""]
    for row in rows:
        pairs = list(zip(row.of("robust"), row.of("seed"), strict=True))
        note = ""
        if len(pairs) > MAX_LISTED:  # the random scenes: the robust default's failures and the first few
            shown = [pair for i, pair in enumerate(pairs) if i < 10 or not pair[0].passed]
            seed_failed = sum(not b.passed for _, b in pairs)
            note = (
                f" Listed: the first 10 points and every robust failure; of all {len(pairs)}, the robust default "
                f"fails {sum(not a.passed for a, _ in pairs)} and the seed scheme {seed_failed}."
            )
            pairs = shown
        lines = [
            [
                point_text(a.point),
                ("pass" if a.passed else "**FAIL**") + ": " + a.measured,
                ("pass" if b.passed else "**FAIL**") + ": " + b.measured,
            ]
            for a, b in pairs
        ]
        parts += [
            f"### {row.title}",
            "",
            f"Criterion: {row.criterion}. Points: {row.declared}.{note}",
            "",
            table(["point", "robust", "seed"], lines),
            "",
        ]
    return parts


def markdown(report: StabilityReport, figure: str) -> str:
    rows = report.rows
    parts = [
        "# Stability on stiff and extreme cases",
        "",
        f"Generated by `python -m reports.stability{' --quick' if report.quick else ' --write-docs'}` in "
        f"{report.run_seconds / 60:.1f} min on {document.machine()} ({report.load}). Every number below comes "
        "from that command.",
        "",
        "Each row is a family of scenes with a measurable pass criterion, run for the robust default and the "
        "seed scheme at the same points. Energy is 0.5 m |v|^2 + 0.5 I w^2 - m g y (floor at y = 0). "
        f"Material, unless the row varies it: the env's penalty stiffness k = {STIFFNESS:g} N/m.",
        "",
        "## The robust default's declared range",
        "",
        table(["quantity", "range"], [[name, value] for name, value in DECLARED_RANGE.items()]),
        "",
        "Every point of every row lies inside this range, so the robust default must pass every row; "
        "a row it fails is marked **FAIL** with the points where it fails.",
        "",
        "## Summary",
        "",
        table(
            ["row", "pass criterion", "points (inside the declared range)", "robust", "seed"],
            [[r.title, r.criterion, r.declared, r.verdict("robust"), r.verdict("seed")] for r in rows],
        ),
        "",
        "## Findings",
        "",
        findings(report),
        "",
        "## Penalty stiffness against dt",
        "",
        map_findings(report),
        "",
        f"![pass/fail map over (k, dt)](figures/{figure})",
        "",
    ]
    random_row = report.row("random_scenes")
    smallest = random_row.smallest_failure
    if smallest is not None:
        parts += [
            "## Smallest random failure of the robust default",
            "",
            "hypothesis's smallest example on which the robust default fails the random-scene criterion, "
            f"as ({', '.join(RANDOM_FIELDS)}):",
            "",
            f"    {tuple(smallest)!r}",
            "",
            f"measured: {random_check(smallest, 'robust').measured}.",
            "",
        ]
    parts += fuzz_section(report)
    parts += every_point_lines(rows)
    return "\n".join(parts)


FUZZ_TEXT = {
    "engine": (
        "robust-solver scenes over the declared range (length 0.02 to 5 m and the quantities above)",
        "finite; penetration < 5% of the smaller side; no recorded step gains energy (allowance: rounding "
        "and m g times the deepest penetration); at rest lying on a face, or ran the whole duration",
    ),
    "env_declared": (
        "BoxToss-v0, robust, arguments inside the declared range, one throw each",
        "no exception (EnergyGainError included); observations finite and inside the space; "
        "penetration < 5% of the smaller side",
    ),
    "env_accepted": (
        "BoxToss-v0, both solvers, arguments anywhere in the accepted ranges (docs/ranges.md)",
        "no exception but the documented EnergyGainError and NonFiniteStateError; what is returned "
        "is finite and inside the observation space",
    ),
}


def fuzz_verdict(result: fuzz.FuzzResult) -> str:
    failed = len(result.failures)
    return (
        f"PASS {result.examples}/{result.examples}"
        if not failed
        else f"**FAIL** {result.examples - failed}/{result.examples}"
    )


def fuzz_section(report: StabilityReport) -> list[str]:
    """The property-based fuzz: what each draws and checks, and what it found."""
    if not report.fuzz:
        return []
    profile = fuzz.REDUCED if report.quick else fuzz.FULL
    rows = []
    for result in report.fuzz:
        draws, checks = FUZZ_TEXT[result.name]
        documented = (
            ", ".join(
                f"{solver}: {error} x{count}" for (solver, error), count in sorted(result.documented_errors.items())
            )
            or "-"
        )
        rows.append([result.name, draws, checks, fuzz_verdict(result), documented])
    parts = [
        "## Property-based fuzz (hypothesis)",
        "",
        f"`reports/fuzz.py`, the {profile.name} profile: {profile.examples} derandomized examples per fuzz, "
        f"engine scenes {profile.engine_duration:g} s each, env throws at most {profile.env_max_sim_time:g} s "
        f"and {profile.env_max_steps:,} steps (the tests run the reduced profile: {fuzz.REDUCED.examples} "
        "examples each).",
        "",
        table(["fuzz", "draws", "properties", "result", "documented errors raised"], rows),
        "",
    ]
    for result in report.fuzz:
        for example, problems in result.failures[:4]:
            parts += [f"- {result.name} fails on `{example!r}`: {'; '.join(problems)}."]
    return parts + [""]


def readme_block(report: StabilityReport) -> str:
    return "\n".join(
        [
            "**Stability on stiff and extreme cases** (`docs/stability.md`): "
            "`python -m reports.stability --write-docs` "
            f"({report.run_seconds / 60:.1f} min on {document.machine().split(',')[1].strip()}, {report.load}; "
            "`--quick` "
            "for the "
            "reduced version the tests run; both need the `reports` extra). Rows inside the robust default's "
            f"declared range ({', '.join(f'{k} {v}' for k, v in list(DECLARED_RANGE.items())[:6])}):",
            "",
            table(
                ["row", "robust", "seed"],
                [[r.title, r.verdict("robust", limit=1), r.verdict("seed", limit=1)] for r in report.rows],
            ),
            "",
            "Property-based fuzz (`reports/fuzz.py`, hypothesis): "
            + "; ".join(f"{result.name} {fuzz_verdict(result)}" for result in report.fuzz)
            + " examples.",
        ]
    )


def write_report(report: StabilityReport, out: Path, readme: Path | None = None) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    figure = "stability_map.png"
    plot_map(report, out / "figures" / figure)
    path = out / "stability.md"
    write_atomic(path, markdown(report, figure))
    if readme is not None:
        document.update_readme("stability", readme_block(report), readme)
    return path
