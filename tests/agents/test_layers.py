"""agents/ imports one way: base -> policies -> evaluation -> training -> reports -> commands."""

import ast
from pathlib import Path

AGENTS = Path(__file__).resolve().parents[2] / "agents"
LAYERS = {
    "algorithms": 0,
    "command_line": 0,
    "targets": 0,
    "env_wrappers": 0,
    "doc_sections": 0,
    "model_card": 0,
    "figures": 1,
    "section_merge": 0,
    "rllib_envs": 0,
    "schema": 1,
    "run_folder": 1,
    "envs": 1,
    "config": 2,
    "run_files": 3,
    "checkpoints": 4,
    "policies": 4,
    "oracle": 4,
    "stack_planner": 4,
    "search_space": 4,
    "evaluation": 5,
    "training": 6,
    "ceiling": 6,
    "pretrained": 6,
    "report": 7,
    "tuning": 7,
    "sweep_report": 7,
    "train": 8,
    "evaluate": 8,
    "baselines": 8,
    "tune": 8,
    "rllib_ppo": 8,
    "variant_gifs": 8,
    "raw_actions": 8,
    "hidden_physics_tier": 8,
    "benchmark": 9,
    "main": 9,
}
COMMANDS = 8
"""The commands (layers 8 and 9) may import their modules inside functions, after parsing their options, so that
``--help`` and a refused option answer without loading torch (still one way: only lower layers)."""


def agents_imports(path: Path) -> list[tuple[str, bool]]:
    """(imported agents module, whether the import is inside a function) for every import."""
    tree = ast.parse(path.read_text())
    found = []
    nested = {
        id(n) for f in ast.walk(tree) if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)) for n in ast.walk(f)
    }
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "agents":
            names = [node.module] if node.module != "agents" else [f"agents.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names if a.name.split(".")[0] == "agents"]
        found += [(name.split(".")[1], id(node) in nested) for name in names if "." in name]
    return found


def test_every_agents_module_has_a_layer():
    modules = {p.stem for p in AGENTS.glob("*.py")} - {"__init__"}
    assert modules == set(LAYERS)


def test_imports_go_one_way_and_only_the_commands_import_in_a_function():
    for name, layer in LAYERS.items():
        for imported, in_function in agents_imports(AGENTS / f"{name}.py"):
            assert not in_function or layer >= COMMANDS, f"agents/{name}.py imports agents.{imported} inside a function"
            assert LAYERS[imported] < layer, (
                f"agents/{name}.py (layer {layer}) imports agents.{imported} (layer {LAYERS[imported]})"
            )
