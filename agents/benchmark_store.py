"""The benchmark's measured runs, kept between sessions: ``docs/agents/benchmark_runs.json``.

Every finished run (a training seed, a random or prior evaluation, a run trained on a train split) is one record,
added as soon as it is scored, and the file is rewritten atomically after each: a session stopped between runs
loses none, and the tables are rebuilt from this file alone (``--report-only``) on a machine without the runs.
A record is keyed by (variant, tier, agent, seed, split); a new measurement of the same key replaces the old.

A record: ``env_id``, ``tier`` (None for random actions, the same in every tier), ``agent`` (``random``,
``prior``, or an algorithm), ``seed``, ``split`` (None, or ``"train"`` for a run trained on the train split),
``results`` (by evaluation tag: ``default`` on the run's own env, ``split=test`` on the test split; each the
scores of ``agents.evaluation``: success, distances, face accuracy, and by target face and distance), ``timing``
(``timing.json``: env steps, wall seconds) and ``training_return`` (the last rollouts' mean return, or None).
``ceilings`` holds each variant's oracle sweep (``agents.ceiling``) per split (``default``, ``split=train``,
``split=test``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from box_toss_env.files import write_atomic

DOCS = Path(__file__).resolve().parents[1] / "docs" / "agents"
STORE = DOCS / "benchmark_runs.json"
KEY = ("env_id", "tier", "agent", "seed", "split")
RESULT_KEYS = (
    "n",
    "success_rate",
    "mean_distance",
    "median_distance",
    "face_accuracy",
    "mean_reward",
    "failures",
    "mean_height",
    "fall_rate",
    "by_face",
    "by_distance",
    "env_kwargs",
)
TIMING_KEYS = ("timesteps", "wall_seconds", "env_seconds", "eval_seconds", "env_share", "torch_threads")


def empty() -> dict[str, Any]:
    return {"runs": [], "ceilings": {}}


def load(path: Path = STORE) -> dict[str, Any]:
    """The store at ``path`` (an empty one if there is none)."""
    if not path.exists():
        return empty()
    data = json.loads(path.read_text())
    return {"runs": list(data.get("runs", [])), "ceilings": dict(data.get("ceilings", {}))}


def save(store: dict[str, Any], path: Path = STORE) -> None:
    """Rewrite ``path`` atomically, records in a stable order (variant, tier, agent, split, seed)."""
    runs = sorted(
        store["runs"],
        key=lambda r: (r["env_id"], str(r["tier"]), r["agent"], str(r["split"]), r["seed"]),
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, json.dumps({"runs": runs, "ceilings": store["ceilings"]}, indent=1) + "\n")


def key_of(record: dict[str, Any]) -> tuple:
    return tuple(record[name] for name in KEY)


def add(store: dict[str, Any], record: dict[str, Any]) -> None:
    """Put ``record`` in the store, replacing a record of the same key."""
    key = key_of(record)
    store["runs"] = [r for r in store["runs"] if key_of(r) != key] + [record]


def trimmed(results: dict[str, Any]) -> dict[str, Any]:
    """The scores the tables use, of an evaluation's ``results.json``."""
    return {key: results[key] for key in RESULT_KEYS if key in results}


def make_record(
    env_id: str,
    tier: str | None,
    agent: str,
    seed: int,
    results: dict[str, dict[str, Any]],
    *,
    split: str | None = None,
    timing: dict[str, Any] | None = None,
    training_return: float | None = None,
) -> dict[str, Any]:
    """One record (module docstring); ``results`` by evaluation tag."""
    return {
        "env_id": env_id,
        "tier": tier,
        "agent": agent,
        "seed": int(seed),
        "split": split,
        "results": {tag: trimmed(value) for tag, value in results.items()},
        "timing": None if timing is None else {key: timing[key] for key in TIMING_KEYS if key in timing},
        "training_return": training_return,
    }


def records(
    store: dict[str, Any],
    env_id: str,
    tier: str | None,
    agent: str,
    split: str | None = None,
    seeds: tuple[int, ...] | list[int] | None = None,
) -> list[dict[str, Any]]:
    """The records of one cell, by seed (only ``seeds`` if given)."""
    found = [
        r
        for r in store["runs"]
        if r["env_id"] == env_id and r["tier"] == tier and r["agent"] == agent and r["split"] == split
    ]
    if seeds is not None:
        found = [r for r in found if r["seed"] in seeds]
    return sorted(found, key=lambda r: r["seed"])


def success(record: dict[str, Any], tag: str = "default") -> float | None:
    """The record's success rate under evaluation ``tag`` (None if it has none)."""
    result = record["results"].get(tag)
    return None if result is None else float(result["success_rate"])
