"""The README is the front page: its test command is .ci/run's, line for line, and the sections that commands
rewrite (``<!-- NAME:start -->`` ... ``<!-- NAME:end -->``) are in the pages ``agents.doc_sections`` names."""

import re
from pathlib import Path

import pytest

from agents.doc_sections import DOCS, README, SECTION_PAGES, page_for, relink, replace_section

REPO = Path(__file__).resolve().parents[1]


def readme_test_command() -> list[str]:
    block = README.read_text().split("<!-- --8<-- [start:tests] -->")[1].split("<!-- --8<-- [end:tests] -->")[0]
    return re.search(r"```bash\n(.*?)\n```", block, flags=re.DOTALL)[1].splitlines()


def test_ci_runs_the_readme_test_command_line_for_line():
    command = readme_test_command()
    ci = (REPO / ".ci" / "run").read_text().splitlines()
    start = ci.index(command[0])
    assert ci[start : start + len(command)] == command
    # one command a line, so that under .ci/run's set -e any failing one stops CI (in an && list, only the last's
    # failure would)
    assert not any("&&" in line or line.endswith("\\") for line in command)
    assert {"ruff check .", "mkdocs build --strict", "pytest"} <= set(command)


def test_readme_is_a_front_page():
    assert len(README.read_text().splitlines()) <= 160


@pytest.mark.parametrize("name", sorted(SECTION_PAGES))
def test_every_written_section_has_its_markers_in_its_page(name):
    text = page_for(name).read_text()
    assert text.count(f"<!-- {name}:start -->") == 1 and text.count(f"<!-- {name}:end -->") == 1
    assert page_for(name) == README or page_for(name).is_relative_to(DOCS)  # docs/agents/benchmark.md too


def test_links_from_the_repository_root_are_made_relative_to_the_page(tmp_path):
    text = "see [the benchmark](docs/agents/benchmark.md) and ![curve](docs/agents/learning_curve.png)"
    assert relink(text, README) == text
    assert relink(text, DOCS / "agents.md") == text.replace("](docs/", "](")
    assert relink(text, DOCS / "agents" / "benchmark.md") == text.replace("](docs/", "](../")
    page = tmp_path / "page.md"
    page.write_text("a\n<!-- x:start -->\nold\n<!-- x:end -->\nb\n")
    replace_section("x", "new", page)
    assert page.read_text() == "a\n<!-- x:start -->\nnew\n<!-- x:end -->\nb\n"


def test_the_readme_example_runs():
    code = re.search(r"## A first throw\n\n```python\n(.*?)```", README.read_text(), flags=re.DOTALL)[1]
    assert len(code.splitlines()) <= 10
    namespace: dict = {}
    exec(code, namespace)
    assert namespace["terminated"] and namespace["venv"].num_envs == 64
    namespace["venv"].close()
