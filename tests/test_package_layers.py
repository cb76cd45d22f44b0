"""The repository's packages import one way: box_toss_env <- agents <- benchmarks <- reports (a package imports
only those before it), so that what two of them share lives below both (``agents/test_layers.py`` orders the
modules inside agents/)."""

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGES = {"box_toss_env": 0, "agents": 1, "benchmarks": 2, "reports": 3}


def imported_packages(path: Path) -> set[str]:
    """The repository packages a file imports (anywhere in it, functions included)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
        elif isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
    return found & set(PACKAGES)


@pytest.mark.parametrize("package", PACKAGES)
def test_packages_import_only_the_packages_below_them(package):
    wrong = {
        str(path.relative_to(REPO)): sorted(
            other for other in imported_packages(path) if PACKAGES[other] > PACKAGES[package]
        )
        for path in (REPO / package).rglob("*.py")
    }
    assert {path: others for path, others in wrong.items() if others} == {}
