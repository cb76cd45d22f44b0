"""Headless, deterministic evaluation on a fixed set of seeded targets (command: ``agents.evaluate``).

Target i is what ``gymnasium.make(env_id, **env_kwargs).reset(seed=first_seed + i)`` draws (the
release pose, the target x and faces), so every agent is scored on the same throws whatever env
settings it was trained with. The policy sees all observations first and answers with all actions
(a batch), then each target is reset again with its seed and thrown once through the env itself.
A throw that the env refuses to finish (``EnergyGainError`` or ``NonFiniteStateError``, possible
only with the seed solver at a large step) counts as a failure and is reported as such.

Scores (``summarize``): the success rate (at rest within the tolerance on a target face), the
mean and median landing distance |x - target x|, the face accuracy (a target face ended down,
wherever the box landed), broken down by target distance and by target face kind.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np
import yaml

import box_toss_env  # noqa: F401  (registers the BoxToss envs)
from agents import oracle
from agents.config import parse_override
from agents.policies import ConstantPolicy, GoalPolicy, Policy, RandomPolicy, TrainedPolicy, load_model
from agents.run_files import read_run_config
from agents.run_folder import LOCK, RunFolderError, check_component, lock_run, unlock_run, write_atomic
from agents.targets import STACK_TEST_EPISODES, TEST_FIRST_SEED, TEST_TARGETS, VALIDATION_FIRST_SEED  # noqa: F401
from box_toss_env.envs import task
from box_toss_env.envs.functional import EnergyGainError
from box_toss_env.files import DamagedFileError, file_action, remove_stale_temporaries
from box_toss_env.physics import NonFiniteStateError

THROWN_IN = {"BoxToss-Goal-v0": "BoxToss-v0"}
"""Envs whose runs are evaluated in another env: the goal env's throws are BoxToss-v0's (the same draws for a
seed, ``tests/envs/test_goal.py``), thrown there with ``GoalPolicy``."""
DISTANCE_BINS = 6


@dataclass
class Throws:
    """One row per target of an evaluation (all arrays (n,) unless noted)."""

    seeds: np.ndarray
    target_x: np.ndarray  # [m]
    target_faces: np.ndarray  # (n, 4) 1 where that face may end down
    actions: np.ndarray  # (n, 3) in [-1, 1]
    final_x: np.ndarray  # [m], nan where the throw failed
    face_down: np.ndarray  # 0-3, -1 where the throw failed
    at_rest: np.ndarray
    success: np.ndarray
    reward: np.ndarray  # nan where the throw failed
    failure: list[str] = field(default_factory=list)  # "" or why the env refused the throw

    @property
    def distance(self) -> np.ndarray:  # [m]
        return np.abs(self.final_x - self.target_x)

    @property
    def face_ok(self) -> np.ndarray:
        """A target face ended down (wherever the box landed)."""
        ok = self.target_faces[np.arange(len(self.seeds)), np.maximum(self.face_down, 0)] > 0
        return ok & (self.face_down >= 0)

    def save(self, path: Path) -> None:
        """``throws.npz``, written atomically."""
        arrays = {
            name: getattr(self, name)
            for name in (
                "seeds",
                "target_x",
                "target_faces",
                "actions",
                "final_x",
                "face_down",
                "at_rest",
                "success",
                "reward",
            )
        }
        write_atomic(path, lambda file: np.savez_compressed(file, failure=np.array(self.failure, dtype=str), **arrays))

    @classmethod
    def load(cls, path: Path) -> Throws:
        with np.load(path) as data:
            arrays = {name: data[name] for name in data.files if name != "failure"}
            return cls(**arrays, failure=[str(v) for v in data["failure"]])


def target_seeds(n: int = TEST_TARGETS, first: int = TEST_FIRST_SEED) -> np.ndarray:
    return np.arange(first, first + n)


def draw_targets(env: gym.Env, seeds) -> tuple[np.ndarray, list[dict[str, Any]]]:
    """The first observations (n, obs) and reset infos of ``env`` for each seed."""
    observations, infos = [], []
    for seed in seeds:
        obs, info = env.reset(seed=int(seed))
        observations.append(obs)
        infos.append(info)
    return np.stack(observations).astype(np.float32), infos


def throw(env: gym.Env, seeds, actions: np.ndarray, reset_infos: list[dict[str, Any]]) -> Throws:
    """Reset ``env`` with each seed and throw the matching action once."""
    n = len(seeds)
    final_x, reward = np.full(n, np.nan), np.full(n, np.nan)
    face_down = np.full(n, -1, dtype=np.int64)
    at_rest, success = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    failure = [""] * n
    for i, seed in enumerate(seeds):
        env.reset(seed=int(seed))
        try:
            _, r, _, _, info = env.step(actions[i])
        except EnergyGainError:
            failure[i] = "energy gain"
            continue
        except NonFiniteStateError:
            failure[i] = "non-finite state"
            continue
        final_x[i], reward[i], face_down[i] = info["final_x"], r, info["face_down"]
        at_rest[i], success[i] = info["at_rest"], info["success"]
    return Throws(
        seeds=np.asarray(seeds),
        target_x=np.array([info["target_x"] for info in reset_infos]),
        target_faces=np.array([info["target_faces"] for info in reset_infos], dtype=np.int8),
        actions=np.asarray(actions, dtype=np.float64),
        final_x=final_x,
        face_down=face_down,
        at_rest=at_rest,
        success=success,
        reward=reward,
        failure=failure,
    )


def evaluate(policy: Policy, env_id: str, env_kwargs: dict[str, Any] | None = None, seeds=None) -> tuple[Throws, float]:
    """Throw once per seed (default: the 1,024 test targets) with ``policy``'s deterministic
    actions. Returns the throws and the seconds the policy took to answer (a planner's planning)."""
    seeds = target_seeds() if seeds is None else np.asarray(seeds)
    env = gym.make(env_id, **(env_kwargs or {}))
    try:
        observations, infos = draw_targets(env, seeds)
        start = time.perf_counter()
        actions = np.asarray(policy.act(observations, infos, cast(Any, env)), dtype=np.float64).reshape(len(seeds), -1)
        act_seconds = time.perf_counter() - start
        return throw(env, seeds, actions, infos), act_seconds
    finally:
        env.close()


# -- episodes of several throws (BoxToss-Stack-v0) ------------------------------------------------


def is_stack(env_id: str) -> bool:
    """Whether ``env_id`` is a stacking env (episodes of several throws, scored per episode)."""
    return env_id.startswith("BoxToss-Stack")


def evaluate_stack(
    policy: Policy, env_id: str, env_kwargs: dict[str, Any] | None = None, seeds=None
) -> tuple[dict[str, np.ndarray], float]:
    """One episode per seed with ``policy``'s deterministic actions, all episodes at once in the env's batched form
    (bit for bit the single env's, one engine thread): per episode its success, final stack height [m], whether
    the stack fell, its return and throws; and the seconds the policy took to answer."""
    seeds = target_seeds(STACK_TEST_EPISODES) if seeds is None else np.asarray(seeds)
    n = len(seeds)
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", threads=1, **(env_kwargs or {}))
    episodes = {
        "seeds": np.asarray(seeds),
        "success": np.zeros(n, dtype=bool),
        "height": np.zeros(n),
        "fell": np.zeros(n, dtype=bool),
        "ret": np.zeros(n),
        "throws": np.zeros(n, dtype=np.int64),
    }
    act_seconds = 0.0
    try:
        observations, _ = env.reset(seed=[int(seed) for seed in seeds])  # type: ignore[arg-type]  # one per env
        infos: list[dict[str, Any]] = [{} for _ in range(n)]
        done = np.zeros(n, dtype=bool)
        while not done.all():
            start = time.perf_counter()
            actions = np.asarray(policy.act(observations, infos, cast(Any, env)), dtype=np.float32).reshape(n, -1)
            act_seconds += time.perf_counter() - start
            observations, reward, terminated, truncated, info = env.step(np.clip(actions, -1.0, 1.0))
            live = ~done
            episodes["ret"][live] += reward[live]
            episodes["throws"][live] += 1
            ended = live & (terminated | truncated)
            if ended.any():
                final = info["final_info"]
                episodes["success"][ended] = final["success"][ended]
                episodes["height"][ended] = final["stack_height"][ended]
                episodes["fell"][ended] = final["fell"][ended]
            done |= ended
    finally:
        env.close()
    return episodes, act_seconds


def stack_scores(episodes: dict[str, np.ndarray]) -> dict[str, Any]:
    """Success rate, mean final stack height, fall rate, mean return of ``evaluate_stack``'s episodes (the one-throw
    scores that mean nothing here, distance and face accuracy, are NaN)."""
    n = len(episodes["seeds"])
    return {
        "n": n,
        "success_rate": float(episodes["success"].mean()),
        "mean_height": float(episodes["height"].mean()),
        "fall_rate": float(episodes["fell"].mean()),
        "mean_reward": float(episodes["ret"].mean()),
        "throws": int(episodes["throws"].sum()),
        "mean_distance": math.nan,
        "median_distance": math.nan,
        "face_accuracy": math.nan,
        "failures": 0,
    }


# -- scores --------------------------------------------------------------------------------------
def scores(throws: Throws, mask: np.ndarray | None = None) -> dict[str, Any]:
    """Success rate, landing distance (mean, median, over throws that finished), face accuracy,
    mean reward and failures, over the throws selected by ``mask``."""
    mask = np.ones(len(throws.seeds), dtype=bool) if mask is None else mask
    finished = mask & np.isfinite(throws.final_x)
    distance = throws.distance[finished]
    n = int(mask.sum())
    return {
        "n": n,
        "success_rate": float(throws.success[mask].mean()) if n else math.nan,
        "mean_distance": float(distance.mean()) if distance.size else math.nan,
        "median_distance": float(np.median(distance)) if distance.size else math.nan,
        "face_accuracy": float(throws.face_ok[mask].mean()) if n else math.nan,
        "mean_reward": float(throws.reward[finished].mean()) if distance.size else math.nan,
        "failures": int(n - finished.sum()),
    }


DISTANCE_CAP = 10.0  # [m] larger mean distances count as this in ``search_objective``


def search_objective(success_rate: float, mean_distance: float, targets: int) -> float:
    """One number ranking evaluations by success rate, then by distance (what ``agents.tune`` maximises):

        success_rate - min(mean_distance, 10 m) / 10 m / (targets + 1)

    The distance term is below one target's worth of success (1 / targets), so a higher success
    always ranks higher and the distance only breaks ties (a NaN distance counts as 10 m)."""
    distance = min(mean_distance, DISTANCE_CAP) if math.isfinite(mean_distance) else DISTANCE_CAP
    if not math.isfinite(success_rate):
        return -math.inf
    return success_rate - distance / DISTANCE_CAP / (targets + 1)


def distance_bins(target_x_range: tuple[float, float], n_bins: int = DISTANCE_BINS) -> np.ndarray:
    low, high = target_x_range
    return np.linspace(low, high, n_bins + 1)


def summarize(throws: Throws, target_x_range: tuple[float, float]) -> dict[str, Any]:
    """``scores`` over all throws, by target distance bin and by target face kind."""
    edges = distance_bins(target_x_range)
    which = np.clip(np.searchsorted(edges, throws.target_x, side="right") - 1, 0, len(edges) - 2)
    by_distance = [
        {"bin": f"{edges[k]:.2f}-{edges[k + 1]:.2f} m", **scores(throws, which == k)} for k in range(len(edges) - 1)
    ]
    kinds = np.array([task.describe_target_faces(mask) for mask in throws.target_faces])
    by_face = [{"kind": kind, **scores(throws, kinds == kind)} for kind in dict.fromkeys(kinds.tolist())]
    reasons = sorted({reason for reason in throws.failure if reason})
    return {
        **scores(throws),
        "by_distance": by_distance,
        "by_face": by_face,
        "failure_reasons": {reason: throws.failure.count(reason) for reason in reasons},
    }


def format_table(rows: list[dict[str, Any]], label: str = "agent") -> str:
    """A plain-text table of scores (one row per dict with a ``label`` key)."""
    width = max([24] + [len(str(row[label])) for row in rows])
    header = f"{label:<{width}} {'targets':>7} {'success':>8} {'mean dist':>10} {'median dist':>12} {'face acc':>9}"
    lines = [header, "-" * len(header)]
    for row in rows:
        failures = f"  ({row['failures']} failed)" if row.get("failures") else ""
        lines.append(
            f"{row[label]:<{width}} {row['n']:>7d} {row['success_rate']:>7.1%} {row['mean_distance']:>8.3f} m "
            f"{row['median_distance']:>10.3f} m {row['face_accuracy']:>8.1%}{failures}"
        )
    return "\n".join(lines)


def format_summary(name: str, summary: dict[str, Any]) -> str:
    text = [
        format_table([{"agent": name, **summary}]),
        "",
        "by target distance:",
        format_table(summary["by_distance"], "bin"),
        "",
        "by target face:",
        format_table(summary["by_face"], "kind"),
    ]
    if summary["failure_reasons"]:
        text += [
            "",
            "throws the env refused to finish (counted as failures): "
            + ", ".join(f"{n} x {reason}" for reason, n in summary["failure_reasons"].items()),
        ]
    return "\n".join(text)


# -- runs ----------------------------------------------------------------------------------------
BASELINES = ("random", "oracle", "constant")


def make_baseline(algo: str, settings: dict[str, Any] | None = None) -> Policy:
    """The baseline policy named ``algo`` ("random", "oracle" or "constant") with its settings."""
    settings = settings or {}
    if algo == "random":
        return RandomPolicy(**settings)
    if algo == "oracle":
        return oracle.OraclePlanner(oracle.OracleSettings(**settings))
    if algo == "constant":
        return ConstantPolicy(**settings)
    raise ValueError(f"unknown baseline {algo!r}; choose one of {BASELINES}")


def make_baseline_run(
    algo: str,
    run_dir: Path,
    env_id: str = "BoxToss-v0",
    env_kwargs: dict[str, Any] | None = None,
    settings: dict[str, Any] | None = None,
    command: str | None = None,
) -> Path:
    """A run folder for a baseline (config.yml, command.txt), evaluated like any run."""
    run_dir.mkdir(parents=True, exist_ok=True)
    write_atomic(
        run_dir / "config.yml",
        yaml.safe_dump(
            {"algo": algo, "env_id": env_id, "env_kwargs": env_kwargs or {}, "baseline": settings or {}},
            sort_keys=False,
        ),
    )
    if command:
        write_atomic(run_dir / "command.txt", command + "\n")
    return run_dir


def load_policy(run_dir: Path, model: str = "final") -> tuple[Policy, dict[str, Any]]:
    """The policy saved in a run folder and the run's ``config.yml``, every file read checked (a
    DamagedFileError naming a damaged one)."""
    config = read_run_config(run_dir)
    algo = config["algo"]
    if algo in BASELINES:
        try:
            return make_baseline(algo, config.get("baseline") or {}), config
        except (TypeError, ValueError) as error:
            raise DamagedFileError(f"{run_dir / 'config.yml'} is damaged: baseline: {error}") from None
    if config.get("goal"):  # Dict observations (BoxToss-Goal-v0): HER's replay buffer is not needed to act
        trained = load_model(
            algo,
            run_dir / "model.zip",
            custom_objects={"replay_buffer_class": None, "replay_buffer_kwargs": {}, "buffer_size": 1},
        )
        return GoalPolicy(trained, config.get("hyperparams", {}).get("env_wrapper")), config
    hyperparams = config.get("hyperparams", {})
    return TrainedPolicy.load(
        run_dir, algo, model, hyperparams.get("env_wrapper"), normalized=bool(hyperparams.get("normalize", True))
    ), config


def evaluate_stack_run(run_dir, config, policy, model, env_id, kwargs, seeds, tag, out, start, quiet):
    """``evaluate_run`` for a stacking env: whole episodes, scored per episode (``stack_scores``), into
    ``out`` (results.json, episodes.npz)."""
    episodes, act_seconds = evaluate_stack(policy, env_id, kwargs, seeds)
    results = {
        "run": run_dir.name,
        "algo": config["algo"],
        "model": model,
        "env_id": env_id,
        "env_kwargs": kwargs,
        "seeds": [int(seeds[0]), int(seeds[-1])],
        "act_seconds": act_seconds,
        "eval_seconds": time.perf_counter() - start,
        "tag": tag,
        **stack_scores(episodes),
    }
    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "episodes.npz", lambda file: np.savez_compressed(file, **episodes))
    write_atomic(out / "results.json", json.dumps(results, indent=2))
    if not quiet:
        print(
            f"{run_dir.name} ({config['algo']}) on {env_id}, episodes of seeds {seeds[0]}-{seeds[-1]}: success "
            f"{results['success_rate']:.1%}, mean final height {results['mean_height']:.3f} m, stack fell "
            f"{results['fall_rate']:.1%}, mean return {results['mean_reward']:.3f}; results in {out}"
        )
    return results


