"""Train a Stable-Baselines3 algorithm (PPO, SAC, TD3) on a BoxToss env; one folder per run.

``runs/NAME/`` holds ``config.yml`` (algorithm, env id, seed and the resolved hyperparameters),
``command.txt`` (the exact commands), ``model.zip`` and ``vecnormalize.pkl`` (the final policy and its
observation statistics), ``best_model.zip`` / ``best_vecnormalize.pkl`` (best validation success),
``evaluations.csv`` (periodic deterministic evaluation on fixed validation targets), ``logs/``
(TensorBoard and progress.csv), ``checkpoints/`` (with the replay buffer for off-policy algorithms),
``timing.json`` (wall time over all sessions of the run, and the env's share of it) and
``eval/default/`` (the final evaluation on the 1,024 test targets).
"""

from __future__ import annotations

import csv
import json
import re
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback, CheckpointCallback
from stable_baselines3.common.logger import configure

from agents import algorithms
from agents import config as configuration
from agents.envs import TimedVecEnv, find_wrapper, make_training_env, make_vector_env, normalizer_of
from agents.evaluation import VALIDATION_FIRST_SEED, evaluate, evaluate_run, scores, target_seeds
from agents.policies import TrainedPolicy, load_model

RUNS = Path("runs")
EVAL_COLUMNS = ("timesteps", "wall_seconds", "success_rate", "mean_distance", "median_distance", "face_accuracy",
                "mean_reward", "failures")


class ValidationCallback(BaseCallback):
    """Every ``eval_freq`` env steps: the deterministic policy on the fixed validation targets;
    logs the scores, appends them to evaluations.csv, keeps the best model by success rate, then
    passes the row to ``on_validation`` if given (``agents.tuning`` reports it to Ray Tune).
    ``wall_seconds`` in the file counts training time over every session of the run."""

    def __init__(self, run_dir: Path, config: dict[str, Any], env_id: str, wall_offset: float = 0.0,
                 on_validation: Callable[[dict[str, Any]], None] | None = None):
        super().__init__()
        self.run_dir, self.config, self.env_id = run_dir, config, env_id
        self.on_validation = on_validation
        self.every = int(config["eval_freq"])
        self.seeds = target_seeds(int(config["eval_targets"]), VALIDATION_FIRST_SEED)
        self.path = run_dir / "evaluations.csv"
        self.best = -1.0
        self.last = 0
        self.seconds = 0.0
        self.start = time.perf_counter()
        self.wall_offset = wall_offset

    def _on_training_start(self) -> None:
        self.last = self.num_timesteps
        if self.path.exists():  # resuming: keep the history, and its best
            with open(self.path) as file:
                rows = list(csv.DictReader(file))
            if rows:
                self.best = max(float(row["success_rate"]) for row in rows)
        else:
            with open(self.path, "w", newline="") as file:
                csv.writer(file).writerow(EVAL_COLUMNS)
        self.start = time.perf_counter()
        if self.num_timesteps == 0:
            self.validate()

    def _on_step(self) -> bool:
        if self.every and self.num_timesteps - self.last >= self.every:
            self.last = self.num_timesteps
            self.validate()
        return True

    def _on_training_end(self) -> None:
        if self.every and self.num_timesteps != self.last:
            self.validate()

    def validate(self) -> None:
        begin = time.perf_counter()
        vec_normalize = normalizer_of(self.training_env)
        policy = TrainedPolicy(self.model, vec_normalize, self.config.get("env_wrapper"))
        throws, _ = evaluate(policy, self.env_id, self.config["env_kwargs"], self.seeds)
        result = scores(throws)
        wall = self.wall_offset + begin - self.start
        for key in ("success_rate", "mean_distance", "face_accuracy", "mean_reward"):
            self.logger.record(f"eval/{key}", result[key])
        row = {"timesteps": self.num_timesteps, "wall_seconds": wall, **{key: result[key] for key in EVAL_COLUMNS[2:]}}
        with open(self.path, "a", newline="") as file:
            csv.writer(file).writerow([row["timesteps"], f"{wall:.2f}"] + [row[key] for key in EVAL_COLUMNS[2:]])
        if result["success_rate"] > self.best:
            self.best = result["success_rate"]
            self.model.save(self.run_dir / "best_model.zip")
            if vec_normalize is not None:
                vec_normalize.save(str(self.run_dir / "best_vecnormalize.pkl"))
        self.seconds += time.perf_counter() - begin
        if self.on_validation is not None:
            self.on_validation(row)


