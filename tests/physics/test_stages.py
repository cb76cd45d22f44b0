"""The stage script is written once (``physics.stages``): the code that runs each script names its stages, in a
comment each, in the script's order, and the docs show the scripts as ``stages.scripts_markdown`` writes them."""

import ast
import io
import tokenize
from pathlib import Path

import pytest

from box_toss_env.physics import stages

REPO = Path(__file__).resolve().parents[2]
PHYSICS = REPO / "box_toss_env" / "physics"

RUNNERS = [
    # (module, function, the script its stage comments follow)
    ("colliding/step.py", "substep", stages.COLLIDING_SUBSTEP),
    ("robust/contact_step.py", "contact_step", stages.FLOOR_PIECE),
    ("robust/contact_step.py", "solve_piece", stages.FLOOR_PIECE[1:5]),
    ("robust/robust_solver.py", "advance_box", stages.FLOOR_STEP),
]


def stage_comments(source: str, function: str) -> list[str]:
    """The stages ``function``'s comments name, in order: a comment naming stages starts with their names, separated
    by commas, before a colon or a parenthesis (``# find contacts, integrate velocities (...)``)."""
    node = next(n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.FunctionDef) and n.name == function)
    named = []
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT and node.lineno <= token.start[0] <= node.end_lineno:
            text = token.string.lstrip("#").strip().strip("-").strip()
            head = text.split(":")[0].split("(")[0]
            names = [name.strip() for name in head.split(",")]
            if names[0] in stages.STAGES:
                named += [name for name in names if name in stages.STAGES]
    return named


def test_every_script_is_made_of_named_stages():
    for name, script in stages.SCRIPTS.items():
        assert set(script) <= set(stages.STAGES), name
        assert len(set(script)) == len(script), name
    assert not any("|" in stage.does for stage in stages.STAGES.values())  # a Markdown table's cell


def test_the_solvers_share_every_stage_both_run():
    # the names are one vocabulary: no stage of a substep is the other solver's under another name
    shared = set(stages.COLLIDING_SUBSTEP) & set(stages.FLOOR_PIECE)
    assert {"find contacts", "integrate velocities", "solve contacts", "restitution", "relax"} <= shared


@pytest.mark.parametrize(("module", "function", "script"), RUNNERS)
def test_the_code_runs_the_script_in_order(module, function, script):
    assert stage_comments((PHYSICS / module).read_text(), function) == list(script)


def test_the_docs_show_the_scripts():
    assert stages.scripts_markdown() in (REPO / "docs" / "box_collisions.md").read_text()


def test_a_comment_names_stages_before_its_colon():
    source = "def f():\n    # solve contacts, store impulses: the rest\n    # not a stage: solve contacts\n    pass\n"
    assert stage_comments(source, "f") == ["solve contacts", "store impulses"]
