"""agents/ imports one way: base -> policies -> evaluation -> training -> reports -> commands."""

import ast
from pathlib import Path

AGENTS = Path(__file__).resolve().parents[2] / "agents"
LAYERS = {
    "algorithms": 0,
    "config": 1,
    "doc_sections": 0,
    "model_card": 0,
    "figures": 1,
    "section_merge": 0,
    "run_folder": 0,
    "envs": 0,
    "rllib_envs": 0,
    "policies": 2,
    "oracle": 2,
    "stack_planner": 2,
    "search_space": 2,
    "evaluation": 3,
    "training": 4,
    "ceiling": 4,
    "pretrained": 4,
    "report": 5,
    "tuning": 5,
    "sweep_report": 5,
    "train": 6,
    "evaluate": 6,
    "baselines": 6,
    "tune": 6,
    "rllib_ppo": 6,
    "variant_gifs": 6,
    "raw_actions": 6,
    "hidden_physics_tier": 6,
    "benchmark": 7,
    "main": 7,
}


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


def test_imports_go_one_way_and_none_hides_in_a_function():
    for name, layer in LAYERS.items():
        for imported, in_function in agents_imports(AGENTS / f"{name}.py"):
            assert not in_function, f"agents/{name}.py imports agents.{imported} inside a function"
            assert LAYERS[imported] < layer, (
                f"agents/{name}.py (layer {layer}) imports agents.{imported} (layer {LAYERS[imported]})"
            )
