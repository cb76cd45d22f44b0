"""Commands change no tracked file unless told: the reports and ``agents.pretrained export`` wrote docs/ by default
(``reports.precision``, ``stability``, ``collisions``, ``reality`` into docs/, ``reality.impacts`` into
docs/reality.md, ``export`` into docs/generated/figures.yml and the README); now only ``--write-docs`` does. The
long runs are replaced by stubs: what is tested is where each command writes."""

import json
from pathlib import Path
from types import SimpleNamespace

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"


def untracked(path: Path) -> bool:
    """Outside the repository, or in its build/ folder (which .gitignore lists)."""
    path = path.resolve()
    return not path.is_relative_to(REPO) or path.is_relative_to(REPO / "build")


@pytest.mark.parametrize("name", ["precision", "stability", "collisions"])
def test_a_report_writes_docs_only_with_write_docs(name, monkeypatch, capsys):
    import importlib

    module = importlib.import_module(f"reports.{name}")
    written: list[tuple[Path, Path | None]] = []

    def write_report(report, out, readme=None):
        written.append((out, readme))
        return out / f"{name}.md"

    monkeypatch.setattr(module, "run", lambda quick: SimpleNamespace(run_seconds=0.0, quick=quick))
    monkeypatch.setattr(module, "write_report", write_report)
    for argv in ([], ["--quick"]):
        written.clear()
        assert module.main(argv) == 0
        ((out, readme),) = written
        assert untracked(out) and readme is None, (argv, out, readme)
    written.clear()
    assert module.main(["--write-docs"]) == 0
    assert written == [(DOCS, DOCS / "reports.md")]
    with pytest.raises(SystemExit):
        module.main(["--write-docs", "--quick"])  # the docs hold the full report only


def test_the_reality_report_writes_docs_only_with_write_docs(tmp_path, monkeypatch, capsys):
    from reports.reality import report

    written: list[Path] = []

    def write_report(result, out, quick=False):
        written.append(out)
        page = tmp_path / "reality.md"
        page.write_text("## Cleaning\n\n## What it teaches\n")
        return page

    monkeypatch.setattr(report, "run", lambda data, quick: SimpleNamespace(run_seconds=0.0))
    monkeypatch.setattr(report, "write_report", write_report)
    for argv in ([], ["--quick"]):
        assert report.main(["--data", str(tmp_path), *argv]) == 0
        assert untracked(written[-1]), (argv, written[-1])
    assert report.main(["--data", str(tmp_path), "--write-docs"]) == 0
    assert written[-1] == DOCS


def test_the_impacts_section_is_written_into_the_docs_only_with_write_docs(tmp_path, monkeypatch, capsys):
    from reports.reality import impacts

    pages: list[Path] = []
    monkeypatch.setattr(impacts, "run_square", lambda *args: None)
    monkeypatch.setattr(impacts, "write_section", lambda text, page: pages.append(page))
    assert impacts.main(["--data", str(tmp_path)]) == 0
    assert untracked(pages[-1]), pages[-1]
    assert impacts.main(["--data", str(tmp_path), "--write-docs"]) == 0
    assert pages[-1] == DOCS / "reality.md"


def test_the_default_impacts_page_is_created_outside_the_tracked_files(tmp_path, monkeypatch):
    from reports.reality import impacts

    page = tmp_path / "build" / "reports" / "reality.md"
    monkeypatch.setattr(impacts, "QUICK_PAGE", page)
    impacts.write_section("the section", page)
    assert page.read_text() == f"<!-- {impacts.SECTION}:start -->\nthe section\n<!-- {impacts.SECTION}:end -->\n"
    impacts.write_section("again", page)  # an existing page: its section is replaced
    assert "again" in page.read_text() and "the section" not in page.read_text()


def test_export_rewrites_the_figures_only_with_write_docs(tmp_path, monkeypatch, capsys):
    from agents import figures, pretrained

    run = tmp_path / "run"
    run.mkdir()
    (run / "config.yml").write_text("algo: ppo\n")
    (run / "model.zip").write_bytes(b"")
    folder = tmp_path / "models" / "ppo-BoxToss-v0"
    folder.mkdir(parents=True)
    (folder / "results.json").write_text(json.dumps({"success_rate": 1.0, "success_interval": [0.9, 1.0], "n": 8}))
    updated: list[str] = []
    monkeypatch.setattr(pretrained, "export", lambda run, models: folder)
    monkeypatch.setattr(pretrained, "headline_figures", lambda models: [])
    monkeypatch.setattr(figures, "update", lambda name, *args, **kwargs: updated.append(name))
    pretrained.main(["export", str(run), "--models", str(tmp_path / "models")])
    assert updated == []
    pretrained.main(["export", str(run), "--models", str(tmp_path / "models"), "--write-docs"])
    assert updated == ["pretrained"]
