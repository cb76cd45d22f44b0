"""The hidden-physics tier (``BoxToss-HiddenPhysics-v0``): its ceiling, its baselines and the gap, measured.

Every agent plays the same test episodes (seeds 10000, 10001, ..., one episode each, all at once in the native
batched env, one engine thread) and is scored per episode: success (the pose reached within the budget of
throws), the throws it took, success at the first throw, and the return.

- **ceiling**: a planner told the true mass, friction and restitution: the one-throw oracle
  (``agents.oracle``) plans the episode's throw on ``BoxToss-v0`` with the same arguments and dynamics (each
  throw of the tier is that env's throw, tested), at its default search and a larger one;
- **blind planner**: the same oracle told the middle of each dynamics range instead, throwing its plan every
  time: what planning without inferring the physics gets;
- **random**: uniform actions;
- **baselines** (3 seeds each): PPO with a recurrent policy (sb3-contrib's ``RecurrentPPO``, ``MlpLstmPolicy``)
  and PPO with stacked observations (SB3's ``VecFrameStack`` over the whole budget of throws, an MLP), both on
  the native batched env, observations normalised (``VecNormalize``), acting deterministically when tested.

    python -m agents.hidden_physics_tier ceiling                  # ceiling, blind planner and random rows
    python -m agents.hidden_physics_tier train                    # the 6 training runs, one after another
    python -m agents.hidden_physics_tier report --readme          # the table into docs/hidden_physics.md

Each command adds its rows to ``docs/agents/hidden_physics.json`` (written atomically; a run already there is
skipped, so ``train`` resumes where a stopped session left it). Its layout, for other tables: ``{"env_id",
"episodes", "first_seed", "max_throws", "agents": {name: {"kind": "ceiling" | "reference" | "baseline",
"per_seed": [{"seed", "success_rate", "first_throw_success", "mean_throws", "mean_return", "timesteps",
"train_seconds"}, ...]}}}``: one entry per training seed (one for the planners and random), each a success rate
over the same test episodes, as rliable's score arrays want them.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np

from agents.doc_sections import REPO, replace_section
from agents.oracle import OraclePlanner, OracleSettings, ThrowSimulator, episodes_from_infos
from box_toss_env.envs import task_columns
from box_toss_env.envs.hidden_physics_task import HiddenPhysicsTask
from box_toss_env.files import write_atomic

ENV_ID = "BoxToss-HiddenPhysics-v0"
RESULTS = REPO / "docs" / "agents" / "hidden_physics.json"
RUNS = REPO / "runs" / "hidden_physics"
TEST_FIRST_SEED = 10_000
TEST_EPISODES = 512
ALGOS = ("recurrent_ppo", "stacked_ppo")
AGENT_NAMES = {
    "recurrent_ppo": "RecurrentPPO (LSTM policy)",
    "stacked_ppo": "PPO, stacked observations",
    "ceiling": "ceiling: oracle told the dynamics",
    "ceiling_large": "ceiling: oracle told the dynamics, larger search",
    "blind": "oracle told the middle dynamics",
    "random": "random",
}

Act = Callable[[np.ndarray, np.ndarray, list[dict[str, Any]]], np.ndarray]
"""``act(observations (n, obs), episode_starts (n,) bool, reset_infos) -> actions (n, 3)``."""


@dataclass(frozen=True)
class TrainSettings:
    """One baseline run: the algorithm's hyperparameters and the throws it trains for (``timesteps``)."""

    timesteps: int = 300_000
    n_envs: int = 16
    n_steps: int = 256
    batch_size: int = 512
    n_epochs: int = 10
    learning_rate: float = 3e-4
    gamma: float = 0.95
    gae_lambda: float = 0.95
    ent_coef: float = 0.0
    net_arch: tuple[int, ...] = (128, 128)
    lstm_hidden_size: int = 64


