"""Trained agents ready to load: PPO for each variant, in huggingface_sb3's folder layout with RL Zoo's model card.

    from agents.pretrained import load_agent
    agent = load_agent("BoxToss-ThisSideUp-v0")   # models/ppo-BoxToss-ThisSideUp-v0/
    obs, info = env.reset(seed=0)                  # env = gymnasium.make("BoxToss-ThisSideUp-v0")
    obs, reward, terminated, truncated, info = env.step(agent.predict(obs))

    python -m agents.pretrained export runs/pretrained/BoxToss-v0 ...   # run folders -> models/, evaluated, carded
    python -m agents.pretrained export RUN ... --write-docs             # and the docs' figures (figures.yml, README)
    python -m agents.pretrained check                                   # every file against models/SHA256SUMS
    python -m agents.pretrained rescore [ENV_ID ...] [--write-docs]     # evaluated again on this engine

A folder ``models/<algo>-<env id>/`` holds what huggingface_sb3 uploads for a model (``<algo>-<env id>.zip``, the
SB3 model; ``vec_normalize.pkl``, the observation statistics; ``config.yml``, the run's algorithm, hyperparameters,
env kwargs and seed; ``env_kwargs.yml``; ``results.json``, the evaluation; ``README.md``, the model card with the
Hub's metadata), so it can be pushed to a model repository as it is. ``models/SHA256SUMS`` holds every file's
checksum, which ``load_agent`` checks before it loads a model.

``agent.predict`` takes the env's own observations and answers with the env's own actions: it normalises the
observations as training saw them and, for a policy that acts in ballistic or stack commands, maps its commands
to the env's actions as the wrapper it was trained through does (``agents.envs.command_map``).
"""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import yaml

import box_toss_env  # noqa: F401  (registers the BoxToss envs)
from agents import evaluation, figures
from agents.config import OneLineParser, load_yaml
from agents.model_card import write_model_card
from agents.policies import TrainedPolicy, UnreadableModelError, load_model
from agents.run_files import read_json_mapping, read_normalizer, read_text
from box_toss_env.files import DamagedFileError, write_atomic

MODELS = Path(__file__).resolve().parents[1] / "models"
CHECKSUMS = "SHA256SUMS"
CONFIDENCE = 0.95


def model_name(algo: str, env_id: str) -> str:
    """``ppo-BoxToss-v0``: the name huggingface_sb3 gives a model (``ModelName``), its folder's and zip's."""
    return f"{algo}-{env_id}"


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def read_checksums(models: Path = MODELS) -> dict[str, str]:
    """``folder/file`` -> sha256 from ``models/SHA256SUMS`` (``sha256sum``'s format)."""
    path = models / CHECKSUMS
    if not path.exists():
        return {}
    pairs = [line.split(maxsplit=1) for line in read_text(path).splitlines() if line.strip()]
    if any(len(pair) != 2 for pair in pairs):
        raise DamagedFileError(f"{path} is damaged: a line is not sha256sum's '<digest>  <file>'")
    return {name: digest for digest, name in pairs}


def write_checksums(models: Path = MODELS) -> None:
    """``models/SHA256SUMS`` for every file of every model folder (``sha256sum -c SHA256SUMS`` checks them)."""
    files = sorted(path for path in models.glob("*/*") if path.is_file())
    lines = [f"{sha256(path)}  {path.relative_to(models).as_posix()}" for path in files]
    write_atomic(models / CHECKSUMS, "\n".join(lines) + "\n")


def check_folder(folder: Path, models: Path = MODELS) -> None:
    """An UnreadableModelError naming the first file of ``folder`` whose checksum is missing or differs."""
    sums = read_checksums(models)
    for path in sorted(p for p in folder.iterdir() if p.is_file()):
        key = path.relative_to(models).as_posix()
        if key not in sums:
            raise UnreadableModelError(f"{path} has no checksum in {models / CHECKSUMS}")
        if sha256(path) != sums[key]:
            raise UnreadableModelError(f"{path} does not match its checksum in {models / CHECKSUMS}: download it again")


