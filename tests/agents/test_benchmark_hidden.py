"""The hidden-physics tier in agents.benchmark: read from its stored rows, reported as IQM cells with the gap to the
ceiling, drawn in the profiles, trained through agents.hidden_physics_tier."""

import json

import numpy as np
import pytest
from scipy import stats as scipy_stats

from agents import benchmark, benchmark_hidden, benchmark_page, benchmark_stats, benchmark_store, hidden_physics_tier


@pytest.fixture(autouse=True)
def few_resamples(monkeypatch):
    monkeypatch.setattr(benchmark_stats, "REPS", 200)
    monkeypatch.setattr(benchmark_stats, "IMPROVEMENT_REPS", 50)


def row(seed: int, success: float) -> dict:
    return {"seed": seed, "success_rate": success, "first_throw_success": success / 4, "mean_throws": 4.0}


def results_file(tmp_path, baselines: dict[str, list[float]], ceiling: float = 0.8):
    agents = {
        "ceiling": {"kind": "ceiling", "per_seed": [row(0, ceiling)]},
        "ceiling_large": {"kind": "ceiling", "per_seed": [row(0, ceiling - 0.1)]},
        "random": {"kind": "reference", "per_seed": [row(0, 0.1)]},
    }
    for name, values in baselines.items():
        agents[name] = {"kind": "baseline", "per_seed": [row(seed, v) for seed, v in enumerate(values)]}
    path = tmp_path / "hidden_physics.json"
    path.write_text(
        json.dumps({"env_id": "BoxToss-HiddenPhysics-v0", "episodes": 64, "first_seed": 7, "agents": agents})
    )
    return path


RECURRENT = [0.2, 0.3, 0.25, 0.9, 0.0]
STACKED = [0.1, 0.2, 0.15]


def test_each_agent_is_an_iqm_cell_and_the_gap_is_the_best_baseline_below_the_ceiling(tmp_path):
    found = benchmark_hidden.rows(results_file(tmp_path, {"recurrent_ppo": RECURRENT, "stacked_ppo": STACKED}))
    assert found["ceiling"] == 0.8  # the best ceiling row
    lines = benchmark_hidden.table(found)
    recurrent = next(line for line in lines if line.startswith("| RecurrentPPO (LSTM policy) | baseline |"))
    iqm = scipy_stats.trim_mean(RECURRENT, 0.25)  # the middle three of five: 0.25
    assert f"| {iqm:.1%} [" in recurrent and "(5) |" in recurrent and recurrent.endswith(f"| {iqm / 0.8:.0%} |")
    stacked = next(line for line in lines if line.startswith("| PPO, stacked observations |"))
    assert f"| {np.mean(STACKED):.1%} [" in stacked and "(3) |" in stacked
    gap = benchmark_hidden.gap_line(found)
    assert gap.startswith("Gap: the best baseline, RecurrentPPO (LSTM policy), reaches 25.0% [")
    assert f"{100 * (0.8 - iqm):.1f} points below it ({iqm / 0.8:.0%} of the ceiling" in gap


def test_no_gap_before_the_baselines_are_trained_and_nothing_without_runs(tmp_path):
    found = benchmark_hidden.rows(results_file(tmp_path, {}))
    assert benchmark_hidden.gap_line(found) == "" and benchmark_hidden.summary_line(found) == ""
    empty = benchmark_hidden.rows(tmp_path / "absent.json")
    assert empty["agents"] == {} and benchmark_hidden.section(empty) == [] and benchmark_hidden.matrices(empty) == {}


def test_the_page_the_readme_and_the_profiles_carry_the_tier(tmp_path):
    found = benchmark_hidden.rows(results_file(tmp_path, {"recurrent_ppo": RECURRENT, "stacked_ppo": STACKED}))
    store = benchmark_store.empty()
    assert benchmark_hidden.TITLE in benchmark_page.summary(store, found)
    page = benchmark_page.page(store, tmp_path, "", found)
    assert f"### {benchmark_hidden.TITLE}" in page and "| random | reference |" in page
    profiles, aggregates = benchmark_page.panels(store, found)
    matrices = profiles[benchmark_hidden.TITLE]
    assert set(matrices) == {"RecurrentPPO (5 seeds)", "PPO stacked (3 seeds)", "random (1 seed)"}  # no ceiling
    np.testing.assert_allclose(matrices["PPO stacked (3 seeds)"][:, 0], np.array(STACKED) / 0.8)
    assert aggregates[benchmark_hidden.TITLE]["RecurrentPPO (5 seeds)"].value == pytest.approx(0.25 / 0.8)


def test_the_benchmark_trains_the_tier_through_its_own_command(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(hidden_physics_tier, "main", lambda argv: calls.append(argv))
    monkeypatch.setattr(benchmark_hidden, "rows", lambda: {"agents": {}})
    args = ["--envs", "BoxToss-HiddenPhysics-v0", "--tiers", "hidden-physics", "--seeds", "3", "4"]
    benchmark.main([*args, "--store", str(tmp_path / "runs.json"), "--root", str(tmp_path / "runs")])
    assert calls == [["ceiling"], ["train", "--seeds", "3", "4"]]  # nothing of the one-throw variants
    assert not (tmp_path / "runs").exists()
