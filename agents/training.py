"""Train a Stable-Baselines3 algorithm (PPO, SAC, TD3) on a BoxToss env; one folder per run.

``runs/NAME/`` holds ``config.yml`` (algorithm, env id, seed and the resolved hyperparameters),
``command.txt`` (the exact commands), ``model.zip`` and ``vecnormalize.pkl`` (the final policy and its
observation statistics), ``best_model.zip`` / ``best_vecnormalize.pkl`` (best validation success),
``evaluations.csv`` (periodic deterministic evaluation on fixed validation targets), ``logs/``
(TensorBoard and progress.csv), ``checkpoints/`` (with the replay buffer for off-policy algorithms),
``timing.json`` (wall time over all sessions of the run, and the env's share of it, written as training
goes so that a killed session's time counts too) and ``eval/default/`` (the final evaluation on the 1,024
test targets).

Nothing completed is ever lost (``agents.run_folder``): every file is written atomically, a checkpoint's
model is written after its statistics and replay buffer (a checkpoint is complete once its model is
there), and the logs are appended; ``--resume`` continues from the newest complete checkpoint and drops,
explicitly, the rows of progress.csv and evaluations.csv written after it, so none is duplicated.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

import numpy as np
import torch
import yaml
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.logger import Logger, TensorBoardOutputFormat

from agents import algorithms, command_line, curriculum, initial_mean
from agents import config as configuration
from agents.checkpoints import (  # noqa: F401  (latest_checkpoint, model_timesteps: re-exported)
    BEST_FILES,
    Checkpoint,
    best_snapshot,
    latest_checkpoint,
    model_timesteps,
    resume_point,
    set_aside,
)
from agents.envs import TimedVecEnv, find_wrapper, make_training_env, make_vector_env, normalizer_of
from agents.evaluation import (
    VALIDATION_FIRST_SEED,
    evaluate,
    evaluate_run,
    evaluate_stack,
    is_stack,
    scores,
    stack_scores,
    target_seeds,
)
from agents.policies import TrainedPolicy, UnreadableModelError, load_model
from agents.run_files import read_json_mapping, read_normalizer
from agents.run_folder import (
    LOCK,
    AppendingCSVOutput,
    RunFolderError,
    append_line,
    atomic_path,
    check_component,
    claim_folder,
    copy_atomic,
    csv_line,
    lock_run,
    read_csv,
    timestamp,
    truncate_csv,
    unlock_run,
    write_atomic,
)
from box_toss_env.files import DamagedFileError, remove_stale_temporaries

RUNS = command_line.RUNS
REPLAY_BUFFERS_KEPT = 2
"""Replay buffers kept in ``checkpoints/``, of the newest checkpoints: a buffer holds every observation twice
(2.3 GB for 100k throws of 96 x 40 images), and one a checkpoint filled the disk in a run of SAC on pixels. An
older checkpoint keeps its model and statistics; resumed from, it trains on with an empty buffer (and says so)."""
EVAL_COLUMNS = (
    "timesteps",
    "wall_seconds",
    "success_rate",
    "mean_distance",
    "median_distance",
    "face_accuracy",
    "mean_reward",
    "failures",
)


class RunClock:
    """Wall, env and validation seconds over every session of a run, written to timing.json as training
    goes (at most a second apart, and at each checkpoint and validation): a kill loses about a second."""

    def __init__(self, run_dir: Path, algo: str, previous: dict[str, Any] | None = None):
        self.path = run_dir / "timing.json"
        self.algo = algo
        self.previous = {
            key: float((previous or {}).get(key, 0.0)) for key in ("wall_seconds", "env_seconds", "eval_seconds")
        }
        self.start = time.perf_counter()
        self.written = 0.0
        self.timed: TimedVecEnv | None = None
        self.eval_seconds = 0.0

    def wall(self) -> float:
        return self.previous["wall_seconds"] + time.perf_counter() - self.start

    def timing(self, timesteps: int) -> dict[str, Any]:
        timing: dict[str, Any] = {
            "algo": self.algo,
            "timesteps": int(timesteps),
            "wall_seconds": self.wall(),  # everything in model.learn, every session (killed ones too)
            "env_seconds": self.previous["env_seconds"] + (self.timed.env_seconds if self.timed else 0.0),
            "eval_seconds": self.previous["eval_seconds"] + self.eval_seconds,  # periodic validation
            "torch_threads": torch.get_num_threads(),
        }
        # the env's share of the training loop (rollouts and updates; periodic validation left out)
        timing["env_share"] = timing["env_seconds"] / max(timing["wall_seconds"] - timing["eval_seconds"], 1e-9)
        return timing

    def write(self, timesteps: int, *, every: float = 0.0) -> dict[str, Any] | None:
        if time.perf_counter() - self.written < every:
            return None
        timing = self.timing(timesteps)
        write_atomic(self.path, json.dumps(timing, indent=2))
        self.written = time.perf_counter()
        return timing


class ClockCallback(BaseCallback):
    """Writes the run's timing.json at most a second apart while training."""

    def __init__(self, clock: RunClock):
        super().__init__()
        self.clock = clock

    def _on_step(self) -> bool:
        self.clock.write(self.num_timesteps, every=1.0)
        return True