def play(act: Act, n_episodes: int = TEST_EPISODES, first_seed: int = TEST_FIRST_SEED, **env_kwargs) -> dict:
    """One episode per seed ``first_seed + i``, all at once (the native batch, one engine thread): each episode's
    success, throws, first-throw success and return (``act`` sees the observations of every env)."""
    envs = gym.make_vec(ENV_ID, num_envs=n_episodes, threads=1, **env_kwargs)
    observations, info = envs.reset(seed=first_seed)
    reset_infos = [{key: value[i] for key, value in info.items() if not key.startswith("_")} for i in range(n_episodes)]
    done, starts = np.zeros(n_episodes, dtype=bool), np.ones(n_episodes, dtype=bool)
    result = {"success": np.zeros(n_episodes, bool), "throws": np.zeros(n_episodes, int), "ret": np.zeros(n_episodes)}
    first_success = np.zeros(n_episodes, dtype=bool)
    while not done.all():
        actions = np.clip(np.asarray(act(observations, starts, reset_infos), dtype=np.float32), -1.0, 1.0)
        observations, reward, terminated, _, info = envs.step(actions)
        live = ~done
        result["ret"][live] += reward[live]
        result["throws"][live] += 1
        step_success = info["success"]
        first_success |= live & (result["throws"] == 1) & step_success
        ended = live & terminated
        result["success"][ended] = step_success[ended]
        done |= ended
        starts = terminated
    envs.close()
    return {
        "success_rate": float(result["success"].mean()),
        "first_throw_success": float(first_success.mean()),
        "mean_throws": float(result["throws"].mean()),
        "mean_return": float(result["ret"].mean()),
    }


def planned(oracle_settings, blind: bool = False, **env_kwargs) -> Act:
    """The oracle's throw of each episode, planned once from the reset infos (the true dynamics, or with
    ``blind`` the middle of each range) and thrown every time."""
    one_throw = gym.make("BoxToss-v0", **HiddenPhysicsTask(**env_kwargs).one_throw_arguments())
    plan: list[np.ndarray] = []

    def act(observations: np.ndarray, starts: np.ndarray, reset_infos: list[dict[str, Any]]) -> np.ndarray:
        if not plan:
            episodes = episodes_from_infos(reset_infos)
            if blind:
                config = cast(Any, one_throw.unwrapped).config
                middle = [0.5 * sum(r) for r in (config.mass_range, config.friction_range, config.restitution_range)]
                episodes.data[:, task_columns.EP_DYNAMICS] = middle
            plan.append(OraclePlanner(oracle_settings).plan(ThrowSimulator(one_throw, threads=1), episodes))
        return plan[0]

    return act


def reference_rows(n_episodes: int = TEST_EPISODES) -> dict[str, dict]:
    """The ceiling (default and larger oracle), the blind planner and random, measured."""
    rng = np.random.default_rng(0)
    agents: dict[str, tuple[str, Act]] = {
        "ceiling": ("ceiling", planned(OracleSettings(threads=1))),
        "ceiling_large": ("ceiling", planned(OracleSettings(initial=512, population=64, elite=8, iterations=24))),
        "blind": ("reference", planned(OracleSettings(threads=1), blind=True)),
        "random": ("reference", lambda obs, starts, infos: rng.uniform(-1, 1, (len(obs), 3))),
    }
    rows = {}
    for name, (kind, act) in agents.items():
        start = time.perf_counter()
        scores = play(act, n_episodes)
        rows[name] = {"kind": kind, "per_seed": [{"seed": 0, **scores, "seconds": time.perf_counter() - start}]}
        print(f"{AGENT_NAMES[name]}: {scores}", flush=True)
    return rows


def training_env(algo: str, settings: TrainSettings, seed: int, n_envs: int | None = None):
    """The native batched env as SB3's VecEnv (``SB3VecEnvAdapter``, ``VecMonitor``), its observations stacked over
    the budget of throws for ``stacked_ppo``, normalised (``VecNormalize``, rewards left as they are)."""
    from stable_baselines3.common.vec_env import VecEnv, VecFrameStack, VecMonitor, VecNormalize

    from box_toss_env.wrappers.sb3_adapter import SB3VecEnvAdapter

    n = n_envs or settings.n_envs
    venv: VecEnv = VecMonitor(SB3VecEnvAdapter(gym.make_vec(ENV_ID, num_envs=n, threads=1)))
    venv.seed(seed)
    if algo == "stacked_ppo":
        venv = VecFrameStack(venv, n_stack=venv.unwrapped.get_attr("env")[0].task.max_throws)
    return VecNormalize(venv, norm_obs=True, norm_reward=False, gamma=settings.gamma)


def make_model(algo: str, env, settings: TrainSettings, seed: int):
    """``RecurrentPPO("MlpLstmPolicy")`` or ``PPO("MlpPolicy")`` with ``settings``, on one torch thread."""
    import torch

    torch.set_num_threads(1)
    kwargs: dict[str, Any] = dict(
        n_steps=settings.n_steps,
        batch_size=settings.batch_size,
        n_epochs=settings.n_epochs,
        learning_rate=settings.learning_rate,
        gamma=settings.gamma,
        gae_lambda=settings.gae_lambda,
        ent_coef=settings.ent_coef,
        seed=seed,
        device="cpu",
        verbose=0,
    )
    arch = list(settings.net_arch)
    if algo == "recurrent_ppo":
        from sb3_contrib import RecurrentPPO

        policy_kwargs = {"net_arch": arch, "lstm_hidden_size": settings.lstm_hidden_size}
        return RecurrentPPO("MlpLstmPolicy", env, policy_kwargs=policy_kwargs, **kwargs)
    from stable_baselines3 import PPO

    return PPO("MlpPolicy", env, policy_kwargs={"net_arch": arch}, **kwargs)


