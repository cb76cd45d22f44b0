"""No function of the repository's packages takes more than MAX_PARAMETERS parameters (a method's ``self`` or
``cls`` not counted): an engine stage takes the two or three named structures it reads (``colliding.state``,
``robust.state``), not dozens of arrays; a function with many options takes them as one mapping or structure."""

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("box_toss_env", "agents", "benchmarks", "reports", "examples")
MAX_PARAMETERS = 12


def parameter_counts(source: str) -> dict[str, int]:
    """Every function of ``source`` by name -> how many parameters it takes (a leading ``self``/``cls`` not)."""
    counts = {}
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = node.args
            positional = [*args.posonlyargs, *args.args]
            bound = bool(positional) and positional[0].arg in ("self", "cls")
            counts[node.name] = (
                len(positional) - bound + len(args.kwonlyargs) + (args.vararg is not None) + (args.kwarg is not None)
            )
    return counts


def test_no_function_takes_more_than_twelve_parameters():
    over = {
        f"{path.relative_to(REPO).as_posix()}:{name}": count
        for package in PACKAGES
        for path in sorted((REPO / package).rglob("*.py"))
        for name, count in parameter_counts(path.read_text()).items()
        if count > MAX_PARAMETERS
    }
    assert over == {}


def test_the_count_sees_every_parameter_but_self():
    source = "def f(a, /, b, *c, d, **e):\n    pass\n\n\nclass C:\n    def m(self, a, *, b):\n        pass\n"
    counts = parameter_counts(source)
    assert counts == {"f": 5, "m": 2}
