"""One benchmark table for every BoxToss variant: random, each algorithm (several training seeds), the ceiling.

    python -m agents.benchmark                      # everything (hours on 2 cores): runs/benchmark/, docs/agents/
    python -m agents.benchmark --envs BoxToss-ShortEnd-v0 --algos ppo --seeds 0 1 2
    python -m agents.benchmark --report-only --readme   # rebuild the table and figures from finished runs

Each training is ``python -m agents.train`` with the hyperparameters of ``agents/hyperparams/<algo>.yml``
for that env id, in ``runs/benchmark/<env id>/<algo>-seed<k>``; a run that has finished is kept, so
the command continues where a killed one stopped. The ceiling is ``agents.ceiling.sweep`` (the oracle
at growing search budgets), saved in ``runs/benchmark/<env id>/ceiling.json``. Everything is scored on
the same test targets (``agents.evaluation``); the results go to ``docs/agents/benchmark.md``, one
learning-curve figure per variant and, with ``--readme``, the README's benchmark section.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from agents import ceiling, report, train
from agents import config as configuration
from agents.algorithms import ALGORITHMS
from agents.evaluation import TEST_TARGETS, evaluate_run, is_stack, make_baseline_run
from agents.training import RUNS, latest_checkpoint, read_timing
from box_toss_env.files import save_figure, write_atomic

VARIANTS = ("BoxToss-v0", "BoxToss-LongSide-v0", "BoxToss-ShortEnd-v0", "BoxToss-ThisSideUp-v0", "BoxToss-Mixed-v0",
            "BoxToss-OnBox-v0")
ROOT = RUNS / "benchmark"
DOCS = report.DOCS
FACE_KINDS = ("any face", "a long side", "a short end", "face 0", "face 1", "face 2", "face 3")


TIERS = {"commands": "the recipe's actions (the ballistic or the stack's throw commands where its file sets an "
                     "env_wrapper)",
         "raw": "the env's own actions (speed, direction, spin; the recipe without its env_wrapper)"}
"""How the agents act: ``commands`` as the hyperparameter file says, ``raw`` without its ``env_wrapper``."""
TIER_OVERRIDES = {"commands": [], "raw": ["env_wrapper=null"]}


def run_dir(root: Path, env_id: str, algo: str, seed: int, tier: str = "commands") -> Path:
    folder = root / env_id if tier == "commands" else root / env_id / tier
    return folder / f"{algo}-seed{seed}"


def ensure_trained(root: Path, env_id: str, algo: str, seed: int, tier: str = "commands",
                   overrides: list[str] | None = None) -> Path:
    """The run of ``algo`` on ``env_id`` with ``seed`` in ``tier``, trained (or resumed) if it has no results;
    ``overrides`` (``--set``) change the file's hyperparameters, e.g. a shorter ``n_timesteps``."""
    path = run_dir(root, env_id, algo, seed, tier)
    if report.read_results(path) is not None:
        return path
    settings = ["--set", *TIER_OVERRIDES[tier], *(overrides or [])] if TIER_OVERRIDES[tier] or overrides else []
    if (path / "config.yml").exists() and latest_checkpoint(path, algo) is not None:
        train.main(["--resume", str(path), "--no-progress"])
    else:
        train.main(["--algo", algo, "--env", env_id, "--seed", str(seed), "--no-progress", "--runs-dir",
                    str(path.parent), "--name", path.name, *settings])
    return path


def ensure_random(root: Path, env_id: str) -> Path:
    path = root / env_id / "random"
    if report.read_results(path) is None:
        make_baseline_run("random", path, env_id, command=f"python -m agents.baselines random --env {env_id}")
        evaluate_run(path, quiet=True)
    return path


def ensure_ceiling(root: Path, env_id: str) -> dict[str, Any]:
    """The variant's ceiling sweep, run if it is not saved yet. Each finished budget is kept in
    ``ceiling.partial.json``, so a killed sweep resumes at the budget it was searching."""
    path = root / env_id / "ceiling.json"
    if not path.exists():
        partial = path.with_suffix(".partial.json")
        done = json.loads(partial.read_text()) if partial.exists() else []
        print(f"{env_id}: oracle at {len(ceiling.BUDGETS)} search budgets on {ceiling.CEILING_TARGETS} targets"
              f"{f' ({len(done)} done before)' if done else ''} ...")
        path.parent.mkdir(parents=True, exist_ok=True)
        rows = ceiling.sweep(env_id, done=done, on_row=lambda rows: write_atomically(partial, rows))
        write_atomically(path, rows)
        partial.unlink(missing_ok=True)
    return json.loads(path.read_text())


