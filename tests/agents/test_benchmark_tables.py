"""agents.benchmark's tables from the stored runs: tiers in their declared order, IQM cells with intervals and seed
counts, the aggregate, the probability of improvement, the held-out split; the store grows run by run."""

import numpy as np
import pytest
from scipy import stats as scipy_stats

from agents import benchmark, benchmark_page, benchmark_stats, benchmark_store, doc_sections
from agents import benchmark_report as tables
from agents import config as configuration
from agents.benchmark_tiers import ASSISTED, RAW, TIERS, tier_named


@pytest.fixture(autouse=True)
def few_resamples(monkeypatch):
    monkeypatch.setattr(benchmark_stats, "REPS", 200)
    monkeypatch.setattr(benchmark_stats, "IMPROVEMENT_REPS", 50)


def result(success: float) -> dict:
    return {"n": 1024, "success_rate": success, "mean_distance": 0.1, "median_distance": 0.05, "face_accuracy": 0.9}


def sweep(success: float) -> list[dict]:
    budget = {"initial": 32, "population": 16, "elite": 4, "iterations": 4}
    return [
        {
            "budget": budget,
            "throws_per_target": 89.0,
            "plan_seconds": 1.0,
            "success_rate": success,
            "face_accuracy": 1.0,
        }
    ]


def make_store(values: dict) -> dict:
    """A store of ``{(env_id, tier, agent, split): [success per seed]}``, ceilings of 100% (ShortEnd's train/test
    splits 90% and 80%)."""
    store = benchmark_store.empty()
    for (env_id, tier, agent, split), successes in values.items():
        for seed, success in enumerate(successes):
            results = {"default": result(success)}
            if split == "train":
                results["split=test"] = result(success - 0.25)
            record = benchmark_store.make_record(env_id, tier, agent, seed, results, split=split)
            benchmark_store.add(store, record)
    for env_id in ("BoxToss-v0", "BoxToss-ShortEnd-v0"):
        store["ceilings"][env_id] = {"default": sweep(1.0)}
    store["ceilings"]["BoxToss-ShortEnd-v0"].update({"split=train": sweep(0.9), "split=test": sweep(0.8)})
    return store


STORE = {
    ("BoxToss-v0", None, "random", None): [0.02] * 5,
    ("BoxToss-v0", "raw", "prior", None): [0.0, 0.01, 0.0],
    ("BoxToss-v0", "raw", "ppo", None): [1.0, 0.99, 0.98, 0.5, 1.0],
    ("BoxToss-v0", "raw", "sac", None): [0.14, 0.13, 0.15],
    ("BoxToss-ShortEnd-v0", None, "random", None): [0.0],
    ("BoxToss-ShortEnd-v0", "raw", "ppo", None): [0.25, 0.11, 0.09],
    ("BoxToss-ShortEnd-v0", "raw", "sac", None): [0.0, 0.0, 0.01],
    ("BoxToss-ShortEnd-v0", "assisted", "ppo", None): [0.97, 0.99, 1.0],
    ("BoxToss-ShortEnd-v0", "assisted", "ppo", "train"): [0.95, 0.85],
}


def test_a_cell_is_the_iqm_of_its_seeds_with_an_interval_and_its_count():
    store = make_store(STORE)
    values = [1.0, 0.99, 0.98, 0.5, 1.0]
    cell = tables.estimate(tables.scores(store, "BoxToss-v0", RAW, "ppo"))
    assert cell.value == pytest.approx(scipy_stats.trim_mean(values, 0.25))  # the middle three of five
    assert cell.runs == 5 and cell.low <= cell.value <= cell.high and cell.low >= 0.5
    three = tables.estimate([0.25, 0.11, 0.09])
    assert three.value == pytest.approx(np.mean([0.25, 0.11, 0.09]))  # three seeds: nothing trimmed
    assert three.percent() == f"{np.mean([0.25, 0.11, 0.09]):.1%} [{100 * three.low:.1f}, {100 * three.high:.1f}] (3)"


