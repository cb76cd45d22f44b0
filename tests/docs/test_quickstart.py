"""The quickstart notebook (docs/quickstart.ipynb) runs from top to bottom, as nbmake runs notebooks, and the site
shows it with the outputs it was saved with."""

import os
from pathlib import Path

import nbformat
import pytest
from nbmake.nb_run import NotebookRun

REPO = Path(__file__).resolve().parents[2]
NOTEBOOK = REPO / "docs" / "quickstart.ipynb"
TIMEOUT_S = 600  # per cell; the whole notebook takes about a minute of CPU


def test_the_quickstart_notebook_runs(monkeypatch):
    pytest.importorskip("pygame")
    # the kernel runs in docs/: the repository's agents package and models/ are found from its root
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    result = NotebookRun(NOTEBOOK, default_timeout=TIMEOUT_S).execute()
    assert result.error is None, f"cell {result.error.failing_cell_index}: {result.error.summary}\n{result.error.trace}"
    printed = "".join(
        output.get("text", "") for cell in result.nb.cells if cell.cell_type == "code" for output in cell.outputs
    )
    assert "trained agent: 100.0% success" in printed  # the committed agent lands every one of the 256 targets


def test_the_notebook_is_saved_with_its_outputs_and_no_error():
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    outputs = [output for cell in code for output in cell.outputs]
    assert not [output for output in outputs if output.output_type == "error"]
    assert sum("image/png" in output.get("data", {}) for output in outputs) == 2  # a throw's frames, the landings
