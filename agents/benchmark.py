"""One benchmark table for every BoxToss variant: random, each algorithm (several training seeds), the ceiling.

    python -m agents.benchmark                      # everything (hours on 2 cores): runs/benchmark/, docs/agents/
    python -m agents.benchmark --envs BoxToss-ShortEnd-v0 --algos ppo --seeds 0 1 2
    python -m agents.benchmark --report-only --readme   # rebuild the table and figures from finished runs
    python -m agents.benchmark --envs BoxToss-Goal-v0 --seeds 0 --readme   # the goal env's rows only (HER or not)
    python -m agents.benchmark --envs BoxToss-Stack-v0 --set n_timesteps=16384   # the stack at a shorter budget
    python -m agents.benchmark --envs BoxToss-v0 --tiers raw --algos ppo       # in the env's own actions

``BoxToss-Stack-v0`` (a hand of throws per episode) is scored per episode (``agents.evaluation.evaluate_stack``);
its ceiling is ``agents.stack_planner``'s measured rows (``docs/agents/stack_ceiling.json``). The ``raw`` tier
trains a recipe without its ``env_wrapper`` (the env's own actions), in ``runs/benchmark/<env id>/raw/``: the
entry of ``agents/hyperparams/raw/<algo>.yml`` where that file has one (a recipe measured in raw actions), else
the commands recipe with ``env_wrapper=null``.

Each training is ``python -m agents.train`` with the hyperparameters of ``agents/hyperparams/<algo>.yml``
for that env id, in ``runs/benchmark/<env id>/<algo>-seed<k>``; a run that has finished is kept, so
the command continues where a killed one stopped. The ceiling is ``agents.ceiling.sweep`` (the oracle
at growing search budgets), saved in ``runs/benchmark/<env id>/ceiling.json``. Everything is scored on
the same test targets (``agents.evaluation``); the results go to ``docs/agents/benchmark.md``, one
learning-curve figure per variant and, with ``--readme``, the README's benchmark section.

``BoxToss-Goal-v0`` (Dict observations, for HER) is trained here with SB3 directly (``ensure_goal_trained``:
``agents.train`` runs the native batched envs), as the ``GOAL_AGENTS``: SAC and TD3 with their recipe's
``HerReplayBuffer`` and SAC without it, at the recipe's budget, so the table shows what HER buys. Its throws
are ``BoxToss-v0``'s, scored on the same test targets (``GoalPolicy``). Its rows are the page's
``benchmark-goal`` section, which ``--envs BoxToss-Goal-v0 --readme`` rewrites alone.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np
import yaml

from agents import algorithms, ceiling, report, section_merge, stack_planner, train
from agents import config as configuration
from agents.algorithms import ALGORITHMS
from agents.command_line import SEED, OneLineParser, folder, one_line_errors
from agents.config import algorithm_kwargs, load_hyperparams
from agents.doc_sections import README, read_section, replace_section
from agents.envs import read_env_wrapper
from agents.evaluation import STACK_TEST_EPISODES, TEST_TARGETS, evaluate_run, is_stack, make_baseline_run
from agents.run_folder import is_file_on_the_way, read_csv
from agents.section_merge import fill_line, merge_section
from agents.training import RUNS, latest_checkpoint, read_timing
from box_toss_env.envs.ballistic import BallisticThrows
from box_toss_env.files import atomic_path, save_figure, write_atomic

VARIANTS = (
    "BoxToss-v0",
    "BoxToss-LongSide-v0",
    "BoxToss-ShortEnd-v0",
    "BoxToss-ThisSideUp-v0",
    "BoxToss-Mixed-v0",
    "BoxToss-OnBox-v0",
    "BoxToss-Stack-v0",
)
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
ROOT = RUNS / "benchmark"
DOCS = report.DOCS
FACE_KINDS = ("any face", "a long side", "a short end", "face 0", "face 1", "face 2", "face 3")


TIERS = {
    "commands": "the recipe's actions (the ballistic or the stack's throw commands where its file sets an env_wrapper)",
    "raw": "the env's own actions (speed, direction, spin; the recipe without its env_wrapper)",
}
"""How the agents act: ``commands`` as the hyperparameter file says, ``raw`` without its ``env_wrapper``."""
TIER_OVERRIDES = {"commands": [], "raw": ["env_wrapper=null"]}


def tier_hyperparams(algo: str, env_id: str, tier: str) -> Path:
    """The folder of the recipe ``tier`` trains: ``agents/hyperparams/raw/`` for a raw run whose file there has an
    entry for ``env_id``, else ``agents/hyperparams/``."""
    raw = tier == "raw" and configuration.has_entry(algo, env_id, configuration.RAW_HYPERPARAMS)
    return configuration.RAW_HYPERPARAMS if raw else configuration.HYPERPARAMS


def run_dir(root: Path, env_id: str, algo: str, seed: int, tier: str = "commands") -> Path:
    folder = root / env_id if tier == "commands" else root / env_id / tier
    return folder / f"{algo}-seed{seed}"


def ensure_trained(
    root: Path, env_id: str, algo: str, seed: int, tier: str = "commands", overrides: list[str] | None = None
) -> Path:
    """The run of ``algo`` on ``env_id`` with ``seed`` in ``tier``, trained (or resumed) if it has no results;
    ``overrides`` (``--set``) change the file's hyperparameters, e.g. a shorter ``n_timesteps``."""
    path = run_dir(root, env_id, algo, seed, tier)
    if report.read_results(path) is not None:
        return path
    settings = ["--set", *TIER_OVERRIDES[tier], *(overrides or [])] if TIER_OVERRIDES[tier] or overrides else []
    if (path / "config.yml").exists() and latest_checkpoint(path, algo) is not None:
        train.main(["--resume", str(path), "--no-progress"])
    else:
        train.main(
            [
                "--algo",
                algo,
                "--env",
                env_id,
                "--seed",
                str(seed),
                "--no-progress",
                "--runs-dir",
                str(path.parent),
                "--name",
                path.name,
                "--hyperparams",
                str(tier_hyperparams(algo, env_id, tier)),
                *settings,
            ]
        )
    return path


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

    path = run_dir(root, GOAL_ENV, agent, seed)
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
    start = time.perf_counter()
    model.learn(int(config["n_timesteps"]))
    wall = time.perf_counter() - start
    venv.close()
    with atomic_path(path / "model.zip") as temp:
        model.save(temp)
    write_atomic(
        path / "timing.json",
        json.dumps(
            {
                "algo": algo,
                "timesteps": int(model.num_timesteps),
                "wall_seconds": wall,
                "torch_threads": torch.get_num_threads(),
            },
            indent=2,
        ),
    )
    evaluate_run(path, quiet=True)
    return path


