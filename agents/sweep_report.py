"""Tables of a finished (or interrupted) sweep, read from its folder; the best configuration as a Zoo entry.

A sweep folder ``runs/tune/NAME/`` holds ``sweep.yml`` (what was asked), ``wall_seconds.json``
(the sweep's wall time per env id, over every session) and one Tune experiment per env id,
``NAME/<env id>/``, whose trial folders are run folders (``agents.tuning``). Everything here is read
from those files: the validation rows of ``evaluations.csv``, the test evaluation of finished
trials (``eval/default/results.json``), the sampled values (Ray's ``params.json``) and Ray's
``error.txt`` for a trial that failed.

For each env id, ``trials.csv`` and ``trials.md`` list the trials, and ``best.yml`` is the best
trial's configuration as an entry of ``agents/hyperparams/<algo>.yml`` (RL Zoo's format): the best
trial is the finished one with the highest objective at its last validation (the validation
success, then the distance; ``agents.evaluation.search_objective``).
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import yaml

from agents import config as configuration
from agents import search_space
from agents.evaluation import search_objective
from agents.search_space import Dimension
from agents.training import read_timing
from box_toss_env.files import atomic_path, write_atomic

TRIAL_COLUMNS = (
    "trial",
    "status",
    "timesteps",
    "validation_success",
    "best_validation_success",
    "mean_distance",
    "objective",
    "test_success",
    "train_seconds",
    "overrides",
    "run",
)


def read_rows(path: Path) -> list[dict[str, str]]:
    if not path.exists():
        return []
    with open(path) as file:
        return list(csv.DictReader(file))


def trial_row(trial_dir: Path, n_timesteps: int, space: dict[str, Dimension]) -> dict[str, Any]:
    """One trial, from its folder."""
    config = configuration.load_yaml(trial_dir / "config.yml") if (trial_dir / "config.yml").exists() else {}
    hyperparams = config.get("hyperparams", {})
    targets = int(hyperparams.get("eval_targets", 1))
    validations = read_rows(trial_dir / "evaluations.csv")
    params = json.loads((trial_dir / "params.json").read_text()) if (trial_dir / "params.json").exists() else {}
    results_path = trial_dir / "eval" / "default" / "results.json"
    results = json.loads(results_path.read_text()) if results_path.exists() else None
    last = validations[-1] if validations else None
    timesteps = int(last["timesteps"]) if last else 0
    if (trial_dir / "error.txt").exists():
        status = "error"
    elif results is not None:
        status = "finished"
    elif timesteps < n_timesteps:
        status = f"pruned at {timesteps:,}" if validations else "not started"
    else:
        status = "stopped"
    timing = read_timing(trial_dir)
    return {
        "trial": trial_dir.name.removeprefix("trial_"),
        "status": status,
        "timesteps": timesteps,
        "validation_success": float(last["success_rate"]) if last else math.nan,
        "best_validation_success": max((float(row["success_rate"]) for row in validations), default=math.nan),
        "mean_distance": float(last["mean_distance"]) if last else math.nan,
        "objective": (
            search_objective(float(last["success_rate"]), float(last["mean_distance"]), targets) if last else -math.inf
        ),
        "test_success": results["success_rate"] if results else math.nan,
        "train_seconds": timing["wall_seconds"] if timing else (float(last["wall_seconds"]) if last else 0.0),
        "params": params,
        "overrides": " ".join(search_space.overrides(space, params)) if params else "",
        "run": str(trial_dir),
        "config": config,
    }


def started(trial_dir: Path) -> float:
    """When the trial first reported (the timestamp of the first row of Ray's progress.csv)."""
    rows = read_rows(trial_dir / "progress.csv")
    return float(rows[0]["timestamp"]) if rows and rows[0].get("timestamp") else math.inf


def experiment_rows(experiment: Path, n_timesteps: int, space: dict[str, Dimension]) -> list[dict[str, Any]]:
    """Every trial of one Tune experiment, in the order Tune started them."""
    trials = [path for path in Path(experiment).glob("trial_*") if path.is_dir()]
    trials.sort(key=started)
    return [trial_row(path, n_timesteps, space) for path in trials]


def best_trial(rows: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The finished trial with the highest objective at its last validation (None if none finished)."""
    finished = [row for row in rows if row["status"] == "finished"]
    return max(finished, key=lambda row: row["objective"]) if finished else None


def best_entry(row: dict[str, Any], sweep_name: str) -> str:
    """The best trial's configuration as a YAML entry of ``<algo>.yml``, with where it comes from."""
    config = row["config"]
    entry = configuration.zoo_entry(config["hyperparams"])
    text = yaml.safe_dump({config["env_id"]: entry}, sort_keys=False)
    return (
        f"# Best of sweep {sweep_name} ({config['algo']} on {config['env_id']}): trial {row['trial']}, "
        f"validation success {row['validation_success']:.1%}, test success {row['test_success']:.1%}\n"
        f"# after n_timesteps={entry['n_timesteps']:,} throws (the sweep's budget per trial). Ready for "
        f"agents/hyperparams/{config['algo']}.yml\n{text}"
    )


def percent(value: float) -> str:
    return "-" if not math.isfinite(value) else f"{value:.1%}"


def trials_markdown(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| trial | status | env steps | validation success | mean distance | test success | training time | "
        "sampled values |",
        "|---|---|---:|---:|---:|---:|---:|---|",
    ]
    for row in rows:
        distance = "-" if not math.isfinite(row["mean_distance"]) else f"{row['mean_distance']:.3f} m"
        lines.append(
            f"| {row['trial']} | {row['status']} | {row['timesteps']:,} | "
            f"{percent(row['validation_success'])} | {distance} | {percent(row['test_success'])} | "
            f"{row['train_seconds']:.0f} s | `{row['overrides']}` |"
        )
    return "\n".join(lines)


def write_experiment_tables(
    experiment: Path, n_timesteps: int, space: dict[str, Dimension], sweep_name: str
) -> list[dict[str, Any]]:
    """``trials.csv``, ``trials.md`` and (when a trial finished) ``best.yml`` of one experiment."""
    rows = experiment_rows(experiment, n_timesteps, space)
    with atomic_path(experiment / "trials.csv") as temp, open(temp, "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=TRIAL_COLUMNS, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    write_atomic(experiment / "trials.md", trials_markdown(rows) + "\n")
    best = best_trial(rows)
    if best is not None:
        write_atomic(experiment / "best.yml", best_entry(best, sweep_name))
    return rows


def read_wall_seconds(sweep_dir: Path) -> dict[str, float]:
    path = Path(sweep_dir) / "wall_seconds.json"
    return json.loads(path.read_text()) if path.exists() else {}


def format_minutes(seconds: float) -> str:
    return f"{seconds / 60:.1f} min"


def summary(sweep_dir: Path) -> tuple[str, list[dict[str, Any]]]:
    """The per-variant table of a sweep (markdown) and its rows; writes each experiment's tables."""
    sweep_dir = Path(sweep_dir)
    settings = configuration.load_yaml(sweep_dir / "sweep.yml")
    walls = read_wall_seconds(sweep_dir)
    space = search_space.read_space(settings["space"], settings["algo"], f"{sweep_dir / 'sweep.yml'}: space")
    variants = []
    for env_id, entry in settings["envs"].items():
        experiment = sweep_dir / env_id
        if not experiment.exists():
            continue
        n_timesteps = int(entry["base"]["n_timesteps"])
        rows = write_experiment_tables(experiment, n_timesteps, space, sweep_dir.name)
        best = best_trial(rows)
        start = next((row for row in rows if entry.get("start_point") and row["params"] == entry["start_point"]), None)
        variants.append(
            {
                "env_id": env_id,
                "trials": len(rows),
                "finished": sum(row["status"] == "finished" for row in rows),
                "pruned": sum(row["status"].startswith("pruned") for row in rows),
                "errors": sum(row["status"] == "error" for row in rows),
                "wall_seconds": walls.get(env_id, math.nan),
                "throws": sum(row["timesteps"] for row in rows),
                "best": best,
                "start": start,
            }
        )
    lines = [
        "| variant | trials (finished / pruned / failed) | throws trained | wall time | best validation success "
        "| its test success | the file's values: validation success | best trial's values |",
        "|---|---|---:|---:|---:|---:|---:|---|",
    ]
    for variant in variants:
        best, start = variant["best"] or {}, variant["start"] or {}
        start_text = percent(start.get("validation_success", math.nan))
        if start and start["status"] != "finished":
            start_text += f" ({start['status']})"
        lines.append(
            f"| {variant['env_id']} | {variant['trials']} ({variant['finished']} / {variant['pruned']} / "
            f"{variant['errors']}) | {variant['throws']:,} | {format_minutes(variant['wall_seconds'])} | "
            f"{percent(best.get('validation_success', math.nan))} | {percent(best.get('test_success', math.nan))} | "
            f"{start_text} | {'`' + best['overrides'] + '`' if best else '-'} |"
        )
    return "\n".join(lines), variants


def sweep_command(settings: dict[str, Any]) -> str:
    """The command as a user types it (``python -m ...``)."""
    return (
        "python " + settings["command"].split(" ", 1)[1]
        if settings["command"].startswith("python")
        else settings["command"]
    )


def docs_page(sweep_dir: Path, settings: dict[str, Any], table: str, variants: list[dict[str, Any]]) -> str:
    """``docs/tune.md``: the sweep's command, the per-variant table, every trial and the best entries."""
    lines = [
        f"# Hyperparameter sweep `{Path(sweep_dir).name}`",
        "",
        f"Written by `python -m agents.tune --report {sweep_dir} --readme` from the sweep folder of:",
        "",
        f"```bash\n{sweep_command(settings)}\n```",
        "",
        f"{settings['algo'].upper()}, {settings['trials']} trials per variant, pruner {settings['pruner']}, "
        f"{settings['cpus_per_trial']} CPU per trial, seed {settings['seed']}; search space: "
        "`agents/search_space.yml` as below. Success is measured on the "
        "validation targets during training and on the 1,024 test targets at the end of a finished trial. "
        "Wall times are from a 2-core machine shared with other work.",
        "",
        table,
        "",
    ]
    space = settings["space"]
    lines += [
        "Search space:",
        "",
        "```yaml",
        yaml.safe_dump(space, sort_keys=False, default_flow_style=None).strip(),
        "```",
        "",
    ]
    for variant in variants:
        experiment = Path(sweep_dir) / variant["env_id"]
        lines += [f"## {variant['env_id']}", "", (experiment / "trials.md").read_text().strip(), ""]
        if (experiment / "best.yml").exists():
            lines += [
                "Best configuration (`best.yml`):",
                "",
                "```yaml",
                (experiment / "best.yml").read_text().strip(),
                "```",
                "",
            ]
    return "\n".join(lines)


def readme_section(sweep_dir: Path, settings: dict[str, Any], table: str, variants: list[dict[str, Any]]) -> str:
    """The section on tuning (docs/hyperparameter-search.md): the commands, the cluster recipe, the measured sweep."""
    return f"""# Hyperparameter search: Optuna on Ray Tune (`agents/tune.py`)

```bash
pip install -e ".[tune]"                                   # Ray Tune and Optuna
python -m agents.tune --env BoxToss-ShortEnd-v0 --trials 12 --timesteps 150000   # starts a local Ray on all CPUs
python -m agents.tune --resume runs/tune/NAME              # a killed sweep continues where it stopped
python -m agents.tune --report runs/tune/NAME              # the tables again
```

Each trial samples the declared space of the algorithm (`agents/search_space.yml`, one Optuna distribution per
hyperparameter; `--space FILE` for another) around `agents/hyperparams/<algo>.yml` (`--set` overrides, `--timesteps`:
each trial's budget); the first trial is the file's own values.

Ray Tune runs the trials with Optuna's TPE sampler
(`OptunaSearch`) and prunes with ASHA (`--pruner asha|median|none`) on the periodic validation: each validation of
`agents.training.ValidationCallback` is reported to Tune, its objective being the validation success, then the mean
distance as a tie-break. Every trial is a run folder (`config.yml`, `evaluations.csv`, `model.zip`, the test
evaluation...; `python -m agents.evaluate` works on it) in `runs/tune/NAME/<env id>/trial_<id>/`, beside Ray's
`result.json`; a trial pins its torch threads, the engine's threads and numba's to the CPUs Ray gives it
(`--cpus-per-trial`, default 1). At the end `trials.md` lists the trials and `best.yml` is the best trial's
configuration as an entry ready for `agents/hyperparams/<algo>.yml`. Each trial reports its newest training
checkpoint to Tune, so `--resume` (`Tuner.restore`) continues unfinished trials from their checkpoints and then runs
the trials not yet started.

On a cluster: the same checkout at the same path and `pip install -e ".[tune]"` on every node (Ray's workers
import `agents` from the path the command runs in), and a folder every node sees at the same path (NFS) for the
results. Ray 2.60 authenticates with a token:

```bash
ray get-auth-token --generate && ray start --head --port 6379       # on the head node; prints the token
RAY_AUTH_MODE=token RAY_AUTH_TOKEN=<token> ray start --address HEAD_IP:6379   # on each worker node
python -m agents.tune --address auto --env BoxToss-Mixed-v0 --trials 64 --runs-dir /shared/tune   # on the head
```

The trials spread over the nodes' CPUs (`--cpus-per-trial` each, `--max-concurrent` at most), each writes its run
folder to `/shared/tune/NAME/<env id>/trial_<id>/`, and `trials.md`, `trials.csv` and `best.yml` land beside them.
`--address` was checked here against a separately started Ray (`RAY_AUTH_MODE=token python -m agents.tune
--address IP:PORT ...`), on one machine only: no multi-node cluster was at hand.

**A real sweep**, run on this project's shared 2-core machine (`{sweep_command(settings)}`; every trial, its
sampled values and the best entries: [docs/tune.md](docs/tune.md)):

{table}
"""
