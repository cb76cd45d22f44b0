"""Hyperparameter search on Ray Tune: Optuna's TPE sampler proposes, a scheduler prunes, every trial is a run.

    Sweep (what to search)  ->  make_tuner / restore_tuner (Ray Tune)  ->  run_trial (one trial, a Ray actor)

``run_trial`` is the trainable: a plain function of the sampled values. It trains with
``agents.training.train`` exactly as ``python -m agents.train --set <the sampled values>`` would,
in the trial's working directory, which becomes a run folder like any other (``config.yml``,
``evaluations.csv``, ``model.zip``, ``eval/default/`` ...) and is copied to the experiment folder
with Ray's own files (``result.json``, ``progress.csv``, ``params.json``). Each periodic validation
is reported to Tune (``on_validation``), so the scheduler (ASHA by default) prunes on the
validation success; the trial's newest training checkpoint goes with the report, so a killed sweep
resumes (``Tuner.restore``) with every unfinished trial continuing from its checkpoint.

The objective is the validation success, then the distance (``agents.evaluation.search_objective``).

A trial uses the CPUs Ray gives it: torch threads, the engine's threads (the vector env's
``threads``) and numba's thread count are all set to that number.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numba
import optuna
import ray
from ray import tune
from ray.tune.schedulers import ASHAScheduler, FIFOScheduler, MedianStoppingRule, TrialScheduler
from ray.tune.search import ConcurrencyLimiter
from ray.tune.search.optuna import OptunaSearch

from agents import search_space
from agents.config import ConfigError
from agents.evaluation import search_objective
from agents.search_space import Dimension
from agents.training import latest_checkpoint, train, write_run_files
from box_toss_env.files import write_atomic

OBJECTIVE = "objective"
PRUNERS = ("asha", "median", "none")


@dataclass(frozen=True)
class Sweep:
    """What one Tune experiment searches: the algorithm on one env id, the configuration every trial
    starts from (hyperparameter files and overrides), the space, and what each trial gets."""

    algo: str
    env_id: str
    base: dict[str, Any]  # the configuration before the sampled values (n_timesteps: each trial's budget)
    space: dict[str, Dimension]
    trials: int
    seed: int = 0  # every trial trains with this seed; Optuna's sampler is seeded with it too
    cpus_per_trial: int = 1
    pruner: str = "asha"
    grace_period: int | None = None  # env steps before the first pruning decision (default: a quarter)
    command: str = ""
    start_point: dict[str, Any] | None = field(default=None)  # first trial: the file's values

    @property
    def n_timesteps(self) -> int:
        return int(self.base["n_timesteps"])

    @property
    def validation_targets(self) -> int:
        return int(self.base["eval_targets"])


def check_sweep(sweep: Sweep) -> None:
    """A ConfigError naming the first setting of the sweep that cannot run."""
    if sweep.trials < 1:
        raise ConfigError(f"trials must be >= 1, got {sweep.trials}")
    if sweep.cpus_per_trial < 1:
        raise ConfigError(f"cpus_per_trial must be >= 1, got {sweep.cpus_per_trial}")
    if sweep.pruner not in PRUNERS:
        raise ConfigError(f"pruner must be one of {PRUNERS}, got {sweep.pruner!r}")
    if not sweep.base.get("eval_freq") or sweep.base["eval_freq"] >= sweep.n_timesteps:
        raise ConfigError(
            f"eval_freq must be in [1, n_timesteps) so that trials report their validation success, "
            f"got eval_freq={sweep.base.get('eval_freq')!r}, n_timesteps={sweep.n_timesteps}"
        )
    if sweep.grace_period is not None and not 0 < sweep.grace_period < sweep.n_timesteps:
        raise ConfigError(
            f"grace_period must be in (0, n_timesteps={sweep.n_timesteps}) env steps, got {sweep.grace_period}"
        )


# -- one trial (runs in a Ray actor) ----------------------------------------------------------------
def trial_cpus() -> int:
    """The CPUs Ray gave this trial (1 outside Ray)."""
    assigned = ray.get_runtime_context().get_assigned_resources() if ray.is_initialized() else {}
    return max(int(assigned.get("CPU", 1)), 1)


def pin_threads(config: dict[str, Any], cpus: int) -> dict[str, Any]:
    """``config`` with torch's and the engine's threads set to ``cpus`` (numba's count too, for the
    kernels that do not take ``threads``); ``train`` sets torch's after the engine's first step."""
    cpus = min(cpus, numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]  # set when numba loads
    numba.set_num_threads(cpus)
    return {
        **config,
        "torch_threads": cpus,
        "vec_env_kwargs": {**(config.get("vec_env_kwargs") or {}), "threads": cpus},
    }


def trial_run_dir() -> Path:
    """The trial's working directory: Ray moves each trial there, and copies what is written in it to
    the experiment folder (``SyncConfig(sync_artifacts=True)``)."""
    if os.environ.get("RAY_CHDIR_TO_TRIAL_DIR", "1") == "0":
        raise ConfigError("RAY_CHDIR_TO_TRIAL_DIR=0: trials must run in their own working directory (unset it)")
    return Path.cwd()


def snapshot(run_dir: Path, algo: str, destination: Path) -> None:
    """Copy the run folder into ``destination``, with only its newest training checkpoint."""
    newest = latest_checkpoint(run_dir, algo)
    keep = {path.name for path in (newest[0], newest[1]) if path is not None} if newest else set()
    if newest:
        keep |= {
            f"{algo}_replay_buffer_{newest[2]}_steps.pkl",
            f"{algo}_best_model_{newest[2]}_steps.zip",
            f"{algo}_best_vecnormalize_{newest[2]}_steps.pkl",
        }

    def ignore(directory: str, names: list[str]) -> list[str]:
        return [name for name in names if Path(directory).name == "checkpoints" and name not in keep]

    shutil.copytree(run_dir, destination, ignore=ignore, dirs_exist_ok=True)


class TrialReporter:
    """``on_validation`` of a trial: each validation row goes to Tune with the objective; a training
    checkpoint newer than the last one reported goes with it (copied out of the run folder)."""

    def __init__(self, run_dir: Path, algo: str, targets: int, reported_steps: int = -1):
        self.run_dir, self.algo, self.targets = run_dir, algo, targets
        self.reported_steps = reported_steps
        self.last: dict[str, Any] = {}

    def __call__(self, row: dict[str, Any]) -> None:
        self.last = {**row, OBJECTIVE: search_objective(row["success_rate"], row["mean_distance"], self.targets)}
        newest = latest_checkpoint(self.run_dir, self.algo)
        if newest is None or newest[2] <= self.reported_steps:
            tune.report(self.last)
            return
        self.reported_steps = newest[2]
        self.report_with_checkpoint(self.last)

    def report_with_checkpoint(self, metrics: dict[str, Any]) -> None:
        with tempfile.TemporaryDirectory() as directory:
            snapshot(self.run_dir, self.algo, Path(directory))
            tune.report(metrics, checkpoint=tune.Checkpoint.from_directory(directory))


def run_trial(params: dict[str, Any], sweep: Sweep) -> None:
    """The trainable: train the base configuration with the sampled ``params`` in this trial's run
    folder (continuing from Tune's checkpoint when the trial is resumed), reporting each validation."""
    run_dir = trial_run_dir()
    config = pin_threads(search_space.trial_config(sweep.base, sweep.space, params, sweep.algo), trial_cpus())
    checkpoint = tune.get_checkpoint()
    if checkpoint is not None and latest_checkpoint(run_dir, sweep.algo) is None:
        with checkpoint.as_directory() as directory:
            shutil.copytree(directory, run_dir, dirs_exist_ok=True)
    newest = latest_checkpoint(run_dir, sweep.algo)
    resume = newest is not None
    overrides = " ".join(search_space.overrides(sweep.space, params))
    write_run_files(
        run_dir,
        sweep.algo,
        sweep.env_id,
        sweep.seed,
        config,
        f"{sweep.command}  # trial of {sweep.env_id}: --set {overrides}",
    )
    reporter = TrialReporter(run_dir, sweep.algo, sweep.validation_targets, newest[2] if newest else -1)
    train(
        run_dir,
        config,
        sweep.env_id,
        sweep.seed,
        sweep.algo,
        resume=resume,
        progress_bar=False,
        final_eval=True,
        on_validation=reporter,
    )
    results = json.loads((run_dir / "eval" / "default" / "results.json").read_text())
    reporter.report_with_checkpoint(
        {**reporter.last, "test_success_rate": results["success_rate"], "test_mean_distance": results["mean_distance"]}
    )


# -- the experiment -----------------------------------------------------------------------------------
def make_scheduler(sweep: Sweep) -> TrialScheduler:
    """ASHA on the env steps (successive halving at grace, 3 grace, 9 grace ... steps), the median
    rule, or none. ASHA's max_t is above the budget: a trial ends itself at n_timesteps, and must
    not be stopped at its last validation, before its test evaluation."""
    grace = sweep.grace_period or max(sweep.n_timesteps // 4, 1)
    if sweep.pruner == "asha":
        return ASHAScheduler(
            time_attr="timesteps",
            metric=OBJECTIVE,
            mode="max",
            max_t=2 * sweep.n_timesteps,
            grace_period=grace,
            reduction_factor=3,
        )
    if sweep.pruner == "median":
        return MedianStoppingRule(
            time_attr="timesteps", metric=OBJECTIVE, mode="max", grace_period=grace, min_samples_required=3
        )
    return FIFOScheduler()


def make_searcher(sweep: Sweep, max_concurrent: int | None) -> ConcurrencyLimiter | OptunaSearch:
    """Optuna's TPE sampler over the declared space, starting from the file's values; a third of the
    trials (at least 2) are drawn at random before TPE models the results."""
    sampler = optuna.samplers.TPESampler(seed=sweep.seed, n_startup_trials=max(2, sweep.trials // 3))
    searcher = OptunaSearch(
        search_space.optuna_space(sweep.space),
        metric=OBJECTIVE,
        mode="max",
        sampler=sampler,
        points_to_evaluate=[sweep.start_point] if sweep.start_point else None,
    )
    return ConcurrencyLimiter(searcher, max_concurrent) if max_concurrent else searcher


class WallClock(tune.Callback):
    """Adds this session's wall time to ``wall_seconds.json`` (one entry per experiment) after every
    result, so a sweep killed and resumed reports the time of all its sessions."""

    def __init__(self, path: Path, key: str):
        self.path, self.key = Path(path), key
        self.previous, self.start = 0.0, time.perf_counter()

    def setup(self, stop=None, num_samples=None, total_num_samples=None, **info) -> None:  # every session's start
        self.previous = self.read().get(self.key, 0.0)
        self.start = time.perf_counter()

    def read(self) -> dict[str, float]:
        return json.loads(self.path.read_text()) if self.path.exists() else {}

    def write(self) -> None:
        walls = self.read()
        walls[self.key] = self.previous + time.perf_counter() - self.start
        write_atomic(self.path, json.dumps(walls, indent=2))

    def on_trial_result(self, iteration, trials, trial, result, **info) -> None:
        self.write()

    def on_experiment_end(self, trials, **info) -> None:
        self.write()


def trial_folder_name(trial) -> str:
    return f"trial_{trial.trial_id}"


def trainable(sweep: Sweep):
    return tune.with_resources(tune.with_parameters(run_trial, sweep=sweep), {"cpu": sweep.cpus_per_trial})


def make_tuner(sweep: Sweep, storage: Path, name: str, max_concurrent: int | None = None) -> tune.Tuner:
    """The Tune experiment ``storage/name`` of ``sweep`` (``Tuner.fit()`` runs it); its wall time
    goes to ``storage/wall_seconds.json``."""
    check_sweep(sweep)
    storage = Path(storage).resolve()
    return tune.Tuner(
        trainable(sweep),
        tune_config=tune.TuneConfig(
            num_samples=sweep.trials,
            search_alg=make_searcher(sweep, max_concurrent),
            scheduler=make_scheduler(sweep),
            trial_dirname_creator=trial_folder_name,
        ),
        run_config=tune.RunConfig(
            name=name,
            storage_path=str(storage),
            verbose=1,
            callbacks=[WallClock(storage / "wall_seconds.json", name)],
            checkpoint_config=tune.CheckpointConfig(num_to_keep=1),
            sync_config=tune.SyncConfig(sync_artifacts=True),
            failure_config=tune.FailureConfig(max_failures=1),
        ),
    )


def restore_tuner(sweep: Sweep, path: Path) -> tune.Tuner:
    """The interrupted experiment at ``path``: unfinished (and errored) trials continue from their last
    checkpoint, the sampler and the scheduler from their saved state, then the remaining trials run."""
    return tune.Tuner.restore(str(Path(path).resolve()), trainable(sweep), resume_unfinished=True, resume_errored=True)


def start_ray(address: str | None = None, num_cpus: int | None = None) -> None:
    """Connect to the cluster at ``address`` (``ray start --head`` printed it; "auto" finds it), or
    start a local Ray with ``num_cpus`` CPUs (default: all)."""
    if ray.is_initialized():
        return
    if address:
        ray.init(address=address)
    else:  # "local": a new Ray of its own, even where another one runs (ray start) on this machine
        ray.init(address="local", num_cpus=num_cpus, include_dashboard=False)
