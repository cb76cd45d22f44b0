"""Train for a few hundred steps in a subprocess, resume, evaluate the run and report on it."""

import json
import subprocess
import sys
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[2]
TINY = ["n_timesteps=256", "n_envs=4", "n_steps=64", "batch_size=64", "n_epochs=2", "eval_freq=128",
        "eval_targets=16", "checkpoint_freq=128", "policy_kwargs.net_arch=[16,16]"]


def run(*args: str) -> str:
    done = subprocess.run([sys.executable, "-m", *args], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def test_train_resume_and_evaluate_a_tiny_run(tmp_path):
    run("agents.train", "--runs-dir", str(tmp_path), "--name", "tiny", "--seed", "3", "--no-progress", "--no-eval",
        "--set", *TINY)
    run_dir = tmp_path / "tiny"
    for name in ("config.yml", "command.txt", "model.zip", "vecnormalize.pkl", "best_model.zip", "evaluations.csv",
                 "timing.json"):
        assert (run_dir / name).exists(), name
    assert list((run_dir / "checkpoints").glob("ppo_*_steps.zip"))
    assert list((run_dir / "logs").glob("events.out.tfevents.*"))
    saved = yaml.safe_load((run_dir / "config.yml").read_text())
    assert saved["seed"] == 3 and saved["hyperparams"]["n_envs"] == 4
    assert "agents.train" in (run_dir / "command.txt").read_text()

    run("agents.train", "--resume", str(run_dir), "--no-progress", "--no-eval", "--set", "n_timesteps=512")
    timing = json.loads((run_dir / "timing.json").read_text())
    assert timing["timesteps"] >= 512 and 0 < timing["env_share"] < 1
    assert len((run_dir / "command.txt").read_text().splitlines()) == 2

    out = run("agents.evaluate", str(run_dir), "--targets", "32")
    results = json.loads((run_dir / "eval" / "default" / "results.json").read_text())
    assert results["n"] == 32 and results["seeds"] == [10_000, 10_031]
    assert 0.0 <= results["success_rate"] <= 1.0 and results["mean_distance"] > 0
    assert sum(row["n"] for row in results["by_distance"]) == 32
    assert (run_dir / "eval" / "default" / "landing_errors.png").exists()
    assert (run_dir / "eval" / "default" / "learning_curve.png").exists()
    assert "success" in out



def test_main_trains_evaluates_and_prints_the_table(tmp_path):
    out = run("agents.main", "--runs-dir", str(tmp_path), "--timesteps", "256", "--no-oracle", "--no-progress")
    assert "random actions" in out and "PPO, short (agents.main)" in out and "total wall time" in out
    assert (tmp_path / "short" / "eval" / "default" / "results.json").exists()
    assert (tmp_path / "random" / "eval" / "default" / "results.json").exists()
