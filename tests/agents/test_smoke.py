"""Train each algorithm for a few hundred throws in a subprocess, resume, evaluate and report."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from agents.evaluation import load_policy

REPO = Path(__file__).resolve().parents[2]
COMMON = [
    "n_timesteps=256",
    "n_envs=4",
    "eval_freq=128",
    "eval_targets=16",
    "checkpoint_freq=128",
    "policy_kwargs.net_arch=[16,16]",
]
TINY = {
    "ppo": ["n_steps=64", "batch_size=64", "n_epochs=2"],
    "sac": ["learning_starts=64", "batch_size=32", "buffer_size=1000"],
    "td3": ["learning_starts=64", "batch_size=32", "buffer_size=1000"],
}


def run(*args: str, ok: bool = True) -> subprocess.CompletedProcess:
    done = subprocess.run([sys.executable, "-m", *args], cwd=REPO, capture_output=True, text=True, timeout=300)
    if ok:
        assert done.returncode == 0, done.stdout + done.stderr
    return done


@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_train_resume_and_evaluate_a_tiny_run(tmp_path, algo):
    run(
        "agents.train",
        "--algo",
        algo,
        "--env",
        "BoxToss-ShortEnd-v0",
        "--runs-dir",
        str(tmp_path),
        "--name",
        "tiny",
        "--seed",
        "3",
        "--no-progress",
        "--no-eval",
        "--set",
        *COMMON,
        *TINY[algo],
    )
    run_dir = tmp_path / "tiny"
    for name in (
        "config.yml",
        "command.txt",
        "model.zip",
        "vecnormalize.pkl",
        "best_model.zip",
        "evaluations.csv",
        "timing.json",
    ):
        assert (run_dir / name).exists(), name
    assert list((run_dir / "checkpoints").glob(f"{algo}_*_steps.zip"))
    assert list((run_dir / "logs").glob("events.out.tfevents.*"))
    saved = yaml.safe_load((run_dir / "config.yml").read_text())
    assert saved["algo"] == algo and saved["seed"] == 3 and saved["hyperparams"]["n_envs"] == 4
    # trained in ballistic commands (the ShortEnd entry's env_wrapper): evaluated through the same mapping
    assert saved["hyperparams"]["env_wrapper"] == "box_toss_env.envs.ballistic.BallisticThrows"
    assert load_policy(run_dir)[0].commands_to_actions is not None
    first = json.loads((run_dir / "timing.json").read_text())

    run("agents.train", "--resume", str(run_dir), "--no-progress", "--no-eval", "--set", "n_timesteps=512")
    timing = json.loads((run_dir / "timing.json").read_text())
    assert timing["timesteps"] >= 512 and 0 < timing["env_share"] < 1
    assert timing["wall_seconds"] > first["wall_seconds"]  # both sessions counted
    assert len((run_dir / "command.txt").read_text().splitlines()) == 2

    out = run("agents.evaluate", str(run_dir), "--targets", "32").stdout
    # 32 targets are not the 1,024 test targets: their own folder, never eval/default
    results = json.loads((run_dir / "eval" / "targets=32" / "results.json").read_text())
    assert results["n"] == 32 and results["seeds"] == [10_000, 10_031] and results["algo"] == algo
    assert 0.0 <= results["success_rate"] <= 1.0 and results["mean_distance"] > 0
    assert sum(row["n"] for row in results["by_distance"]) == 32
    assert (run_dir / "eval" / "targets=32" / "landing_errors.png").exists()
    assert "success" in out


@pytest.mark.parametrize(
    "args, message",
    [
        (["--set", "n_timestep=5"], "unknown hyperparameter 'n_timestep'"),
        (["--set", "env_kwargs.mass=-1"], "env_kwargs: mass"),
        (["--env", "BoxToss-v9"], "--env 'BoxToss-v9' is not registered"),
        (["--resume", "nowhere"], "not a run folder"),
    ],
)
def test_a_bad_configuration_is_one_line_and_creates_nothing(tmp_path, args, message):
    done = run("agents.train", "--runs-dir", str(tmp_path), "--name", "bad", "--no-progress", *args, ok=False)
    assert done.returncode != 0 and message in done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "bad").exists()


def test_main_trains_evaluates_and_prints_the_table(tmp_path):
    out = run("agents.main", "--runs-dir", str(tmp_path), "--timesteps", "256", "--no-oracle", "--no-progress").stdout
    assert "random actions" in out and "PPO, short (agents.main)" in out and "total wall time" in out
    assert "BoxToss-ThisSideUp-v0" in out  # the default task scores the face
    assert (tmp_path / "short" / "eval" / "default" / "results.json").exists()
    assert (tmp_path / "random" / "eval" / "default" / "results.json").exists()


def test_a_truncated_model_is_one_line(tmp_path):
    run(
        "agents.train",
        "--runs-dir",
        str(tmp_path),
        "--name",
        "tiny",
        "--no-progress",
        "--no-eval",
        "--set",
        *COMMON,
        *TINY["ppo"],
    )
    model = tmp_path / "tiny" / "model.zip"
    model.write_bytes(model.read_bytes()[:200])
    done = run("agents.evaluate", str(tmp_path / "tiny"), "--targets", "8", ok=False)
    assert done.returncode != 0 and "model.zip is damaged: not a whole zip archive" in done.stderr
    assert "Traceback" not in done.stderr


def test_main_keeps_an_evaluated_random_baseline_unless_it_rewrites_the_docs(tmp_path):
    from agents.main import baseline

    results = baseline("random", tmp_path) / "eval" / "default" / "results.json"
    first = results.read_bytes()
    baseline("random", tmp_path, reevaluate=False)  # what `box-toss main` does on a second call
    assert results.read_bytes() == first
    baseline("random", tmp_path)  # what --readme does: evaluated afresh (its timing differs)
    assert results.read_bytes() != first
