"""No function or method of the repository's packages is longer than ``MAX_LINES`` lines (from its ``def`` line
to its last line, decorators not counted; a nested function counts in its own right and inside the one that
holds it), except the few in ``ALLOWED``, each with the length it has now: an allowed function may shrink but
not grow, and one that is back under the limit (or gone) must leave the list."""

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("box_toss_env", "agents", "benchmarks", "reports")
MAX_LINES = 80

ALLOWED: dict[str, int] = {}
"""``file:function`` (``Class.method``, ``outer.inner``) -> its length in lines."""


def function_lengths(source: str) -> dict[str, int]:
    """Every function and method of ``source`` by its qualified name -> its length in lines."""
    lengths = {}

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = prefix + child.name
                lengths[name] = child.end_lineno - child.lineno + 1
                visit(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, prefix + child.name + ".")
            else:
                visit(child, prefix)

    visit(ast.parse(source), "")
    return lengths


def too_long(lengths: dict[str, int], path: str) -> dict[str, int]:
    return {f"{path}:{name}": n for name, n in lengths.items() if n > MAX_LINES}


def repository_lengths() -> dict[str, int]:
    found = {}
    for package in PACKAGES:
        for path in sorted((REPO / package).rglob("*.py")):
            relative = path.relative_to(REPO).as_posix()
            found.update({f"{relative}:{name}": n for name, n in function_lengths(path.read_text()).items()})
    return found


@pytest.fixture(scope="module")
def lengths():
    return repository_lengths()


def test_no_function_is_longer_than_the_limit_unless_allowed(lengths):
    over = {name: n for name, n in lengths.items() if n > MAX_LINES and name not in ALLOWED}
    assert over == {}, f"split these functions (at most {MAX_LINES} lines each), or argue for them in ALLOWED"


def test_allowed_functions_do_not_grow(lengths):
    grown = {name: (lengths[name], limit) for name, limit in ALLOWED.items() if lengths.get(name, 0) > limit}
    assert grown == {}, "(now, allowed): an allowed function may shrink, not grow"


def test_the_allow_list_holds_only_long_functions(lengths):
    stale = [name for name in ALLOWED if lengths.get(name, 0) <= MAX_LINES]
    assert stale == [], "these are gone or back under the limit: remove them from ALLOWED"


def test_the_check_catches_a_long_function_and_method():
    body = "".join(f"    x{i} = {i}\n" for i in range(MAX_LINES - 1))
    method_body = body.replace("    ", "        ")
    source = (
        f"def short():\n    pass\n\n\ndef long():\n{body}    return 0\n\n\n"
        f"class C:\n    def method(self):\n{method_body}"
    )
    lengths = function_lengths(source)
    assert lengths["short"] == 2
    assert lengths["long"] == MAX_LINES + 1
    assert lengths["C.method"] == MAX_LINES
    assert too_long(lengths, "example.py") == {"example.py:long": MAX_LINES + 1}
