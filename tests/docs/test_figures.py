"""The headline figures have one source, docs/generated/figures.yml: the README says what the file says, the trained
agents' group is what their folders' evaluations say, and the user pages quote the file instead of typing figures."""

import re
from pathlib import Path

import pytest
import yaml

from agents import figures, pretrained
from agents.doc_sections import README, read_section

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs"
QUOTING_PAGES = ["index.md", "getting-started.md", "agents.md", "pretrained.md", "batched.md", "environment.md"]
"""User pages that state headline figures: each quotes them from the file (mkdocs-macros)."""
TYPED_FIGURE = re.compile(r"\b(?!95%)\d+(?:\.\d+)? ?(?:min\b|%)|\b\d{1,3}(?:,\d{3})+ (?:throws|boxes)\b")
"""A duration, a percentage (95%, a confidence level, aside) or a count of throws, as typed into a page."""


def without_generated(text: str) -> str:
    """The page as typed: no code blocks, no macro expressions, no sections that commands write."""
    text = re.sub(r"```.*?```", "", text, flags=re.DOTALL)
    text = re.sub(r"\{\{.*?\}\}|\{%.*?%\}", "", text, flags=re.DOTALL)
    return re.sub(r"<!-- ([\w-]+):start -->.*?<!-- \1:end -->", "", text, flags=re.DOTALL)


def test_the_readme_headline_is_the_figures_file():
    assert read_section(figures.HEADLINE, README) == figures.headline(figures.load()).strip()


def test_the_trained_agents_group_is_their_evaluations():
    assert figures.load()["pretrained"] == pretrained.headline_figures()


@pytest.mark.parametrize("page", QUOTING_PAGES)
def test_user_pages_quote_headline_figures_from_the_file(page):
    text = (DOCS / page).read_text()
    if "{{" in text:
        assert yaml.safe_load(text.split("---")[1]) == {"render_macros": True}  # the front matter turns macros on
    assert TYPED_FIGURE.findall(without_generated(text)) == []


def test_the_readme_types_no_headline_figure_outside_its_written_sections():
    assert TYPED_FIGURE.findall(without_generated(README.read_text())) == []


def test_update_keeps_the_other_groups_and_rewrites_the_readme_headline(tmp_path):
    path, readme = tmp_path / "figures.yml", tmp_path / "README.md"
    readme.write_text("intro\n<!-- headline:start -->\nold\n<!-- headline:end -->\nend\n")
    figures.update("throughput", {"single": "9,000"}, path, readme)
    main = {
        "env_id": "BoxToss-ThisSideUp-v0",
        "throws": "501,760",
        "test_targets": "1,024",
        "success": "99.0%",
        "random_success": "0.4%",
        "train_cpu": "3.0 min",
        "train_wall": "6.0 min",
        "command_cpu": "3.5 min",
        "command_wall": "7.0 min",
        "machine": "a 2-core machine",
    }
    figures.update("main", main, path, readme)
    assert figures.load(path) == {"throughput": {"single": "9,000"}, "main": main}
    headline = read_section(figures.HEADLINE, readme)
    assert "99.0% success" in headline and "takes 3.0 min of CPU time and the whole command 3.5 min" in headline
    assert readme.read_text().startswith("intro\n") and readme.read_text().endswith("end\n")
