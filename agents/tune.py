"""Tune hyperparameters with Optuna (TPE) on Ray Tune, with pruning; one machine or a Ray cluster.

    python -m agents.tune --env BoxToss-ShortEnd-v0 --trials 12 --timesteps 150000   # a local Ray, all CPUs
    python -m agents.tune --env BoxToss-v0 BoxToss-ThisSideUp-v0 --name face --num-cpus 2
    python -m agents.tune --algo sac --env BoxToss-v0 --set n_envs=64 --space my_space.yml
    python -m agents.tune --address auto --env BoxToss-Mixed-v0 --runs-dir /shared/tune   # on a cluster
    python -m agents.tune --resume runs/tune/face       # a killed sweep continues where it stopped
    python -m agents.tune --report runs/tune/face --readme   # the tables again (and the README's section)

Each env id is one Tune experiment in ``runs/tune/NAME/<env id>/``: trials sample the declared space
of the algorithm (``agents/search_space.yml``) around its hyperparameter file
(``agents/hyperparams/<algo>.yml``, with ``--set`` overrides and ``--timesteps``, each trial's
budget), the first trial being the file's own values. Every trial is a run folder
(``agents.tuning``); at the end, ``trials.md`` / ``trials.csv`` list them and ``best.yml`` is the best
configuration as an entry for ``agents/hyperparams/<algo>.yml`` (``agents.sweep_report``).
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path

import gymnasium as gym

import box_toss_env  # noqa: F401  (registers the BoxToss envs)
from agents import algorithms, search_space, sweep_report, tuning
from agents import config as configuration
from agents.report import write_readme
from box_toss_env.files import write_atomic

RUNS = Path("runs") / "tune"
DOCS = Path(__file__).resolve().parents[1] / "docs" / "tune.md"


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--algo", default="ppo", choices=sorted(algorithms.ALGORITHMS))
    parser.add_argument("--env", nargs="+", default=["BoxToss-v0"], help="env ids, one experiment each")
    parser.add_argument("--trials", type=int, default=12, help="trials per env id")
    parser.add_argument("--timesteps", type=int, help="env steps (throws) per trial (default: the file's n_timesteps)")
    parser.add_argument(
        "--set",
        nargs="*",
        default=[],
        action="extend",
        metavar="KEY=VALUE",
        dest="overrides",
        help="override the hyperparameters every trial starts from",
    )
    parser.add_argument(
        "--hyperparams", type=Path, default=configuration.HYPERPARAMS, help="folder of <algo>.yml and project.yml"
    )
    parser.add_argument("--space", type=Path, default=search_space.SEARCH_SPACE, help="search space file")
    parser.add_argument("--seed", type=int, default=0, help="training seed of every trial, and the sampler's")
    parser.add_argument("--pruner", default="asha", choices=tuning.PRUNERS)
    parser.add_argument(
        "--grace-period", type=int, help="env steps before a trial can be pruned (default: a quarter of the budget)"
    )
    parser.add_argument("--cpus-per-trial", type=int, default=1)
    parser.add_argument("--max-concurrent", type=int, help="trials at once (default: as many as the CPUs allow)")
    parser.add_argument(
        "--address",
        help="a running Ray cluster (ray start --head ...; 'auto' finds it on this node); default: start a local Ray",
    )
    parser.add_argument("--num-cpus", type=int, help="CPUs of the local Ray (default: all)")
    parser.add_argument("--name", help="sweep folder name (default: algorithm and time)")
    parser.add_argument(
        "--runs-dir", type=Path, default=RUNS, help="where sweep folders go (on a cluster: a path every node sees)"
    )
    parser.add_argument("--resume", type=Path, metavar="SWEEP", help="continue a killed sweep")
    parser.add_argument("--report", type=Path, metavar="SWEEP", help="only write the tables of a sweep")
    parser.add_argument(
        "--readme", action="store_true", help="also write docs/tune.md and docs/hyperparameter-search.md"
    )
    return parser.parse_args(argv)


def base_config(args: argparse.Namespace, env_id: str) -> dict:
    """What every trial on ``env_id`` starts from, checked."""
    overrides = list(args.overrides) + ([f"n_timesteps={args.timesteps}"] if args.timesteps else [])
    config = configuration.apply_overrides(
        configuration.load_hyperparams(args.algo, env_id, args.hyperparams), overrides, args.algo
    )
    config.setdefault("env_kwargs", {})
    configuration.check_config(config, args.algo)
    if env_id not in gym.registry:
        raise configuration.ConfigError(
            f"--env {env_id!r} is not registered; BoxToss ids: "
            f"{sorted(k for k in gym.registry if k.startswith('BoxToss'))}"
        )
    return config


def new_sweep(args: argparse.Namespace, command: str) -> tuple[Path, dict]:
    """The sweep folder and ``sweep.yml``: everything needed to run or resume each experiment."""
    space_entries = configuration.read_mapping(args.space).get(args.algo)
    space = search_space.load_space(args.algo, args.space)
    envs = {}
    for env_id in args.env:
        base = base_config(args, env_id)
        search_space.trial_config(base, space, search_space.first_point(space), args.algo)  # the space's values fit
        envs[env_id] = {"base": base, "start_point": search_space.current_point(space, base)}
    name = args.name or f"{args.algo}-{time.strftime('%Y%m%d-%H%M%S')}"
    sweep_dir = args.runs_dir / name
    if (sweep_dir / "sweep.yml").exists():
        raise configuration.ConfigError(
            f"{sweep_dir} already holds a sweep: choose another --name, or --resume {sweep_dir}"
        )
    settings = {
        "command": command,
        "algo": args.algo,
        "trials": args.trials,
        "seed": args.seed,
        "pruner": args.pruner,
        "grace_period": args.grace_period,
        "cpus_per_trial": args.cpus_per_trial,
        "max_concurrent": args.max_concurrent,
        "space": space_entries,
        "envs": envs,
    }
    sweep = make_sweep(settings, args.env[0])
    tuning.check_sweep(sweep)
    sweep_dir.mkdir(parents=True, exist_ok=True)
    configuration.save_yaml(settings, sweep_dir / "sweep.yml")
    return sweep_dir, settings


def make_sweep(settings: dict, env_id: str) -> tuning.Sweep:
    entry = settings["envs"][env_id]
    space = search_space.read_space(settings["space"], settings["algo"], "sweep.yml: space")
    return tuning.Sweep(
        algo=settings["algo"],
        env_id=env_id,
        base=entry["base"],
        space=space,
        trials=settings["trials"],
        seed=settings["seed"],
        cpus_per_trial=settings["cpus_per_trial"],
        pruner=settings["pruner"],
        grace_period=settings["grace_period"],
        command=settings["command"],
        start_point=entry["start_point"],
    )


def run(sweep_dir: Path, settings: dict) -> None:
    """Run (or continue) each env id's experiment; an experiment with its tables written is done."""
    for env_id in settings["envs"]:
        experiment = sweep_dir / env_id
        if (experiment / "trials.md").exists():
            print(f"{env_id}: done ({experiment / 'trials.md'})")
            continue
        sweep = make_sweep(settings, env_id)
        if (experiment / "tuner.pkl").exists():
            print(f"{env_id}: resuming {experiment}")
            tuner = tuning.restore_tuner(sweep, experiment)
        else:
            print(
                f"{env_id}: {sweep.trials} trials of {sweep.n_timesteps:,} throws, {sweep.algo.upper()}, "
                f"pruner {sweep.pruner}, into {experiment}"
            )
            tuner = tuning.make_tuner(sweep, sweep_dir, env_id, settings["max_concurrent"])
        grid = tuner.fit()
        if grid.num_terminated + grid.num_errors < sweep.trials:
            sys.exit(
                f"agents.tune: {env_id} stopped before its {sweep.trials} trials ended; "
                f"continue with: python -m agents.tune --resume {sweep_dir}"
            )
        sweep_report.write_experiment_tables(experiment, sweep.n_timesteps, sweep.space, sweep_dir.name)


