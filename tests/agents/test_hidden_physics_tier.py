"""The hidden-physics tier's command: the ceiling is the one-throw oracle told the dynamics (it succeeds at the
first throw), a blind planner and random do worse, a tiny training run of each baseline trains, is scored on the
test episodes and lands in the results file, and the table reports the gap."""

import json
import tempfile

import numpy as np
import pytest

from agents import hidden_physics_tier as hidden_physics
from agents.oracle import OracleSettings

SMALL = OracleSettings(initial=64, population=16, elite=4, iterations=4, threads=1)


def test_the_ceiling_succeeds_at_the_first_throw_and_the_blind_planner_does_not():
    ceiling = hidden_physics.play(hidden_physics.planned(SMALL), 32)
    blind = hidden_physics.play(hidden_physics.planned(SMALL, blind=True), 32)
    assert ceiling["success_rate"] >= 0.9 and ceiling["first_throw_success"] == ceiling["success_rate"]
    assert ceiling["mean_throws"] < 1.5 and blind["success_rate"] < ceiling["success_rate"] - 0.3
    rng = np.random.default_rng(0)
    random = hidden_physics.play(lambda obs, starts, infos: rng.uniform(-1, 1, (len(obs), 3)), 32)
    assert random["success_rate"] < 0.3 and random["mean_throws"] > 4.0


@pytest.mark.parametrize("algo", hidden_physics.ALGOS)
def test_a_tiny_run_trains_is_scored_and_saved(algo, tmp_path, monkeypatch):
    settings = hidden_physics.TrainSettings(timesteps=128, n_envs=4, n_steps=32, batch_size=64, n_epochs=1)
    temp = tmp_path / "temp"  # the temp directory, where SB3's default logger makes a folder at each learn
    temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    monkeypatch.delenv("SB3_LOGDIR", raising=False)
    row = hidden_physics.train_run(algo, 0, settings, out=tmp_path, n_episodes=16)
    assert not list(temp.glob("SB3-*"))  # it logs nowhere, and leaves no folder there
    assert (tmp_path / f"{algo}_0" / "model.zip").exists() and (tmp_path / f"{algo}_0" / "vecnormalize.pkl").exists()
    assert 0.0 <= row["success_rate"] <= 1.0 and 1.0 <= row["mean_throws"] <= 5.0 and row["timesteps"] == 128
    results = hidden_physics.load_results(tmp_path / "results.json")
    hidden_physics.save_rows(results, algo, "baseline", [row], tmp_path / "results.json")
    hidden_physics.save_rows(results, "ceiling", "ceiling", [{**row, "success_rate": 1.0}], tmp_path / "results.json")
    saved = json.loads((tmp_path / "results.json").read_text())
    assert saved["agents"][algo]["per_seed"][0]["seed"] == 0 and saved["env_id"] == "BoxToss-HiddenPhysics-v0"
    rows = hidden_physics.benchmark_rows(tmp_path / "results.json")
    assert rows["ceiling"] == 1.0
    assert rows["agents"][hidden_physics.AGENT_NAMES[algo]]["success"] == [row["success_rate"]]
    text = hidden_physics.table(saved)
    assert "| ceiling: oracle told the dynamics | 1 | 100.0% |" in text and "Gap: the best baseline reaches" in text
