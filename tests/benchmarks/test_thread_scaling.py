"""benchmarks.thread_scaling: its options are checked before anything runs, and ``--write-docs`` puts the table
between the page's markers (the runs themselves are stood in for: what a second thread buys is the benchmark's)."""

import math
from types import SimpleNamespace

import numba
import numpy as np
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
    timings = thread_scaling.Timings({1: [2.0], 2: [1.0]}, {1: [3.0], 2: [2.0]}, [0.5], True)
    monkeypatch.setattr(thread_scaling, "measure", lambda s, counts, repeats: timings)
    thread_scaling.main(["--write-docs", "--repeats", "1"])
    text = page.read_text()
    assert "old" not in text and text.endswith("<!-- thread-scaling:end -->\n\nafter\n")
    assert "| tiny | 30 | 2.00 | 1.00 | 2.00x (2.00/1.00) | 1.50x (1.50) | 0.50-0.50 | yes |" in text
    assert "1 interleaved repeats" in text and "| tiny |" in capsys.readouterr().out


def test_the_control_does_the_same_work_on_any_number_of_threads():
    """The control's regions split one sum into equal shares, one a thread: the shares' results do not depend on the
    thread count (what differs is only how long they take, which the benchmark reports)."""
    out_one, out_two = np.zeros(2), np.zeros(2)
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        thread_scaling.control_region(out_one, 1000)
    finally:
        numba.set_num_threads(before)
    thread_scaling.control_region(out_two, 1000)
    expected = [sum(math.sqrt(i + share) for i in range(1000)) for share in range(2)]
    np.testing.assert_allclose(out_one, expected, rtol=1e-12)
    assert np.array_equal(out_one, out_two)
    assert thread_scaling.control_run(1, 2) > 0.0
