"""agents.benchmark's page: stacking and raw-tier tables from stored rows, sections without data kept as they were."""

import json

from agents import benchmark
from agents import config as configuration


def stack_row(algo: str, success: float, seed: int) -> dict:
    return {
        "agent": f"{algo.upper()} (1 seed)",
        "algo": algo,
        "seeds": [seed],
        "results": [{"success_rate": success, "mean_height": 0.5, "fall_rate": 0.1, "mean_reward": 2.0}],
        "timing": [{"timesteps": 16384, "wall_seconds": 120.0}],
    }


def test_stored_rows_make_the_tables_and_old_sections_stay(tmp_path):
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "benchmark.md").write_text("# BoxToss benchmark\n\nintro\n\n### BoxToss-v0\n\n| kept as it was |\n")
    readme = tmp_path / "README.md"
    readme.write_text(
        "<!-- benchmark:start -->\n| variant | random |\n|---|\n| BoxToss-v0 | 9.9% |\n<!-- benchmark:end -->\n"
    )
    stored = {"BoxToss-Stack-v0": [stack_row("ppo", 0.25, 0), stack_row("sac", 0.5, 0)]}
    stored["BoxToss-Stack-v0"][0]["results"].append(
        {**stored["BoxToss-Stack-v0"][0]["results"][0], "success_rate": 0.75}
    )
    stored["BoxToss-Stack-v0"][0]["timing"].append(stored["BoxToss-Stack-v0"][0]["timing"][0])
    envs = ["BoxToss-v0", "BoxToss-Stack-v0"]
    text = benchmark.document(tmp_path / "runs", envs, ["ppo", "sac", "td3"], [0, 1, 2], docs=docs, stored=stored)
    assert "| kept as it was |" in text
    assert "### BoxToss-Stack-v0" in text
    assert "| PPO (1 seed) | 50.0% (25.0%-75.0%) | 0.500 m | 10.0% | 2.00 | - |" in text
    assert "ceiling: planner" in text  # docs/agents/stack_ceiling.json
    summary = benchmark.headline(tmp_path / "runs", envs, ["ppo", "sac", "td3"], [0, 1, 2], stored, readme)
    assert "| BoxToss-v0 | 9.9% |" in summary
    assert "| BoxToss-Stack-v0 | - | 50.0% (25.0%-75.0%) | 50.0% | - |" in summary
    json.dumps(stored)  # what --readme writes to docs/agents/benchmark_results.json


def test_random_actions_alone_do_not_replace_a_table(tmp_path):
    from agents.evaluation import make_baseline_run

    root = tmp_path / "runs"
    path = make_baseline_run("random", root / "BoxToss-v0" / "random", "BoxToss-v0")
    (path / "eval" / "default").mkdir(parents=True)
    (path / "eval" / "default" / "results.json").write_text(json.dumps({"success_rate": 0.02}))
    stored = {"BoxToss-v0": [stack_row("ppo", 1.0, 0)]}
    assert benchmark.table_rows(root, "BoxToss-v0", "commands", ["ppo"], [0], stored) == stored["BoxToss-v0"]
    assert benchmark.table_rows(root, "BoxToss-v0", "raw", ["ppo"], [0], stored) == []


def test_a_run_of_some_variants_shows_every_variant():
    """``--envs BoxToss-Stack-v0 --readme`` rewrote the page and the README with the stack's rows alone."""
    assert benchmark.shown_variants(["BoxToss-Stack-v0"]) == list(benchmark.VARIANTS)
    assert benchmark.shown_variants([]) == list(benchmark.VARIANTS)


def test_the_raw_tier_trains_the_raw_recipe_where_there_is_one():
    raw, main = configuration.RAW_HYPERPARAMS, configuration.HYPERPARAMS
    assert benchmark.tier_hyperparams("ppo", "BoxToss-ThisSideUp-v0", "raw") == raw
    assert benchmark.tier_hyperparams("ppo", "BoxToss-ThisSideUp-v0", "commands") == main
    assert benchmark.tier_hyperparams("ppo", "BoxToss-v0", "raw") == main  # no entry: ppo.yml's, unwrapped
    assert benchmark.tier_hyperparams("sac", "BoxToss-ThisSideUp-v0", "raw") == main
    assert benchmark.tier_hyperparams("td3", "BoxToss-v0", "raw") == raw  # raw/td3.yml: the narrow action noise
    assert benchmark.tier_hyperparams("td3", "BoxToss-ThisSideUp-v0", "raw") == main


def test_the_share_of_the_ceiling_keeps_every_tier_without_data_here(tmp_path):
    """A variant or tier with no runs here keeps its share as the README has it: the raw tier's too, not only the
    commands' (regenerating one variant's rows had dropped every raw share)."""
    readme = tmp_path / "README.md"
    readme.write_text(
        "Best learned agent's success as a share of the ceiling's: BoxToss-v0 100% (PPO (3 seeds)), "
        "BoxToss-v0 (raw) 97% (PPO (3 seeds)), BoxToss-LongSide-v0 99% (SAC (3 seeds)).\n"
    )
    line = benchmark.ratios(tmp_path / "runs", ["BoxToss-v0", "BoxToss-LongSide-v0"], ["ppo"], [0], {}, readme)
    assert line == (
        "Best learned agent's success as a share of the ceiling's: BoxToss-v0 100% (PPO (3 seeds)), "
        "BoxToss-v0 (raw) 97% (PPO (3 seeds)), BoxToss-LongSide-v0 99% (SAC (3 seeds))."
    )


def test_a_tier_trained_without_the_ceiling_sweep_takes_the_variants_ceiling_from_the_readme(tmp_path):
    """The raw tier's rows were trained in roots without the variant's ceiling sweep: their ceiling cell stayed
    ``-`` and their share was left out, though the ceiling is the variant's, in the README's row for it."""
    readme = tmp_path / "README.md"
    readme.write_text(
        "<!-- benchmark:start -->\n| variant | random | PPO | ceiling |\n|---|---:|---:|---:|\n"
        "| BoxToss-ShortEnd-v0 | 0.0% | 98.5% | 100.0% |\n<!-- benchmark:end -->\n"
    )
    assert benchmark.stored_ceiling(readme, "BoxToss-ShortEnd-v0") == 1.0
    assert benchmark.stored_ceiling(readme, "BoxToss-Mixed-v0") is None
    stored = {benchmark.section_key("BoxToss-ShortEnd-v0", "raw"): [stack_row("ppo", 0.4, 0)]}
    summary = benchmark.headline(tmp_path / "runs", ["BoxToss-ShortEnd-v0"], ["ppo"], [0], stored, readme)
    assert "| BoxToss-ShortEnd-v0, raw actions | - | 40.0% | 100.0% |" in summary
    line = benchmark.ratios(tmp_path / "runs", ["BoxToss-ShortEnd-v0"], ["ppo"], [0], stored, readme)
    assert "BoxToss-ShortEnd-v0 (raw) 40% (PPO (1 seed))" in line
