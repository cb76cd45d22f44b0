"""RL Baselines3 Zoo trains and evaluates from our hyperparameter files, unchanged."""

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rl_zoo3")
REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_zoo_trains_from_our_file_and_enjoy_evaluates(tmp_path, algo):
    params = ["n_envs:2"] + ([] if algo == "ppo" else ["learning_starts:64", "buffer_size:1000"])
    train = [
        sys.executable,
        "-m",
        "rl_zoo3.train",
        "--algo",
        algo,
        "--env",
        "BoxToss-Mixed-v0",
        "--gym-packages",
        "box_toss_env",
        "--conf-file",
        str(REPO / "agents" / "hyperparams" / f"{algo}.yml"),
        "-n",
        "300",
        "-f",
        str(tmp_path),
        "--eval-freq",
        "-1",
        "--seed",
        "1",
        "-params",
        *params,
    ]
    done = subprocess.run(train, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert (tmp_path / algo / "BoxToss-Mixed-v0_1" / "BoxToss-Mixed-v0.zip").exists()
    enjoy = [
        sys.executable,
        "-m",
        "rl_zoo3.enjoy",
        "--algo",
        algo,
        "--env",
        "BoxToss-Mixed-v0",
        "--gym-packages",
        "box_toss_env",
        "-f",
        str(tmp_path),
        "--exp-id",
        "1",
        "-n",
        "10",
        "--no-render",
    ]
    done = subprocess.run(enjoy, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert "Mean reward" in done.stdout


def test_zoo_trains_the_stack_recipe(tmp_path):
    """BoxToss-Stack-v0's PPO entry (throw commands through its env_wrapper) trains in Zoo, unchanged."""
    train = [
        sys.executable,
        "-m",
        "rl_zoo3.train",
        "--algo",
        "ppo",
        "--env",
        "BoxToss-Stack-v0",
        "--gym-packages",
        "box_toss_env",
        "--conf-file",
        str(REPO / "agents" / "hyperparams" / "ppo.yml"),
        "-n",
        "128",
        "-f",
        str(tmp_path),
        "--eval-freq",
        "-1",
        "--seed",
        "1",
        "-params",
        "n_envs:2",
        "n_steps:32",
    ]
    done = subprocess.run(train, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert (tmp_path / "ppo" / "BoxToss-Stack-v0_1" / "BoxToss-Stack-v0.zip").exists()
