"""Write a command's measured output into the documentation page that holds its section, between its
markers, so every figure the docs quote comes from a command (``<!-- NAME:start -->`` ... ``<!-- NAME:end -->``).

The README is the front page: it holds the ``benchmark`` section, the engine's summary (``engine-scale-summary``)
and the headline figures (``headline``, from ``agents.figures``). The other sections live in the pages of the
documentation site (``docs/``), most in its methodology pages (``docs/methodology/``), named in ``SECTION_PAGES``.
"""

from __future__ import annotations

import os
from pathlib import Path

from box_toss_env.files import write_atomic

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
DOCS = REPO / "docs"
METHODOLOGY = DOCS / "methodology"
SECTION_PAGES = {
    "benchmark": README,  # the headline table of the front page (python -m agents.benchmark --report-only --readme)
    "engine-scale-summary": README,  # python -m benchmarks.engine_scale --write-docs (the page's table: its own marker)
    "headline": README,  # the headline figures (agents.figures, from docs/generated/figures.yml)
    "benchmark-goal": DOCS / "agents" / "benchmark.md",  # python -m agents.benchmark --envs BoxToss-Goal-v0 --readme
    "agents": METHODOLOGY / "main-command.md",  # python -m agents.main --full --readme
    "variant-gifs": DOCS / "environment.md",  # python -m agents.variant_gifs --write-docs
    "tune": DOCS / "hyperparameter-search.md",  # python -m agents.tune ... --readme
    "thread-scaling": DOCS / "engine_scale.md",  # python -m benchmarks.thread_scaling --write-docs
    "engine-benchmark": METHODOLOGY / "engine-benchmark.md",  # python -m benchmarks.engine --readme
    "throughput": DOCS / "throughput.md",  # python -m benchmarks.throughput --readme
    "throughput-pixels": DOCS / "throughput.md",  # python -m benchmarks.throughput --pixels-only --readme
    "vector-reset": METHODOLOGY / "vector-reset.md",  # python -m benchmarks.vector_reset --readme
    "cold-start": DOCS / "cold-start.md",  # python -m benchmarks.cold_start --readme
    "rllib-sampling": METHODOLOGY / "rllib.md",  # python -m benchmarks.rllib_sampling --readme
    "reports": DOCS / "reports.md",  # python -m reports.precision / stability / collisions --write-docs
    "raw-actions": METHODOLOGY / "raw-actions.md",  # python -m agents.raw_actions --readme
    # python -m agents.raw_actions --by-face --envs BoxToss-ThisSideUp-v0 --readme
    "raw-faces": METHODOLOGY / "raw-actions.md",
    # python -m agents.raw_actions --reach RUN --envs BoxToss-ThisSideUp-v0 --readme
    "raw-face-reach": METHODOLOGY / "raw-actions.md",
    "stack-ceiling": DOCS / "stack.md",  # python -m agents.stack_planner --readme
    "stack-ppo": DOCS / "stack.md",  # python -m agents.stack_planner --model RUN --readme
    "stack-throughput": DOCS / "stack.md",  # python -m benchmarks.stack_throughput --readme
    "hidden-physics": DOCS / "hidden_physics.md",  # python -m agents.hidden_physics_tier report --readme
    # python -m reports.reality.impacts --data DIR --ellipse FILE --write-docs
    "reality-impacts": DOCS / "reality.md",
}


def page_for(name: str) -> Path:
    """The file that holds section ``name`` (the README for a section not in ``SECTION_PAGES``)."""
    return SECTION_PAGES.get(name, README)


def relink(text: str, page: Path) -> str:
    """Links written relative to the repository's root (``](docs/...``), made relative to ``page``."""
    if page.resolve().parent == REPO:
        return text
    prefix = os.path.relpath(DOCS, page.resolve().parent).replace(os.sep, "/")
    return text.replace("](docs/", "](" if prefix == "." else f"]({prefix}/")


def read_section(name: str, page: Path | None = None) -> str | None:
    """What stands between the ``name`` markers of ``page`` (default: the page that holds the section); None
    if the page or its markers are missing."""
    page = page if page is not None else page_for(name)
    start, end = f"<!-- {name}:start -->", f"<!-- {name}:end -->"
    content = page.read_text() if page.exists() else ""
    if start not in content or end not in content:
        return None
    return content.split(start, 1)[1].split(end, 1)[0].strip()


def replace_section(name: str, text: str, readme: Path | None = None) -> None:
    """Replace what stands between the ``name`` markers of ``readme`` (default: the page that holds
    the section) with ``text``."""
    page = readme if readme is not None else page_for(name)
    start, end = f"<!-- {name}:start -->", f"<!-- {name}:end -->"
    content = page.read_text()
    if start not in content or end not in content:
        raise ValueError(f"{page} has no {start} ... {end} markers")
    head, rest = content.split(start, 1)
    _, tail = rest.split(end, 1)
    write_atomic(page, f"{head}{start}\n{relink(text.strip(), page)}\n{end}{tail}")
