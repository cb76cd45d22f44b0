"""The main command's table says what the oracle row is, so that it does not read as the ceiling."""

import json

from agents import report


def test_oracle_row_names_its_search_budget():
    assert "default search" in report.AGENT_LABELS["oracle"]
    assert f"at most {report.ORACLE_MAX_THROWS} simulated throws per target" in report.AGENT_LABELS["oracle"]
    assert report.ORACLE_MAX_THROWS == 128 + 12 * 32  # OracleSettings: initial + iterations x population


def test_ceiling_note_gives_the_ceiling_when_the_benchmark_has_measured_it(tmp_path):
    env_id = "BoxToss-ThisSideUp-v0"
    store = tmp_path / "runs.json"
    assert "python -m agents.benchmark --envs BoxToss-ThisSideUp-v0" in report.ceiling_note(env_id, store)
    rows = [
        {"n": 256, "throws_per_target": 93.0, "success_rate": 0.785},
        {"n": 256, "throws_per_target": 11060.0, "success_rate": 1.0},
    ]
    store.write_text(json.dumps({"runs": [], "ceilings": {env_id: {"default": rows}}}))
    note = report.ceiling_note(env_id, store)
    assert "it is not the ceiling" in note
    assert "100.0% with 11,060 simulated throws per target, on the first 256 targets" in note
    assert "78.5% with 93" in note
