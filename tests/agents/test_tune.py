"""A 2-trial sweep on a local Ray, killed during its first trial and resumed, writes its table; every trial
is a run folder trained on the CPU Ray gave it, and the best entry loads as a hyperparameter file."""

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("ray.tune")
pytest.importorskip("optuna")

from agents import config as configuration  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
SWEEP = [
    "--env",
    "BoxToss-v0",
    "--trials",
    "2",
    "--timesteps",
    "4096",
    "--max-concurrent",
    "1",
    "--num-cpus",
    "2",
    "--set",
    "n_envs=16",
    "eval_freq=1024",
    "eval_targets=16",
    "checkpoint_freq=1024",
]


def agents_tune(*args, **kwargs):
    return subprocess.Popen(
        [sys.executable, "-m", "agents.tune", *args],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        **kwargs,
    )


def rows(path: Path) -> list[dict[str, str]]:
    with open(path) as file:
        return list(csv.DictReader(file))


def checkpoint_recorded(experiment: Path) -> bool:
    """Whether a trial's checkpoint folder exists and Tune's experiment state names it: Tune writes the
    folder first and its state up to a second later, and a sweep killed in between resumes without it
    (its first trial starts again from nothing)."""
    names = [path.name for path in experiment.glob("trial_*/checkpoint_*")]
    states = ""
    for path in experiment.glob("experiment_state-*.json"):
        try:
            states += path.read_text()
        except FileNotFoundError:  # replaced while we looked: the next poll reads the new one
            pass
    return any(name in states for name in names)


def test_a_killed_two_trial_sweep_resumes_from_its_checkpoints_and_writes_its_table(tmp_path):
    experiment = tmp_path / "sweep" / "BoxToss-v0"
    sweep = agents_tune(*SWEEP, "--runs-dir", str(tmp_path), "--name", "sweep", start_new_session=True)
    deadline = time.monotonic() + 240
    while not checkpoint_recorded(experiment):  # the first trial's training checkpoint, in Tune's state
        assert sweep.poll() is None, sweep.stdout.read()[-3000:]
        assert time.monotonic() < deadline, "no checkpoint within 240 s"
        time.sleep(0.1)
    os.killpg(sweep.pid, signal.SIGKILL)  # the command and the local Ray it started
    sweep.wait()
    assert not (experiment / "trials.md").exists()
    killed = next(experiment.glob("trial_*"))
    steps_at_kill = int(rows(killed / "evaluations.csv")[-1]["timesteps"])
    assert steps_at_kill < 4096

    resumed = agents_tune("--resume", str(tmp_path / "sweep"), "--num-cpus", "2")
    output, _ = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, output[-3000:]

    table = (experiment / "trials.md").read_text().splitlines()
    assert len(table) == 2 + 2, table  # header and the 2 trials
    assert f"| {killed.name.removeprefix('trial_')} | finished |" in table[2], table  # alone at every rung: kept
    assert "| finished |" in table[3] or "| pruned at " in table[3], table  # ASHA may stop the second
    trials = sorted(experiment.glob("trial_*"))
    assert len(trials) == 2 and killed in trials
    validations = rows(killed / "evaluations.csv")
    steps = [int(row["timesteps"]) for row in validations]
    assert steps.count(0) == 1, steps  # continued from its checkpoint, not started again
    assert steps[-1] >= 4096 and len((killed / "command.txt").read_text().splitlines()) == 2
    for trial in trials:  # run folders, on the one CPU Ray gave each trial
        saved = configuration.load_yaml(trial / "config.yml")
        assert saved["hyperparams"]["torch_threads"] == 1 and saved["hyperparams"]["vec_env_kwargs"]["threads"] == 1
        assert (trial / "evaluations.csv").exists() and (trial / "result.json").exists()  # ours and Ray's record
    assert json.loads((killed / "timing.json").read_text())["torch_threads"] == 1
    assert (killed / "model.zip").exists() and (killed / "eval" / "default" / "results.json").exists()
    settings = configuration.load_yaml(tmp_path / "sweep" / "sweep.yml")
    first = json.loads((killed / "params.json").read_text())
    assert first == settings["envs"]["BoxToss-v0"]["start_point"]  # the first trial is the file's values
    assert json.loads((tmp_path / "sweep" / "wall_seconds.json").read_text())["BoxToss-v0"] > 0

    hyperparams = tmp_path / "hyperparams"  # best.yml is an entry ready for agents/hyperparams/ppo.yml
    hyperparams.mkdir()
    shutil.copy(experiment / "best.yml", hyperparams / "ppo.yml")
    shutil.copy(REPO / "agents" / "hyperparams" / "project.yml", hyperparams / "project.yml")
    best = configuration.load_hyperparams("ppo", "BoxToss-v0", hyperparams)
    configuration.check_config(best, "ppo")
    assert best["n_timesteps"] == 4096 and best["n_envs"] == 16


@pytest.mark.parametrize(
    "args, message",
    [
        (["--env", "BoxToss-Nope-v0"], "has no entry for 'BoxToss-Nope-v0'"),
        (["--trials", "0"], "trials must be >= 1"),
        (["--cpus-per-trial", "0"], "cpus_per_trial must be >= 1"),
        (["--timesteps", "5000"], "eval_freq must be in \\[1, n_timesteps\\)"),
        (["--set", "policy_kwargs.activation_fn=nn.Nope"], "activation_fn must be the name of a torch.nn"),
        (["--space", "missing.yml"], "no hyperparameter file missing.yml"),
    ],
)
def test_a_sweep_that_cannot_run_is_one_line_before_ray_starts(tmp_path, args, message):
    from agents import tune

    with pytest.raises(SystemExit, match=message):
        tune.main([*args, "--runs-dir", str(tmp_path)])
    assert not list(tmp_path.iterdir())  # nothing created