def save_checkpoint(model, run_dir: Path, algo: str, *, replay_buffer: bool) -> Path:
    """``checkpoints/<algo>_<steps>_steps.zip`` with its VecNormalize statistics, replay buffer and the
    run's best model as it is at this checkpoint (``best_snapshot``: a hard link where possible), each
    file written atomically, the model last: a checkpoint whose model exists is complete."""
    folder = run_dir / "checkpoints"
    folder.mkdir(exist_ok=True)
    steps = model.num_timesteps
    for name in BEST_FILES:
        if (run_dir / name).exists():
            copy_atomic(run_dir / name, best_snapshot(run_dir, algo, steps, name))
    if replay_buffer and getattr(model, "replay_buffer", None) is not None:
        with atomic_path(folder / f"{algo}_replay_buffer_{steps}_steps.pkl", ".pkl") as temp:
            model.save_replay_buffer(temp)
    vec_normalize = model.get_vec_normalize_env()
    if vec_normalize is not None:
        with atomic_path(folder / f"{algo}_vecnormalize_{steps}_steps.pkl") as temp:
            vec_normalize.save(str(temp))
    path = folder / f"{algo}_{steps}_steps.zip"
    with atomic_path(path, ".zip") as temp:
        model.save(temp)
    if replay_buffer:
        prune_replay_buffers(folder, algo)
    return path


def prune_replay_buffers(folder: Path, algo: str, keep: int = REPLAY_BUFFERS_KEPT) -> None:
    """The replay buffers of ``folder`` but the ``keep`` of the most steps removed."""
    buffers = []
    for path in folder.glob(f"{algo}_replay_buffer_*_steps.pkl"):
        if match := re.fullmatch(rf"{algo}_replay_buffer_(\d+)_steps\.pkl", path.name):
            buffers.append((int(match.group(1)), path))
    for _, path in sorted(buffers)[:-keep]:
        path.unlink(missing_ok=True)


def save_model(model, vec_normalize, run_dir: Path, prefix: str = "") -> None:
    """``<prefix>model.zip`` and ``<prefix>vecnormalize.pkl``, each written atomically."""
    if vec_normalize is not None:
        with atomic_path(run_dir / f"{prefix}vecnormalize.pkl") as temp:
            vec_normalize.save(str(temp))
    with atomic_path(run_dir / f"{prefix}model.zip", ".zip") as temp:
        model.save(temp)


class AtomicCheckpointCallback(BaseCallback):
    """``save_checkpoint`` (and timing.json) every ``save_freq`` env steps, at the start of a rollout:
    after the previous rollout's row of progress.csv and the update that followed it, so the
    checkpoint at T steps has every log row up to T, and a resume from it writes the next at T + rollout."""

    def __init__(self, save_freq: int, run_dir: Path, algo: str, clock: RunClock, replay_buffer: bool):
        super().__init__()
        self.save_freq, self.run_dir, self.algo, self.clock = save_freq, run_dir, algo, clock
        self.replay_buffer = replay_buffer
        self.last = 0

    def _on_training_start(self) -> None:
        self.last = self.num_timesteps

    def _on_rollout_start(self) -> None:
        if self.num_timesteps - self.last >= self.save_freq:
            self.last = self.num_timesteps
            save_checkpoint(self.model, self.run_dir, self.algo, replay_buffer=self.replay_buffer)
            self.clock.write(self.num_timesteps)

    def _on_step(self) -> bool:
        return True


