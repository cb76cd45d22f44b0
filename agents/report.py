"""Tables and figures from evaluated runs, and the main command's methodology page (written by
``python -m agents.main --full --readme``: docs/methodology/main-command.md, section ``agents``).

Every figure there is written here from the runs' ``results.json`` and ``timing.json`` files, which the
training, evaluation and baseline scripts measured; the headline figures go to ``agents.figures``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np
from gymnasium import error as gym_error

from agents import benchmark_store, figures
from agents.ceiling import ceiling_of
from agents.config import load_yaml
from agents.doc_sections import page_for, replace_section
from agents.evaluation import TEST_FIRST_SEED, TEST_TARGETS, VALIDATION_FIRST_SEED, Throws, load_policy
from agents.oracle import OracleSettings
from agents.run_files import read_json_mapping
from agents.run_folder import number_column, read_csv
from agents.training import read_timing
from box_toss_env.files import save_figure, write_atomic
from box_toss_env.rendering import write_video

RUNS = Path("runs")
DOCS = Path(__file__).resolve().parents[1] / "docs" / "agents"  # figures the README shows
ORACLE_MAX_THROWS = OracleSettings().initial + OracleSettings().iterations * OracleSettings().population
AGENT_LABELS = {
    "random": "random actions",
    "short": "PPO, short (agents.main)",
    "full": "PPO, full",
    # the oracle at its default search budget, which is not the ceiling (agents.ceiling)
    "oracle": f"oracle, default search (at most {ORACLE_MAX_THROWS} simulated throws per target)",
}
COLOURS = {"random": "tab:gray", "short": "tab:orange", "full": "tab:blue", "oracle": "tab:green"}


# -- reading runs --------------------------------------------------------------------------------
def read_results(run_dir: Path, tag: str = "default") -> dict[str, Any] | None:
    """An evaluation's results.json (None if the run has none; a DamagedFileError naming it if damaged)."""
    path = Path(run_dir) / "eval" / tag / "results.json"
    return read_json_mapping(path, ("success_rate",)) if path.exists() else None


def read_evaluations(run_dir: Path) -> dict[str, np.ndarray] | None:
    """A run's evaluations.csv as columns of numbers (None if it has no rows; a DamagedFileError naming it if a
    value is not a number)."""
    path = Path(run_dir) / "evaluations.csv"
    columns, rows = read_csv(path)
    return {key: np.array(number_column(path, rows, key)) for key in columns} if rows else None


def wall_seconds(run_dir: Path, results: dict[str, Any]) -> float:
    """What it took to get the policy: training for PPO, planning the test throws for the oracle."""
    timing = read_timing(run_dir)
    return timing["wall_seconds"] if timing else results["act_seconds"]


def summary_row(name: str, run_dir: Path, tag: str = "default") -> dict[str, Any] | None:
    results = read_results(run_dir, tag)
    if results is None:
        return None
    timing = read_timing(run_dir)
    return {
        "name": name,
        "label": AGENT_LABELS.get(name, name),
        **results,
        "run": str(run_dir),
        "wall_seconds": wall_seconds(run_dir, results),
        "timesteps": timing["timesteps"] if timing else None,
        "env_share": timing["env_share"] if timing else None,
    }


# -- tables --------------------------------------------------------------------------------------
format_seconds = figures.duration  # one format for a duration, in the tables and the headline figures