def ensure_random(root: Path, env_id: str) -> Path:
    path = root / env_id / "random"
    if report.read_results(path) is None:
        make_baseline_run("random", path, env_id, command=f"python -m agents.baselines random --env {env_id}")
        evaluate_run(path, quiet=True)
    return path


def ensure_ceiling(root: Path, env_id: str) -> dict[str, Any]:
    """The variant's ceiling sweep, run if it is not saved yet. Each finished budget is kept in
    ``ceiling.partial.json``, so a killed sweep resumes at the budget it was searching."""
    path = root / env_id / "ceiling.json"
    if not path.exists():
        partial = path.with_suffix(".partial.json")
        done = json.loads(partial.read_text()) if partial.exists() else []
        print(
            f"{env_id}: oracle at {len(ceiling.BUDGETS)} search budgets on {ceiling.CEILING_TARGETS} targets"
            f"{f' ({len(done)} done before)' if done else ''} ..."
        )
        path.parent.mkdir(parents=True, exist_ok=True)
        rows = ceiling.sweep(env_id, done=done, on_row=lambda rows: write_atomically(partial, rows))
        write_atomically(path, rows)
        partial.unlink(missing_ok=True)
    return json.loads(path.read_text())


def write_atomically(path: Path, rows: list[dict[str, Any]]) -> None:
    """JSON to a temporary file renamed over ``path``: a kill leaves the old file or the new one."""
    write_atomic(path, json.dumps(rows, indent=2))


# -- the table ------------------------------------------------------------------------------------
def spread(values: list[float]) -> str:
    """mean, and min-max over seeds when there are several."""
    if not values:
        return "-"
    mean = float(np.mean(values))
    return f"{mean:.1%}" if len(values) == 1 else f"{mean:.1%} ({min(values):.1%}-{max(values):.1%})"


