"""Writing the reports: number formatting, Markdown tables, figures and the reports page's section.

The page docs/reports.md holds one section between ``<!-- reports:start -->`` and ``<!-- reports:end -->``; each
report command rewrites only its own block inside it (``<!-- reports:NAME:start -->`` ...), so the
commands can run in any order and every figure in the section comes from a command.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import re
from pathlib import Path

import matplotlib

from box_toss_env import files
from box_toss_env.files import write_atomic

matplotlib.use("Agg")

REPO = Path(__file__).resolve().parent.parent
DOCS = REPO / "docs"
QUICK_OUT = REPO / "build" / "reports"  # --quick writes here (ignored by git), never into docs/
README = DOCS / "reports.md"  # the page that holds the reports section (the README links to it)
SECTION_START, SECTION_END = "<!-- reports:start -->", "<!-- reports:end -->"
SECTION_TITLE = "# Precision and stability reports"


def sci(value: float, digits: int = 2) -> str:
    """A number in compact scientific notation, e.g. 1.2e-03; 0 as 0; nan as '-'."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if value == 0:
        return "0"
    if math.isinf(value):
        return "inf"
    return f"{value:.{digits - 1}e}"


def seconds(value: float) -> str:
    """A duration with a unit that keeps three significant digits: 12.3 us, 4.56 ms, 7.89 s."""
    if value is None or math.isnan(value):
        return "-"
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if value >= scale:
            return f"{value / scale:.3g} {unit}"
    return f"{value * 1e9:.3g} ns"


def percent(value: float) -> str:
    return "-" if value is None or math.isnan(value) else f"{100 * value:.1f}%"


def dt_label(exponent: int) -> str:
    return f"2^-{exponent}"


def table(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def machine() -> str:
    """One line saying where the figures were measured."""
    import numba
    import numpy

    return (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {numpy.__version__}, numba {numba.__version__}"
    )


def load() -> str:
    """The machine's 1-minute load average against its cores: other jobs share it, and timings move with it."""
    try:
        return f"load {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores, shared with other jobs"
    except OSError:  # no load average on this platform
        return "load unknown, shared with other jobs"


def save_figure(figure, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    files.save_figure(figure, path, dpi=110, bbox_inches="tight", metadata={"Software": None})
    import matplotlib.pyplot as plt

    plt.close(figure)


BLOCK_ORDER = ("precision", "stability", "collisions")


def update_readme(name: str, body: str, readme: Path = README) -> None:
    """Set the block ``<!-- reports:NAME:start -->`` ... ``end`` inside the reports section of ``readme`` to
    ``body``, keeping the other blocks (in ``BLOCK_ORDER``); create the section at the end of the file if absent.
    Nothing outside the section changes."""
    text = readme.read_text()
    if SECTION_START not in text or SECTION_END not in text:
        text = text.rstrip("\n") + f"\n\n{SECTION_START}\n{SECTION_END}\n"
    start, end = text.index(SECTION_START), text.index(SECTION_END)
    section = text[start + len(SECTION_START) : end]
    blocks = {
        match[0]: match[1]
        for match in re.findall(
            r"<!-- reports:(\w+):start -->\n(.*?)\n<!-- reports:\1:end -->", section, flags=re.DOTALL
        )
    }
    blocks[name] = body.strip()
    names = [n for n in BLOCK_ORDER if n in blocks] + sorted(n for n in blocks if n not in BLOCK_ORDER)
    inner = "\n".join(f"<!-- reports:{n}:start -->\n{blocks[n]}\n<!-- reports:{n}:end -->" for n in names)
    write_atomic(readme, f"{text[:start]}{SECTION_START}\n{SECTION_TITLE}\n\n{inner}\n{text[end:]}")


def report_parser(name: str, doc: str) -> argparse.ArgumentParser:
    """The options of ``python -m reports.NAME``."""
    parser = argparse.ArgumentParser(prog=f"python -m reports.{name}", description=doc.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a few points of each part (what the tests run)")
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help=f"output folder (default: {QUICK_OUT.relative_to(REPO)}, ignored by git)",
    )
    parser.add_argument(
        "--write-docs",
        action="store_true",
        help=f"write the full report into docs/ and its block of {README.relative_to(REPO)} (tracked files)",
    )
    return parser


def report_destination(parser: argparse.ArgumentParser, args: argparse.Namespace) -> tuple[Path, Path | None]:
    """The folder the report is written to and the page whose block it rewrites (None: no block): docs/ and
    docs/reports.md only with ``--write-docs``, else ``--out`` or build/reports/, which git ignores."""
    if args.write_docs and (args.quick or args.out is not None):
        parser.error("--write-docs writes the full report into docs/: drop " + ("--quick" if args.quick else "--out"))
    if args.write_docs:
        return DOCS, README
    return args.out or QUICK_OUT, None


def report_command(name: str, doc: str, run, write_report, argv=None) -> int:
    """The command line of ``python -m reports.NAME``: run the report (``--quick``: a few points, as the
    tests do) and write it to build/reports/ or ``--out``; docs/ and its block of docs/reports.md only with
    ``--write-docs``."""
    parser = report_parser(name, doc)
    args = parser.parse_args(argv)
    out, readme = report_destination(parser, args)
    report = run(quick=args.quick)
    path = write_report(report, out, readme)
    print(f"wrote {path} in {report.run_seconds:.0f} s")
    return 0
