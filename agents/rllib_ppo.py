"""Train RLlib's PPO on a BoxToss env (``pip install -e ".[rllib]"``; RLlib pins its own gymnasium).

    python -m agents.rllib_ppo --env BoxToss-v0 --iterations 40
    python -m agents.rllib_ppo --env BoxToss-ShortEnd-v0 --env-config max_spin=10 --num-envs 256
    python -m agents.rllib_ppo --vectorize sync          # RLlib's default vectorisation (SyncVectorEnv)
    python -m agents.rllib_ppo --address auto --num-env-runners 8   # sample on a Ray cluster

The env comes from ``agents.rllib_envs`` (``env_config``: the env's kwargs). ``--vectorize native``
(default) gives each env runner the native batched env with one engine thread, ``sync`` RLlib's default;
with 256 envs per runner the native env sampled a little faster (``python -m benchmarks.rllib_sampling``;
RLlib's per-episode work, not the env, sets the pace). Observations are normalised by RLlib's
``MeanStdFilter`` (their bounds span hundreds of metres), and the PPO settings mirror
``agents/hyperparams/ppo.yml``: one-throw episodes, so gamma = 0. Each iteration prints the mean
return and the success rate of the sampled (exploring) throws.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

import ray
from ray.rllib.algorithms.ppo import PPO, PPOConfig
from ray.rllib.connectors.env_to_module import MeanStdFilter
from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig

from agents.config import read_value
from agents.rllib_envs import ENV_IDS, VECTORIZE_MODES, register_rllib_envs

SUCCESS = "box_toss_success"  # the metric each finished episode logs


def log_success(*, episode, metrics_logger, **_) -> None:
    """``on_episode_end``: whether the throw succeeded, averaged over an iteration's episodes."""
    metrics_logger.log_value(SUCCESS, float(episode.get_infos(-1)["success"]), reduce="mean")


def make_config(env_id: str, env_config: dict[str, Any] | None = None, *, num_envs: int = 256,
                vectorize: str = "native", num_env_runners: int = 0, train_batch_size: int = 2048,
                minibatch_size: int = 128, num_epochs: int = 10, lr: float = 5e-4, seed: int = 0) -> PPOConfig:
    """RLlib PPO on ``env_id`` (the BoxToss envs must be registered: ``register_rllib_envs``)."""
    if vectorize not in VECTORIZE_MODES:
        raise ValueError(f"vectorize must be one of {sorted(VECTORIZE_MODES)}, got {vectorize!r}")
    env_config = dict(env_config or {})
    if vectorize == "native":
        env_config.setdefault("threads", 1)  # an env runner has one CPU
    return (
        PPOConfig()
        .environment(env_id, env_config=env_config)
        .env_runners(num_env_runners=num_env_runners, num_envs_per_env_runner=num_envs,
                     gym_env_vectorize_mode=VECTORIZE_MODES[vectorize],
                     env_to_module_connector=lambda env, spaces, device: MeanStdFilter())
        .training(train_batch_size_per_learner=train_batch_size, minibatch_size=minibatch_size,
                  num_epochs=num_epochs, lr=lr, gamma=0.0, lambda_=1.0, clip_param=0.2)
        .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=[128, 128], fcnet_activation="tanh"))
        .callbacks(on_episode_end=log_success)
        .debugging(seed=seed)
    )


def summary(result: dict[str, Any]) -> dict[str, float]:
    """The figures of one ``algo.train()`` result that matter here."""
    runners = result["env_runners"]
    return {"env_steps": runners["num_env_steps_sampled_lifetime"], "return": runners["episode_return_mean"],
            "success": runners[SUCCESS], "episode_length": runners["episode_len_mean"]}


def train(config: PPOConfig, iterations: int) -> tuple[PPO, list[dict[str, float]]]:
    algo = config.build_algo()
    history = []
    for iteration in range(iterations):
        start = time.perf_counter()
        figures = summary(algo.train())
        figures["seconds"] = time.perf_counter() - start
        history.append(figures)
        print(f"iteration {iteration + 1}: {figures['env_steps']:,.0f} throws, return {figures['return']:.3f}, "
              f"success {figures['success']:.1%} ({figures['seconds']:.1f} s)", flush=True)
    return algo, history


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="BoxToss-v0", choices=ENV_IDS)
    parser.add_argument("--env-config", nargs="*", default=[], metavar="KEY=VALUE", help="env kwargs")
    parser.add_argument("--iterations", type=int, default=40)
    parser.add_argument("--num-envs", type=int, default=256, help="envs per env runner")
    parser.add_argument("--vectorize", default="native", choices=sorted(VECTORIZE_MODES))
    parser.add_argument("--num-env-runners", type=int, default=0, help="0: sample in the training process")
    parser.add_argument("--train-batch-size", type=int, default=2048)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--address", help="a running Ray cluster; default: a local Ray")
    parser.add_argument("--num-cpus", type=int, help="CPUs of the local Ray (default: all)")
    return parser.parse_args(argv)


def env_config_of(items: list[str]) -> dict[str, Any]:
    config = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            sys.exit(f"agents.rllib_ppo: --env-config takes key=value, got {item!r}")
        config[key] = read_value(value)
    return config


def main(argv: list[str] | None = None) -> list[dict[str, float]]:
    args = parse_args(sys.argv[1:] if argv is None else list(argv))
    env_config = env_config_of(args.env_config)
    if args.address:
        ray.init(address=args.address)
    else:
        ray.init(address="local", num_cpus=args.num_cpus, include_dashboard=False)
    register_rllib_envs()
    config = make_config(args.env, env_config, num_envs=args.num_envs, vectorize=args.vectorize,
                         num_env_runners=args.num_env_runners, train_batch_size=args.train_batch_size,
                         seed=args.seed)
    algo, history = train(config, args.iterations)
    algo.stop()
    return history


if __name__ == "__main__":
    main()
