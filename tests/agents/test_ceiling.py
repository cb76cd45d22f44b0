"""The ceiling sweep: one row per budget, and a killed sweep resumes where it stopped with the same result."""

import json

import pytest

from agents import benchmark_store, ceiling
from agents.benchmark import ensure_ceiling
from agents.oracle import OracleSettings

ENV_ID = "BoxToss-ThisSideUp-v0"
TARGETS = 6
BUDGETS = (
    OracleSettings(initial=8, population=8, elite=2, iterations=1),
    OracleSettings(initial=16, population=8, elite=2, iterations=2),
)
real_sweep = ceiling.sweep  # the tests below stand in for ceiling.sweep to kill it


def small_sweep(env_id, done=None, on_row=None):
    return real_sweep(env_id, budgets=BUDGETS, n_targets=TARGETS, done=done, on_row=on_row)


def measured(row):
    return {key: value for key, value in row.items() if key != "plan_seconds"}


@pytest.fixture(scope="module")
def uninterrupted():
    return small_sweep(ENV_ID)


def test_a_row_per_budget_with_more_throws_for_the_bigger_search(uninterrupted):
    assert [row["budget"]["initial"] for row in uninterrupted] == [8, 16]
    assert all(row["n"] == TARGETS and 0.0 <= row["success_rate"] <= 1.0 for row in uninterrupted)
    assert uninterrupted[1]["throws_per_target"] > uninterrupted[0]["throws_per_target"]
    assert ceiling.ceiling_of(uninterrupted)["last_rise"] == pytest.approx(
        uninterrupted[1]["success_rate"] - uninterrupted[0]["success_rate"]
    )


def test_a_killed_sweep_resumes_at_the_budget_it_was_searching(tmp_path, monkeypatch, uninterrupted):
    def killed_after_first_budget(env_id, env_kwargs=None, done=None, on_row=None):
        def save_then_die(rows):
            on_row(rows)
            raise KeyboardInterrupt

        return small_sweep(env_id, done, save_then_die)

    store = benchmark_store.empty()
    monkeypatch.setattr(ceiling, "sweep", killed_after_first_budget)
    with pytest.raises(KeyboardInterrupt):
        ensure_ceiling(store, tmp_path, ENV_ID)
    partial = tmp_path / ENV_ID / "ceiling-default.partial.json"
    assert store["ceilings"] == {}
    assert [measured(row) for row in json.loads(partial.read_text())] == [measured(uninterrupted[0])]

    resumed_with = []

    def resumed(env_id, env_kwargs=None, done=None, on_row=None):
        resumed_with.append(len(done))
        return small_sweep(env_id, done, on_row)

    monkeypatch.setattr(ceiling, "sweep", resumed)
    ensure_ceiling(store, tmp_path, ENV_ID)
    rows = store["ceilings"][ENV_ID]["default"]
    assert resumed_with == [1]
    assert [measured(row) for row in rows] == [measured(row) for row in uninterrupted]
    assert not partial.exists()
    ensure_ceiling(store, tmp_path, ENV_ID)  # stored: not searched a third time
    assert resumed_with == [1] and store["ceilings"][ENV_ID]["default"] == rows