def write_atomically(path: Path, rows: list[dict[str, Any]]) -> None:
    """JSON to a temporary file renamed over ``path``: a kill leaves the old file or the new one."""
    write_atomic(path, json.dumps(rows, indent=2))


# -- the table ------------------------------------------------------------------------------------
def spread(values: list[float]) -> str:
    """mean, and min-max over seeds when there are several."""
    if not values:
        return "-"
    mean = float(np.mean(values))
    return f"{mean:.1%}" if len(values) == 1 else f"{mean:.1%} ({min(values):.1%}-{max(values):.1%})"


def agent_rows(root: Path, env_id: str, algos: list[str], seeds: list[int]) -> list[dict[str, Any]]:
    rows = []
    random = report.read_results(root / env_id / "random")
    if random:
        rows.append({"agent": "random actions", "results": [random], "timing": [None]})
    for algo in algos:
        found = [(report.read_results(p), read_timing(p)) for seed in seeds
                 if report.read_results(p := run_dir(root, env_id, algo, seed)) is not None]
        if found:
            rows.append({"agent": f"{algo.upper()} ({len(found)} seed{'s' * (len(found) > 1)})",
                         "results": [r for r, _ in found], "timing": [t for _, t in found]})
    return rows


def variant_table(env_id: str, rows: list[dict[str, Any]], sweep: list[dict[str, Any]] | None) -> list[str]:
    lines = [f"### {env_id}", "",
             "| agent | success | mean distance | median distance | face accuracy | env steps | wall time |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for row in rows:
        results, timing = row["results"], [t for t in row["timing"] if t]
        steps = f"{int(np.mean([t['timesteps'] for t in timing])):,}" if timing else "-"
        wall = report.format_seconds(float(np.mean([t["wall_seconds"] for t in timing]))) if timing else "-"
        lines.append(f"| {row['agent']} | {spread([r['success_rate'] for r in results])} | "
                     f"{np.mean([r['mean_distance'] for r in results]):.3f} m | "
                     f"{np.mean([r['median_distance'] for r in results]):.3f} m | "
                     f"{np.mean([r['face_accuracy'] for r in results]):.1%} | {steps} | {wall} |")
    if sweep:
        top = ceiling.ceiling_of(sweep)
        note = "" if top["converged"] else " (still rising)"
        lines.append(f"| ceiling: oracle, {top['throws_per_target']:,.0f} simulated throws per target, "
                     f"{top['n']} targets{note} | {top['success_rate']:.1%} | {top['mean_distance']:.3f} m | "
                     f"{top['median_distance']:.3f} m | {top['face_accuracy']:.1%} | - | "
                     f"{report.format_seconds(top['plan_seconds'])} |")
    return lines


def breakdowns(rows: list[dict[str, Any]]) -> list[str]:
    """Success by target face kind and by target distance, one column per agent (seed means)."""
    if not rows:
        return []
    header = "| " + " | ".join(row["agent"] for row in rows) + " |"
    rule = "|---|" + "---:|" * len(rows)
    lines = ["Success by target face:", "", "| target face " + header, rule]
    kinds = [k for k in FACE_KINDS if any(e["kind"] == k for e in rows[0]["results"][0]["by_face"])]
    for kind in kinds:
        cells = []
        for row in rows:
            values = [e["success_rate"] for r in row["results"] for e in r["by_face"] if e["kind"] == kind]
            cells.append(f"{np.mean(values):.1%}" if values else "-")
        lines.append(f"| {kind} | " + " | ".join(cells) + " |")
    lines += ["", "Success by target x:", "", "| target x " + header, rule]
    for k, entry in enumerate(rows[0]["results"][0]["by_distance"]):
        cells = [f"{np.mean([r['by_distance'][k]['success_rate'] for r in row['results']]):.1%}" for row in rows]
        lines.append(f"| {entry['bin']} | " + " | ".join(cells) + " |")
    return lines


def sweep_table(sweep: list[dict[str, Any]]) -> list[str]:
    lines = ["Oracle success as its search grows (the ceiling is the last row):", "",
             "| initial, population x rounds (elite) | throws per target | success | face accuracy | planning |",
             "|---|---:|---:|---:|---:|"]
    for row in sweep:
        b = row["budget"]
        lines.append(f"| {b['initial']}, {b['population']} x {b['iterations']} ({b['elite']}) | "
                     f"{row['throws_per_target']:,.0f} | {row['success_rate']:.1%} | {row['face_accuracy']:.1%} | "
                     f"{report.format_seconds(row['plan_seconds'])} |")
    return lines


def plot_curves(root: Path, env_id: str, algos: list[str], seeds: list[int], sweep, path: Path) -> Path | None:
    """Validation success against throws and against wall time, one line per training run."""
    plt = report.pyplot()
    fig, (ax_steps, ax_wall) = plt.subplots(1, 2, figsize=(10, 3.6))
    drawn = False
    for k, algo in enumerate(algos):
        for seed in seeds:
            curve = report.read_evaluations(run_dir(root, env_id, algo, seed))
            if curve is None:
                continue
            label = algo.upper() if seed == seeds[0] else None
            ax_steps.plot(curve["timesteps"], curve["success_rate"], color=f"C{k}", alpha=0.8, label=label)
            ax_wall.plot(curve["wall_seconds"] / 60, curve["success_rate"], color=f"C{k}", alpha=0.8, label=label)
            drawn = True
    if not drawn:
        plt.close(fig)
        return None
    if sweep:
        for ax in (ax_steps, ax_wall):
            ax.axhline(ceiling.ceiling_of(sweep)["success_rate"], color="k", linestyle="--", linewidth=1,
                       label="ceiling (oracle)")
    ax_steps.set(xlabel="throws (env steps)", ylabel="success (validation targets)", ylim=(0, 1.02))
    ax_wall.set(xlabel="wall time [min]", ylim=(0, 1.02))
    ax_steps.legend(fontsize=8)
    for ax in (ax_steps, ax_wall):
        ax.grid(alpha=0.3)
    fig.suptitle(f"{env_id}: learning curves, one line per training seed")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path


def document(root: Path, envs: list[str], algos: list[str], seeds: list[int], docs: Path = DOCS) -> str:
    lines = [f"Every agent on the same {TEST_TARGETS:,} test targets per variant (the ceiling on the first "
             f"{ceiling.CEILING_TARGETS}); success: at rest within the tolerance on a target face. Training runs: "
             "`python -m agents.train --algo A --env E --seed S` with the file's hyperparameters, on this 2-core "
             "machine; several seeds give the mean and (min-max).", ""]
    for env_id in envs:
        sweep_path = root / env_id / "ceiling.json"
        sweep = json.loads(sweep_path.read_text()) if sweep_path.exists() else None
        rows = agent_rows(root, env_id, algos, seeds)
        if not rows and not sweep:
            continue
        lines += variant_table(env_id, rows, sweep) + [""]
        lines += breakdowns(rows) + [""]
        if sweep:
            lines += sweep_table(sweep) + [""]
        figure = plot_curves(root, env_id, algos, seeds, sweep, docs / f"curves_{env_id}.png")
        if figure is not None:
            lines += [f"![learning curves on {env_id}](curves_{env_id}.png)", ""]
    return "\n".join(lines)


def headline(root: Path, envs: list[str], algos: list[str], seeds: list[int]) -> str:
    """The README's summary: success per variant and agent, against the ceiling."""
    lines = ["| variant | random | " + " | ".join(a.upper() for a in algos) + " | ceiling |",
             "|---|---:|" + "---:|" * len(algos) + "---:|"]
    for env_id in envs:
        rows = {row["agent"].split(" ")[0]: row for row in agent_rows(root, env_id, algos, seeds)}
        sweep_path = root / env_id / "ceiling.json"
        top = math.nan
        if sweep_path.exists():
            top = ceiling.ceiling_of(json.loads(sweep_path.read_text()))["success_rate"]
        cells = [spread([r["success_rate"] for r in rows[a.upper()]["results"]]) if a.upper() in rows else "-"
                 for a in algos]
        random = rows.get("random")
        lines.append(f"| {env_id} | {spread([random['results'][0]['success_rate']]) if random else '-'} | "
                     + " | ".join(cells) + f" | {'-' if math.isnan(top) else f'{top:.1%}'} |")
    return "\n".join(lines)


def ratios(root: Path, envs: list[str], algos: list[str], seeds: list[int]) -> str:
    """One line: the best learned agent's share of the ceiling's success, per variant."""
    parts = []
    for env_id in envs:
        sweep_path = root / env_id / "ceiling.json"
        rows = [row for row in agent_rows(root, env_id, algos, seeds) if row["agent"] != "random actions"]
        if not sweep_path.exists() or not rows:
            continue
        top = ceiling.ceiling_of(json.loads(sweep_path.read_text()))["success_rate"]
        best = max(rows, key=lambda row: np.mean([r["success_rate"] for r in row["results"]]))
        share = np.mean([r["success_rate"] for r in best["results"]]) / top
        parts.append(f"{env_id} {share:.0%} ({best['agent']})")
    return "Best learned agent's success as a share of the ceiling's: " + ", ".join(parts) + "."


def check_options(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Every env id registered, every training's hyperparameters (with the tier's and ``--set`` overrides) valid:
    a one-line error before anything is created or trained."""
    for env_id in args.envs:
        if env_id not in gym.registry:
            parser.error(f"--envs: {env_id!r} is not registered")
    if args.report_only:
        return
    for env_id in args.envs:
        for algo in args.algos:
            for tier in args.tiers:
                try:
                    config = configuration.apply_overrides(configuration.load_hyperparams(algo, env_id),
                                                           [*TIER_OVERRIDES[tier], *args.overrides], algo)
                    configuration.check_config(config, algo)
                except configuration.ConfigError as error:
                    parser.error(f"{algo} on {env_id} ({tier}): {error}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--envs", nargs="+", default=list(VARIANTS))
    parser.add_argument("--algos", nargs="+", default=sorted(ALGORITHMS), choices=sorted(ALGORITHMS))
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--root", type=Path, default=ROOT)
    parser.add_argument("--tiers", nargs="+", default=["commands"], choices=list(TIERS),
                        help="commands: the recipes as their files say; raw: in the env's own actions (no env_wrapper)")
    parser.add_argument("--set", nargs="*", default=[], action="extend", metavar="KEY=VALUE", dest="overrides",
                        help="override the files' hyperparameters of every training, e.g. n_timesteps=16384")
    parser.add_argument("--no-ceiling", action="store_true", help="skip the oracle sweep")
    parser.add_argument("--report-only", action="store_true", help="train nothing: tables from finished runs")
    parser.add_argument("--readme", action="store_true", help="write docs/agents/benchmark.md and the README section")
    args = parser.parse_args(argv)
    check_options(parser, args)
    if not args.report_only:
        for env_id in args.envs:
            ensure_random(args.root, env_id)
            if not args.no_ceiling and not is_stack(env_id):  # the stack's ceiling: agents.stack_planner
                ensure_ceiling(args.root, env_id)
            for seed in args.seeds:
                for tier in args.tiers:
                    for algo in args.algos:
                        ensure_trained(args.root, env_id, algo, seed, tier, args.overrides)
    text = document(args.root, args.envs, args.algos, args.seeds)
    summary = headline(args.root, args.envs, args.algos, args.seeds)
    print(summary)
    if args.readme:
        DOCS.mkdir(parents=True, exist_ok=True)
        write_atomic(DOCS / "benchmark.md", "# BoxToss benchmark\n\nGenerated by `python -m agents.benchmark "
                                           "--report-only --readme` from the runs in `runs/benchmark/`.\n\n" + text)
        report.write_readme("### Benchmark: every variant, every algorithm, against the ceiling\n\n"
                            "`python -m agents.benchmark` (then `--report-only --readme`). Success on the test "
                            "targets; the ceiling is the oracle whose search grew until its success stopped rising "
                            "(details, breakdowns by face and distance, the oracle's budgets and the learning curves: "
                            "[docs/agents/benchmark.md](docs/agents/benchmark.md)):\n\n" + summary + "\n\n"
                            + ratios(args.root, args.envs, args.algos, args.seeds), "benchmark")


if __name__ == "__main__":
    main()