class PretrainedAgent:
    """A trained model that plays an env with the env's own observations and actions (module docstring)."""

    def __init__(self, folder: Path, policy: TrainedPolicy, config: dict[str, Any]):
        self.folder = folder
        self.policy = policy
        self.config = config
        """The run's configuration (``config.yml``): algorithm, env id, hyperparameters, env kwargs, seed."""
        self.env_id: str = config["env_id"]
        self.results: dict[str, Any] = read_json_mapping(folder / "results.json")
        """The evaluation the model card reports (``results.json``)."""
        self._env = gym.make(self.env_id, **config.get("env_kwargs", {}))  # its task settings map commands

    @property
    def model(self):
        """The Stable-Baselines3 model (``PPO``)."""
        return self.policy.model

    def act(self, observations: np.ndarray, reset_infos: list[dict[str, Any]], env: gym.Env) -> np.ndarray:
        """``agents.evaluation``'s policy interface: env actions (n, 3) for observations (n, obs) of ``env``."""
        return self.policy.act(observations, reset_infos, env)

    def predict(self, observation: np.ndarray) -> np.ndarray:
        """The deterministic env action for one observation (obs,), or actions (n, 3) for a batch (n, obs)."""
        observation = np.asarray(observation, dtype=np.float32)
        batch = observation.reshape(-1, observation.shape[-1])
        actions = np.asarray(self.policy.act(batch, [{} for _ in batch], self._env), dtype=np.float32)
        return np.clip(actions, -1.0, 1.0).reshape(*observation.shape[:-1], -1)


def load_agent(env_id: str, algo: str = "ppo", models: Path | str = MODELS) -> PretrainedAgent:
    """The trained agent of ``env_id`` from ``models/<algo>-<env id>/`` (its checksums checked first)."""
    models = Path(models)
    folder = models / model_name(algo, env_id)
    if not folder.is_dir():
        have = sorted(p.name for p in models.glob("*-*") if p.is_dir()) if models.is_dir() else []
        raise FileNotFoundError(
            f"no trained agent {folder.name} in {models} (there: {', '.join(have) or 'none'}); pass models= the "
            "folder that holds the model folders (the repository's models/, or a release's archives unpacked)"
        )
    check_folder(folder, models)
    config = load_yaml(folder / "config.yml")
    model = load_model(algo, folder / f"{folder.name}.zip")
    stats = folder / "vec_normalize.pkl"
    vec_normalize = read_normalizer(stats, model.observation_space.shape) if stats.exists() else None
    policy = TrainedPolicy(model, vec_normalize, config["hyperparams"].get("env_wrapper"))
    return PretrainedAgent(folder, policy, config)


