"""Evaluate a baseline as a run folder: random throws, or the oracle that plans with the simulator.

python -m agents.baselines random            # runs/random: uniform actions
python -m agents.baselines oracle            # runs/oracle: cross-entropy search per target (agents.oracle)
python -m agents.baselines oracle --env BoxToss-ShortEnd-v0 --set initial=2048 population=256
python -m agents.evaluate runs/oracle --env-kwargs solver=seed dt=0.0009765625   # as any run
"""

from __future__ import annotations

import argparse
import shlex
import sys

from agents.command_line import COUNT, RUNS, OneLineParser, folder, one_line_errors, single_name
from agents.targets import TEST_TARGETS

PROG = "python -m agents.baselines"


def make_parser() -> OneLineParser:
    parser = OneLineParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("algo", choices=("random", "oracle"))
    parser.add_argument("--env", default="BoxToss-v0", help="env id (default: BoxToss-v0)")
    parser.add_argument("--env-kwargs", nargs="*", default=[], metavar="KEY=VALUE")
    parser.add_argument(
        "--set",
        nargs="*",
        default=[],
        action="extend",
        metavar="KEY=VALUE",
        dest="settings",
        help="baseline settings, e.g. seed=1 (random) or population=128 iterations=8 (oracle)",
    )
    parser.add_argument("--name", type=single_name, help="run folder name (default: the baseline's name)")
    parser.add_argument("--runs-dir", type=folder, default=RUNS)
    parser.add_argument("--targets", type=COUNT, default=TEST_TARGETS, help=f"test targets, {COUNT.allowed}")
    return parser


def check_args(args: argparse.Namespace) -> tuple[dict, dict]:
    """(env kwargs, baseline settings), the env id, its kwargs and the settings checked before anything is made."""
    import gymnasium as gym

    import box_toss_env  # noqa: F401  (registers the BoxToss envs)
    from agents.config import ConfigError
    from agents.evaluation import make_baseline, parse_kwargs

    try:
        env_kwargs, settings = parse_kwargs(args.env_kwargs), parse_kwargs(args.settings)
    except ConfigError as error:
        raise ConfigError(f"--env-kwargs / --set: {error}") from None
    if args.env not in gym.registry:
        raise ConfigError(f"--env {args.env!r} is not registered")
    try:
        gym.make(args.env, **env_kwargs).close()
    except (TypeError, ValueError) as error:
        raise ConfigError(f"--env-kwargs: {error}") from None
    try:
        make_baseline(args.algo, settings)
    except (TypeError, ValueError) as error:
        raise ConfigError(f"--set: {error}") from None
    return env_kwargs, settings


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = make_parser().parse_args(argv)
    with one_line_errors(PROG):
        env_kwargs, settings = check_args(args)
        from agents.evaluation import evaluate_run, make_baseline_run
        from agents.run_folder import check_runs_dir

        check_runs_dir(args.runs_dir)
        run_dir = make_baseline_run(
            args.algo,
            args.runs_dir / (args.name or args.algo),
            args.env,
            env_kwargs,
            settings,
            shlex.join(["python", "-m", "agents.baselines", *argv]),
        )
        results = evaluate_run(run_dir, n_targets=args.targets)
    print(f"{args.algo}: acted on {args.targets} targets in {results['act_seconds']:.1f} s")


if __name__ == "__main__":
    main()