def test_every_tier_has_a_table_headline_first_with_random_prior_algorithms_and_ceiling():
    store = make_store(STORE)
    text = benchmark_page.summary(store, {"agents": {}, "ceiling": None})
    assert [tier.headline for tier in TIERS][0] and text.index(RAW.title) < text.index(ASSISTED.title)
    raw = tables.tier_table(store, RAW)
    assert raw[0] == "| variant | random | prior | PPO | SAC | TD3 | ceiling |"
    row = next(line for line in raw if line.startswith("| BoxToss-v0 |"))
    assert "2.0% [2.0, 2.0] (5)" in row and "(3) | - | 100.0% |" in row  # random over 5 seeds; TD3 has none
    assert "(3 of 5) |" in row  # the prior: PPO's plan on the headline tier is 5 seeds, 3 were measured
    short_end = next(line for line in raw if line.startswith("| BoxToss-ShortEnd-v0 |"))
    assert short_end.startswith("| BoxToss-ShortEnd-v0 | 0.0% [0.0, 0.0] (1 of 5) | - | 15.0% [")
    assert short_end.endswith("(3 of 5) | - | 100.0% |")  # a five-seed variant: SAC's 3 seeds said short too
    assert tables.cell_text(tables.estimate([0.5, 0.7]), 2).endswith("(2)")  # as planned: the count alone
    assert raw[-1].startswith("| **all variants** (success / ceiling) |")
    assert "(2 x 3)" in raw[-1]  # PPO on both variants, three runs each (the fewest)


def test_the_probability_of_improvement_compares_runs_variant_by_variant():
    store = make_store(STORE)
    line = tables.improvement_line(store, RAW)
    assert "P(PPO > SAC) = 1.00 [1.00, 1.00] over 2 variants" in line  # every PPO run beats every SAC run
    assert benchmark_stats.probability_of_improvement(np.zeros((3, 1)), np.zeros((3, 1))).value == 0.5
    goals = tables.goals_line(store, RAW)
    assert f"BoxToss-ShortEnd-v0 {np.mean([0.25, 0.11, 0.09]):.0%} (PPO, 3 seeds; missed)" in goals


def test_the_heldout_table_reports_train_test_and_their_gap():
    store = make_store(STORE)
    lines = tables.heldout_table(store, ASSISTED)
    row = next(line for line in lines if line.startswith("| BoxToss-ShortEnd-v0 | PPO |"))
    assert "| 90.0% [" in row and "| 65.0% [" in row and "| 25.0% [" in row and row.endswith("| 90.0% | 80.0% |")
    assert tables.heldout_table(store, RAW) == []


def test_the_store_adds_run_by_run_and_a_record_replaces_its_own_key(tmp_path):
    path = tmp_path / "runs.json"
    store = benchmark_store.load(path)
    first = benchmark_store.make_record("BoxToss-v0", "raw", "ppo", 0, {"default": result(0.5)})
    benchmark.record(store, first, path)
    benchmark.record(store, benchmark_store.make_record("BoxToss-v0", "raw", "ppo", 1, {"default": result(0.7)}), path)
    benchmark.record(store, {**first, "results": {"default": result(0.9)}}, path)
    again = benchmark_store.load(path)
    assert [benchmark_store.success(r) for r in benchmark_store.records(again, "BoxToss-v0", "raw", "ppo")] == [
        0.9,
        0.7,
    ]


