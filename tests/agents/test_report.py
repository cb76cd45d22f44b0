"""Tables and figures from evaluated runs."""

import json

import numpy as np

from agents import report
from agents.evaluation import evaluate, make_baseline_run, summarize, target_seeds
from agents.policies import ConstantPolicy, RandomPolicy


def fake_run(path, policy, name, timing=None):
    throws, act_seconds = evaluate(policy, "BoxToss-v0", {}, target_seeds(24))
    out = path / name / "eval" / "default"
    out.mkdir(parents=True)
    throws.save(out / "throws.npz")
    results = {"env_id": "BoxToss-v0", "env_kwargs": {}, "act_seconds": act_seconds, **summarize(throws, (1.0, 4.0))}
    (out / "results.json").write_text(json.dumps(results))
    if timing:
        (path / name / "timing.json").write_text(json.dumps(timing))
        (path / name / "evaluations.csv").write_text(
            "timesteps,wall_seconds,success_rate,mean_distance\n0,0,0.0,1.0\n100,1.0,0.5,0.2\n"
        )
    return path / name


def test_readme_section_has_the_table_and_writes_the_figures(tmp_path):
    runs = {
        "random": fake_run(tmp_path, RandomPolicy(), "random"),
        "short": fake_run(
            tmp_path,
            ConstantPolicy((-0.3, 0.0, 0.0)),
            "short",
            {"timesteps": 100, "wall_seconds": 12.0, "env_seconds": 2.0, "eval_seconds": 1.0, "env_share": 2 / 11},
        ),
    }
    section = report.readme_section(runs, [], docs=tmp_path / "docs")
    assert "| random actions | - |" in section and "| PPO, short (agents.main) | 100 |" in section
    assert "18%" in section  # the env share
    assert (tmp_path / "docs" / "learning_curve.png").stat().st_size > 1000
    assert (tmp_path / "docs" / "landing_errors.png").stat().st_size > 1000
    row = report.summary_row("random", runs["random"])
    assert (
        row["success_rate"]
        == json.loads((runs["random"] / "eval" / "default" / "results.json").read_text())["success_rate"]
    )
    assert np.isfinite(row["wall_seconds"])


def test_a_gif_of_a_baselines_throws(tmp_path):
    run_dir = make_baseline_run("constant", tmp_path / "drop", settings={"action": [-1.0, 0.0, 0.0]})
    path = report.record_video(
        run_dir, tmp_path / "throws.gif", 2, env_kwargs={"render_width": 120, "render_height": 80}
    )
    assert path.stat().st_size > 1000