def wilson_interval(successes: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """The Wilson score interval of a success rate (scipy's ``binomtest``)."""
    from scipy.stats import binomtest

    interval = binomtest(successes, n).proportion_ci(confidence, method="wilson")
    return float(interval.low), float(interval.high)


def evaluate_agent(agent: PretrainedAgent, seeds=None) -> dict[str, Any]:
    """The agent's scores on the test targets (test episodes for a stack), as ``agents.evaluate`` measures them,
    with the success rate's 95% interval and the reward's mean and standard deviation (the Hub's metric)."""
    if evaluation.is_stack(agent.env_id):
        episodes, _ = evaluation.evaluate_stack(agent, agent.env_id, agent.config.get("env_kwargs"), seeds)
        results, success, rewards = evaluation.stack_scores(episodes), episodes["success"], episodes["ret"]
    else:
        throws, _ = evaluation.evaluate(agent, agent.env_id, agent.config.get("env_kwargs"), seeds)
        results, success, rewards = evaluation.scores(throws), throws.success, throws.reward
    low, high = wilson_interval(int(success.sum()), len(success))
    finite = rewards[np.isfinite(rewards)]
    first_seed = int(evaluation.target_seeds(1)[0] if seeds is None else np.asarray(seeds)[0])
    return {
        **{key: value for key, value in results.items() if not (isinstance(value, float) and np.isnan(value))},
        "success_interval": [low, high],
        "confidence": CONFIDENCE,
        "mean_reward": float(finite.mean()),
        "std_reward": float(finite.std()),
        "n_eval_episodes": len(success),
        "first_seed": first_seed,
        "is_deterministic": True,
    }


def export(run_dir: Path, models: Path = MODELS) -> Path:
    """Copy a run folder's final model into ``models/<algo>-<env id>/``, evaluate it there and write its model card
    (the checksums and the ``pretrained`` headline figures are written by ``main``)."""
    config = load_yaml(run_dir / "config.yml")
    name = model_name(config["algo"], config["env_id"])
    folder = models / name
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(run_dir / "model.zip", folder / f"{name}.zip")
    if (run_dir / "vecnormalize.pkl").exists():
        shutil.copyfile(run_dir / "vecnormalize.pkl", folder / "vec_normalize.pkl")
    write_atomic(folder / "config.yml", yaml.safe_dump(config, sort_keys=False))
    write_atomic(folder / "env_kwargs.yml", yaml.safe_dump(config.get("env_kwargs", {})))
    timing = json.loads((run_dir / "timing.json").read_text())
    results = {
        "env_id": config["env_id"],
        "algo": config["algo"],
        "seed": config["seed"],
        "timesteps": timing["timesteps"],
        "train_seconds": timing["wall_seconds"],
        "command": (run_dir / "command.txt").read_text().strip(),
        "version": config.get("version"),
    }
    write_atomic(folder / "results.json", json.dumps(results, indent=2) + "\n")  # what load_agent reads first
    write_checksums(models)
    results.update(evaluate_agent(load_agent(config["env_id"], config["algo"], models)))
    write_atomic(folder / "results.json", json.dumps(results, indent=2) + "\n")
    write_model_card(folder, config, results)
    write_checksums(models)
    return folder


def rescore(folder: Path, models: Path = MODELS) -> dict[str, Any]:
    """The committed agent of ``folder`` evaluated again as ``export`` evaluates it (after an engine change that moves
    its episodes), its ``results.json``, model card and the checksums rewritten; its training figures kept."""
    config = load_yaml(folder / "config.yml")
    results = json.loads((folder / "results.json").read_text())
    results.update(evaluate_agent(load_agent(config["env_id"], config["algo"], models)))
    write_atomic(folder / "results.json", json.dumps(results, indent=2) + "\n")
    write_model_card(folder, config, results)
    write_checksums(models)
    return results


def headline_figures(models: Path = MODELS) -> list[dict[str, Any]]:
    """The ``pretrained`` group of the headline figures: each model's success and interval, in the order the ids
    are registered."""
    order = {env_id: k for k, env_id in enumerate(gym.registry)}
    found = [json.loads(path.read_text()) for path in models.glob("*/results.json")]
    group = []
    for results in sorted(found, key=lambda r: (order.get(r["env_id"], len(order)), r["env_id"], r["algo"])):
        low, high = results["success_interval"]
        group.append(
            {
                "env_id": results["env_id"],
                "folder": model_name(results["algo"], results["env_id"]),
                "success": figures.percent(results["success_rate"]),
                "interval": f"{figures.percent(low)}-{figures.percent(high)}",
                "n": figures.count(results["n_eval_episodes"]),
                "throws": figures.count(results["timesteps"]),
                "train_time": figures.duration(results["train_seconds"]),
            }
        )
    return group


def main(argv: list[str] | None = None) -> None:
    parser = OneLineParser(prog="python -m agents.pretrained", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    export_parser = commands.add_parser("export", help="run folders -> models/, evaluated, with model cards")
    export_parser.add_argument("runs", type=Path, nargs="+", metavar="RUN")
    export_parser.add_argument("--models", type=Path, default=MODELS)
    export_parser.add_argument(
        "--write-docs",
        action="store_true",
        help="also rewrite the agents' figures in docs/generated/figures.yml and the README (tracked files)",
    )
    check_parser = commands.add_parser("check", help="every model's files against models/SHA256SUMS")
    check_parser.add_argument("--models", type=Path, default=MODELS)
    rescore_parser = commands.add_parser("rescore", help="evaluate models/ again: results, model cards, checksums")
    rescore_parser.add_argument("env_ids", nargs="*", metavar="ENV_ID", help="the agents of these ids (default: all)")
    rescore_parser.add_argument("--models", type=Path, default=MODELS)
    rescore_parser.add_argument("--write-docs", action="store_true", help="also rewrite the agents' figures")
    args = parser.parse_args(argv)
    if args.command == "check":
        for folder in sorted(p for p in args.models.iterdir() if p.is_dir()):
            check_folder(folder, args.models)
            print(f"{folder.name}: ok")
        return
    if args.command == "rescore":
        rescore_all(parser, args)
        return
    for run in args.runs:
        if not (run / "config.yml").exists() or not (run / "model.zip").exists():
            parser.error(f"{run} is not a finished run folder (config.yml and model.zip)")
    for run in args.runs:
        folder = export(run, args.models)
        results = json.loads((folder / "results.json").read_text())
        low, high = results["success_interval"]
        print(f"{folder}: success {results['success_rate']:.1%} ({low:.1%}-{high:.1%}) on {results['n']:,}")
    if args.write_docs:
        figures.update("pretrained", headline_figures(args.models))


def rescore_all(parser, args) -> None:
    """``rescore`` for the agents of ``args.env_ids`` (every folder of ``args.models`` if none), each checked first."""
    env_of = {
        p: load_yaml(p / "config.yml")["env_id"] for p in sorted(args.models.iterdir()) if (p / "config.yml").exists()
    }
    chosen = [p for p, env_id in env_of.items() if not args.env_ids or env_id in args.env_ids]
    if missing := [env_id for env_id in args.env_ids if env_id not in env_of.values()]:
        have = ", ".join(sorted(env_of.values()))
        parser.error(f"no trained agent of {', '.join(missing)} in {args.models} (there: {have})")
    for folder in chosen:
        check_folder(folder, args.models)
    for folder in chosen:
        results = rescore(folder, args.models)
        print(f"{folder.name}: success {results['success_rate']:.1%} on {results['n_eval_episodes']:,}")
    if args.write_docs:
        figures.update("pretrained", headline_figures(args.models))


if __name__ == "__main__":
    main()
