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
from pathlib import Path

from agents.evaluation import TEST_TARGETS, evaluate_run, make_baseline_run, parse_kwargs
from agents.run_folder import RunFolderError, check_component
from agents.training import RUNS


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("algo", choices=("random", "oracle"))
    parser.add_argument("--env", default="BoxToss-v0")
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
    parser.add_argument("--name", help="run folder name (default: the baseline's name)")
    parser.add_argument("--runs-dir", type=Path, default=RUNS)
    parser.add_argument("--targets", type=int, default=TEST_TARGETS)
    args = parser.parse_args(argv)
    try:
        if args.name is not None:
            check_component(args.name, "--name")
        if args.targets < 1:
            raise RunFolderError(f"--targets must be an integer >= 1, got {args.targets}")
    except RunFolderError as error:
        print(f"agents.baselines: {error}", file=sys.stderr)
        sys.exit(2)
    run_dir = make_baseline_run(
        args.algo,
        args.runs_dir / (args.name or args.algo),
        args.env,
        parse_kwargs(args.env_kwargs),
        parse_kwargs(args.settings),
        shlex.join(["python", "-m", "agents.baselines", *argv]),
    )
    results = evaluate_run(run_dir, n_targets=args.targets)
    print(f"{args.algo}: acted on {args.targets} targets in {results['act_seconds']:.1f} s")


if __name__ == "__main__":
    main()
