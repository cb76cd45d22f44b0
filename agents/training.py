"""Train PPO (Stable-Baselines3) on a BoxToss env; one folder per run.

    python -m agents.train                                        # BoxToss-v0, agents/hyperparams/ppo.yml
    python -m agents.train --name long --set n_timesteps=1000000 learning_rate=1e-4
    python -m agents.train --env BoxToss-ThisSideUp-v0 --set env_kwargs.max_spin=10
    python -m agents.train --resume runs/long --set n_timesteps=2000000   # continue from the last checkpoint

``runs/NAME/`` holds ``config.yml`` (the resolved hyperparameters, env kwargs and seed),
``command.txt`` (the exact command), ``model.zip`` and ``vecnormalize.pkl`` (the final policy and its
observation statistics), ``best_model.zip`` / ``best_vecnormalize.pkl`` (best validation success),
``evaluations.csv`` (periodic deterministic evaluation on fixed validation targets), ``logs/``
(TensorBoard and progress.csv), ``checkpoints/``, ``timing.json`` (wall time and the env's share of
it) and ``eval/default/`` (the final evaluation on the 1,024 test targets).
"""

from __future__ import annotations

import argparse
import csv
import json
import pickle
import re
import shlex
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents import config as configuration
from agents.evaluate import VALIDATION_FIRST_SEED, evaluate, scores, target_seeds

RUNS = Path("runs")
EVAL_COLUMNS = ("timesteps", "wall_seconds", "success_rate", "mean_distance", "median_distance", "face_accuracy",
                "mean_reward", "failures")


class TrainedPolicy:
    """A PPO model's deterministic action on observations normalised as in training."""

    def __init__(self, model, vec_normalize=None):
        from agents.envs import observation_normalizer

        self.model = model
        self.normalize = observation_normalizer(vec_normalize)

    def act(self, observations: np.ndarray, reset_infos, env) -> np.ndarray:
        actions, _ = self.model.predict(self.normalize(observations), deterministic=True)
        return actions

    @classmethod
    def load(cls, run_dir: Path, which: str = "final") -> TrainedPolicy:
        from stable_baselines3 import PPO

        prefix = "" if which == "final" else "best_"
        model = PPO.load(run_dir / f"{prefix}model.zip", device="cpu")
        stats = run_dir / f"{prefix}vecnormalize.pkl"
        vec_normalize = None
        if stats.exists():
            with open(stats, "rb") as file:
                vec_normalize = pickle.load(file)  # the statistics only (SB3 pickles it without its venv)
        return cls(model, vec_normalize)