def latest_checkpoint(run_dir: Path, algo: str) -> tuple[Path, Path | None, int] | None:
    """(model, vecnormalize or None, timesteps) of the newest checkpoint of a run (or None)."""
    found = []
    for path in (run_dir / "checkpoints").glob(f"{algo}_*_steps.zip"):
        match = re.fullmatch(rf"{algo}_(\d+)_steps\.zip", path.name)
        if match:
            found.append((int(match.group(1)), path))
    timing = read_timing(run_dir)
    if (run_dir / "model.zip").exists() and timing:
        found.append((timing["timesteps"], run_dir / "model.zip"))
    if not found:
        return None
    steps, path = max(found)
    stats = (run_dir / "vecnormalize.pkl" if path.name == "model.zip"
             else path.with_name(f"{algo}_vecnormalize_{steps}_steps.pkl"))
    return path, (stats if stats.exists() else None), steps


def read_timing(run_dir: Path) -> dict[str, Any] | None:
    """A run's timing.json (None before its training first finished)."""
    path = Path(run_dir) / "timing.json"
    return json.loads(path.read_text()) if path.exists() else None


def new_run_dir(runs: Path, name: str | None, env_id: str, algo: str) -> Path:
    """A fresh folder ``runs/name``; an error if a finished run holds it. A folder left by a run that
    failed before its first checkpoint holds nothing to keep, and is cleared."""
    if name is None:
        name = f"{algo}-{env_id}-{time.strftime('%Y%m%d-%H%M%S')}"
    run_dir = runs / name
    if (run_dir / "config.yml").exists():
        if (run_dir / "timing.json").exists() or list((run_dir / "checkpoints").glob("*.zip")):
            raise configuration.ConfigError(
                f"{run_dir} already holds a run: choose another --name, or --resume {run_dir}")
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    return run_dir


def write_run_files(run_dir: Path, algo: str, env_id: str, seed: int, config: dict[str, Any], command: str) -> None:
    """``config.yml`` (what the run trains) and a line of ``command.txt`` (the command that started it)."""
    configuration.save_yaml({"algo": algo, "env_id": env_id, "seed": seed, "env_kwargs": config["env_kwargs"],
                             "hyperparams": config}, run_dir / "config.yml")
    with open(run_dir / "command.txt", "a") as file:
        file.write(f"{command}\n")


def warm_up_engine(env_id: str, config: dict[str, Any]) -> None:
    """Load the env's compiled kernel with one throw in a throwaway env, so that compiling (or
    loading from numba's cache) is not counted as env time."""
    venv = make_vector_env(env_id, 1, config["env_kwargs"], config.get("vec_env_kwargs"))
    venv.reset()
    venv.step(np.zeros((1, *venv.action_space.shape), dtype=np.float32))
    venv.close()


