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


def test_the_tests_mirror_the_package_layout():
    """Each folder of tests/ is named after the package folder whose code it tests (``tests/wrappers`` tests
    ``box_toss_env/wrappers``, ``tests/agents`` the ``agents`` package, ``tests/docs`` the site, ...)."""
    tests = (REPO / "tests").iterdir()
    folders = {path.name for path in tests if path.is_dir() and not path.name.startswith((".", "_"))}
    packages = {path.name for path in (REPO / "box_toss_env").iterdir() if (path / "__init__.py").exists()}
    packages |= {name for name in ("agents", "benchmarks", "reports", "examples", "docs") if (REPO / name).is_dir()}
    assert folders - packages == set()


def test_the_task_envs_hold_no_engine_set_up_of_their_own():
    """The multi-throw envs are thin wrappers over their core: of the engine they import its array layout at most
    (no scene, kernel, simulator or settings)."""
    envs = REPO / "box_toss_env" / "envs"
    for name in ("stack.py", "stack_vector.py", "hidden_physics.py"):
        engine_names = {
            alias.name
            for node in ast.walk(ast.parse((envs / name).read_text()))
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("box_toss_env.physics")
            for alias in node.names
        }
        assert engine_names <= {"layout"}, name
