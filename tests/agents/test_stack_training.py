"""BoxToss-Stack-v0 in agents.train (a smoke test per algorithm), its batched throw commands, the raw tier and the
benchmark's checks of its options."""

import json
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml

import box_toss_env  # noqa: F401
from agents.evaluation import evaluate_stack, load_policy, stack_scores
from agents.policies import RandomPolicy
from box_toss_env.envs.stack_commands import StackCommands
from box_toss_env.wrappers.stack_commands import StackCommandsVector

REPO = Path(__file__).resolve().parents[2]
COMMON = [
    "n_timesteps=128",
    "n_envs=4",
    "eval_freq=64",
    "eval_targets=4",
    "checkpoint_freq=64",
    "policy_kwargs.net_arch=[16,16]",
]
TINY = {
    "ppo": ["n_steps=16", "batch_size=32", "n_epochs=2"],
    "sac": ["learning_starts=32", "batch_size=16", "buffer_size=500", "gradient_steps=1"],
    "td3": ["learning_starts=32", "batch_size=16", "buffer_size=500", "gradient_steps=1"],
}


def run(*args: str, ok: bool = True) -> subprocess.CompletedProcess:
    done = subprocess.run([sys.executable, "-m", *args], cwd=REPO, capture_output=True, text=True, timeout=300)
    if ok:
        assert done.returncode == 0, done.stdout + done.stderr
    return done


@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_train_and_evaluate_a_tiny_run_on_the_stack(tmp_path, algo):
    out = run(
        "agents.train",
        "--algo",
        algo,
        "--env",
        "BoxToss-Stack-v0",
        "--runs-dir",
        str(tmp_path),
        "--name",
        "tiny",
        "--no-progress",
        "--no-eval",
        "--set",
        *COMMON,
        *TINY[algo],
    ).stdout
    run_dir = tmp_path / "tiny"
    for name in ("model.zip", "best_model.zip", "evaluations.csv", "timing.json"):
        assert (run_dir / name).exists(), name
    # PPO's recipe normalises the observations; SAC's and TD3's read them raw (their untrained actors throw near c = 0)
    assert (run_dir / "vecnormalize.pkl").exists() == (algo == "ppo")
    saved = yaml.safe_load((run_dir / "config.yml").read_text())
    assert saved["hyperparams"]["env_wrapper"] == "box_toss_env.envs.stack_commands.StackCommands"
    assert load_policy(run_dir)[0].commands_to_actions is not None
    assert "training" in out
    run("agents.evaluate", str(run_dir), "--targets", "6")
    results = json.loads((run_dir / "eval" / "targets=6" / "results.json").read_text())
    assert results["n"] == 6 and results["seeds"] == [10_000, 10_005] and results["algo"] == algo
    assert 0.0 <= results["success_rate"] <= 1.0 and results["mean_height"] > 0.0
    assert 6 <= results["throws"] <= 6 * gym.make("BoxToss-Stack-v0").unwrapped.config.n_boxes


def test_the_raw_tier_trains_in_the_env_actions(tmp_path):
    run(
        "agents.train",
        "--env",
        "BoxToss-Stack-v0",
        "--runs-dir",
        str(tmp_path),
        "--name",
        "raw",
        "--no-progress",
        "--no-eval",
        "--set",
        *COMMON,
        *TINY["ppo"],
        "env_wrapper=null",
    )
    saved = yaml.safe_load((tmp_path / "raw" / "config.yml").read_text())
    assert saved["hyperparams"]["env_wrapper"] is None
    assert load_policy(tmp_path / "raw")[0].commands_to_actions is None


@pytest.mark.parametrize(
    "args, message",
    [
        (
            ["--env", "BoxToss-Stack-v0", "--set", "env_wrapper=box_toss_env.envs.ballistic.BallisticThrows"],
            "does not act on BoxToss-Stack-v0",
        ),
        (
            ["--env", "BoxToss-v0", "--set", "env_wrapper=box_toss_env.envs.stack_commands.StackCommands"],
            "for BoxToss-Stack envs only",
        ),
        (
            [
                "--env",
                "BoxToss-Stack-v0",
                "--set",
                "env_wrapper={box_toss_env.envs.stack_commands.StackCommands: {offset_range: -1}}",
            ],
            "offset_range",
        ),
    ],
)
def test_a_wrapper_that_does_not_fit_is_one_line_and_creates_nothing(tmp_path, args, message):
    done = run("agents.train", "--runs-dir", str(tmp_path), "--name", "bad", "--no-progress", *args, ok=False)
    assert done.returncode != 0 and message in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and not (tmp_path / "bad").exists()


def test_the_benchmark_checks_its_options_before_anything(tmp_path):
    done = run(
        "agents.benchmark",
        "--envs",
        "BoxToss-Stack-v0",
        "--root",
        str(tmp_path / "b"),
        "--set",
        "n_timestep=5",
        ok=False,
    )
    assert done.returncode == 2 and "unknown hyperparameter 'n_timestep'" in done.stderr
    assert not (tmp_path / "b").exists()


def test_batched_commands_are_the_single_wrappers_throws():
    n, seeds = 3, [5, 6, 7]
    commands = np.random.default_rng(0).uniform(-1, 1, (4, n, 3)).astype(np.float32)
    vector = StackCommandsVector(
        gym.make_vec("BoxToss-Stack-v0", num_envs=n, vectorization_mode="vector_entry_point", threads=1)
    )
    observations, _ = vector.reset(seed=seeds)
    singles = [StackCommands(gym.make("BoxToss-Stack-v0")) for _ in range(n)]
    single_obs = [env.reset(seed=seed)[0] for env, seed in zip(singles, seeds, strict=True)]
    np.testing.assert_array_equal(observations, np.stack(single_obs))
    for step in range(2):  # episodes of 4 throws: no autoreset within two steps
        observations, rewards, *_ = vector.step(commands[step])
        for i, env in enumerate(singles):
            obs, reward, *_ = env.step(commands[step, i])
            np.testing.assert_array_equal(observations[i], obs)
            assert rewards[i] == reward


def test_random_policy_throws_differ_within_an_episode_and_repeat_across_evaluations():
    first, _ = evaluate_stack(RandomPolicy(seed=0), "BoxToss-Stack-v0", seeds=range(10_000, 10_004))
    again, _ = evaluate_stack(RandomPolicy(seed=0), "BoxToss-Stack-v0", seeds=range(10_000, 10_004))
    for key in first:
        np.testing.assert_array_equal(first[key], again[key])
    policy = RandomPolicy(seed=0)
    assert not np.array_equal(policy.act(np.zeros((2, 1)), [], None), policy.act(np.zeros((2, 1)), [], None))
    assert stack_scores(first)["n"] == 4
