"""The headline figures that the README and the documentation quote, kept in one generated file,
``docs/generated/figures.yml``, so that no two pages can disagree.

Each group of the file is written by the command that measures it (``update``):

========== =========================================================== ======================================
group      written by                                                  what it holds
========== =========================================================== ======================================
main       ``python -m agents.main --full --readme``                   the main command: success, time
pretrained ``python -m agents.pretrained export RUN ... --write-docs`` the trained agents' success
throughput ``python -m benchmarks.throughput --readme``                throws per second, one env and batched
========== =========================================================== ======================================

Values are stored as the pages print them ("100.0%", "3.2 min"), formatted once here. The site's pages quote
them through mkdocs-macros (``{{ main.train_cpu }}`` on a page whose front matter sets
``render_macros: true``); the README, which GitHub shows as written, gets the same sentences in its
``headline`` section, rewritten from the file on every ``update`` (``tests/docs/test_figures.py`` checks both).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from agents.doc_sections import DOCS, README, read_section, replace_section
from box_toss_env.files import write_atomic

FIGURES = DOCS / "generated" / "figures.yml"
HEADER = (
    "# Generated: every value is written by the command that measured it (agents/figures.py names each group's).\n"
    "# Pages quote them ({{ main.train_cpu }} with render_macros: true); do not edit by hand.\n"
)
HEADLINE = "headline"
"""The README's section written from this file."""


def load(path: Path = FIGURES) -> dict[str, Any]:
    """Every group of the figures file (empty if there is none yet)."""
    return yaml.safe_load(path.read_text()) or {} if path.exists() else {}


def percent(rate: float) -> str:
    return f"{rate:.1%}"


def duration(seconds: float) -> str:
    """A duration as every table and page prints it: "0.50 s", "42 s", "3.2 min"."""
    if seconds < 1:
        return f"{seconds:.2f} s"
    if seconds < 120:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.1f} min"


def count(n: float) -> str:
    return f"{n:,.0f}"


def update(
    group: str, values: dict[str, Any] | list[dict[str, Any]], path: Path = FIGURES, readme: Path | None = README
) -> None:
    """Replace ``group`` in the figures file (the other groups kept), written atomically, then the README's
    ``headline`` section from the file (``readme=None`` leaves the README alone)."""
    figures = {**load(path), group: values}
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, HEADER + yaml.safe_dump(figures, sort_keys=True, allow_unicode=True, width=120))
    if readme is not None and read_section(HEADLINE, readme) is not None:
        replace_section(HEADLINE, headline(figures), readme)


def headline(figures: dict[str, Any]) -> str:
    """The README's headline sentences, from the figures (what the site's pages say with the same values)."""
    main = figures.get("main")
    if main is None:
        return "The main command has not been measured yet (`python -m agents.main --full --readme`)."
    return (
        f"`python -m agents.main` trains PPO on `{main['env_id']}` for {main['throws']} throws and scores it on "
        f"{main['test_targets']} fixed test targets: {main['success']} success (random throws: "
        f"{main['random_success']}). Its training run takes {main['train_cpu']} of CPU time and the whole "
        f"command {main['command_cpu']}; their wall time was {main['train_wall']} and {main['command_wall']} on "
        f"{main['machine']} ([how it was measured](docs/methodology/main-command.md))."
    )