def play_model(algo: str, model, obs_rms, settings: TrainSettings, n_episodes: int = TEST_EPISODES) -> dict:
    """``play``'s scores of a trained model on the test episodes, acting deterministically through the training
    stack (observations stacked as in training, normalised with the training statistics ``obs_rms``; the LSTM's
    state carried within each episode, reset at its start)."""
    venv = training_env(algo, settings, TEST_FIRST_SEED, n_envs=n_episodes)
    venv.obs_rms, venv.training = obs_rms, False
    observations = venv.reset()
    done, starts, state = np.zeros(n_episodes, dtype=bool), np.ones(n_episodes, dtype=bool), None
    success, first_success = np.zeros(n_episodes, dtype=bool), np.zeros(n_episodes, dtype=bool)
    throws, ret = np.zeros(n_episodes, dtype=int), np.zeros(n_episodes)
    while not done.all():
        actions, state = model.predict(observations, state=state, episode_start=starts, deterministic=True)
        observations, rewards, dones, infos = venv.step(actions)
        live = ~done
        ret[live] += rewards[live]
        throws[live] += 1
        step_success = np.array([bool(info["success"]) for info in infos])
        first_success |= live & (throws == 1) & step_success
        ended = live & dones
        success[ended] = step_success[ended]
        done |= ended
        starts = dones
    venv.close()
    return {
        "success_rate": float(success.mean()),
        "first_throw_success": float(first_success.mean()),
        "mean_throws": float(throws.mean()),
        "mean_return": float(ret.mean()),
    }


def train_run(algo: str, seed: int, settings: TrainSettings, out: Path = RUNS, n_episodes: int = TEST_EPISODES) -> dict:
    """Train one baseline run, save it under ``out`` (``ALGO_SEED/model.zip`` and ``vecnormalize.pkl``) and score
    it on the test episodes."""
    from agents.training import quiet_logger

    env = training_env(algo, settings, seed)
    model = make_model(algo, env, settings, seed)
    model.set_logger(quiet_logger())
    wall, cpu = time.perf_counter(), time.process_time()
    model.learn(settings.timesteps)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    folder = out / f"{algo}_{seed}"
    folder.mkdir(parents=True, exist_ok=True)
    model.save(folder / "model.zip")
    env.save(str(folder / "vecnormalize.pkl"))
    scores = play_model(algo, model, env.obs_rms, settings, n_episodes)
    env.close()
    row = {"seed": seed, **scores, "timesteps": settings.timesteps, "train_seconds": wall, "train_cpu_seconds": cpu}
    print(f"{AGENT_NAMES[algo]} seed {seed}: {row}", flush=True)
    return row


def benchmark_rows(path: Path = RESULTS) -> dict[str, Any]:
    """The tier's rows for the benchmark's tables (``agents.benchmark``): per agent its kind and its success rate on
    the test episodes per seed (the scores rliable aggregates: one per training seed), and the ceiling's success
    (the best ceiling row). Empty ``agents`` before ``ceiling`` and ``train`` have run."""
    results = load_results(path)
    agents = {
        AGENT_NAMES.get(name, name): {
            "kind": agent["kind"],
            "seeds": [row["seed"] for row in agent["per_seed"]],
            "success": [row["success_rate"] for row in agent["per_seed"]],
            "first_throw_success": [row["first_throw_success"] for row in agent["per_seed"]],
            "mean_throws": [row["mean_throws"] for row in agent["per_seed"]],
        }
        for name, agent in results["agents"].items()
    }
    ceilings = [max(a["success"]) for a in agents.values() if a["kind"] == "ceiling"]
    return {
        "tier": "hidden physics",
        "env_id": results["env_id"],
        "episodes": results["episodes"],
        "first_seed": results["first_seed"],
        "ceiling": max(ceilings) if ceilings else None,
        "agents": agents,
    }


# -- the results file and the docs' table ---------------------------------------------------------------
def load_results(path: Path = RESULTS) -> dict:
    if path.exists():
        return json.loads(path.read_text())
    return {"env_id": ENV_ID, "episodes": TEST_EPISODES, "first_seed": TEST_FIRST_SEED, "agents": {}}