class ValidationCallback(BaseCallback):
    """Every ``eval_freq`` env steps: the deterministic policy on the fixed validation targets;
    logs the scores, appends them to evaluations.csv, keeps the best model by success rate, then
    passes the row to ``on_validation`` if given (``agents.tuning`` reports it to Ray Tune).
    ``wall_seconds`` in the file counts training time over every session of the run. A session
    starts with a validation unless the file has a row of the steps it starts from."""

    def __init__(
        self,
        run_dir: Path,
        config: dict[str, Any],
        env_id: str,
        clock: RunClock | None = None,
        on_validation: Callable[[dict[str, Any]], None] | None = None,
    ):
        super().__init__()
        self.run_dir, self.config, self.env_id = run_dir, config, env_id
        self.on_validation = on_validation
        self.every = int(config["eval_freq"])
        self.seeds = target_seeds(int(config["eval_targets"]), VALIDATION_FIRST_SEED)
        self.path = run_dir / "evaluations.csv"
        self.best = -1.0
        self.last = 0
        self.clock = clock or RunClock(run_dir, "")

    @property
    def seconds(self) -> float:
        return self.clock.eval_seconds

    def _on_training_start(self) -> None:
        self.last = self.num_timesteps
        _, rows = read_csv(self.path)
        if rows and (self.run_dir / "best_model.zip").exists():  # resuming: keep the history, and its best
            self.best = max(float(row["success_rate"]) for row in rows)
        elif not self.path.exists():
            write_atomic(self.path, csv_line(list(EVAL_COLUMNS)))
        if not any(int(row["timesteps"]) == self.num_timesteps for row in rows):
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
        if is_stack(self.env_id):
            result = stack_scores(evaluate_stack(policy, self.env_id, self.config["env_kwargs"], self.seeds)[0])
        else:
            result = scores(evaluate(policy, self.env_id, self.config["env_kwargs"], self.seeds)[0])
        wall = self.clock.wall() - (time.perf_counter() - begin)
        for key in ("success_rate", "mean_distance", "face_accuracy", "mean_reward"):
            self.logger.record(f"eval/{key}", result[key])
        row = {"timesteps": self.num_timesteps, "wall_seconds": wall, **{key: result[key] for key in EVAL_COLUMNS[2:]}}
        if result["success_rate"] > self.best:  # the best model first: its row then exists only with it
            self.best = result["success_rate"]
            save_model(self.model, vec_normalize, self.run_dir, "best_")
        append_line(self.path, csv_line([row["timesteps"], f"{wall:.2f}"] + [row[key] for key in EVAL_COLUMNS[2:]]))
        self.clock.eval_seconds += time.perf_counter() - begin
        self.clock.write(self.num_timesteps)
        if self.on_validation is not None:
            self.on_validation(row)


def restore_best(run_dir: Path, algo: str, steps: int) -> str:
    """On a resume from the checkpoint at ``steps``: ``best_model.zip`` and ``best_vecnormalize.pkl``
    put back as they were at that checkpoint (its ``best_snapshot``), so the best model is one of the
    validation rows kept, never one of the rows the resume dropped. A checkpoint written before these
    snapshots existed has none: a best model trained beyond ``steps`` is then removed (the next
    validation saves one). Returns what was done, for the resume's message ("" if nothing)."""
    snapshots = {name: best_snapshot(run_dir, algo, steps, name) for name in BEST_FILES}
    if snapshots["best_model.zip"].exists():
        changed = False
        for name, snapshot in snapshots.items():
            current = run_dir / name
            if snapshot.exists() and not (current.exists() and os.path.samefile(snapshot, current)):
                copy_atomic(snapshot, current)
                changed = True
            elif not snapshot.exists() and current.exists():
                current.unlink()
                changed = True
        return f"; best_model.zip put back as it was at {steps} steps" if changed else ""
    trained = model_timesteps(run_dir / "best_model.zip") if (run_dir / "best_model.zip").exists() else None
    if trained is not None and trained <= steps:
        return ""
    removed = [name for name in BEST_FILES if (run_dir / name).exists()]
    for name in removed:
        (run_dir / name).unlink()
    return f"; removed {' and '.join(removed)} (saved after {steps} steps)" if removed else ""


def quiet_logger() -> Logger:
    """An SB3 logger that writes nothing and makes no folder, for a training run that logs nowhere. SB3's own for a
    model with ``verbose=0`` and no tensorboard folder still makes an empty folder ``SB3-<date and time>`` in the
    temp directory at every ``learn``."""
    return Logger(folder=None, output_formats=[])


def read_timing(run_dir: Path) -> dict[str, Any] | None:
    """A run's timing.json (None before its training first started; a DamagedFileError naming it if damaged)."""
    path = Path(run_dir) / "timing.json"
    if not path.exists():
        return None
    timing = read_json_mapping(path, ("wall_seconds",))
    for key in ("wall_seconds", "env_seconds", "eval_seconds"):
        if not isinstance(timing.get(key, 0.0), (int, float)):
            raise DamagedFileError(f"{path} is damaged: {key} is {timing[key]!r}, not a number of seconds")
    return timing


