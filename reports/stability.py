"""Stability on stiff and extreme cases: a matrix of scenes, each with a measurable pass criterion,
run for the seed scheme and the robust default.

    python -m reports.stability --write-docs   # the full report: docs/stability.md, docs/figures/stability_map.png
    python -m reports.stability                # the full report into build/reports/ (ignored by git), or --out DIR
    python -m reports.stability --quick        # a few points of each row, into build/reports/ (the tests run this)

Each row is a function returning a ``Row``: its criterion, the robust solver's declared range for it,
and one ``Check`` per parameter point and solver. Every point of every row lies inside the robust
solver's declared range (``DECLARED_RANGE``), so the robust default must pass them all; where it does
not, the row says FAIL and names the points. The seed scheme is run on the same points and shown as it is.

Its parts: ``stability_checks`` (the constants, ``Check``, ``Row``, a single box's ``Run``, the report),
``stability_rows`` (the single-box rows), ``stability_bodies`` (boxes that collide), ``stability_random``
(hypothesis's random scenes), ``stability_writer`` (the figure, the page, the README block); this module
runs them (``run``, ``main``) and keeps every name importable from ``reports.stability``.
"""

from __future__ import annotations

from . import cases, document, fuzz
from .stability_bodies import BodiesRun, body_impacts, mass_ratio_stacks, passed_through, run_bodies, stacks
from .stability_checks import (
    DECLARED_RANGE,
    ENERGY_ROUNDING,
    FULL_DTS,
    MAP_DTS,
    MAP_STIFFNESS,
    MAX_LISTED,
    QUICK_DTS,
    QUICK_MAP_DTS,
    QUICK_MAP_STIFFNESS,
    SOLVERS,
    Check,
    Row,
    Run,
    StabilityReport,
    k_text,
    not_finite,
    point_text,
    run_scene,
)
from .stability_random import (
    KNOWN_EXAMPLES,
    RANDOM_FIELDS,
    random_check,
    random_examples,
    random_scene,
    random_scenes,
    random_strategy,
    shrink_failure,
)
from .stability_rows import (
    CORNER_HITS,
    contact_omega,
    corner_friction,
    elastic_bouncing,
    embedded_box,
    energy_check,
    far_from_origin,
    fast_impacts,
    fast_spin,
    long_rest,
    masses,
    resting_drift,
    sliding,
    stiffness_map,
    thin_boxes,
)
from .stability_writer import (
    FUZZ_TEXT,
    findings,
    fuzz_section,
    fuzz_verdict,
    map_findings,
    markdown,
    plot_map,
    readme_block,
    write_report,
)
from .timing import Stopwatch

__all__ = [
    "BodiesRun",
    "CORNER_HITS",
    "Check",
    "DECLARED_RANGE",
    "ENERGY_ROUNDING",
    "FULL_DTS",
    "FUZZ_TEXT",
    "KNOWN_EXAMPLES",
    "MAP_DTS",
    "MAP_STIFFNESS",
    "MAX_LISTED",
    "QUICK_DTS",
    "QUICK_MAP_DTS",
    "QUICK_MAP_STIFFNESS",
    "RANDOM_FIELDS",
    "Row",
    "Run",
    "SOLVERS",
    "StabilityReport",
    "body_impacts",
    "contact_omega",
    "corner_friction",
    "elastic_bouncing",
    "embedded_box",
    "energy_check",
    "far_from_origin",
    "fast_impacts",
    "fast_spin",
    "findings",
    "fuzz_section",
    "fuzz_verdict",
    "k_text",
    "long_rest",
    "main",
    "map_findings",
    "markdown",
    "mass_ratio_stacks",
    "masses",
    "not_finite",
    "passed_through",
    "plot_map",
    "point_text",
    "random_check",
    "random_examples",
    "random_scene",
    "random_scenes",
    "random_strategy",
    "readme_block",
    "resting_drift",
    "run",
    "run_bodies",
    "run_scene",
    "shrink_failure",
    "sliding",
    "stacks",
    "stiffness_map",
    "thin_boxes",
    "write_report",
]


def run(quick: bool = False, log=print) -> StabilityReport:
    dts = QUICK_DTS if quick else FULL_DTS
    builders = [
        lambda: stiffness_map(QUICK_MAP_STIFFNESS if quick else MAP_STIFFNESS, QUICK_MAP_DTS if quick else MAP_DTS),
        lambda: elastic_bouncing(dts),
        lambda: long_rest(dts),
        lambda: sliding((5.0,) if quick else (1.0, 5.0, 20.0), (0.3,) if quick else (0.3, 1.0), dts),
        lambda: fast_impacts((5.0, 200.0) if quick else (5.0, 20.0, 50.0, 200.0), dts),
        lambda: fast_spin((600.0,) if quick else (50.0, 200.0, 600.0), dts),
        lambda: thin_boxes((200.0,) if quick else (10.0, 100.0, 200.0), dts),
        lambda: masses((1e-3, 1e3) if quick else (1e-3, 1e-1, 1e1, 1e3), dts),
        lambda: embedded_box((1e2, 1e5) if quick else (1e2, 1e5, 1e9), dts),
        lambda: far_from_origin((8,) if quick else dts),
        lambda: corner_friction(
            (1.0,) if quick else (0.2, 1.0),
            (0.5,) if quick else (0.0, 0.5),
            dts,
            CORNER_HITS[:1] if quick else CORNER_HITS,
        ),
        lambda: stacks((10,) if quick else (2, 10), dts, 2.0 if quick else 60.0),
        lambda: body_impacts((200.0,) if quick else (50.0, 200.0), dts),
        lambda: mass_ratio_stacks(
            1000.0, ("heavy on top",) if quick else tuple(cases.MASS_ORDERS), dts, 2.0 if quick else 10.0
        ),
        lambda: random_scenes(10 if quick else 1000, shrink=not quick),
    ]
    rows = []
    with Stopwatch() as watch:
        for build in builders:
            rows.append(build())
            row = rows[-1]
            log(f"  {row.name:18} robust {row.verdict('robust', 2)[:60]:60} seed {row.verdict('seed', 1)[:40]}")
        profile = fuzz.REDUCED if quick else fuzz.FULL
        fuzzed = []
        for name in fuzz.FUZZES:
            fuzzed.append(fuzz.run_fuzz(name, profile))
            log(f"  fuzz {name:13} {len(fuzzed[-1].failures)} of {fuzzed[-1].examples} examples fail")
    return StabilityReport(quick, rows, watch.seconds, fuzzed, document.load())


def main(argv=None) -> int:
    return document.report_command("stability", __doc__, run, write_report, argv)


if __name__ == "__main__":
    raise SystemExit(main())