def evaluate_run(
    run_dir: Path,
    *,
    model: str = "final",
    env_kwargs: dict[str, Any] | None = None,
    tag: str | None = None,
    n_targets: int | None = None,
    first_seed: int = TEST_FIRST_SEED,
    quiet: bool = False,
) -> dict[str, Any]:
    """Evaluate the run's policy on the test targets, under the env settings it was trained with,
    updated with ``env_kwargs``; write ``RUN/eval/TAG/`` (results.json, throws.npz) and return the
    results. The default tag names every setting that differs from the defaults (``default_tag``);
    a folder holding the results of other settings is never overwritten (a RunFolderError)."""
    run_dir = Path(run_dir)
    policy, config = load_policy(run_dir, model)
    env_id = THROWN_IN.get(config["env_id"], config["env_id"])
    default_count = STACK_TEST_EPISODES if is_stack(env_id) else TEST_TARGETS  # a stacking env: episodes
    n_targets = default_count if n_targets is None else n_targets
    tag = (
        check_component(tag, "--tag")
        if tag is not None
        else default_tag(env_kwargs, model, n_targets, first_seed, default_count)
    )
    kwargs = {**config.get("env_kwargs", {}), **(env_kwargs or {})}
    seeds = target_seeds(n_targets, first_seed)
    out = run_dir / "eval" / tag
    settings = {"model": model, "env_id": env_id, "env_kwargs": kwargs, "seeds": [int(seeds[0]), int(seeds[-1])]}
    check_results_folder(out, settings)
    made = [folder for folder in (out.parent, out) if not folder.exists()]  # what a failed evaluation removes
    claim_results_folder(out)
    try:
        start = time.perf_counter()
        if is_stack(env_id):
            return evaluate_stack_run(run_dir, config, policy, model, env_id, kwargs, seeds, tag, out, start, quiet)
        return evaluate_throws_run(run_dir, config, policy, model, env_id, kwargs, seeds, tag, out, start, quiet)
    finally:
        unlock_run(out)
        remove_if_unused(out, made)


