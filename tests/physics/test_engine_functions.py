"""The engine's functions take at most MAX_PARAMETERS parameters each: a stage takes the two or three named
structures it reads (``colliding.state``, ``robust.state``), not dozens of arrays."""

import ast
from pathlib import Path

ENGINE = Path(__file__).resolve().parents[2] / "box_toss_env" / "physics"
MAX_PARAMETERS = 12


def parameter_counts(source: str) -> dict[str, int]:
    """Every function of ``source`` by name -> how many parameters it takes."""
    counts = {}
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = node.args
            counts[node.name] = (
                len(args.posonlyargs)
                + len(args.args)
                + len(args.kwonlyargs)
                + (args.vararg is not None)
                + (args.kwarg is not None)
            )
    return counts


def test_no_engine_function_takes_more_than_twelve_parameters():
    over = {
        f"{path.relative_to(ENGINE).as_posix()}:{name}": count
        for path in sorted(ENGINE.rglob("*.py"))
        for name, count in parameter_counts(path.read_text()).items()
        if count > MAX_PARAMETERS
    }
    assert over == {}


def test_the_count_sees_every_parameter():
    counts = parameter_counts("def f(a, /, b, *c, d, **e):\n    pass\n")
    assert counts == {"f": 5}