def agent_rows(
    root: Path, env_id: str, algos: list[str], seeds: list[int], tier: str = "commands"
) -> list[dict[str, Any]]:
    """The rows of the runs found in ``root``: random actions (the same in every tier), then each algorithm's
    seeds in ``tier``."""
    rows: list[dict[str, Any]] = []
    random = report.read_results(root / env_id / "random")
    if random:
        rows.append({"agent": "random actions", "algo": "random", "results": [random], "timing": [None]})
    for algo in algos:
        found = [
            (seed, report.read_results(p), read_timing(p))
            for seed in seeds
            if report.read_results(p := run_dir(root, env_id, algo, seed, tier)) is not None
        ]
        if found:
            rows.append(
                {
                    "agent": f"{algo.upper()} ({len(found)} seed{'s' * (len(found) > 1)})",
                    "algo": algo,
                    "seeds": [seed for seed, _, _ in found],
                    "results": [r for _, r, _ in found],
                    "timing": [t for _, _, t in found],
                    "training_return": [
                        training_return(run_dir(root, env_id, algo, seed, tier)) for seed, _, _ in found
                    ],
                }
            )
    return rows


def goal_rows(root: Path, algos: list[str], seeds: list[int]) -> list[dict[str, Any]]:
    """The goal env's rows: random actions, then each of ``GOAL_AGENTS`` whose algorithm is in ``algos``."""
    rows = []
    random = report.read_results(root / GOAL_ENV / "random")
    if random:
        rows.append({"agent": "random actions", "results": [random], "timing": [None]})
    for agent, (algo, _, _, label) in GOAL_AGENTS.items():
        found = [
            (report.read_results(p), read_timing(p))
            for seed in seeds
            if algo in algos and report.read_results(p := run_dir(root, GOAL_ENV, agent, seed)) is not None
        ]
        if found:
            rows.append(
                {
                    "agent": f"{label} ({len(found)} seed{'s' * (len(found) > 1)})",
                    "results": [r for r, _ in found],
                    "timing": [t for _, t in found],
                }
            )
    return rows


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
        "own actions where the row says so (the recipe without `env_wrapper`). "
        f"`python -m agents.benchmark --envs {GOAL_ENV} --seeds 0 --readme` trains what is missing and rewrites "
        "this section.",
        "",
    ]
    return "\n".join(lines + variant_table(f"### {GOAL_ENV}", rows, None)[2:])  # under this heading, not the variant's


def training_return(path: Path) -> float | None:
    """The mean episode return of the last rollouts while training (the exploring policy's: SB3's
    ``rollout/ep_rew_mean`` in the last row of ``logs/progress.csv`` that has it), or None."""
    rows = read_csv(path / "logs" / "progress.csv")[1] if (path / "logs" / "progress.csv").exists() else []
    values = [row.get("rollout/ep_rew_mean") for row in rows if row.get("rollout/ep_rew_mean")]
    return float(cast(str, values[-1])) if values else None


# -- tables kept between runs -------------------------------------------------------------------
RESULTS = DOCS / "benchmark_results.json"
"""Every table's rows as measured (the runs' results.json and timing.json), keyed by ``section_key``: written with
``--readme``, so that ``--report-only`` rebuilds a table whose runs are not in ``--root`` on this machine."""
STACK = "BoxToss-Stack-v0"


def section_key(env_id: str, tier: str) -> str:
    return env_id if tier == "commands" else f"{env_id} ({tier})"


def heading(env_id: str, tier: str) -> str:
    return f"### {env_id}" if tier == "commands" else f"### {env_id}, {tier} actions (no env_wrapper)"


def stored_rows(path: Path = RESULTS) -> dict[str, list[dict[str, Any]]]:
    return json.loads(path.read_text()) if path.exists() else {}


def table_rows(
    root: Path, env_id: str, tier: str, algos: list[str], seeds: list[int], stored: dict[str, list[dict[str, Any]]]
) -> list[dict[str, Any]]:
    """The rows of the runs in ``root`` if it holds a trained one in ``tier`` (random actions alone are not a
    table: they are shared by the tiers), else the rows stored in ``RESULTS`` (none if neither); a found row
    replaces its algorithm's stored row, the stored rows of the other algorithms stay."""
    rows = agent_rows(root, env_id, algos, seeds, tier)
    key = section_key(env_id, tier)
    if any(row["algo"] != "random" for row in rows):
        found = {row["algo"] for row in rows}
        kept = [row for row in stored.get(key, []) if row["algo"] not in found]
        stored[key] = sorted(rows + kept, key=lambda row: section_merge.ORDER.index(row["algo"]))
        return stored[key]
    return stored.get(key, [])


