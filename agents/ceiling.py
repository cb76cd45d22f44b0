"""The ceiling: how often a throw exists, found by searching with the simulator, as the search grows.

The oracle (``agents.oracle``) plans each target with a cross-entropy search over the action that
simulates candidate throws with the env's own engine. Its success is a lower bound on what any policy
can reach, and it rises with the search budget; the ceiling of a variant is its success once a bigger
search stops raising it. ``sweep`` runs the oracle at growing budgets on the same targets and records,
for each budget, the success and the throws simulated per target.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from agents.evaluation import TEST_FIRST_SEED, draw_targets, scores, target_seeds, throw
from agents.oracle import OraclePlanner, OracleSettings, ThrowSimulator, episodes_from_infos

# growing searches: (initial uniform candidates, population per round, elite, rounds)
BUDGETS = (
    OracleSettings(initial=32, population=16, elite=4, iterations=4),
    OracleSettings(initial=128, population=32, elite=8, iterations=12),  # the oracle's default
    OracleSettings(initial=512, population=64, elite=8, iterations=16),
    OracleSettings(initial=2048, population=256, elite=16, iterations=20),
    OracleSettings(initial=8192, population=512, elite=32, iterations=24),
)
CEILING_TARGETS = 256  # the first test targets (seeds 10000...)
RISE_TOLERANCE = 0.01  # "stopped rising": the last budget adds at most this much success


def sweep(
    env_id: str,
    env_kwargs: dict[str, Any] | None = None,
    budgets=BUDGETS,
    n_targets: int = CEILING_TARGETS,
    threads: int | None = None,
    done: list[dict[str, Any]] | None = None,
    on_row: Callable[[list[dict[str, Any]]], None] | None = None,
) -> list[dict[str, Any]]:
    """For each budget: the oracle's success, distance and face accuracy on the first ``n_targets``
    test targets, the throws it simulated per target and its planning seconds.

    ``done`` are rows of an earlier, interrupted sweep: their budgets are not searched again (rows of
    budgets not in ``budgets`` are dropped). ``on_row`` is called with the rows so far after each budget
    (to save them)."""
    keys = [dataclasses.asdict(settings) | {"threads": None} for settings in budgets]
    rows = [row for row in done or [] if row["budget"] in keys]
    finished = [row["budget"] for row in rows]
    todo = [settings for settings, key in zip(budgets, keys, strict=True) if key not in finished]
    if not todo:
        return rows
    env = gym.make(env_id, **(env_kwargs or {}))
    seeds = target_seeds(n_targets, TEST_FIRST_SEED)
    observations, infos = draw_targets(env, seeds)
    simulator = ThrowSimulator(env, threads)
    for settings in todo:
        planner = OraclePlanner(dataclasses.replace(settings, threads=threads))
        start = time.perf_counter()
        actions = planner.plan(simulator, episodes_from_infos(infos))
        seconds = time.perf_counter() - start
        result = scores(throw(env, seeds, actions, infos))
        rows.append(
            {
                "budget": dataclasses.asdict(settings) | {"threads": None},
                "n": result["n"],
                "throws_per_target": planner.simulated / n_targets,
                "plan_seconds": seconds,
                **{key: result[key] for key in ("success_rate", "mean_distance", "median_distance", "face_accuracy")},
            }
        )
        if on_row is not None:
            on_row(rows)
    env.close()
    return rows


def ceiling_of(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The sweep's last (largest) budget, with whether success had stopped rising there."""
    last = rows[-1]
    rise = last["success_rate"] - rows[-2]["success_rate"] if len(rows) > 1 else float("nan")
    return {**last, "last_rise": rise, "converged": bool(np.isfinite(rise) and rise <= RISE_TOLERANCE)}
