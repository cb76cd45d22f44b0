"""Train PPO, SAC or TD3 (Stable-Baselines3) on a BoxToss env; one folder per run.

    box-toss train                                           # PPO on BoxToss-v0 (agents/hyperparams/ppo.yml)
    box-toss train --algo sac --env BoxToss-ShortEnd-v0      # hyperparameters: agents/hyperparams/sac.yml
    box-toss train --name long --set n_timesteps=1000000 learning_rate=1e-4
    box-toss train --env BoxToss-ThisSideUp-v0 --set env_kwargs.max_spin=10
    box-toss train --resume runs/long --set n_timesteps=2000000   # continue from the last checkpoint

(``python -m agents.train`` is the same command.) Hyperparameters come from ``agents/hyperparams/<algo>.yml``
(RL Zoo's format) and ``agents/hyperparams/project.yml`` (our own settings); see ``agents.config``. The run folder
is described in ``agents.training``. Every option, the configuration and, on ``--resume``, every file of the run
is checked before anything is created or rewritten: a refusal is one line naming the option, key or file.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

from agents import algorithms
from agents import config as configuration
from agents.command_line import RUNS, SEED, Integer, OneLineParser, folder, one_line_errors, single_name

PROG = "box-toss train"


def make_parser() -> OneLineParser:
    """The command's options, each checked as it is parsed (its type names its range)."""
    parser = OneLineParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("--algo", choices=sorted(algorithms.ALGORITHMS), help="algorithm (default: ppo)")
    parser.add_argument("--env", help="env id, a key of the hyperparameter file (default: BoxToss-v0)")
    parser.add_argument(
        "--hyperparams", type=folder, default=configuration.HYPERPARAMS, help="folder of <algo>.yml and project.yml"
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
    parser.add_argument("--seed", type=SEED, help=f"seed of the model and the envs, {SEED.allowed} (default: 0)")
    parser.add_argument("--name", type=single_name, help="run folder name (default: algorithm, env id and time)")
    parser.add_argument("--runs-dir", type=folder, default=RUNS, help="folder of the run folders (default: runs)")
    parser.add_argument("--resume", type=folder, metavar="RUN", help="continue a run from its newest checkpoint")
    parser.add_argument(
        "--from-steps",
        type=Integer(0),
        metavar="STEPS",
        help="with --resume: continue from the checkpoint at STEPS (when the newer ones are damaged)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--no-eval", action="store_true", help="skip the final evaluation on the test targets")
    return parser


def parse_args(argv: list[str]) -> argparse.Namespace:
    return make_parser().parse_args(argv)


@dataclass
class TrainingPlan:
    """What a command trains, every part checked: the algorithm, env id, seed, configuration and the shape
    of the env's observations."""

    algo: str
    env_id: str
    seed: int
    config: dict[str, Any]
    observation_shape: tuple[int, ...]


def resume_settings(args: argparse.Namespace) -> tuple[str, str, int, dict[str, Any]]:
    """(algo, env id, seed, configuration) of the run ``--resume`` names, from its checked config.yml, with
    ``--set``; a ConfigError if an option disagrees with the run."""
    import box_toss_env
    from agents.run_files import read_run_config

    try:
        saved = read_run_config(args.resume)
    except ValueError as error:  # RunFolderError, DamagedFileError: named after the option
        raise type(error)(f"--resume {args.resume}: {error}") from None
    algo, env_id = saved["algo"], saved["env_id"]
    if algo not in algorithms.ALGORITHMS or saved.get("goal"):
        raise configuration.ConfigError(f"--resume {args.resume}: a {algo} run is not trained by this command")
    version = saved.get("version", box_toss_env.__version__)
    for option, given, recorded in (
        ("--algo", args.algo, algo),
        ("--env", args.env, env_id),
        ("--seed", args.seed, saved["seed"]),
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
    return algo, env_id, saved["seed"], with_overrides(saved["hyperparams"], args.overrides, algo)


def with_overrides(config: dict[str, Any], overrides: list[str], algo: str) -> dict[str, Any]:
    """``config`` with ``--set``'s overrides (a ConfigError naming ``--set`` for a malformed or unknown one)."""
    try:
        return configuration.apply_overrides(config, overrides, algo)
    except configuration.ConfigError as error:
        raise configuration.ConfigError(f"--set: {error}") from None


def resolve(args: argparse.Namespace) -> TrainingPlan:
    """What the command trains, checked; raises ConfigError (or DamagedFileError for a damaged config.yml)."""
    import gymnasium as gym

    import box_toss_env  # noqa: F401  (registers the BoxToss envs)

    if args.from_steps is not None and args.resume is None:
        raise configuration.ConfigError("--from-steps goes with --resume RUN")
    if args.resume:
        algo, env_id, seed, config = resume_settings(args)
    else:
        algo = "ppo" if args.algo is None else args.algo
        env_id = "BoxToss-v0" if args.env is None else args.env
        seed = 0 if args.seed is None else args.seed
        if not Path(args.hyperparams).is_dir():
            raise configuration.ConfigError(f"--hyperparams {args.hyperparams} is not a folder (of <algo>.yml)")
        if env_id not in gym.registry:
            raise configuration.ConfigError(
                f"--env {env_id!r} is not registered; BoxToss ids: "
                f"{sorted(k for k in gym.registry if k.startswith('BoxToss'))}"
            )
        config = with_overrides(configuration.load_hyperparams(algo, env_id, args.hyperparams), args.overrides, algo)
    config.setdefault("env_kwargs", {})
    configuration.check_config(config, algo)
    if env_id not in gym.registry:
        raise configuration.ConfigError(
            f"--env {env_id!r} is not registered; BoxToss ids: "
            f"{sorted(k for k in gym.registry if k.startswith('BoxToss'))}"
        )
    try:
        env = gym.make(env_id, **(config["env_kwargs"] or {}))  # the env's own checks of env_kwargs
    except (TypeError, ValueError) as error:
        raise configuration.ConfigError(f"env_kwargs: {error}") from None
    try:
        if not hasattr(env.observation_space, "shape") or env.observation_space.shape is None:
            raise configuration.ConfigError(
                f"--env {env_id}: its observations are a {type(env.observation_space).__name__}; this command "
                "trains on flat ones (the goal env's agents: python -m agents.benchmark --envs BoxToss-Goal-v0)"
            )
        from stable_baselines3.common.preprocessing import is_image_space

        images = is_image_space(env.observation_space)
        wanted, kind = ("CnnPolicy", "image") if images else ("MlpPolicy", "flat (Box)")
        if config["policy"] != wanted:
            raise configuration.ConfigError(
                f"policy {config['policy']} does not read {env_id}'s {kind} observations: use {wanted}"
            )
        check_env_wrapper(env, env_id, config)
        shape = tuple(env.observation_space.shape)
    finally:
        env.close()
    return TrainingPlan(algo, env_id, seed, config, shape)


def check_env_wrapper(env, env_id: str, config: dict[str, Any]) -> None:
    """A ConfigError unless ``config``'s ``env_wrapper`` acts on ``env`` with kwargs it accepts."""
    from agents.envs import BALLISTIC, STACK_COMMANDS, read_env_wrapper
    from box_toss_env.envs.ballistic import DEFAULT_OFFSET_RANGE, DEFAULT_TURN_RANGE, check_command_settings
    from box_toss_env.envs.stack_commands import check_stack_command_settings
    from box_toss_env.envs.stack_task import StackConfig

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


def prepare_resume(run_dir: Path, plan: TrainingPlan, from_steps: int | None):
    """The checkpoint a resume starts from, after every file the resume reads is checked (the checkpoint's,
    timing.json, the CSV logs); then the run is locked and damaged newer checkpoints set aside."""
    from agents import training
    from agents.run_folder import lock_run, read_csv, truncate_csv

    checkpoint, damaged = training.resume_point(run_dir, plan.algo, plan.config, from_steps, plan.observation_shape)
    training.read_timing(run_dir)
    for path, column in (
        (run_dir / "logs" / "progress.csv", "time/total_timesteps"),
        (run_dir / "evaluations.csv", "timesteps"),
    ):
        read_csv(path)  # text, not damaged
        if path.exists():
            truncate_csv(path, column, checkpoint.steps, dry_run=True)
    lock_run(run_dir)  # one training of a run at a time
    moved = training.set_aside(damaged, plan.algo)
    if moved:
        print(f"set aside the files of the damaged newer checkpoints: {', '.join(str(path) for path in moved)}")
    return checkpoint


def resumable_hint(run_dir: Path, algo: str) -> str:
    """What a user does after a file-system error stopped the training of ``run_dir``."""
    from agents.checkpoints import latest_checkpoint

    if latest_checkpoint(run_dir, algo) is not None:
        return f"the run is kept: once the file system allows, continue it with {PROG} --resume {run_dir}"
    return (
        f"no checkpoint was written yet: once the file system allows, run the command again "
        f"({run_dir} holds nothing to keep)"
    )


def main(argv: list[str] | None = None) -> Path:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parse_args(argv)
    with one_line_errors(PROG):
        plan = resolve(args)
        from agents import training

        if args.resume:
            checkpoint = prepare_resume(args.resume, plan, args.from_steps)
            run_dir = args.resume
        else:
            from agents.run_folder import check_runs_dir

            check_runs_dir(args.runs_dir)
            run_dir, checkpoint = training.new_run_dir(args.runs_dir, args.name, plan.env_id, plan.algo), None
    with one_line_errors(PROG, lambda: resumable_hint(run_dir, plan.algo)):
        return run_training(run_dir, plan, checkpoint, args, argv)


def run_training(run_dir: Path, plan: TrainingPlan, checkpoint, args: argparse.Namespace, argv: list[str]) -> Path:
    """Write the run's files, train, evaluate and print the results (the run folder is locked)."""
    import json

    from agents import training
    from agents.run_folder import unlock_run

    algo, env_id, seed, config = plan.algo, plan.env_id, plan.seed, plan.config
    command = shlex.join([Path(sys.executable).name, "-m", "agents.train", *argv])
    try:
        training.write_run_files(run_dir, algo, env_id, seed, config, command)
        print(f"training {algo.upper()} on {env_id} for {config['n_timesteps']:,} steps (seed {seed}) into {run_dir}")
        timing = training.train(
            run_dir,
            config,
            env_id,
            seed,
            algo,
            resume=checkpoint or False,
            progress_bar=not args.no_progress,
            final_eval=not args.no_eval,
        )
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