def train(run_dir: Path, config: dict[str, Any], env_id: str, seed: int, algo: str = "ppo", *, resume: bool = False,
          progress_bar: bool = True, final_eval: bool = True,
          on_validation: Callable[[dict[str, Any]], None] | None = None) -> dict[str, Any]:
    """Train (or continue) the run in ``run_dir`` up to ``config["n_timesteps"]``; returns the timing.
    ``on_validation`` receives each periodic validation's row of evaluations.csv (a dict)."""
    warm_up_engine(env_id, config)
    torch.set_num_threads(int(config.get("torch_threads", 1)))
    checkpoint = latest_checkpoint(run_dir, algo) if resume else None
    # a resumed run draws new episodes (seeded after the steps already taken), not the first ones again
    env_seed = seed + (checkpoint[2] if checkpoint else 0)
    venv = make_training_env(env_id, config["n_envs"], seed=env_seed, env_kwargs=config["env_kwargs"],
                             vec_env_kwargs=config.get("vec_env_kwargs"), normalize=config.get("normalize", True),
                             normalize_path=str(checkpoint[1]) if checkpoint and checkpoint[1] else None,
                             env_wrapper=config.get("env_wrapper"))
    cls = algorithms.algorithm_class(algo)
    off_policy = algorithms.is_off_policy(algo)
    if checkpoint:
        model = load_model(algo, checkpoint[0], env=venv)
        buffer = checkpoint[0].with_name(f"{algo}_replay_buffer_{checkpoint[2]}_steps.pkl")
        if off_policy and buffer.exists():
            model.load_replay_buffer(buffer)
        print(f"resuming {run_dir} from {checkpoint[0]} at {model.num_timesteps} steps")
    else:
        model = cls(env=venv, seed=seed, device="cpu", verbose=0,
                    **configuration.algorithm_kwargs(config, algo, venv.action_space.shape[0]))
    model.set_logger(configure(str(run_dir / "logs"), ["csv", "tensorboard"]))
    # wall time of earlier sessions: the last validation row written before the run stopped
    previous = read_timing(run_dir) if checkpoint else None
    evaluations = run_dir / "evaluations.csv"
    wall_offset = 0.0
    if checkpoint and evaluations.exists():
        with open(evaluations) as file:
            rows = [row for row in csv.DictReader(file) if int(row["timesteps"]) <= checkpoint[2]]
        wall_offset = float(rows[-1]["wall_seconds"]) if rows else 0.0
    validation = ValidationCallback(run_dir, config, env_id, wall_offset, on_validation)
    callbacks = [validation]
    if config.get("checkpoint_freq"):  # first: a checkpoint of this step exists when the validation is reported
        callbacks.insert(0, CheckpointCallback(save_freq=max(int(config["checkpoint_freq"]) // config["n_envs"], 1),
                                               save_path=str(run_dir / "checkpoints"), name_prefix=algo,
                                               save_vecnormalize=True, save_replay_buffer=off_policy))
    remaining = max(int(config["n_timesteps"]) - model.num_timesteps, 0)
    start = time.perf_counter()
    model.learn(remaining, callback=callbacks, progress_bar=progress_bar, reset_num_timesteps=not checkpoint)
    learn_seconds = time.perf_counter() - start
    model.save(run_dir / "model.zip")
    vec_normalize = normalizer_of(venv)
    if vec_normalize is not None:
        vec_normalize.save(str(run_dir / "vecnormalize.pkl"))
    timed = find_wrapper(venv, TimedVecEnv)
    if previous is None:  # killed before it finished: earlier sessions' time is in the validation rows
        previous = {"wall_seconds": wall_offset, "env_seconds": 0.0, "eval_seconds": 0.0}
    timing = {
        "algo": algo,
        "timesteps": int(model.num_timesteps),
        "wall_seconds": previous["wall_seconds"] + learn_seconds,  # everything in model.learn, every session
        "env_seconds": previous["env_seconds"] + timed.env_seconds,  # inside the vector env's reset and step
        "eval_seconds": previous["eval_seconds"] + validation.seconds,  # periodic validation
        "torch_threads": torch.get_num_threads(),
    }
    # the env's share of the training loop (rollouts and updates; periodic validation left out)
    timing["env_share"] = timing["env_seconds"] / max(timing["wall_seconds"] - timing["eval_seconds"], 1e-9)
    (run_dir / "timing.json").write_text(json.dumps(timing, indent=2))
    venv.close()
    if final_eval:
        evaluate_run(run_dir, quiet=True)
    return timing