def test_report_only_writes_the_page_figures_and_readme_from_the_store(tmp_path, monkeypatch):
    path = tmp_path / "runs.json"
    benchmark_store.save(make_store(STORE), path)
    docs, readme = tmp_path / "docs", tmp_path / "README.md"
    readme.write_text("# x\n\n<!-- benchmark:start -->\nold\n<!-- benchmark:end -->\n")
    monkeypatch.setattr(benchmark_page, "DOCS", docs)
    monkeypatch.setattr(benchmark_page, "PAGE", docs / "benchmark.md")
    monkeypatch.setitem(doc_sections.SECTION_PAGES, "benchmark", readme)
    envs = ["BoxToss-v0", "BoxToss-ShortEnd-v0"]
    benchmark.main(
        ["--report-only", "--readme", "--store", str(path), "--root", str(tmp_path / "runs"), "--envs", *envs]
    )
    text = readme.read_text()
    assert "old" not in text and text.index("Raw actions (headline)") < text.index("Assisted")
    assert '- **Held-out split** (trained on `split="train"`), assisted: ballistic commands: ' in text
    assert "BoxToss-ShortEnd-v0 PPO: train split 90.0% [" in text and ", test split 65.0% [" in text
    assert (docs / "profiles.png").exists() and (docs / "aggregates.png").exists()
    page = (docs / "benchmark.md").read_text()
    assert "### BoxToss-ShortEnd-v0, assisted: ballistic commands" in page and "Held-out split" in page


def test_default_seeds_follow_the_plan_and_tiers_pick_their_recipes():
    assert RAW.default_seeds("BoxToss-v0", "ppo") == (0, 1, 2, 3, 4)  # the headline algorithm everywhere
    assert RAW.default_seeds("BoxToss-v0", "sac") == (0, 1, 2)
    assert RAW.default_seeds("BoxToss-Pixels-v0", "ppo") == tuple(range(5))  # BoxToss-v0 seen as an image
    assert RAW.has_recipe("sac", "BoxToss-Pixels-v0") and not ASSISTED.has_recipe("sac", "BoxToss-Pixels-v0")
    assert RAW.default_seeds("BoxToss-ShortEnd-v0", "td3") == tuple(range(5))
    assert ASSISTED.default_seeds("BoxToss-Stack-v0", "sac") == tuple(range(5))
    assert ASSISTED.default_seeds("BoxToss-Mixed-v0", "ppo") == (0, 1, 2)
    raw, main = configuration.RAW_HYPERPARAMS, configuration.HYPERPARAMS
    assert RAW.hyperparams("ppo", "BoxToss-ThisSideUp-v0") == raw
    assert ASSISTED.hyperparams("ppo", "BoxToss-ThisSideUp-v0") == main
    assert RAW.hyperparams("ppo", "BoxToss-v0") == main  # no entry: ppo.yml's, unwrapped by the tier's override
    assert RAW.hyperparams("td3", "BoxToss-v0") == raw
    assert tier_named("raw") is RAW
    with pytest.raises(ValueError, match="tier must be one of"):
        tier_named("commands")


def test_a_trial_is_a_row_of_its_variant_found_in_its_folder(tmp_path):
    import json

    root = tmp_path / "runs"
    folder = root / "BoxToss-ShortEnd-v0" / "raw" / "ppo-start-seed2"
    (folder / "eval" / "default").mkdir(parents=True)
    (folder / "eval" / "default" / "results.json").write_text(json.dumps(result(0.4)))
    (folder / "command.txt").write_text("python -m agents.train --set initial_mean=ballistic\n")
    store = make_store(STORE)
    benchmark.collect(store, root, tmp_path / "runs.json")
    records = benchmark_store.records(store, "BoxToss-ShortEnd-v0", "raw", "ppo:start")
    assert [r["seed"] for r in records] == [2] and records[0]["command"].endswith("initial_mean=ballistic")
    detail = tables.detail_table(store, "BoxToss-ShortEnd-v0", RAW)
    assert any(line.startswith("| PPO, start | 40.0% [40.0, 40.0] (1) |") for line in detail)
    assert tables.tier_table(store, RAW) == tables.tier_table(make_store(STORE), RAW)  # not a column of the table
    assert "- PPO, start: `python -m agents.train --set initial_mean=ballistic`" in tables.trial_lines(
        store, "BoxToss-ShortEnd-v0", RAW
    )