def make_callbacks(run_dir: Path, config: dict[str, Any], env_id: str):
    """The validation (and best model) callback, and the checkpoint callback."""
    from stable_baselines3.common.callbacks import BaseCallback, CheckpointCallback

    from agents.envs import normalizer_of

    class ValidationCallback(BaseCallback):
        """Every ``eval_freq`` env steps: the deterministic policy on the fixed validation targets;
        logs the scores, appends them to evaluations.csv, keeps the best model by success rate."""

        def __init__(self):
            super().__init__()
            self.every = int(config["eval_freq"])
            self.seeds = target_seeds(int(config["eval_targets"]), VALIDATION_FIRST_SEED)
            self.path = run_dir / "evaluations.csv"
            self.best = -1.0
            self.last = 0
            self.seconds = 0.0
            self.start = time.perf_counter()
            self.wall_offset = 0.0

        def _on_training_start(self) -> None:
            self.last = self.num_timesteps
            if self.path.exists():  # resuming: keep the history, and its best
                with open(self.path) as file:
                    rows = list(csv.DictReader(file))
                if rows:
                    self.best = max(float(row["success_rate"]) for row in rows)
                    self.wall_offset = float(rows[-1]["wall_seconds"])
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
            throws, _ = evaluate(TrainedPolicy(self.model, vec_normalize), env_id, config["env_kwargs"], self.seeds)
            result = scores(throws)
            wall = self.wall_offset + begin - self.start
            for key in ("success_rate", "mean_distance", "face_accuracy", "mean_reward"):
                self.logger.record(f"eval/{key}", result[key])
            with open(self.path, "a", newline="") as file:
                row = [self.num_timesteps, f"{wall:.2f}"] + [result[key] for key in EVAL_COLUMNS[2:]]
                csv.writer(file).writerow(row)
            if result["success_rate"] > self.best:
                self.best = result["success_rate"]
                self.model.save(run_dir / "best_model.zip")
                if vec_normalize is not None:
                    vec_normalize.save(str(run_dir / "best_vecnormalize.pkl"))
            self.seconds += time.perf_counter() - begin

    callbacks = [ValidationCallback()]
    if config.get("checkpoint_freq"):
        callbacks.append(CheckpointCallback(save_freq=max(int(config["checkpoint_freq"]) // config["n_envs"], 1),
                                            save_path=str(run_dir / "checkpoints"), name_prefix="ppo",
                                            save_vecnormalize=True))
    return callbacks


def latest_checkpoint(run_dir: Path) -> tuple[Path, Path | None, int] | None:
    """(model, vecnormalize or None, timesteps) of the newest checkpoint of a run (or None)."""
    found = []
    for path in (run_dir / "checkpoints").glob("ppo_*_steps.zip"):
        match = re.fullmatch(r"ppo_(\d+)_steps\.zip", path.name)
        if match:
            found.append((int(match.group(1)), path))
    if (run_dir / "model.zip").exists():
        timing = run_dir / "timing.json"
        steps = json.loads(timing.read_text())["timesteps"] if timing.exists() else 0
        found.append((steps, run_dir / "model.zip"))
    if not found:
        return None
    steps, path = max(found)
    stats = (run_dir / "vecnormalize.pkl" if path.name == "model.zip"
             else path.with_name(f"ppo_vecnormalize_{steps}_steps.pkl"))
    return path, (stats if stats.exists() else None), steps


def new_run_dir(runs: Path, name: str | None, env_id: str) -> Path:
    if name is None:
        name = f"{env_id}-{time.strftime('%Y%m%d-%H%M%S')}"
    run_dir = runs / name
    if (run_dir / "config.yml").exists():
        raise SystemExit(f"{run_dir} already holds a run: choose another --name, or --resume {run_dir}")
    run_dir.mkdir(parents=True, exist_ok=True)
    return run_dir


def warm_up_engine(env_id: str, config: dict[str, Any]) -> None:
    """Load the env's compiled kernel with one throw in a throwaway env, so that compiling (or
    loading from numba's cache) is not counted as env time. It also starts numba's OpenMP threads,
    which resets the OpenMP thread count that torch reads: set torch's threads after this."""
    from agents.envs import make_vector_env

    venv = make_vector_env(env_id, 1, config["env_kwargs"], config.get("vec_env_kwargs"))
    venv.reset()
    venv.step(np.zeros((1, *venv.action_space.shape), dtype=np.float32))
    venv.close()


def train(run_dir: Path, config: dict[str, Any], env_id: str, seed: int, *, resume: bool = False,
          progress_bar: bool = True, final_eval: bool = True) -> dict[str, Any]:
    """Train (or continue) the run in ``run_dir`` up to ``config["n_timesteps"]``; returns the timing."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import configure

    from agents.envs import TimedVecEnv, find_wrapper, make_training_env, normalizer_of

    warm_up_engine(env_id, config)
    torch.set_num_threads(int(config.get("torch_threads", 1)))  # after the engine's threads started (see above)
    checkpoint = latest_checkpoint(run_dir) if resume else None
    # a resumed run draws new episodes (seeded after the steps already taken), not the first ones again
    env_seed = seed + (checkpoint[2] if checkpoint else 0)
    venv = make_training_env(env_id, config["n_envs"], seed=env_seed, env_kwargs=config["env_kwargs"],
                             vec_env_kwargs=config.get("vec_env_kwargs"), normalize=config.get("normalize", True),
                             normalize_path=str(checkpoint[1]) if checkpoint and checkpoint[1] else None)
    if checkpoint:
        model = PPO.load(checkpoint[0], env=venv, device="cpu")
        print(f"resuming {run_dir} from {checkpoint[0]} at {model.num_timesteps} steps")
    else:
        model = PPO(env=venv, seed=seed, device="cpu", verbose=0, **configuration.ppo_kwargs(config))
    model.set_logger(configure(str(run_dir / "logs"), ["csv", "tensorboard"]))
    callbacks = make_callbacks(run_dir, config, env_id)
    remaining = max(int(config["n_timesteps"]) - model.num_timesteps, 0)
    start = time.perf_counter()
    model.learn(remaining, callback=callbacks, progress_bar=progress_bar, reset_num_timesteps=not checkpoint)
    learn_seconds = time.perf_counter() - start
    model.save(run_dir / "model.zip")
    vec_normalize = normalizer_of(venv)
    if vec_normalize is not None:
        vec_normalize.save(str(run_dir / "vecnormalize.pkl"))
    timed = find_wrapper(venv, TimedVecEnv)
    previous = json.loads((run_dir / "timing.json").read_text()) if checkpoint and (run_dir / "timing.json").exists() \
        else {"wall_seconds": 0.0, "env_seconds": 0.0, "eval_seconds": 0.0}
    eval_seconds = callbacks[0].seconds
    timing = {
        "timesteps": int(model.num_timesteps),
        "wall_seconds": previous["wall_seconds"] + learn_seconds,  # everything in model.learn
        "env_seconds": previous["env_seconds"] + timed.env_seconds,  # inside the vector env's reset and step
        "eval_seconds": previous["eval_seconds"] + eval_seconds,  # periodic validation
        "torch_threads": torch.get_num_threads(),
    }
    # the env's share of the training loop (rollouts and updates; periodic validation left out)
    timing["env_share"] = timing["env_seconds"] / max(timing["wall_seconds"] - timing["eval_seconds"], 1e-9)
    (run_dir / "timing.json").write_text(json.dumps(timing, indent=2))
    venv.close()
    if final_eval:
        from agents.evaluate import evaluate_run

        evaluate_run(run_dir, quiet=True)
    return timing


def main(argv: list[str] | None = None) -> Path:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="BoxToss-v0", help="env id (a key of the hyperparameter file)")
    parser.add_argument("--hyperparams", type=Path, default=configuration.HYPERPARAMS, help="YAML keyed by env id")
    parser.add_argument("--set", nargs="*", default=[], action="extend", metavar="KEY=VALUE", dest="overrides",
                        help="override hyperparameters, e.g. n_timesteps=100000 policy_kwargs.net_arch=[64,64]")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--name", help="run folder name (default: env id and time)")
    parser.add_argument("--runs-dir", type=Path, default=RUNS)
    parser.add_argument("--resume", type=Path, metavar="RUN", help="continue a run from its last checkpoint")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--no-eval", action="store_true", help="skip the final evaluation on the test targets")
    args = parser.parse_args(argv)

    if args.resume:
        run_dir = args.resume
        saved = configuration.load_yaml(run_dir / "config.yml")
        env_id, seed = saved["env_id"], saved["seed"]
        config = configuration.apply_overrides(saved["hyperparams"], args.overrides)
    else:
        env_id, seed = args.env, args.seed
        config = configuration.apply_overrides(configuration.load_hyperparams(env_id, args.hyperparams),
                                               args.overrides)
        run_dir = new_run_dir(args.runs_dir, args.name, env_id)
    configuration.check_config(config)
    config.setdefault("env_kwargs", {})
    configuration.save_yaml({"algo": "ppo", "env_id": env_id, "seed": seed, "env_kwargs": config["env_kwargs"],
                             "hyperparams": config}, run_dir / "config.yml")
    command = shlex.join([Path(sys.executable).name, "-m", "agents.train", *argv])
    with open(run_dir / "command.txt", "a") as file:
        file.write(f"{command}\n")
    print(f"training PPO on {env_id} for {config['n_timesteps']:,} steps (seed {seed}) into {run_dir}")
    timing = train(run_dir, config, env_id, seed, resume=bool(args.resume), progress_bar=not args.no_progress,
                   final_eval=not args.no_eval)
    print(f"trained {timing['timesteps']:,} steps in {timing['wall_seconds']:.1f} s "
          f"(env {timing['env_share']:.0%} of the training loop, validation {timing['eval_seconds']:.1f} s)")
    if not args.no_eval:
        results = json.loads((run_dir / "eval" / "default" / "results.json").read_text())
        print(f"test targets: success {results['success_rate']:.1%}, mean distance {results['mean_distance']:.3f} m, "
              f"face accuracy {results['face_accuracy']:.1%}")
    return run_dir


if __name__ == "__main__":
    main()
