"""``BoxToss-Goal-v0`` in the benchmark: what HER buys, and the ballistic command, at the same budget.

The goal env (Dict observations, for HER) is trained here with SB3 directly (``ensure_goal_trained``:
``agents.train`` runs the native batched envs), as the ``GOAL_AGENTS``: SAC and TD3 with their recipe's
``HerReplayBuffer`` and SAC without it, in the recipe's ballistic commands and in the env's own actions. Its throws
are ``BoxToss-v0``'s, scored on the same test targets (``GoalPolicy``). Its rows are the benchmark page's
``benchmark-goal`` section, which ``python -m agents.benchmark --envs BoxToss-Goal-v0 --readme`` rewrites alone.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from agents import algorithms, report
from agents.config import algorithm_kwargs, load_hyperparams
from agents.envs import read_env_wrapper
from agents.evaluation import TEST_TARGETS, evaluate_run, make_baseline_run
from agents.training import quiet_logger, read_timing
from box_toss_env.envs.ballistic import BallisticThrows
from box_toss_env.files import atomic_path, write_atomic

GOAL_ENV = "BoxToss-Goal-v0"
GOAL_AGENTS = {
    "sac-her": ("sac", True, True, "SAC + HER"),
    "td3-her": ("td3", True, True, "TD3 + HER"),
    "sac-no-her": ("sac", False, True, "SAC without HER"),
    "sac-her-env-actions": ("sac", True, False, "SAC + HER, env actions"),
    "sac-no-her-env-actions": ("sac", False, False, "SAC without HER, env actions"),
}
"""The goal env's agents: run name -> (algorithm, with the recipe's HerReplayBuffer, in the recipe's ballistic
commands (else in env actions), the table's label)."""
GOAL_SECTION = "benchmark-goal"


def goal_dir(root: Path, agent: str, seed: int) -> Path:
    return root / GOAL_ENV / f"{agent}-seed{seed}"


def goal_hyperparams(agent: str) -> tuple[str, dict[str, Any]]:
    """The algorithm and settings of the goal agent ``agent``: its recipe for ``BoxToss-Goal-v0`` in
    ``<algo>.yml``, without the replay buffer class (SB3's plain ``DictReplayBuffer``) for an agent without HER,
    without the ``env_wrapper`` (env actions) for an agent in env actions."""
    algo, her, commands, _ = GOAL_AGENTS[agent]
    config = load_hyperparams(algo, GOAL_ENV)
    if not her:
        config.pop("replay_buffer_class", None)
        config.pop("replay_buffer_kwargs", None)
    if not commands:
        config.pop("env_wrapper", None)
    return algo, config


def ensure_goal_trained(root: Path, agent: str, seed: int) -> Path:
    """The goal agent ``agent`` trained with SB3 on ``BoxToss-Goal-v0`` (``n_envs`` single goal envs in a
    ``DummyVecEnv``, one torch thread) and evaluated, unless its results exist. A killed run starts again."""
    import torch
    from stable_baselines3.common.env_util import make_vec_env

    path = goal_dir(root, agent, seed)
    if report.read_results(path) is not None:
        return path
    algo, config = goal_hyperparams(agent)
    path.mkdir(parents=True, exist_ok=True)
    write_atomic(
        path / "config.yml",
        yaml.safe_dump(
            {"algo": algo, "env_id": GOAL_ENV, "env_kwargs": {}, "goal": True, "seed": seed, "hyperparams": config},
            sort_keys=False,
        ),
    )
    write_atomic(path / "command.txt", f"python -m agents.benchmark --envs {GOAL_ENV} --seeds {seed}\n")
    torch.set_num_threads(int(config.get("torch_threads", 1)))
    wrapper = read_env_wrapper(config.get("env_wrapper"))  # ballistic commands, as the flat recipes
    venv = make_vec_env(
        GOAL_ENV,
        n_envs=int(config["n_envs"]),
        seed=seed,
        wrapper_class=BallisticThrows if wrapper else None,
        wrapper_kwargs=wrapper[1] if wrapper else None,
    )
    model = algorithms.algorithm_class(algo)(
        env=venv, seed=seed, device="cpu", verbose=0, **algorithm_kwargs(config, algo)
    )
    print(f"{GOAL_ENV}: {GOAL_AGENTS[agent][-1]}, seed {seed}, {int(config['n_timesteps']):,} throws ...", flush=True)
    model.set_logger(quiet_logger())
    start = time.perf_counter()
    model.learn(int(config["n_timesteps"]))
    wall = time.perf_counter() - start
    venv.close()
    with atomic_path(path / "model.zip") as temp:
        model.save(temp)
    timing = {"algo": algo, "timesteps": int(model.num_timesteps), "wall_seconds": wall}
    write_atomic(path / "timing.json", json.dumps({**timing, "torch_threads": torch.get_num_threads()}, indent=2))
    evaluate_run(path, quiet=True)
    return path


