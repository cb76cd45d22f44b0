"""Evaluate a run folder headless on fixed seeded targets: a table, figures and optionally a GIF.

    box-toss evaluate runs/NAME                                   # 1,024 targets, seeds 10000...
    box-toss evaluate runs/NAME --env-kwargs solver=seed dt=0.0009765625 --tag seed-1024
    box-toss evaluate runs/NAME --video 4                         # also a GIF of 4 throws (the render extra)

(``python -m agents.evaluate`` is the same command.) How targets are drawn and scored: ``agents.evaluation``.
Every option and every file the evaluation reads (config.yml, the model, its statistics) is checked before
anything is written: a refusal is one line naming the option or file.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from typing import Any

from agents.command_line import (
    COUNT,
    SEED,
    CommandError,
    Integer,
    OneLineParser,
    check_seed_range,
    folder,
    one_line_errors,
    single_name,
)
from agents.targets import STACK_TEST_EPISODES, TEST_FIRST_SEED, TEST_TARGETS

PROG = "box-toss evaluate"
RENDER_MODULES = {"pygame": "pygame-ce", "PIL": "Pillow"}  # what drawing a GIF imports (the render extra)
PLOT_MODULES = {"matplotlib": "matplotlib"}  # what the figures import (the train extra)


def make_parser() -> OneLineParser:
    """The command's options, each checked as it is parsed (its type names its range)."""
    parser = OneLineParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=folder, help="run folder (runs/NAME)")
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
    parser.add_argument(
        "--tag", type=single_name, help="name of the results folder RUN/eval/TAG (default: from the env kwargs)"
    )
    parser.add_argument(
        "--targets",
        type=COUNT,
        help=f"number of test targets (default: {TEST_TARGETS}; a stacking env's episodes: {STACK_TEST_EPISODES})",
    )
    parser.add_argument(
        "--first-seed", type=SEED, default=TEST_FIRST_SEED, help=f"seed of the first target, {SEED.allowed}"
    )
    parser.add_argument(
        "--video", type=Integer(0), default=0, metavar="N", help="also write a GIF of N throws (the render extra)"
    )
    parser.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    return parser


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    return make_parser().parse_args(argv)


def missing_extra(modules: dict[str, str], extra: str, option: str) -> None:
    """A CommandError naming ``extra`` if a module ``option`` needs is not installed."""
    missing = [package for module, package in modules.items() if importlib.util.find_spec(module) is None]
    if missing:
        raise CommandError(
            f"{option} needs {' and '.join(missing)}, which the {extra} extra installs: "
            f"pip install 'box_toss_env[{extra}]' (or give no {option})"
        )


def check_args(args: argparse.Namespace) -> tuple[dict[str, Any], dict[str, Any]]:
    """(the run's checked config.yml, the env kwargs of the command), every option checked first."""
    import gymnasium as gym

    import box_toss_env  # noqa: F401  (registers the BoxToss envs)
    from agents.config import ConfigError
    from agents.evaluation import THROWN_IN, is_stack, parse_kwargs
    from agents.run_files import read_run_config

    if args.video:
        missing_extra(RENDER_MODULES, "render", "--video")
    if not args.no_plots:
        missing_extra(PLOT_MODULES, "train", "plots (without --no-plots)")
    config = read_run_config(args.run)
    env_id = THROWN_IN.get(config["env_id"], config["env_id"])
    count = args.targets or (STACK_TEST_EPISODES if is_stack(env_id) else TEST_TARGETS)
    try:
        check_seed_range("--first-seed", args.first_seed, count)
    except ValueError as error:
        raise ConfigError(str(error)) from None
    try:
        env_kwargs = parse_kwargs(args.env_kwargs)
    except ConfigError as error:
        raise ConfigError(f"--env-kwargs: {error}") from None
    if env_id not in gym.registry:
        raise ConfigError(f"{args.run / 'config.yml'} names env {env_id!r}, which is not registered")
    try:
        gym.make(env_id, **{**(config.get("env_kwargs") or {}), **env_kwargs}).close()
    except (TypeError, ValueError) as error:
        raise ConfigError(f"--env-kwargs: {error}") from None
    return config, env_kwargs


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    with one_line_errors(PROG):
        _, env_kwargs = check_args(args)
        from agents import report
        from agents.evaluation import evaluate_run

        results = evaluate_run(
            args.run,
            model=args.model,
            env_kwargs=env_kwargs,
            tag=args.tag,
            n_targets=args.targets,
            first_seed=args.first_seed,
        )
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
    main(sys.argv[1:])
