"""benchmarks.thread_scaling: its options are checked before anything runs, and ``--write-docs`` puts the table
between the page's markers (the runs themselves are stood in for: what a second thread buys is the benchmark's)."""

from types import SimpleNamespace

import pytest

from benchmarks import thread_scaling


def test_write_docs_takes_the_whole_table_only():
    with pytest.raises(SystemExit):
        thread_scaling.parse(["--write-docs", "--cases", "large_pyramid"])
    with pytest.raises(SystemExit):
        thread_scaling.parse(["--write-docs", "--seconds", "1"])
    with pytest.raises(SystemExit):
        thread_scaling.parse(["--cases", "large pyramid"])  # unknown: the names are the table's
    assert thread_scaling.parse(["--write-docs"]).write_docs


def test_write_docs_puts_the_table_between_the_markers(tmp_path, monkeypatch, capsys):
    page = tmp_path / "engine_scale.md"
    page.write_text("# Page\n\n<!-- thread-scaling:start -->\nold\n<!-- thread-scaling:end -->\n\nafter\n")
    start = SimpleNamespace(scene=SimpleNamespace(n_bodies=10), steps=3)
    monkeypatch.setattr(thread_scaling, "CASES", {"tiny": lambda seconds: start})
    monkeypatch.setattr(thread_scaling, "DOCS_PAGE", page)
    monkeypatch.setattr(thread_scaling, "measure", lambda s, counts, repeats: ({1: [2.0], 2: [1.0]}, [0.5], True))
    thread_scaling.main(["--write-docs", "--repeats", "1"])
    text = page.read_text()
    assert "old" not in text and text.endswith("<!-- thread-scaling:end -->\n\nafter\n")
    assert "| tiny | 30 | 2.00 | 1.00 | 2.00x (2.00/1.00) | 0.50-0.50 | yes |" in text
    assert "1 interleaved repeats" in text and "| tiny |" in capsys.readouterr().out