def remove_if_unused(out: Path, made: list[Path]) -> None:
    """After an evaluation that wrote no results (stopped by a full disk, an error, Ctrl-C), remove the folders
    it made (``made``, outermost first) if they hold nothing but its lock: no empty ``eval/TAG`` is left behind."""
    if (out / "results.json").exists():
        return
    for folder in reversed(made):
        try:
            (folder / LOCK).unlink(missing_ok=True)
            folder.rmdir()  # only an empty folder: anything else in it stays
        except OSError:
            return


def evaluate_throws_run(run_dir, config, policy, model, env_id, kwargs, seeds, tag, out, start, quiet):
    """``evaluate_run`` for an env of one throw per episode: the throws, scored (``summarize``), into ``out``
    (results.json, throws.npz)."""
    throws, act_seconds = evaluate(policy, env_id, kwargs, seeds)
    wall = time.perf_counter() - start
    target_x_range = cast(Any, gym.make(env_id, **kwargs).unwrapped).config.target_x_range
    summary = summarize(throws, target_x_range)
    results = {
        "run": run_dir.name,
        "algo": config["algo"],
        "model": model,
        "env_id": env_id,
        "env_kwargs": kwargs,
        "seeds": [int(seeds[0]), int(seeds[-1])],
        "act_seconds": act_seconds,
        "eval_seconds": wall,
        "tag": tag,
        **summary,
    }
    throws.save(out / "throws.npz")
    write_atomic(out / "results.json", json.dumps(results, indent=2))
    if not quiet:
        which = "" if config["algo"] in BASELINES else f", {model} model"
        print(
            f"{run_dir.name} ({config['algo']}{which}) on {env_id}{' ' + str(kwargs) if kwargs else ''}, "
            f"targets of seeds {seeds[0]}-{seeds[-1]}:"
        )
        print(format_summary(run_dir.name, summary))
        print(f"results in {out}")
    return results


