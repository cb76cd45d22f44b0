"""Tables and figures from evaluated runs, and the README's agents section (written by
``python -m agents.main --full --readme``).

Every figure in the README's agents section is written here from the runs' ``results.json`` and
``timing.json`` files, which the training, evaluation and baseline scripts measured.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import error as gym_error

from agents.ceiling import ceiling_of
from agents.config import load_yaml
from agents.doc_sections import page_for, replace_section
from agents.evaluation import TEST_FIRST_SEED, TEST_TARGETS, VALIDATION_FIRST_SEED, Throws, load_policy
from agents.oracle import OracleSettings
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
    path = Path(run_dir) / "eval" / tag / "results.json"
    return json.loads(path.read_text()) if path.exists() else None


def read_evaluations(run_dir: Path) -> dict[str, np.ndarray] | None:
    path = Path(run_dir) / "evaluations.csv"
    if not path.exists():
        return None
    with open(path) as file:
        rows = list(csv.DictReader(file))
    return {key: np.array([float(row[key]) for row in rows]) for key in rows[0]} if rows else None


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
def format_seconds(seconds: float) -> str:
    if seconds < 1:
        return f"{seconds:.2f} s"
    if seconds < 120:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.1f} min"


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
    from agents import benchmark_store

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
    config = gym.make(results["env_id"], **results["env_kwargs"]).unwrapped.config
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
        frames += env.render()
    env.close()
    return write_video(frames, path, env.metadata["render_fps"])


# -- the README section --------------------------------------------------------------------------
INTRO = """# Agents: PPO, SAC and TD3, baselines, the ceiling and evaluation (`agents/`)

```bash
python -m agents.main                                    # short PPO run on {env_id} + random and oracle: the table
python -m agents.train --algo sac --env BoxToss-ShortEnd-v0   # hyperparameters: agents/hyperparams/sac.yml (by env id)
python -m agents.train --name long --set n_timesteps=1e6 # override any hyperparameter
python -m agents.train --resume runs/long --set n_timesteps=2e6   # continue from the last checkpoint
python -m agents.evaluate runs/short --video 4           # table by distance and face, plots, a GIF (render extra)
python -m agents.evaluate runs/short --env-kwargs solver=seed dt=0.0009765625   # under other physics
python -m agents.baselines oracle --env BoxToss-ShortEnd-v0   # the simulator-planning oracle, as a run folder
python -m agents.benchmark                               # every variant x algorithm x seed, and the ceiling
python -m agents.main --full --readme                    # this section, rewritten from the measurements
tensorboard --logdir runs
```

`agents/hyperparams/ppo.yml`, `sac.yml` and `td3.yml` are in RL Baselines3 Zoo's format and load unchanged
(`pip install -e ".[zoo]"`, then `python -m rl_zoo3.train --algo ppo --env BoxToss-ShortEnd-v0 --gym-packages
box_toss_env --conf-file agents/hyperparams/ppo.yml` and `python -m rl_zoo3.enjoy ...`); the settings only our
scripts use (engine and torch threads, validation and checkpoints) are in `agents/hyperparams/project.yml`.
Our training runs the algorithm on the batched vector env (`gymnasium.make_vec`, all envs thrown in one engine
call, through `box_toss_env.wrappers.sb3_adapter.SB3VecEnvAdapter`), with observations normalised by
`VecNormalize` and one torch thread. Where a face counts (`BoxToss-ShortEnd-v0`, `-ThisSideUp-v0`, `-Mixed-v0`)
and on a box (`BoxToss-OnBox-v0`, touching down on the base's top) the algorithms act in ballistic commands
(`env_wrapper: box_toss_env.envs.ballistic.BallisticThrows` in the hyperparameter files: flight time, landing
offset and lean from a throw that lands a target face flat on the target, see the environment section);
evaluation maps a policy's commands to the env's actions the same way, so every agent is scored on the env's
own throws. Each run folder `runs/NAME/` keeps `config.yml` (algorithm, resolved
hyperparameters, env kwargs, seed, package version), `command.txt`, `model.zip` and `vecnormalize.pkl`, the best
model by validation success, `evaluations.csv` and `logs/progress.csv` (appended, never rewritten: a resume drops
the rows after its checkpoint), TensorBoard logs, checkpoints (with the replay buffer for SAC and TD3; a final one
at the end of every session), `timing.json` (written as training goes, so a killed run's time counts) and
`eval/*/results.json` (an evaluation with other settings, `--targets 8` say, goes to `eval/targets=8`, never over
another); what a run folder guarantees is in [run folders](docs/agents/run_folders.md).

The main job trains on `{env_id}`, where the face counts: each episode draws one face that must end down.
Every agent is scored on the same {targets} test targets: target i is what
`gymnasium.make("{env_id}").reset(seed={first} + i)` draws ({first} to {last}), thrown once with the
deterministic policy. Success: at rest within {tolerance:g} m of the target on the target face; distance
error: |x - target x| where the box came to rest; face accuracy: the target face ended down, wherever the box
landed. During training the policy is evaluated on {validation_targets} other fixed targets (seeds
{validation}...). Random: uniform actions. Oracle: for each target, a cross-entropy search over the 3-D action
that simulates candidate throws with the env's own engine kernel (all targets' candidates in one call) and
throws the best; it stops refining a target once a throw lands within {settle:g} m. Its wall time is its
planning time for all test targets; PPO's is its training time (seed 0, on the shared 2-core machine these
figures come from). The oracle's default search is not the ceiling: see [the benchmark](docs/agents/benchmark.md),
where the search grows until its success stops rising.

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


def readme_section(runs: dict[str, Path], fidelity: list[tuple[str, str, str]], docs: Path = DOCS) -> str:
    """The agents section (markdown) from evaluated runs: the results table, the breakdown by
    target distance, the physics-fidelity table and the figures (written to ``docs``)."""
    rows = [row for name, run in runs.items() if (row := summary_row(name, run)) is not None]
    env = gym.make(rows[0]["env_id"], **rows[0]["env_kwargs"]).unwrapped
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
            f"The default run (`python -m agents.main`) lands {short['success_rate']:.1%} of the throws "
            f"after {format_seconds(short['wall_seconds'])} of training; random actions land "
            f"{random['success_rate']:.1%}."
        )
    if "full" in by_name and "oracle" in by_name:
        full, oracle = by_name["full"], by_name["oracle"]
        lines.append(
            f"PPO (full) reaches {full['success_rate'] / oracle['success_rate']:.1%} of the "
            "default-search oracle's success "
            f"rate in {full['timesteps']:,} env steps and {format_seconds(full['wall_seconds'])}."
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


def write_docs(runs: dict[str, Path], fidelity: list[tuple[str, str, str]], docs: Path = DOCS) -> str:
    """Figures and a GIF of the full PPO run into ``docs``, and the README's agents section."""
    try:
        print(f"wrote {record_video(runs['full'], docs / 'throws.gif', 3, env_kwargs=GIF_ENV_KWARGS)}")
    except (ImportError, gym_error.DependencyNotInstalled) as error:  # the render extra is not installed
        print(f"no GIF ({error})")
    section = readme_section(runs, fidelity, docs)
    write_readme(section)
    return section
