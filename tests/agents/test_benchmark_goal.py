"""agents.benchmark on BoxToss-Goal-v0: SAC and TD3 with HER and SAC without it, trained on the goal env,
scored on BoxToss-v0's test targets, written in the page's benchmark-goal section alone."""

import json

import pytest
from stable_baselines3 import HerReplayBuffer

from agents import benchmark, benchmark_goal, doc_sections, evaluation


def test_the_goal_agents_differ_only_in_her():
    algo, her = benchmark_goal.goal_hyperparams("sac-her")
    _, plain = benchmark_goal.goal_hyperparams("sac-no-her")
    assert algo == "sac" and her["replay_buffer_class"] == "HerReplayBuffer"
    assert "replay_buffer_class" not in plain and "replay_buffer_kwargs" not in plain
    assert {k: v for k, v in her.items() if not k.startswith("replay_buffer")} == plain
    _, env_actions = benchmark_goal.goal_hyperparams("sac-her-env-actions")
    assert her["env_wrapper"] and {k: v for k, v in her.items() if k != "env_wrapper"} == env_actions
    td3_algo, td3 = benchmark_goal.goal_hyperparams("td3-her")
    assert td3_algo == "td3" and td3["n_timesteps"] == her["n_timesteps"]  # the same budget


@pytest.fixture
def tiny(monkeypatch):
    real = benchmark_goal.goal_hyperparams

    def small(agent):
        algo, config = real(agent)
        return algo, {
            **config,
            "n_timesteps": 64,
            "n_envs": 2,
            "learning_starts": 16,
            "batch_size": 16,
            "buffer_size": 1000,
            "policy_kwargs": {"net_arch": [16]},
        }

    monkeypatch.setattr(benchmark_goal, "goal_hyperparams", small)
    monkeypatch.setattr(
        benchmark_goal,
        "evaluate_run",
        lambda path, quiet: evaluation.evaluate_run(path, quiet=quiet, n_targets=16, tag="default"),
    )


def test_goal_runs_are_trained_scored_and_written_in_their_section(tiny, tmp_path, monkeypatch):
    page = tmp_path / "benchmark.md"
    page.write_text("# page\n\nkept\n<!-- benchmark-goal:start -->\nold\n<!-- benchmark-goal:end -->\n")
    monkeypatch.setitem(doc_sections.SECTION_PAGES, "benchmark-goal", page)
    benchmark.main(["--envs", benchmark_goal.GOAL_ENV, "--seeds", "0", "--root", str(tmp_path / "runs"), "--readme"])
    for agent in benchmark_goal.GOAL_AGENTS:
        run = tmp_path / "runs" / benchmark_goal.GOAL_ENV / f"{agent}-seed0"
        results = json.loads((run / "eval" / "default" / "results.json").read_text())
        assert results["env_id"] == "BoxToss-v0" and results["n"] == 16  # thrown at BoxToss-v0's targets
        assert json.loads((run / "timing.json").read_text())["timesteps"] >= 64
    policy, _ = evaluation.load_policy(tmp_path / "runs" / benchmark_goal.GOAL_ENV / "sac-her-seed0")
    assert not isinstance(policy.model.replay_buffer, HerReplayBuffer)  # loaded to act, without HER's env
    text = page.read_text()
    assert text.startswith("# page\n\nkept\n") and "old" not in text
    for label in (
        "random actions",
        "SAC + HER (1 seed)",
        "TD3 + HER (1 seed)",
        "SAC without HER (1 seed)",
        "SAC + HER, env actions (1 seed)",
        "SAC without HER, env actions (1 seed)",
    ):
        assert f"| {label} |" in text