def new_run_dir(runs: Path, name: str | None, env_id: str, algo: str) -> Path:
    """A fresh folder ``runs/name``, made atomically and locked (``lock_run``) for this process; without
    a name ``<algo>-<env id>-<time>``, with ``-2``, ``-3``, ... if another run took it in the same second.
    A named folder left by a run that died before its first checkpoint holds nothing to keep, and is
    cleared; one that holds a checkpoint, or that a live training holds, is an error."""
    if name is None:
        run_dir = claim_folder(runs, f"{algo}-{env_id}-{timestamp()}")
        lock_run(run_dir)
        return run_dir
    check_component(name, "--name")
    run_dir = claim_folder(runs, name)
    if run_dir.name == name:
        lock_run(run_dir)
        return run_dir
    run_dir.rmdir()
    run_dir = runs / name
    taken = RunFolderError(f"{run_dir} already holds a run: choose another --name, or --resume {run_dir}")
    if not (run_dir / "config.yml").exists():
        raise taken  # not a run folder, or one being made this instant
    lock_run(run_dir)  # an error if its training is going on
    if latest_checkpoint(run_dir, algo) is not None or (run_dir / "model.zip").exists():
        unlock_run(run_dir)
        raise taken
    for path in run_dir.iterdir():  # a run that died before its first checkpoint: nothing to keep
        if path.name != LOCK:
            shutil.rmtree(path) if path.is_dir() else path.unlink()
    return run_dir


def package_version() -> str:
    import box_toss_env

    return box_toss_env.__version__


def write_run_files(run_dir: Path, algo: str, env_id: str, seed: int, config: dict[str, Any], command: str) -> None:
    """``config.yml`` (what the run trains, and the package version) and a line of ``command.txt``."""
    write_atomic(
        run_dir / "config.yml",
        yaml.safe_dump(
            {
                "algo": algo,
                "env_id": env_id,
                "seed": seed,
                "version": package_version(),
                "env_kwargs": config["env_kwargs"],
                "hyperparams": config,
            },
            sort_keys=False,
        ),
    )
    append_line(run_dir / "command.txt", command)


def observation_shape(env_id: str, config: dict[str, Any]) -> tuple[int, ...]:
    """The shape of ``env_id``'s observations under ``config``'s env kwargs."""
    import gymnasium as gym

    env = gym.make(env_id, **(config.get("env_kwargs") or {}))
    try:
        return tuple(env.observation_space.shape or ())
    finally:
        env.close()


def warm_up_engine(env_id: str, config: dict[str, Any]) -> None:
    """Load the env's compiled kernel with one throw in a throwaway env, so that compiling (or
    loading from numba's cache) is not counted as env time."""
    venv = make_vector_env(env_id, 1, config["env_kwargs"], config.get("vec_env_kwargs"))
    venv.reset()
    venv.step(np.zeros((1, *(venv.action_space.shape or ())), dtype=np.float32))
    venv.close()


def resume_model(run_dir: Path, algo: str, checkpoint: Checkpoint, venv, off_policy: bool):
    """The model of ``checkpoint`` on ``venv``, with its replay buffer; the files a kill left half-written are
    removed and the log rows written after the checkpoint dropped (and said)."""
    model = load_model(algo, checkpoint.model, env=venv)
    if model.num_timesteps != checkpoint.steps:
        raise UnreadableModelError(
            f"{checkpoint.model} holds a model of {model.num_timesteps} steps, not {checkpoint.steps}"
        )
    empty_buffer = ""
    if off_policy and checkpoint.replay_buffer.exists():
        model.load_replay_buffer(checkpoint.replay_buffer)  # type: ignore[attr-defined]  # an off-policy algorithm's
    elif off_policy:
        empty_buffer = f"; no replay buffer kept with it (the newest {REPLAY_BUFFERS_KEPT} are): it starts empty"
    for folder in (run_dir, run_dir / "checkpoints", run_dir / "logs"):  # temporary files cut by a kill
        remove_stale_temporaries(folder)
    _, progress_dropped = truncate_csv(run_dir / "logs" / "progress.csv", "time/total_timesteps", checkpoint.steps)
    _, evaluations_dropped = truncate_csv(run_dir / "evaluations.csv", "timesteps", checkpoint.steps)
    dropped = (
        f"; dropped the rows written after it: {progress_dropped} of logs/progress.csv, "
        f"{evaluations_dropped} of evaluations.csv"
        if progress_dropped or evaluations_dropped
        else ""
    )
    dropped += restore_best(run_dir, algo, checkpoint.steps) + empty_buffer
    print(f"resuming {run_dir} from {checkpoint.model} at {model.num_timesteps} steps{dropped}")
    return model