def ensure_goal_random(root: Path) -> Path:
    path = root / GOAL_ENV / "random"
    if report.read_results(path) is None:
        make_baseline_run("random", path, GOAL_ENV, command=f"python -m agents.benchmark --envs {GOAL_ENV}")
        evaluate_run(path, quiet=True)
    return path


def goal_rows(root: Path, algos: list[str], seeds: list[int]) -> list[dict[str, Any]]:
    """The goal env's rows: random actions, then each of ``GOAL_AGENTS`` whose algorithm is in ``algos``."""
    rows = []
    random = report.read_results(root / GOAL_ENV / "random")
    if random:
        rows.append({"agent": "random actions", "results": [random], "timing": [None]})
    for agent, (algo, _, _, name) in GOAL_AGENTS.items():
        found = [
            (report.read_results(p), read_timing(p))
            for seed in seeds
            if algo in algos and report.read_results(p := goal_dir(root, agent, seed)) is not None
        ]
        if found:
            rows.append(
                {
                    "agent": f"{name} ({len(found)} seed{'s' * (len(found) > 1)})",
                    "results": [r for r, _ in found],
                    "timing": [t for _, t in found],
                }
            )
    return rows


def spread(values: list[float]) -> str:
    """mean, and min-max over seeds when there are several."""
    mean = float(np.mean(values))
    return f"{mean:.1%}" if len(values) == 1 else f"{mean:.1%} ({min(values):.1%}-{max(values):.1%})"


def goal_table(rows: list[dict[str, Any]]) -> list[str]:
    lines = [
        "| agent | success | mean distance | median distance | face accuracy | env steps | wall time |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for row in rows:
        results, timing = row["results"], [t for t in row["timing"] if t]
        steps = f"{int(np.mean([t['timesteps'] for t in timing])):,}" if timing else "-"
        wall = report.format_seconds(float(np.mean([t["wall_seconds"] for t in timing]))) if timing else "-"
        lines.append(
            f"| {row['agent']} | {spread([r['success_rate'] for r in results])} | "
            f"{np.mean([r['mean_distance'] for r in results]):.3f} m | "
            f"{np.mean([r['median_distance'] for r in results]):.3f} m | "
            f"{np.mean([r['face_accuracy'] for r in results]):.1%} | {steps} | {wall} |"
        )
    return lines


def goal_document(root: Path, algos: list[str], seeds: list[int]) -> str:
    """The goal env's section of the page: what HER buys at the same budget."""
    rows = goal_rows(root, algos, seeds)
    if not rows:
        return ""
    budgets = sorted({int(goal_hyperparams(agent)[1]["n_timesteps"]) for agent in GOAL_AGENTS})
    lines = [
        f"### {GOAL_ENV}: what HER buys, and ballistic commands",
        "",
        f"The goal-conditioned form of `BoxToss-v0` (Dict observations): its throws are `BoxToss-v0`'s, scored on "
        f"the same {TEST_TARGETS:,} test targets (the ceiling is `BoxToss-v0`'s). Each agent is trained with "
        f"SB3 on `{GOAL_ENV}`'s recipe in `agents/hyperparams/sac.yml` or `td3.yml` "
        f"({' / '.join(f'{b:,}' for b in budgets)} throws), with the recipe's `HerReplayBuffer` or, without HER, "
        "the same settings with SB3's plain replay buffer; in the recipe's ballistic commands, or in the env's "
        "own actions where the row says so (the recipe without `env_wrapper`); the mean over seeds and (min-max). "
        f"`python -m agents.benchmark --envs {GOAL_ENV} --seeds 0 --readme` trains what is missing and rewrites "
        "this section.",
        "",
    ]
    return "\n".join(lines + goal_table(rows))