def markdown_table(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| agent | env steps | success | mean distance error | median distance error | face accuracy | wall time |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for row in rows:
        steps = f"{row['timesteps']:,}" if row.get("timesteps") else "-"
        lines.append(
            f"| {row['label']} | {steps} | {row['success_rate']:.1%} | {row['mean_distance']:.3f} m | "
            f"{row['median_distance']:.3f} m | {row['face_accuracy']:.1%} | "
            f"{format_seconds(row['wall_seconds'])} |"
        )
    return "\n".join(lines)


def text_table(rows: list[dict[str, Any]]) -> str:
    width = max([36, *(len(row["label"]) for row in rows)])
    header = (
        f"{'agent':<{width}} {'env steps':>10} {'success':>8} {'mean dist':>10} {'median dist':>12} "
        f"{'face acc':>9} {'wall time':>10}"
    )
    lines = [header, "-" * len(header)]
    for row in rows:
        steps = f"{row['timesteps']:,}" if row.get("timesteps") else "-"
        lines.append(
            f"{row['label']:<{width}} {steps:>10} {row['success_rate']:>8.1%} {row['mean_distance']:>8.3f} m "
            f"{row['median_distance']:>10.3f} m {row['face_accuracy']:>9.1%} "
            f"{format_seconds(row['wall_seconds']):>10}"
        )
    return "\n".join(lines)


def breakdown_table(rows: list[dict[str, Any]]) -> str:
    """Success rate by target distance bin, one column per agent (markdown)."""
    bins = [entry["bin"] for entry in rows[0]["by_distance"]]
    lines = ["| target x | " + " | ".join(row["label"] for row in rows) + " |", "|---|" + "---:|" * len(rows)]
    for k, label in enumerate(bins):
        lines.append(
            f"| {label} | " + " | ".join(f"{row['by_distance'][k]['success_rate']:.1%}" for row in rows) + " |"
        )
    return "\n".join(lines)


def ceiling_note(env_id: str, store: Path | None = None) -> str:
    """What the oracle row is and where the ceiling is: the ceiling's figures if ``agents.benchmark`` has
    stored the variant's sweep (``docs/agents/benchmark_runs.json``, or ``store``), else the command that measures
    it."""
    note = (
        f"oracle: the default search, at most {ORACLE_MAX_THROWS} simulated throws per target; it is not the "
        "ceiling, which the search reaches as it grows"
    )
    path = benchmark_store.STORE if store is None else Path(store)
    sweep = benchmark_store.load(path)["ceilings"].get(env_id, {}).get("default")
    if not sweep:
        return f"{note} (python -m agents.benchmark --envs {env_id}; docs/agents/benchmark.md)"
    top, first = ceiling_of(sweep), sweep[0]
    return (
        f"{note}.\nceiling ({path.name}): {top['success_rate']:.1%} with {top['throws_per_target']:,.0f} simulated "
        f"throws per target, on the first {top['n']} targets (the first budget of its sweep: "
        f"{first['success_rate']:.1%} with {first['throws_per_target']:,.0f})"
    )


# -- figures -------------------------------------------------------------------------------------
def pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_learning_curves(
    curves: dict[str, dict[str, np.ndarray]], path: Path, levels: dict[str, float] | None = None
) -> Path:
    """Validation success rate and mean landing distance against env steps (one line per run),
    with the baselines' success rates as horizontal lines."""
    plt = pyplot()
    fig, (ax_success, ax_distance) = plt.subplots(1, 2, figsize=(10, 3.8))
    for name, curve in curves.items():
        colour = COLOURS.get(name)
        label = AGENT_LABELS.get(name, name)
        ax_success.plot(curve["timesteps"], curve["success_rate"], marker=".", color=colour, label=label)
        ax_distance.plot(curve["timesteps"], curve["mean_distance"], marker=".", color=colour, label=label)
    for name, level in (levels or {}).items():
        ax_success.axhline(
            level, color=COLOURS.get(name, "k"), linestyle="--", linewidth=1, label=AGENT_LABELS.get(name, name)
        )
    ax_success.set(xlabel="env steps (throws)", ylabel="success rate (validation targets)", ylim=(0, 1.02))
    ax_distance.set(xlabel="env steps (throws)", ylabel="mean landing distance [m]", yscale="log")
    ax_success.legend(fontsize=8, loc="lower right")
    for ax in (ax_success, ax_distance):
        ax.grid(alpha=0.3)
    fig.suptitle("Deterministic policy on fixed validation targets")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return path


def plot_landing_errors(
    throws: dict[str, Throws], path: Path, target_x_range: tuple[float, float], tolerance: float = 0.1
) -> Path:
    """Left: the distribution of landing distances |x - target x| (the fraction of throws landing
    closer than d, log d). Right: the signed landing error against the target's x, per agent."""
    plt = pyplot()
    fig, (ax_cdf, ax_error) = plt.subplots(1, 2, figsize=(10, 3.8))
    for name, t in throws.items():
        distance = np.sort(np.where(np.isfinite(t.final_x), t.distance, np.inf))
        fraction = np.arange(1, len(distance) + 1) / len(distance)
        ax_cdf.step(
            np.maximum(distance, 1e-4),
            fraction,
            where="post",
            color=COLOURS.get(name),
            label=AGENT_LABELS.get(name, name),
        )
        if name == "random":  # off the scale
            continue
        error = t.final_x - t.target_x
        ax_error.scatter(
            t.target_x,
            np.clip(error, -3 * tolerance, 3 * tolerance),
            s=4,
            alpha=0.6,
            color=COLOURS.get(name),
            label=AGENT_LABELS.get(name, name),
        )
    ax_cdf.axvline(tolerance, color="k", linestyle=":", linewidth=1, label="success tolerance")
    ax_cdf.set(
        xscale="log",
        xlim=(1e-3, 10),
        ylim=(0, 1.02),
        xlabel="landing distance |x - target x| [m]",
        ylabel="fraction of throws closer than that",
    )
    ax_error.axhspan(-tolerance, tolerance, color="tab:green", alpha=0.1)
    ax_error.set(
        xlim=target_x_range,
        ylim=(-3 * tolerance, 3 * tolerance),
        xlabel="target x [m]",
        ylabel="landing x - target x [m]",
    )
    for ax in (ax_cdf, ax_error):
        ax.grid(alpha=0.3)
    fig.suptitle(f"Landing errors on the {len(next(iter(throws.values())).seeds):,} test targets")
    fig.legend(*ax_cdf.get_legend_handles_labels(), loc="lower center", ncol=5, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return path


def plot_run(run_dir: Path, eval_dir: Path) -> list[Path]:
    """The learning curve of a run (if it trained) and the landing errors of one evaluation."""
    paths = []
    curve = read_evaluations(run_dir)
    if curve is not None:
        paths.append(plot_learning_curves({run_dir.name: curve}, eval_dir / "learning_curve.png"))
    results = json.loads((eval_dir / "results.json").read_text())
    if not (eval_dir / "throws.npz").exists():  # a stacking env's episodes: no landing errors to draw
        return paths
    config = cast(Any, gym.make(results["env_id"], **results["env_kwargs"]).unwrapped).config
    paths.append(
        plot_landing_errors(
            {run_dir.name: Throws.load(eval_dir / "throws.npz")},
            eval_dir / "landing_errors.png",
            config.target_x_range,
            config.position_tolerance,
        )
    )
    return paths


def record_video(
    run_dir: Path,
    path: Path,
    n_throws: int,
    *,
    model: str = "final",
    env_kwargs: dict[str, Any] | None = None,
    first_seed: int = 10_000,
) -> Path:
    """A GIF (or MP4) of the run's policy throwing at the first ``n_throws`` test targets
    (needs the ``render`` extra)."""
    policy, config = load_policy(run_dir, model)
    kwargs = {**config.get("env_kwargs", {}), **(env_kwargs or {})}
    env = gym.make(config["env_id"], render_mode="rgb_array_list", **kwargs)
    frames: list[np.ndarray] = []
    path.parent.mkdir(parents=True, exist_ok=True)
    for seed in range(first_seed, first_seed + n_throws):
        obs, info = env.reset(seed=seed)
        action = policy.act(obs[None], [info], env)[0]
        env.reset(seed=seed)  # a planner may have used the env; start the throw afresh
        env.step(action)
        frames += cast(list[np.ndarray], env.render())
    env.close()
    return write_video(frames, path, env.metadata["render_fps"])


# -- the README section --------------------------------------------------------------------------
INTRO = """**Targets.** Every agent is scored on the same {targets} test targets: target i is what
`gymnasium.make("{env_id}").reset(seed={first} + i)` draws ({first} to {last}), thrown once with the
deterministic policy. During training the policy is evaluated on {validation_targets} other fixed targets (seeds
{validation}...).

**Scores.** Success: at rest within {tolerance:g} m of the target on the target face. Distance error:
|x - target x| where the box came to rest. Face accuracy: the target face ended down, wherever the box landed.

**Agents.** Random: uniform actions. PPO: `agents/hyperparams/ppo.yml`'s entry for `{env_id}` (the short run at
the main command's budget, the full run at the file's), seed 0, acting in ballistic commands. Oracle: for each
target, a cross-entropy search over the 3-D action that simulates candidate throws with the env's own engine
kernel and throws the best; it stops refining a target once a throw lands within {settle:g} m. This default
search is not the ceiling: [the benchmark](docs/agents/benchmark.md) grows the search until its success stops
rising.

**Time.** PPO's wall time is its training; the oracle's is its planning for all test targets. The main
command's time adds the random baseline, the short run and the oracle, as `python -m agents.main` runs them, in
wall time and in the CPU time of its process, which other jobs on the machine do not inflate. Every figure comes
from one 2-core machine shared with other jobs.

"""


def validation_targets(runs: dict[str, Path]) -> int | str:
    """The number of validation targets of the PPO runs (from their config.yml)."""
    counts = {
        load_yaml(run / "config.yml")["hyperparams"]["eval_targets"]
        for run in runs.values()
        if (run / "config.yml").exists() and load_yaml(run / "config.yml")["algo"] == "ppo"
    }
    return counts.pop() if len(counts) == 1 else "/".join(str(c) for c in sorted(counts)) or "-"


def fidelity_lines(runs: dict[str, Path], fidelity: list[tuple[str, str, str]]) -> list[str]:
    """The physics-fidelity table: the same policies under another solver or step (none if not evaluated)."""
    fidelity_rows = []
    for name, tag, label in fidelity:
        results = read_results(runs[name], tag)
        if results is not None:
            failures = results["failures"]
            fidelity_rows.append(
                f"| {AGENT_LABELS[name]} | {label} | {results['success_rate']:.1%} | "
                f"{results['mean_distance']:.3f} m | "
                f"{failures} |"
            )
    if not fidelity_rows:
        return []
    return [
        "Physics fidelity: the same policies evaluated on the same targets under another solver or step "
        "(PPO trained on the default, robust solver at dt = 1/128 s; the oracle plans again with the "
        "physics it is evaluated under). Throws the seed scheme blows up (`EnergyGainError`) count as "
        "failures.",
        "",
        "| agent | physics | success | mean distance error | throws refused |",
        "|---|---|---:|---:|---:|",
        *fidelity_rows,
        "",
    ]


def readme_section(
    runs: dict[str, Path],
    fidelity: list[tuple[str, str, str]],
    docs: Path = DOCS,
    times: dict[str, dict[str, float]] | None = None,
) -> str:
    """The agents section (markdown) from evaluated runs: the results table, the breakdown by
    target distance, the physics-fidelity table and the figures (written to ``docs``)."""
    rows = [row for name, run in runs.items() if (row := summary_row(name, run)) is not None]
    env = cast(Any, gym.make(rows[0]["env_id"], **rows[0]["env_kwargs"]).unwrapped)
    curves = {name: curve for name, run in runs.items() if (curve := read_evaluations(run)) is not None}
    levels = {row["name"]: row["success_rate"] for row in rows if row["name"] in ("random", "oracle")}
    plot_learning_curves(curves, docs / "learning_curve.png", levels)
    throws = {row["name"]: Throws.load(Path(row["run"]) / "eval" / "default" / "throws.npz") for row in rows}
    plot_landing_errors(throws, docs / "landing_errors.png", env.config.target_x_range, env.config.position_tolerance)
    by_name = {row["name"]: row for row in rows}
    lines = [
        INTRO.format(
            targets=f"{TEST_TARGETS:,}",
            first=TEST_FIRST_SEED,
            last=TEST_FIRST_SEED + TEST_TARGETS - 1,
            tolerance=env.config.position_tolerance,
            validation=VALIDATION_FIRST_SEED,
            validation_targets=validation_targets(runs),
            settle=OracleSettings().settle * env.config.position_tolerance,
            env_id=rows[0]["env_id"],
        ),
        markdown_table(rows),
        "",
    ]
    if "oracle" in by_name:
        lines += [
            f"The oracle row is its default search (at most {ORACLE_MAX_THROWS} simulated throws per target), "
            f"not the ceiling: the ceiling of `{rows[0]['env_id']}`, the search grown until its success stops "
            "rising, is in [the benchmark](docs/agents/benchmark.md).",
            "",
        ]
    if "short" in by_name and "random" in by_name:
        short, random = by_name["short"], by_name["random"]
        lines.append(
            f"The main command's run (`python -m agents.main`) lands {short['success_rate']:.1%} of the throws "
            f"after {format_seconds(short['wall_seconds'])} of training; random actions land "
            f"{random['success_rate']:.1%}."
        )
    if times is not None:
        lines.append(
            f"The main command took {format_seconds(times['command']['wall'])} of wall time and "
            f"{format_seconds(times['command']['cpu'])} of CPU time (its process, every thread); its training run "
            f"(the short run's training and test evaluation) took {format_seconds(times['training']['wall'])} and "
            f"{format_seconds(times['training']['cpu'])}."
        )
    shares = [f"{AGENT_LABELS[row['name']]} {row['env_share']:.0%}" for row in rows if row.get("env_share")]
    if shares:
        lines.append(
            "The env's share of the training loop's wall time (rollouts and updates, periodic "
            f"validation excluded): {', '.join(shares)}; the rest is the network."
        )
    lines += ["", "Success rate by target distance:", "", breakdown_table(rows), ""]
    lines += fidelity_lines(runs, fidelity)
    lines += [
        "![learning curve](docs/agents/learning_curve.png)",
        "",
        "![landing errors](docs/agents/landing_errors.png)",
    ]
    if (docs / "throws.gif").exists():
        lines += ["", "![PPO (full) throwing at the first test targets](docs/agents/throws.gif)"]
    return "\n".join(lines)


GIF_ENV_KWARGS = {"render_width": 360, "render_height": 240, "render_fps": 20}  # a small GIF for the README


def write_readme(section: str, name: str = "agents") -> None:
    """Replace the ``<!-- name:start -->`` ... ``<!-- name:end -->`` block of the page that holds it (the README
    for ``benchmark``, a page of docs/ for the others: ``agents.doc_sections.SECTION_PAGES``; appended if
    missing)."""
    page = page_for(name)
    if f"<!-- {name}:start -->" not in page.read_text():
        write_atomic(page, page.read_text() + f"\n<!-- {name}:start -->\n<!-- {name}:end -->\n")
    replace_section(name, section)
    print(f"wrote the {name} section of {page}")


def main_figures(runs: dict[str, Path], times: dict[str, dict[str, float]], machine: str) -> dict[str, Any]:
    """The main command's headline figures (``agents.figures``' ``main`` group): its short run's success and throws,
    random throws' success, and the CPU and wall time of the short run's training and of the whole command."""
    short, random = summary_row("short", runs["short"]), summary_row("random", runs["random"])
    assert short is not None and random is not None  # both evaluated by agents.main
    return {
        "env_id": short["env_id"],
        "throws": figures.count(short["timesteps"]),
        "test_targets": figures.count(TEST_TARGETS),
        "success": figures.percent(short["success_rate"]),
        "random_success": figures.percent(random["success_rate"]),
        "train_cpu": figures.duration(times["training"]["cpu"]),
        "train_wall": figures.duration(times["training"]["wall"]),
        "command_cpu": figures.duration(times["command"]["cpu"]),
        "command_wall": figures.duration(times["command"]["wall"]),
        "machine": machine,
    }


def write_docs(
    runs: dict[str, Path],
    fidelity: list[tuple[str, str, str]],
    docs: Path = DOCS,
    *,
    times: dict[str, dict[str, float]] | None = None,
    machine: str = "",
) -> str:
    """Figures and a GIF of the full PPO run into ``docs``, the methodology page's agents section, and (given the
    main command's times, ``{"command" | "training": {"wall": s, "cpu": s}}``) the headline figures' ``main``."""
    try:
        print(f"wrote {record_video(runs['full'], docs / 'throws.gif', 3, env_kwargs=GIF_ENV_KWARGS)}")
    except (ImportError, gym_error.DependencyNotInstalled) as error:  # the render extra is not installed
        print(f"no GIF ({error})")
    section = readme_section(runs, fidelity, docs, times)
    write_readme(section)
    if times is not None:
        figures.update("main", main_figures(runs, times, machine))
        print(f"wrote the main group of {figures.FIGURES} and the README's headline")
    return section