def claim_results_folder(out: Path) -> None:
    """Make ``out`` (a results folder, ``RUN/eval/TAG``), hold its lock for this process (a RunFolderError if
    another evaluation writes there) and remove the temporary files an interrupted write left there."""
    with file_action("make the results folder", out):
        out.mkdir(parents=True, exist_ok=True)
    lock_run(out, "evaluation")
    remove_stale_temporaries(out)


def check_results_folder(out: Path, settings: dict[str, Any]) -> None:
    """A RunFolderError if ``out`` holds the results of an evaluation with other settings."""
    path = out / "results.json"
    if not path.exists():
        return
    try:
        held = json.loads(path.read_text())
    except ValueError:
        return  # not results: replaced
    held = {key: held.get(key) for key in settings}
    if held != json.loads(json.dumps(settings)):
        differ = ", ".join(
            f"{key} {held[key]} there, {settings[key]} here"
            for key in settings
            if held[key] != json.loads(json.dumps(settings[key]))
        )
        raise RunFolderError(f"{out} holds an evaluation with other settings ({differ}); choose another --tag")


def default_tag(
    env_kwargs: dict[str, Any] | None,
    model: str = "final",
    n_targets: int = TEST_TARGETS,
    first_seed: int = TEST_FIRST_SEED,
    default_count: int = TEST_TARGETS,
) -> str:
    """ "default" for the test targets under the run's own env settings; otherwise the settings that
    differ (``best-dt=0.000976562-targets=8``), so that no evaluation overwrites another."""
    parts = [] if model == "final" else [model]
    for key, value in sorted((env_kwargs or {}).items()):
        parts.append(f"{key}={value:.6g}" if isinstance(value, float) else f"{key}={value}")
    if n_targets != default_count:
        parts.append(f"targets={n_targets}")
    if first_seed != TEST_FIRST_SEED:
        parts.append(f"first_seed={first_seed}")
    return "-".join(parts).replace("/", "_") or "default"


def parse_kwargs(items: list[str] | None) -> dict[str, Any]:
    """``["solver=seed", "dt=0.001"]`` as a dict (values read with yaml.safe_load)."""
    kwargs = {}
    for item in items or ():
        keys, value = parse_override(item)
        kwargs[".".join(keys)] = value
    return kwargs
