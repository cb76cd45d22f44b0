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
    "benchmark_store": 0,
    "figures": 1,
    "rllib_envs": 0,
    "schema": 1,
    "run_folder": 1,
    "envs": 1,
    "recipe_options": 0,
    "curriculum": 2,
    "initial_mean": 2,
    "config": 3,
    "run_files": 4,
    "benchmark_tiers": 4,
    "checkpoints": 5,
    "policies": 5,
    "oracle": 5,
    "stack_planner": 5,
    "search_space": 5,
    "evaluation": 6,
    "training": 7,
    "ceiling": 7,
    "pretrained": 7,
    "report": 8,
    "tuning": 8,
    "sweep_report": 8,
    "train": 9,
    "evaluate": 9,
    "baselines": 9,
    "tune": 9,
    "rllib_ppo": 9,
    "variant_gifs": 9,
    "raw_actions": 9,
    "hidden_physics_tier": 9,
    "benchmark_stats": 9,
    "benchmark_goal": 9,
    "benchmark_report": 10,
    "benchmark_hidden": 10,
    "benchmark_page": 11,
    "benchmark": 12,
    "main": 12,
}
COMMANDS = 9
"""The commands (layers 9 and up) may import their modules inside functions, after parsing their options, so that
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