def new_model(venv, config: dict[str, Any], env_id: str, seed: int, algo: str, run_dir: Path | None = None):
    """The untrained model a run starts from: ``algo`` with the recipe's arguments on ``venv``, seeded, its starting
    mean moved as the recipe's ``initial_mean`` says (``agents.initial_mean``; its fit reported in ``run_dir``)."""
    model = algorithms.algorithm_class(algo)(
        env=venv,
        seed=seed,
        device="cpu",
        verbose=0,
        **configuration.algorithm_kwargs(config, algo, cast(tuple[int, ...], venv.action_space.shape)[0]),
    )
    initial_mean.apply(model, config, env_id, seed, run_dir)
    return model


def train(
    run_dir: Path,
    config: dict[str, Any],
    env_id: str,
    seed: int,
    algo: str = "ppo",
    *,
    resume: bool | Checkpoint = False,
    progress_bar: bool = True,
    final_eval: bool = True,
    on_validation: Callable[[dict[str, Any]], None] | None = None,
) -> dict[str, Any]:
    """Train (or continue) the run in ``run_dir`` up to ``config["n_timesteps"]``; returns the timing.
    ``resume``: True continues from the newest checkpoint (``resume_point``: checked), a ``Checkpoint`` from that
    one (checked by the caller). ``on_validation`` receives each periodic validation's row of evaluations.csv."""
    checkpoint = (
        resume if isinstance(resume, Checkpoint) else (resume_point(run_dir, algo, config)[0] if resume else None)
    )
    warm_up_engine(env_id, config)
    torch.set_num_threads(int(config.get("torch_threads", 1)))
    # a resumed run draws new episodes (seeded after the steps already taken), not the first ones again
    env_seed = seed + (checkpoint.steps if checkpoint else 0)
    venv = make_training_env(
        env_id,
        config["n_envs"],
        seed=env_seed,
        env_kwargs=curriculum.env_kwargs_at(config, checkpoint.steps if checkpoint else 0),  # a stage's or the recipe's
        vec_env_kwargs=config.get("vec_env_kwargs"),
        normalize=config.get("normalize", True),
        statistics=read_normalizer(checkpoint.statistics, observation_shape(env_id, config))
        if checkpoint and checkpoint.statistics.exists()
        else None,
        env_wrapper=config.get("env_wrapper"),
    )
    off_policy = algorithms.is_off_policy(algo)
    (run_dir / "logs").mkdir(exist_ok=True)
    if checkpoint:
        model = resume_model(run_dir, algo, checkpoint, venv, off_policy)
    else:
        model = new_model(venv, config, env_id, seed, algo, run_dir)
    model.set_logger(
        Logger(
            str(run_dir / "logs"),
            [AppendingCSVOutput(run_dir / "logs" / "progress.csv"), TensorBoardOutputFormat(str(run_dir / "logs"))],
        )
    )
    # time of earlier sessions, killed ones included (timing.json is written as training goes)
    clock = RunClock(run_dir, algo, read_timing(run_dir) if checkpoint else None)
    clock.timed = find_wrapper(venv, TimedVecEnv)
    validation = ValidationCallback(run_dir, config, env_id, clock, on_validation)
    callbacks = [validation, ClockCallback(clock)]
    if config.get("curriculum"):
        callbacks.append(curriculum.CurriculumCallback(env_id, config, seed))
    if config.get("checkpoint_freq"):
        callbacks.insert(0, AtomicCheckpointCallback(int(config["checkpoint_freq"]), run_dir, algo, clock, off_policy))
    remaining = max(int(config["n_timesteps"]) - model.num_timesteps, 0)
    model.learn(remaining, callback=callbacks, progress_bar=progress_bar, reset_num_timesteps=not checkpoint)
    save_checkpoint(model, run_dir, algo, replay_buffer=off_policy)  # where a later --resume starts
    save_model(model, normalizer_of(venv), run_dir)
    timing = clock.write(model.num_timesteps)
    assert timing is not None  # written when not throttled (every=0)
    venv.close()
    if final_eval:
        evaluate_run(run_dir, quiet=True)
    return timing