def report(sweep_dir: Path, readme: bool) -> str:
    table, variants = sweep_report.summary(sweep_dir)
    print(table)
    for variant in variants:
        print(
            f"\n{variant['env_id']}: {sweep_dir / variant['env_id'] / 'trials.md'}"
            + (f", best configuration {sweep_dir / variant['env_id'] / 'best.yml'}" if variant["best"] else "")
        )
    if readme:
        settings = configuration.load_yaml(sweep_dir / "sweep.yml")
        section = sweep_report.readme_section(sweep_dir, settings, table, variants)
        write_atomic(DOCS, sweep_report.docs_page(sweep_dir, settings, table, variants))
        write_readme(section, "tune")
    return table


def main(argv: list[str] | None = None) -> Path:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parse_args(argv)
    command = shlex.join([Path(sys.executable).name, "-m", "agents.tune", *argv])
    if args.report:
        report(args.report, args.readme)
        return args.report
    try:
        if args.resume:
            sweep_dir = args.resume
            if not (sweep_dir / "sweep.yml").exists():
                raise configuration.ConfigError(f"--resume {sweep_dir}: not a sweep folder (no sweep.yml)")
            settings = configuration.load_yaml(sweep_dir / "sweep.yml")
        else:
            sweep_dir, settings = new_sweep(args, command)
    except configuration.ConfigError as error:
        sys.exit(f"agents.tune: {error}")
    tuning.start_ray(args.address, args.num_cpus)
    run(sweep_dir, settings)
    report(sweep_dir, args.readme)
    return sweep_dir


if __name__ == "__main__":
    main()