def test_what_the_store_holds_is_not_trained_again(tmp_path, monkeypatch):
    store = make_store(STORE)  # BoxToss-v0: raw PPO seeds 0-4, SAC 0-2; random 0-4; prior 0-2
    trained, evaluated = [], []
    monkeypatch.setattr(
        benchmark, "ensure_trained", lambda root, env, tier, algo, seed, *a: trained.append((algo, seed))
    )
    monkeypatch.setattr(benchmark, "training_record", lambda *a: None)
    monkeypatch.setattr(benchmark, "ensure_prior", lambda root, env, tier, seed, o: evaluated.append(seed))
    args = benchmark.make_parser().parse_args(["--envs", "BoxToss-v0", "--tiers", "raw", "--no-ceiling"])
    args.store = tmp_path / "runs.json"
    benchmark.train_variant(args, store, "BoxToss-v0")
    assert trained == [("td3", seed) for seed in range(3)]  # TD3 had no run; PPO's 5 and SAC's 3 seeds are kept
    assert evaluated == [3, 4]  # the prior's seeds 0-2 are there; the plan asks PPO's 5


def test_an_assisted_cell_whose_recipe_has_no_wrapper_says_it_repeats_the_raw_runs():
    from agents.benchmark_tiers import same_as_headline

    # ppo.yml's BoxToss-v0 and LongSide entries act in env actions: the assisted tier trains them as the raw tier does
    assert same_as_headline(ASSISTED, "ppo", "BoxToss-v0") and same_as_headline(ASSISTED, "ppo", "BoxToss-LongSide-v0")
    assert not same_as_headline(ASSISTED, "ppo", "BoxToss-ShortEnd-v0")  # ballistic commands
    assert not same_as_headline(ASSISTED, "sac", "BoxToss-v0") and not same_as_headline(RAW, "ppo", "BoxToss-v0")
    store = make_store({**STORE, ("BoxToss-v0", "assisted", "ppo", None): [1.0] * 3})
    table = tables.tier_table(store, ASSISTED)
    row = next(line for line in table if line.startswith("| BoxToss-v0 |"))
    assert "| 100.0% [100.0, 100.0] (3) = raw |" in row and row.count("= raw") == 1  # no prior stored: "-"
    short_end = next(line for line in table if line.startswith("| BoxToss-ShortEnd-v0 |"))
    assert "= raw" not in short_end
    line = tables.repeated_line(ASSISTED)
    assert line.startswith(
        "`= raw`: prior on `BoxToss-v0`, `BoxToss-LongSide-v0`; PPO on `BoxToss-v0`, `BoxToss-LongSide"
    )
    assert tables.repeated_line(RAW) == "" and "= raw" not in "".join(tables.tier_table(store, RAW))
    assert "(prior on `BoxToss-v0`" in benchmark_page.summary(store, {"agents": {}, "ceiling": None})
    store = make_store(
        {("BoxToss-v0", "assisted", "ppo", "train"): [1.0], ("BoxToss-v0", "raw", "ppo", "train"): [1.0]}
    )
    assert tables.heldout_table(store, ASSISTED)[2].startswith("| BoxToss-v0 | PPO = raw | 100.0% [")
    assert tables.heldout_table(store, RAW)[2].startswith("| BoxToss-v0 | PPO | 100.0% [")


def test_every_tier_title_fits_its_panel():
    """A panel is 5.2 inches wide: a title over about 45 characters at medium size ran past the figure's edge
    (the hidden-physics panel's did)."""
    from agents import benchmark_hidden

    for title in [*(tier.title for tier in TIERS), benchmark_hidden.TITLE]:
        lines = benchmark_stats.panel_title(title).split("\n")
        assert " ".join(lines) == title
        assert max(len(line) for line in lines) <= benchmark_stats.PANEL_TITLE_WIDTH
    assert "\n" in benchmark_stats.panel_title(benchmark_hidden.TITLE)
