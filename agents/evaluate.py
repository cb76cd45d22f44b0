"""Evaluate a run folder headless on fixed seeded targets: a table, figures and optionally a GIF.

    python -m agents.evaluate runs/NAME                                   # 1,024 targets, seeds 10000...
    python -m agents.evaluate runs/NAME --env-kwargs solver=seed dt=0.0009765625 --tag seed-1024
    python -m agents.evaluate runs/NAME --video 4                         # also a GIF of 4 throws

How targets are drawn and scored: ``agents.evaluation``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import gymnasium as gym

from agents import report
from agents.config import ConfigError, OneLineParser, load_yaml
from agents.evaluation import STACK_TEST_EPISODES, TEST_FIRST_SEED, TEST_TARGETS, evaluate_run, parse_kwargs
from agents.policies import UnreadableModelError
from agents.run_folder import RunFolderError, check_component


def check_args(args: argparse.Namespace) -> dict:
    """The env kwargs of the command, every option checked first (a ConfigError or RunFolderError)."""
    if not (args.run / "config.yml").exists():
        raise ConfigError(f"{args.run} is not a run folder (no config.yml)")
    for option, value, low in (
        ("--targets", 1 if args.targets is None else args.targets, 1),
        ("--first-seed", args.first_seed, 0),
        ("--video", args.video, 0),
    ):
        if value < low:
            raise ConfigError(f"{option} must be an integer >= {low}, got {value}")
    if args.tag is not None:
        check_component(args.tag, "--tag")
    env_kwargs = parse_kwargs(args.env_kwargs)
    config = load_yaml(args.run / "config.yml")
    if not isinstance(config, dict) or "env_id" not in config:
        raise ConfigError(f"{args.run / 'config.yml'} is not a run's configuration (no env_id)")
    try:
        gym.make(config["env_id"], **{**config.get("env_kwargs", {}), **env_kwargs}).close()
    except (TypeError, ValueError) as error:
        raise ConfigError(f"--env-kwargs: {error}") from None
    return env_kwargs


def main(argv: list[str] | None = None) -> None:
    parser = OneLineParser(prog="python -m agents.evaluate", description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path, help="run folder (runs/NAME)")
    parser.add_argument(
        "--model",
        default="final",
        choices=("final", "best"),
        help="the model at the end of training, or the one with the best validation success",
    )
    parser.add_argument(
        "--env-kwargs",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="change env settings for the evaluation, e.g. solver=seed dt=0.0009765625",
    )
    parser.add_argument("--tag", help="name of the results folder RUN/eval/TAG (default: from the env kwargs)")
    parser.add_argument(
        "--targets",
        type=int,
        help=f"number of test targets (default: {TEST_TARGETS}; a stacking env's episodes: {STACK_TEST_EPISODES})",
    )
    parser.add_argument("--first-seed", type=int, default=TEST_FIRST_SEED)
    parser.add_argument("--video", type=int, default=0, metavar="N", help="also write a GIF of N throws")
    parser.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    args = parser.parse_args(argv)
    try:
        env_kwargs = check_args(args)
    except (ConfigError, RunFolderError) as error:
        print(f"agents.evaluate: {error}", file=sys.stderr)
        sys.exit(2)
    try:
        results = evaluate_run(
            args.run,
            model=args.model,
            env_kwargs=env_kwargs,
            tag=args.tag,
            n_targets=args.targets,
            first_seed=args.first_seed,
        )
    except (UnreadableModelError, RunFolderError) as error:
        sys.exit(f"agents.evaluate: {error}")
    out = args.run / "eval" / results["tag"]
    if not args.no_plots:
        for path in report.plot_run(args.run, out):
            print(f"figure: {path}")
    if args.video:
        path = report.record_video(
            args.run, out / "throws.gif", args.video, model=args.model, env_kwargs=results["env_kwargs"]
        )
        print(f"video: {path}")


if __name__ == "__main__":
    main()