def previous_sections(path: Path) -> dict[str, str]:
    """The sections of the page as it is, by heading line: a variant whose runs are neither in ``--root`` nor in
    ``RESULTS`` keeps its section as the command last wrote it."""
    if not path.exists():
        return {}
    sections: dict[str, str] = {}
    current = None
    for line in path.read_text().splitlines():
        if line.startswith(f"<!-- {GOAL_SECTION}:start"):  # the goal env's section is kept on its own
            break
        if line.startswith("### "):
            current = line
            sections[current] = ""
        if current is not None:
            sections[current] += line + "\n"
    return sections


def stack_ceiling() -> dict[str, Any] | None:
    """The stack planner's measured row of the largest budget (``agents.stack_planner --readme``), or None."""
    rows = stack_planner.saved_rows()
    return rows[-1] if rows else None


def stack_table(title: str, rows: list[dict[str, Any]], top: dict[str, Any] | None) -> list[str]:
    lines = [
        title,
        "",
        "| agent | success | mean final height | stack fell | mean return | return while training | "
        "throws (env steps) | wall time |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in rows:
        results, timing = row["results"], [t for t in row["timing"] if t]
        steps = f"{int(np.mean([t['timesteps'] for t in timing])):,}" if timing else "-"
        wall = report.format_seconds(float(np.mean([t["wall_seconds"] for t in timing]))) if timing else "-"
        exploring = [v for v in row.get("training_return", []) if v is not None]
        lines.append(
            f"| {row['agent']} | {spread([r['success_rate'] for r in results])} | "
            f"{np.mean([r['mean_height'] for r in results]):.3f} m | "
            f"{np.mean([r['fall_rate'] for r in results]):.1%} | "
            f"{np.mean([r['mean_reward'] for r in results]):.2f} | "
            f"{f'{np.mean(exploring):.2f}' if exploring else '-'} | {steps} | {wall} |"
        )
    if top:
        lines.append(
            f"| ceiling: planner, {top['name']} budget ({top['simulated_per_throw']:.0f} throws simulated per "
            f"throw), {top['episodes']} episodes | {top['success_rate']:.1%} | {top['mean_height']:.3f} m | "
            f"{top['fall_rate']:.1%} | - | - | - | {report.format_seconds(top['seconds'])} |"
        )
    lines += [
        "",
        "Success, height, falls and return: the final policy acting deterministically on the test episodes. "
        "Return while training: the mean episode return of the last rollouts (SB3's `rollout/ep_rew_mean`), the "
        "exploring policy's (PPO's Gaussian, SAC's sampled actions, TD3's action noise).",
    ]
    return lines


def variant_table(title: str, rows: list[dict[str, Any]], sweep: list[dict[str, Any]] | None) -> list[str]:
    lines = [
        title,
        "",
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
    if sweep:
        top = ceiling.ceiling_of(sweep)
        note = "" if top["converged"] else " (still rising)"
        lines.append(
            f"| ceiling: oracle, {top['throws_per_target']:,.0f} simulated throws per target, "
            f"{top['n']} targets{note} | {top['success_rate']:.1%} | {top['mean_distance']:.3f} m | "
            f"{top['median_distance']:.3f} m | {top['face_accuracy']:.1%} | - | "
            f"{report.format_seconds(top['plan_seconds'])} |"
        )
    return lines


def breakdowns(rows: list[dict[str, Any]]) -> list[str]:
    """Success by target face kind and by target distance, one column per agent (seed means)."""
    if not rows:
        return []
    header = "| " + " | ".join(row["agent"] for row in rows) + " |"
    rule = "|---|" + "---:|" * len(rows)
    lines = ["Success by target face:", "", "| target face " + header, rule]
    kinds = [k for k in FACE_KINDS if any(e["kind"] == k for e in rows[0]["results"][0]["by_face"])]
    for kind in kinds:
        cells = []
        for row in rows:
            values = [e["success_rate"] for r in row["results"] for e in r["by_face"] if e["kind"] == kind]
            cells.append(f"{np.mean(values):.1%}" if values else "-")
        lines.append(f"| {kind} | " + " | ".join(cells) + " |")
    lines += ["", "Success by target x:", "", "| target x " + header, rule]
    for k, entry in enumerate(rows[0]["results"][0]["by_distance"]):
        cells = [f"{np.mean([r['by_distance'][k]['success_rate'] for r in row['results']]):.1%}" for row in rows]
        lines.append(f"| {entry['bin']} | " + " | ".join(cells) + " |")
    return lines


def sweep_table(sweep: list[dict[str, Any]]) -> list[str]:
    lines = [
        "Oracle success as its search grows (the ceiling is the last row):",
        "",
        "| initial, population x rounds (elite) | throws per target | success | face accuracy | planning |",
        "|---|---:|---:|---:|---:|",
    ]
    for row in sweep:
        b = row["budget"]
        lines.append(
            f"| {b['initial']}, {b['population']} x {b['iterations']} ({b['elite']}) | "
            f"{row['throws_per_target']:,.0f} | {row['success_rate']:.1%} | {row['face_accuracy']:.1%} | "
            f"{report.format_seconds(row['plan_seconds'])} |"
        )
    return lines


def plot_curves(
    root: Path, env_id: str, algos: list[str], seeds: list[int], top: float | None, path: Path, tier: str = "commands"
) -> Path | None:
    """Validation success against throws and against wall time, one line per training run; ``top`` the ceiling's
    success (a dashed line)."""
    plt = report.pyplot()
    fig, (ax_steps, ax_wall) = plt.subplots(1, 2, figsize=(10, 3.6))
    drawn = False
    for k, algo in enumerate(algos):
        for seed in seeds:
            curve = report.read_evaluations(run_dir(root, env_id, algo, seed, tier))
            if curve is None:
                continue
            label = algo.upper() if seed == seeds[0] else None
            ax_steps.plot(curve["timesteps"], curve["success_rate"], color=f"C{k}", alpha=0.8, label=label)
            ax_wall.plot(curve["wall_seconds"] / 60, curve["success_rate"], color=f"C{k}", alpha=0.8, label=label)
            drawn = True
    if not drawn:
        plt.close(fig)
        return None
    if top is not None:
        for ax in (ax_steps, ax_wall):
            ax.axhline(top, color="k", linestyle="--", linewidth=1, label="ceiling")
    episodes = "episodes" if is_stack(env_id) else "targets"
    ax_steps.set(xlabel="throws (env steps)", ylabel=f"success (validation {episodes})", ylim=(0, 1.02))
    ax_wall.set(xlabel="wall time [min]", ylim=(0, 1.02))
    ax_steps.legend(fontsize=8)
    for ax in (ax_steps, ax_wall):
        ax.grid(alpha=0.3)
    fig.suptitle(f"{heading(env_id, tier)[4:]}: learning curves, one line per training seed")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path


def read_sweep(root: Path, env_id: str) -> list[dict[str, Any]] | None:
    path = root / env_id / "ceiling.json"
    return json.loads(path.read_text()) if path.exists() else None


def ceiling_success(root: Path, env_id: str) -> float | None:
    """The ceiling's success rate: the stack planner's for a stacking env, the oracle sweep's otherwise."""
    if is_stack(env_id):
        top = stack_ceiling()
        return None if top is None else top["success_rate"]
    sweep = read_sweep(root, env_id)
    return None if sweep is None else ceiling.ceiling_of(sweep)["success_rate"]


INTRO = (
    "Every agent on the same {targets:,} test targets per variant (the ceiling on the first "
    "{ceiling_targets}); success: at rest within the tolerance on a target face. Training runs: `python -m "
    "agents.train --algo A --env E --seed S` with the file's hyperparameters, on this 2-core machine; several "
    "seeds give the mean and (min-max). `BoxToss-Stack-v0` (an episode is a hand of 4 throws, "
    "[docs/stack.md](../stack.md)) is scored on {episodes} test episodes (seeds 10000...): success is the "
    "whole hand stacked on the target, the ceiling is `agents.stack_planner`'s on its own episodes. A table "
    "titled *raw actions* is the same recipe trained in the env's own actions (speed, direction, spin: `--set "
    "env_wrapper=null`, `python -m agents.benchmark --tiers raw`; PPO's recipes for BoxToss-v0 and BoxToss-"
    "LongSide-v0 have no env_wrapper, so there both tiers train the same thing), or where "
    "`agents/hyperparams/raw/<algo>.yml` has an entry for the variant, that recipe; a smaller budget than the "
    "recipe's is given by `--set n_timesteps=N` (the env steps column says what was trained). A section whose "
    "runs are not on the machine that wrote this page is rebuilt from `docs/agents/benchmark_results.json` "
    "(the rows as measured), or kept as it was."
)


def document(
    root: Path,
    envs: list[str],
    algos: list[str],
    seeds: list[int],
    docs: Path = DOCS,
    stored: dict[str, list[dict[str, Any]]] | None = None,
) -> str:
    stored = {} if stored is None else stored
    previous = previous_sections(docs / "benchmark.md")
    lines = [
        INTRO.format(targets=TEST_TARGETS, ceiling_targets=ceiling.CEILING_TARGETS, episodes=STACK_TEST_EPISODES),
        "",
    ]
    for env_id in envs:
        for tier in TIERS:
            title = heading(env_id, tier)
            rows = table_rows(root, env_id, tier, algos, seeds, stored)
            sweep = None if is_stack(env_id) else read_sweep(root, env_id)
            if not rows and not (sweep and tier == "commands"):
                if title in previous:
                    lines += previous[title].rstrip("\n").splitlines() + [""]
                continue
            section = []
            if is_stack(env_id):
                section += stack_table(title, rows, stack_ceiling()) + [""]
            else:
                section += variant_table(title, rows, sweep if tier == "commands" else None) + [""]
                section += breakdowns(rows) + [""]
                if sweep and tier == "commands":
                    section += sweep_table(sweep) + [""]
            name = f"curves_{env_id}{'' if tier == 'commands' else '_' + tier}.png"
            figure = plot_curves(root, env_id, algos, seeds, ceiling_success(root, env_id), docs / name, tier)
            if figure is not None or (docs / name).exists():
                section += [f"![learning curves on {title[4:]}]({name})", ""]
            lines += merge_section(section, previous.get(title, "").rstrip("\n").splitlines() + [""])
    return "\n".join(lines)


def previous_headline(readme: Path) -> dict[str, str]:
    """The README's benchmark rows as they are, by their first cell (kept for a variant with no data here)."""
    if not readme.exists():
        return {}
    text = readme.read_text()
    if "<!-- benchmark:start -->" not in text:
        return {}
    section = text.split("<!-- benchmark:start -->", 1)[1].split("<!-- benchmark:end -->", 1)[0]
    return {
        line.split("|")[1].strip(): line
        for line in section.splitlines()
        if line.startswith("| ") and not line.startswith("| variant")
    }


def headline(
    root: Path,
    envs: list[str],
    algos: list[str],
    seeds: list[int],
    stored: dict[str, list[dict[str, Any]]] | None = None,
    readme: Path = README,
) -> str:
    """The README's summary: success per variant (and tier) and agent, against the ceiling."""
    stored = {} if stored is None else stored
    previous = previous_headline(readme)
    lines = [
        "| variant | random | " + " | ".join(a.upper() for a in algos) + " | ceiling |",
        "|---|---:|" + "---:|" * len(algos) + "---:|",
    ]
    for env_id in envs:
        for tier in TIERS:
            label = env_id if tier == "commands" else f"{env_id}, {tier} actions"
            found = table_rows(root, env_id, tier, algos, seeds, stored)
            if not found:
                if label in previous:
                    lines.append(previous[label])
                continue
            rows = {row["algo"]: row for row in found}
            top = ceiling_success(root, env_id) or stored_ceiling(readme, env_id)
            cells = [spread([r["success_rate"] for r in rows[a]["results"]]) if a in rows else "-" for a in algos]
            random = rows.get("random")
            line = (
                f"| {label} | {spread([random['results'][0]['success_rate']]) if random else '-'} | "
                + " | ".join(cells)
                + f" | {'-' if top is None else f'{top:.1%}'} |"
            )
            lines.append(fill_line(line, previous.get(label)))
    return "\n".join(lines)


def ratios(
    root: Path,
    envs: list[str],
    algos: list[str],
    seeds: list[int],
    stored: dict[str, list[dict[str, Any]]] | None = None,
    readme: Path = README,
) -> str:
    """One line: the best learned agent's share of the ceiling's success, per variant and tier."""
    stored = {} if stored is None else stored
    parts = []
    for env_id in envs:
        for tier in TIERS:
            top = ceiling_success(root, env_id)
            rows = [row for row in table_rows(root, env_id, tier, algos, seeds, stored) if row["algo"] != "random"]
            label = env_id if tier == "commands" else f"{env_id} ({tier})"
            old = previous_share(readme, label)
            if top is None and old is None:  # a tier trained without the sweep: the variant's ceiling as written
                top = stored_ceiling(readme, env_id)
            if rows and top:
                best = max(rows, key=lambda row: np.mean([r["success_rate"] for r in row["results"]]))
                share = np.mean([r["success_rate"] for r in best["results"]]) / top
                parts.append(f"{label} {share:.0%} ({best['agent']})")
            elif old:
                parts.append(old)
    return "Best learned agent's success as a share of the ceiling's: " + ", ".join(parts) + "."


def stored_ceiling(readme: Path, env_id: str) -> float | None:
    """The variant's ceiling as the README's table gives it (its own row, the ceiling of every tier), for a root
    without the variant's ceiling sweep: a tier trained in another root gets the same ceiling."""
    line = previous_headline(readme).get(env_id)
    cell = None if line is None else line.rstrip(" |").rsplit("|", 1)[-1].strip()
    return float(cell.rstrip("%")) / 100 if cell and cell.endswith("%") else None


def previous_share(readme: Path, label: str) -> str | None:
    """The README's share for ``label`` (a variant, ``BoxToss-v0``, or a variant's tier, ``BoxToss-v0 (raw)``) as
    it is (kept for one with no data here)."""
    if not readme.exists() or "share of the ceiling's: " not in readme.read_text():
        return None
    line = readme.read_text().split("share of the ceiling's: ", 1)[1].split("\n", 1)[0].rstrip(".")
    return next(
        (part for part in line.split(", ") if part.startswith(label + " ") and part[len(label) + 1].isdigit()), None
    )


def shown_variants(trained: list[str]) -> list[str]:
    """The variants the page and the README show: every one, not only those trained in this call (a variant without
    runs in ``--root`` shows its stored rows or its section as written), so that ``--envs X --readme`` rewrites X's
    rows and loses no other."""
    return list(dict.fromkeys([*VARIANTS, *trained]))


def check_options(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Every env id registered, every training's hyperparameters (with the tier's and ``--set`` overrides) valid:
    a one-line error before anything is created or trained."""
    for env_id in args.envs:
        if env_id not in gym.registry:
            parser.error(f"--envs: {env_id!r} is not registered")
    if is_file_on_the_way(args.root):
        parser.error(f"--root {args.root} is a file, not a folder (or lies under one)")
    if args.readme and not DOCS.parent.is_dir():
        parser.error(f"--readme rewrites the repository's pages ({DOCS}): run it in a clone")
    if args.report_only:
        return
    for text in args.overrides:
        try:
            configuration.parse_override(text)
        except configuration.ConfigError as error:
            parser.error(f"--set: {error}")
    for env_id in args.envs:
        if env_id == GOAL_ENV:  # its agents' settings: GOAL_AGENTS and the goal recipes (goal_hyperparams)
            for agent, (algo, *_) in GOAL_AGENTS.items():
                if algo in args.algos:
                    try:
                        configuration.check_config(goal_hyperparams(agent)[1], algo)
                    except configuration.ConfigError as error:
                        parser.error(f"{agent} on {env_id}: {error}")
            continue
        for algo in args.algos:
            for tier in args.tiers:
                try:
                    config = configuration.apply_overrides(
                        configuration.load_hyperparams(algo, env_id, tier_hyperparams(algo, env_id, tier)),
                        [*TIER_OVERRIDES[tier], *args.overrides],
                        algo,
                    )
                    configuration.check_config(config, algo)
                except configuration.ConfigError as error:
                    given = f" with --set {' '.join(args.overrides)}" if args.overrides else ""
                    parser.error(f"{algo} on {env_id} ({tier}){given}: {error}")


def train_missing(args: argparse.Namespace, variants: list[str], goal: bool) -> None:
    """Every run the command's options ask for that is not finished yet: random actions, the oracle's sweep, each
    algorithm, seed and tier on each variant, and the goal env's agents."""
    for env_id in variants:
        ensure_random(args.root, env_id)
        if not args.no_ceiling and not is_stack(env_id):  # the stack's ceiling: agents.stack_planner
            ensure_ceiling(args.root, env_id)
        for seed in args.seeds:
            for tier in args.tiers:
                for algo in args.algos:
                    ensure_trained(args.root, env_id, algo, seed, tier, args.overrides)
    if goal:
        ensure_random(args.root, GOAL_ENV)
        for seed in args.seeds:
            for agent, (algo, *_) in GOAL_AGENTS.items():
                if algo in args.algos:
                    ensure_goal_trained(args.root, agent, seed)


def make_parser() -> OneLineParser:
    """The command's options (``check_options`` checks what their types cannot)."""
    parser = OneLineParser(prog="python -m agents.benchmark", description=__doc__.split("\n\n")[0])
    parser.add_argument("--envs", nargs="+", default=[*VARIANTS, GOAL_ENV])
    parser.add_argument("--algos", nargs="+", default=sorted(ALGORITHMS), choices=sorted(ALGORITHMS))
    parser.add_argument("--seeds", nargs="+", type=SEED, default=[0, 1, 2], help=f"training seeds, {SEED.allowed}")
    parser.add_argument("--root", type=folder, default=ROOT, help="folder of the benchmark's runs")
    parser.add_argument(
        "--tiers",
        nargs="+",
        default=["commands"],
        choices=list(TIERS),
        help="commands: the recipes as their files say; raw: in the env's own actions (no env_wrapper)",
    )
    parser.add_argument(
        "--set",
        nargs="*",
        default=[],
        action="extend",
        metavar="KEY=VALUE",
        dest="overrides",
        help="override the files' hyperparameters of every training, e.g. n_timesteps=16384",
    )
    parser.add_argument("--no-ceiling", action="store_true", help="skip the oracle sweep")
    parser.add_argument("--report-only", action="store_true", help="train nothing: tables from finished runs")
    parser.add_argument("--readme", action="store_true", help="write docs/agents/benchmark.md and the README section")
    return parser


def main(argv: list[str] | None = None) -> None:
    """The command; a damaged run file or a file-system error ends it in one line (``one_line_errors``)."""
    with one_line_errors("python -m agents.benchmark"):
        run(argv)


def run(argv: list[str] | None = None) -> None:
    parser = make_parser()
    args = parser.parse_args(argv)
    variants = [env_id for env_id in args.envs if env_id != GOAL_ENV]
    goal = GOAL_ENV in args.envs
    check_options(parser, args)
    if not args.report_only:
        train_missing(args, variants, goal)
    goal_text = goal_document(args.root, args.algos, args.seeds) if goal else None
    if goal_text:
        print(goal_text)
    if not variants:
        if args.readme and goal_text:
            replace_section(GOAL_SECTION, goal_text)
        return
    stored = stored_rows()
    shown = shown_variants(variants)
    algos = sorted(ALGORITHMS)  # the page shows every algorithm (those not trained here: their rows as stored)
    text = document(args.root, shown, algos, args.seeds, stored=stored)
    summary = headline(args.root, shown, algos, args.seeds, stored)
    print(summary)
    if args.readme:
        DOCS.mkdir(parents=True, exist_ok=True)
        write_atomic(RESULTS, json.dumps(stored, indent=1) + "\n")
        page = DOCS / "benchmark.md"
        kept = goal_text if goal_text else (read_section(GOAL_SECTION, page) or "")
        write_atomic(
            page,
            "# BoxToss benchmark\n\nGenerated by `python -m agents.benchmark --report-only --readme` "
            "from the runs in `runs/benchmark/`.\n\n"
            + text
            + f"\n<!-- {GOAL_SECTION}:start -->\n{kept}\n<!-- {GOAL_SECTION}:end -->\n",
        )
        report.write_readme(
            "### Benchmark: every variant, every algorithm, against the ceiling\n\n"
            "`python -m agents.benchmark` (then `--report-only --readme`). Success on the test "
            "targets (`BoxToss-Stack-v0`: on test episodes, its ceiling the stack planner's; *raw "
            "actions*: the recipe without its ballistic command, or `agents/hyperparams/raw/`'s); the ceiling is "
            "the oracle whose "
            "search grew until its success stopped rising "
            "(details, breakdowns by face and distance, the oracle's budgets and the learning curves: "
            "[docs/agents/benchmark.md](docs/agents/benchmark.md)):\n\n"
            + summary
            + "\n\n"
            + ratios(args.root, shown, algos, args.seeds, stored),
            "benchmark",
        )


if __name__ == "__main__":
    main()