def save_rows(results: dict, name: str, kind: str, rows: list[dict], path: Path = RESULTS, **extra) -> None:
    """Add ``rows`` (one per seed, replacing rows of the same seed) to agent ``name`` and write the file."""
    agent = results["agents"].setdefault(name, {"kind": kind, "per_seed": []})
    agent.update(kind=kind, **extra)
    seeds = {row["seed"] for row in rows}
    agent["per_seed"] = sorted([r for r in agent["per_seed"] if r["seed"] not in seeds] + rows, key=lambda r: r["seed"])
    write_atomic(path, json.dumps(results, indent=1) + "\n")


def table(results: dict) -> str:
    """The Markdown table of every agent (mean over seeds, the seeds' range beside it) and the gap."""
    agents = results["agents"]
    ceiling = max((a for n, a in agents.items() if a["kind"] == "ceiling"), key=_mean("success_rate"), default=None)
    top = _mean("success_rate")(ceiling) if ceiling else float("nan")
    lines = [
        "| agent | seeds | success | first-throw success | throws an episode | return | share of the ceiling |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, agent in agents.items():
        rows = agent["per_seed"]
        cells = [_cell(rows, key) for key in ("success_rate", "first_throw_success")]
        cells += [f"{np.mean([r[key] for r in rows]):.2f}" for key in ("mean_throws", "mean_return")]
        share = f"{_mean('success_rate')(agent) / top:.0%}" if top > 0 else "-"
        lines.append(f"| {AGENT_NAMES.get(name, name)} | {len(rows)} | {' | '.join(cells)} | {share} |")
    baselines = [a for a in agents.values() if a["kind"] == "baseline"]
    if not baselines or ceiling is None:
        return "\n".join(lines)
    best = max(_mean("success_rate")(a) for a in baselines)
    costs = [
        f"{AGENT_NAMES.get(name, name)} {int(np.mean([r['timesteps'] for r in a['per_seed']])):,} throws a run, "
        f"{np.mean([r['train_seconds'] for r in a['per_seed']]):,.0f} s wall "
        f"({np.mean([r['train_cpu_seconds'] for r in a['per_seed']]):,.0f} s CPU) on average"
        for name, a in agents.items()
        if a["kind"] == "baseline"
    ]
    lines.append(f"\nTraining, one run at a time on the shared 2-core machine: {'; '.join(costs)}.")
    return "\n".join(lines) + (
        f"\n\nGap: the best baseline reaches {best:.1%} against the ceiling's {top:.1%}, "
        f"{100 * (top - best):.1f} points below it ({best / top:.0%} of the ceiling)."
    )


def _mean(key: str):
    return lambda agent: float(np.mean([row[key] for row in agent["per_seed"]]))


def _cell(rows: list[dict], key: str) -> str:
    values = [row[key] for row in rows]
    spread = f" ({min(values):.1%}-{max(values):.1%})" if len(values) > 1 else ""
    return f"{np.mean(values):.1%}{spread}"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m agents.hidden_physics_tier", description=__doc__.split("\n\n")[0])
    parser.add_argument("command", choices=("ceiling", "train", "report"))
    parser.add_argument("--episodes", type=int, default=TEST_EPISODES, help="test episodes (ceiling)")
    parser.add_argument("--algos", nargs="+", choices=ALGOS, default=list(ALGOS))
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--timesteps", type=int, default=TrainSettings.timesteps, help="throws per training run")
    parser.add_argument("--again", action="store_true", help="train runs already in the results file again")
    parser.add_argument("--readme", action="store_true", help="write the table into docs/hidden_physics.md")
    args = parser.parse_args(argv)
    results = load_results()
    if args.command == "ceiling":
        for name, row in reference_rows(args.episodes).items():
            save_rows(results, name, row["kind"], row["per_seed"])
    elif args.command == "train":
        settings = TrainSettings(timesteps=args.timesteps)
        for algo in args.algos:
            for seed in args.seeds:
                done = results["agents"].get(algo, {}).get("per_seed", [])
                if not args.again and any(r["seed"] == seed and r["timesteps"] == args.timesteps for r in done):
                    continue
                save_rows(results, algo, "baseline", [train_run(algo, seed, settings)], settings=asdict(settings))
    print(table(results))
    if args.readme:
        command = "python -m agents.hidden_physics_tier ceiling; python -m agents.hidden_physics_tier train"
        replace_section("hidden-physics", f"Measured by `{command}` (then `report --readme`):\n\n{table(results)}")


if __name__ == "__main__":
    main()
