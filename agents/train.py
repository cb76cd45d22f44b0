"""Train PPO, SAC or TD3 (Stable-Baselines3) on a BoxToss env; one folder per run.

    python -m agents.train                                           # PPO on BoxToss-v0 (agents/hyperparams/ppo.yml)
    python -m agents.train --algo sac --env BoxToss-ShortEnd-v0      # hyperparameters: agents/hyperparams/sac.yml
    python -m agents.train --name long --set n_timesteps=1000000 learning_rate=1e-4
    python -m agents.train --env BoxToss-ThisSideUp-v0 --set env_kwargs.max_spin=10
    python -m agents.train --resume runs/long --set n_timesteps=2000000   # continue from the last checkpoint

Hyperparameters come from ``agents/hyperparams/<algo>.yml`` (RL Zoo's format) and
``agents/hyperparams/project.yml`` (our own settings); see ``agents.config``. The run folder is
described in ``agents.training``. A bad configuration is one line naming the key, before anything
is created.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path
from typing import Any, cast

import gymnasium as gym

import box_toss_env  # noqa: F401  (registers the BoxToss envs)
from agents import algorithms
from agents import config as configuration
from agents.envs import BALLISTIC, STACK_COMMANDS, read_env_wrapper
from agents.policies import UnreadableModelError
from agents.run_folder import RunFolderError, check_component, check_runs_dir, lock_run, unlock_run
from agents.training import RUNS, check_resume, new_run_dir, train, write_run_files
from box_toss_env.envs.ballistic import DEFAULT_OFFSET_RANGE, DEFAULT_TURN_RANGE, check_command_settings
from box_toss_env.envs.stack_commands import check_stack_command_settings
from box_toss_env.envs.stack_task import StackConfig


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = configuration.OneLineParser(prog="python -m agents.train", description=__doc__.split("\n\n")[0])
    parser.add_argument("--algo", choices=sorted(algorithms.ALGORITHMS), help="algorithm (default: ppo)")
    parser.add_argument("--env", help="env id, a key of the hyperparameter file (default: BoxToss-v0)")
    parser.add_argument(
        "--hyperparams", type=Path, default=configuration.HYPERPARAMS, help="folder of <algo>.yml and project.yml"
    )
    parser.add_argument(
        "--set",
        nargs="*",
        default=[],
        action="extend",
        metavar="KEY=VALUE",
        dest="overrides",
        help="override hyperparameters, e.g. n_timesteps=100000 policy_kwargs.net_arch=[64,64]",
    )
    parser.add_argument("--seed", type=int, help="seed of the model and the envs, >= 0 (default: 0)")
    parser.add_argument("--name", help="run folder name (default: algorithm, env id and time)")
    parser.add_argument("--runs-dir", type=Path, default=RUNS)
    parser.add_argument("--resume", type=Path, metavar="RUN", help="continue a run from its last checkpoint")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--no-eval", action="store_true", help="skip the final evaluation on the test targets")
    return parser.parse_args(argv)


def resolve(args: argparse.Namespace) -> tuple[str, str, int, dict]:
    """(algo, env id, seed, configuration) of the command, checked; raises ConfigError."""
    if args.resume:
        saved_path = args.resume / "config.yml"
        if not saved_path.exists():
            raise configuration.ConfigError(f"--resume {args.resume}: not a run folder (no config.yml)")
        saved = configuration.load_yaml(saved_path)
        algo, env_id, seed = saved.get("algo", "ppo"), saved["env_id"], saved["seed"]
        version = saved.get("version", box_toss_env.__version__)
        for option, given, recorded in (
            ("--algo", args.algo, algo),
            ("--env", args.env, env_id),
            ("--seed", args.seed, seed),
            ("version", box_toss_env.__version__, version),
        ):
            if given is not None and given != recorded:
                what = "box_toss_env" if option == "version" else option
                raise configuration.ConfigError(
                    f"--resume {args.resume}: the run was trained with {what} {recorded}, "
                    f"not {given}; resume it as it was, or start a new run"
                )
        if args.name is not None:
            raise configuration.ConfigError("--name and --resume: a resumed run keeps its folder; drop --name")
        config = configuration.apply_overrides(saved["hyperparams"], args.overrides, algo)
    else:
        algo, env_id = args.algo or "ppo", args.env or "BoxToss-v0"
        seed = 0 if args.seed is None else args.seed
        if args.name is not None:
            check_component(args.name, "--name")
        config = configuration.apply_overrides(
            configuration.load_hyperparams(algo, env_id, args.hyperparams), args.overrides, algo
        )
    if seed < 0:
        raise configuration.ConfigError(f"--seed must be an integer >= 0, got {seed}")
    config.setdefault("env_kwargs", {})
    configuration.check_config(config, algo)
    if env_id not in gym.registry:
        raise configuration.ConfigError(
            f"--env {env_id!r} is not registered; BoxToss ids: "
            f"{sorted(k for k in gym.registry if k.startswith('BoxToss'))}"
        )
    try:
        env = gym.make(env_id, **config["env_kwargs"])  # the env's own checks of env_kwargs
    except (TypeError, ValueError) as error:
        raise configuration.ConfigError(f"env_kwargs: {error}") from None
    try:
        wrapper = read_env_wrapper(config.get("env_wrapper"))
        stack = isinstance(cast(Any, env.unwrapped).config, StackConfig)
        if wrapper is not None and (wrapper[0] == STACK_COMMANDS) != stack:
            raise ValueError(
                f"{wrapper[0]} does not act on {env_id}; "
                f"{'BoxToss-Stack envs take' if stack else 'it is for BoxToss-Stack envs only, use'} "
                f"{STACK_COMMANDS if stack else BALLISTIC}, or no env_wrapper (the env's own actions)"
            )
        if wrapper is not None and stack:
            check_stack_command_settings(**wrapper[1])
        elif wrapper is not None:  # the wrapper's own checks of its kwargs
            defaults = {
                "flight_time_range": None,
                "offset_range": DEFAULT_OFFSET_RANGE,
                "turn_range": DEFAULT_TURN_RANGE,
            }
            check_command_settings(cast(Any, env.unwrapped).config, **{**defaults, **wrapper[1]})
    except (TypeError, ValueError) as error:
        raise configuration.ConfigError(f"env_wrapper: {error}") from None
    finally:
        env.close()
    return algo, env_id, seed, config


def main(argv: list[str] | None = None) -> Path:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parse_args(argv)
    try:
        algo, env_id, seed, config = resolve(args)
        if args.resume:
            check_resume(args.resume, algo, config)
            lock_run(args.resume)  # one training of a run at a time
        else:
            check_runs_dir(args.runs_dir)
        run_dir = args.resume or new_run_dir(args.runs_dir, args.name, env_id, algo)
    except (configuration.ConfigError, RunFolderError) as error:
        print(f"agents.train: {error}", file=sys.stderr)
        sys.exit(2)
    write_run_files(
        run_dir, algo, env_id, seed, config, shlex.join([Path(sys.executable).name, "-m", "agents.train", *argv])
    )
    print(f"training {algo.upper()} on {env_id} for {config['n_timesteps']:,} steps (seed {seed}) into {run_dir}")
    try:
        timing = train(
            run_dir,
            config,
            env_id,
            seed,
            algo,
            resume=bool(args.resume),
            progress_bar=not args.no_progress,
            final_eval=not args.no_eval,
        )
    except UnreadableModelError as error:
        sys.exit(f"agents.train: {error}")
    finally:
        unlock_run(run_dir)
    print(
        f"trained {timing['timesteps']:,} steps in {timing['wall_seconds']:.1f} s "
        f"(env {timing['env_share']:.0%} of the training loop, validation {timing['eval_seconds']:.1f} s)"
    )
    if not args.no_eval:
        results = json.loads((run_dir / "eval" / "default" / "results.json").read_text())
        if "mean_height" in results:  # a stacking env: scored per episode
            print(
                f"test episodes: success {results['success_rate']:.1%}, mean final height "
                f"{results['mean_height']:.3f} m, stack fell {results['fall_rate']:.1%}"
            )
            return run_dir
        print(
            f"test targets: success {results['success_rate']:.1%}, mean distance {results['mean_distance']:.3f} m, "
            f"face accuracy {results['face_accuracy']:.1%}"
        )
    return run_dir


if __name__ == "__main__":
    main()
