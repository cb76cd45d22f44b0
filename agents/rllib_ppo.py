"""Train RLlib's PPO on a BoxToss env (``pip install -e ".[rllib]"``; RLlib pins its own gymnasium).

    python -m agents.rllib_ppo --env BoxToss-v0 --iterations 40
    python -m agents.rllib_ppo --env BoxToss-ShortEnd-v0 --env-config max_spin=10 --num-envs 256
    python -m agents.rllib_ppo --vectorize sync          # RLlib's default vectorisation (SyncVectorEnv)
    python -m agents.rllib_ppo --address auto --num-env-runners 8   # sample on a Ray cluster

The env comes from ``agents.rllib_envs`` (``env_config``: the env's kwargs). ``--vectorize native``
(default) gives each env runner the native batched env with one engine thread, ``sync`` RLlib's default;
with 256 envs per runner the native env sampled a little faster (``python -m benchmarks.rllib_sampling``;
RLlib's per-episode work, not the env, sets the pace). Observations are normalised by RLlib's
``MeanStdFilter`` (their bounds span hundreds of metres).

The PPO settings are SB3's recipe for the env, read from ``agents/hyperparams/ppo.yml`` (``recipe``): the batch,
minibatch and epochs, the learning rate decaying linearly to 0 over the recipe's throws, the clip range, value and
entropy coefficients, gradient clipping, gamma and lambda, separate policy and value networks of the recipe's
sizes, a state-independent action std started at ``exp(log_std_init)``, no KL penalty (SB3's PPO has none), and
ballistic commands where the recipe names ``BallisticThrows``. Two settings are RLlib's mechanics rather than
options, and both are set as SB3's here: RLlib adds an artificial (loss-masked) bootstrap timestep to every
episode, so with one-throw episodes half its rows are artificial; it standardised the advantages over them too
(``MaskedAdvantagePPOLearner`` standardises over the real throws of each minibatch) and cuts minibatches by rows
(``ROWS_PER_THROW``). The first was why RLlib's PPO did not learn where SB3's did (docs/methodology/rllib.md has the
figures). Each iteration prints the mean return and the success rate of the sampled (exploring) throws
(``--diagnostics``: and the learner's figures, ``--eval-every``: and the mean action's success); at the end the
policy's mean action is evaluated on ``--eval-episodes`` fresh throws.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import Any, cast

import numpy as np
import ray
import torch
from ray.rllib.algorithms.algorithm import Algorithm
from ray.rllib.algorithms.ppo import PPOConfig
from ray.rllib.algorithms.ppo.torch.default_ppo_torch_rl_module import DefaultPPOTorchRLModule
from ray.rllib.algorithms.ppo.torch.ppo_torch_learner import PPOTorchLearner
from ray.rllib.connectors.env_to_module import MeanStdFilter
from ray.rllib.core.columns import Columns
from ray.rllib.core.rl_module.rl_module import RLModuleSpec
from ray.rllib.evaluation.postprocessing import Postprocessing

from agents.config import load_hyperparams, read_value
from agents.rllib_envs import BALLISTIC, ENV_IDS, VECTORIZE_MODES, register_rllib_envs

SUCCESS = "box_toss_success"  # the metric each finished episode logs


def log_success(*, episode, metrics_logger, **_) -> None:
    """``on_episode_end``: whether the throw succeeded, averaged over an iteration's episodes."""
    metrics_logger.log_value(SUCCESS, float(episode.get_infos(-1)["success"]), reduce="mean")


class PPOModule(DefaultPPOTorchRLModule):
    """RLlib's default PPO module whose free log std starts at ``model_config["log_std_init"]`` (SB3's
    ``log_std_init``; RLlib starts it at 0, an action std of 1)."""

    def setup(self):
        super().setup()
        if self.model_config.get("free_log_std") and self.model_config.get("log_std_init") is not None:
            with torch.no_grad():
                self.pi.log_std.fill_(float(self.model_config["log_std_init"]))


class MaskedAdvantagePPOLearner(PPOTorchLearner):
    """RLlib's PPO learner with SB3's advantage standardisation: over each minibatch's real timesteps.

    RLlib adds an artificial timestep to every episode (``AddOneTsToEpisodesAndTruncate``, for the value
    bootstrap; ``loss_mask`` False) and standardises the advantages over the whole batch *including* those
    rows. With one-throw episodes half the rows are artificial, and with gamma 0 their advantage is
    ``-V(landing)``, about +1 once the value has learned the mean return of about -1: the real advantages come
    out with a negative mean (the policy loss of the sampled throws, ``-mean(A)``, about +0.6), so every update
    lowers the probability of every sampled throw and widens the action std instead of aiming. This learner
    standardises the advantages again over the rows of ``loss_mask`` (an affine map of RLlib's values, so
    the same as standardising the raw advantages of the real throws), per minibatch as SB3 does."""

    def compute_loss_for_module(self, *, module_id, config, batch, fwd_out):
        advantages = batch[Postprocessing.ADVANTAGES]
        real = advantages[batch[Columns.LOSS_MASK]] if Columns.LOSS_MASK in batch else advantages
        if real.numel() > 1:
            batch = {**batch, Postprocessing.ADVANTAGES: (advantages - real.mean()) / (real.std() + 1e-8)}
        return super().compute_loss_for_module(module_id=module_id, config=config, batch=batch, fwd_out=fwd_out)


ROWS_PER_THROW = 2
"""Rows of RLlib's train batch per one-throw episode: the throw and the artificial bootstrap timestep that RLlib
adds to every episode (loss-masked). RLlib cuts minibatches by rows, so a minibatch of SB3's ``batch_size``
throws is ``ROWS_PER_THROW`` times as many rows (measured: ``num_module_steps_trained`` is 40,960 for 2,048 throws
and 10 epochs)."""

ACTIVATIONS = {"nn.Tanh": "tanh", "nn.ReLU": "relu"}


def recipe(env_id: str) -> dict[str, Any]:
    """SB3's PPO recipe for ``env_id`` (``agents/hyperparams/ppo.yml``) in RLlib's terms."""
    entry = load_hyperparams("ppo", env_id)
    policy = entry.get("policy_kwargs") or {}
    rate = entry["learning_rate"]
    decays = isinstance(rate, str)  # lin_<x>: x decaying linearly to 0
    clip = entry.get("clip_range", 0.2)
    if isinstance(clip, str):
        raise ValueError(f"ppo.yml's {env_id} has a clip_range schedule {clip!r}, which recipe() does not map")
    wrapper = entry.get("env_wrapper")
    if wrapper not in (None, BALLISTIC):
        raise ValueError(f"ppo.yml's {env_id} names env_wrapper {wrapper!r}; recipe() maps only {BALLISTIC}")
    return {
        "n_throws": entry["n_timesteps"],
        "train_batch_size": entry["n_envs"] * entry["n_steps"],
        "minibatch_size": entry["batch_size"],
        "num_epochs": entry["n_epochs"],
        "lr": float(rate.partition("_")[2]) if decays else float(rate),
        "lr_decays": decays,
        "gamma": entry.get("gamma", 0.99),
        "lambda_": entry.get("gae_lambda", 0.95),
        "clip_param": clip,
        "entropy_coeff": entry.get("ent_coef", 0.0),
        "vf_loss_coeff": entry.get("vf_coef", 0.5),
        "grad_clip": entry.get("max_grad_norm", 0.5),
        "hiddens": list(policy.get("net_arch", [64, 64])),
        "activation": ACTIVATIONS[policy.get("activation_fn", "nn.Tanh")],
        "log_std_init": policy.get("log_std_init", 0.0),
        "ballistic": wrapper == BALLISTIC,
    }


def make_config(
    env_id: str,
    env_config: dict[str, Any] | None = None,
    *,
    num_envs: int = 256,
    vectorize: str = "native",
    num_env_runners: int = 0,
    seed: int = 0,
    masked_advantages: bool = True,
    **overrides: Any,
) -> PPOConfig:
    """RLlib PPO on ``env_id`` with SB3's recipe (``recipe``; ``overrides`` replace its keys, e.g.
    ``train_batch_size=256``), the advantages standardised over the real timesteps of each minibatch
    (``MaskedAdvantagePPOLearner``; ``masked_advantages=False``: RLlib's, over the batch with its artificial
    timesteps). The BoxToss envs must be registered: ``register_rllib_envs``."""
    if vectorize not in VECTORIZE_MODES:
        raise ValueError(f"vectorize must be one of {sorted(VECTORIZE_MODES)}, got {vectorize!r}")
    settings = recipe(env_id)
    unknown = set(overrides) - set(settings)
    if unknown:
        raise ValueError(f"unknown settings {sorted(unknown)}; known: {sorted(settings)}")
    settings.update(overrides)
    env_config = dict(env_config or {})
    if vectorize == "native":
        env_config.setdefault("threads", 1)  # an env runner has one CPU
    if settings["ballistic"]:
        env_config.setdefault("ballistic", True)
    lr = [[0, settings["lr"]], [settings["n_throws"], 0.0]] if settings["lr_decays"] else settings["lr"]
    model_config = {
        "fcnet_hiddens": settings["hiddens"],
        "fcnet_activation": settings["activation"],
        "vf_share_layers": False,
        "free_log_std": True,
        "log_std_init": settings["log_std_init"],
    }
    return (
        PPOConfig()
        .environment(env_id, env_config=env_config)
        .env_runners(
            num_env_runners=num_env_runners,
            num_envs_per_env_runner=num_envs,
            gym_env_vectorize_mode=VECTORIZE_MODES[vectorize],
            env_to_module_connector=mean_std_filter,
        )
        .training(
            train_batch_size_per_learner=settings["train_batch_size"],
            minibatch_size=settings["minibatch_size"] * ROWS_PER_THROW,
            num_epochs=settings["num_epochs"],
            lr=lr,
            gamma=settings["gamma"],
            lambda_=settings["lambda_"],
            clip_param=settings["clip_param"],
            entropy_coeff=settings["entropy_coeff"],
            vf_loss_coeff=settings["vf_loss_coeff"],
            grad_clip=settings["grad_clip"],
            grad_clip_by="global_norm",
            use_kl_loss=False,
            vf_clip_param=math.inf,
            learner_class=MaskedAdvantagePPOLearner if masked_advantages else PPOTorchLearner,
        )
        .rl_module(rl_module_spec=RLModuleSpec(module_class=PPOModule, model_config=model_config))
        .callbacks(on_episode_end=log_success)
        .debugging(seed=seed)
    )


def iterations_of(config: PPOConfig, env_id: str) -> int:
    """Iterations that sample the recipe's throws (``n_throws`` / the train batch, rounded up)."""
    return math.ceil(recipe(env_id)["n_throws"] / config.train_batch_size_per_learner)


def mean_std_filter(env: Any, spaces: Any = None, device: Any = None) -> MeanStdFilter:
    """RLlib's running mean and std filter of the observations, a new one for each env runner."""
    return MeanStdFilter()


def evaluate(algo: Algorithm, episodes: int) -> dict[str, float]:
    """Success and mean return of the policy's mean action (``explore=False``) on at least ``episodes`` fresh
    throws of the local env runner (its env's own draws, not the SB3 test seeds)."""
    done = [
        episode
        for episode in algo.env_runner.sample(num_episodes=episodes, explore=False, force_reset=True)
        if episode.is_done
    ]
    success = [float(episode.get_infos(-1)["success"]) for episode in done]
    return {
        "episodes": len(done),
        "success": float(np.mean(success)),
        "return": float(np.mean([episode.get_return() for episode in done])),
    }


LEARNER_FIGURES = {
    "lr": "default_optimizer_learning_rate",
    "entropy": "entropy",
    "policy_loss": "policy_loss",
    "vf_loss": "vf_loss",
    "vf_explained_var": "vf_explained_var",
    "grad_norm": "gradients_default_optimizer_global_norm",
    "rows_trained": "num_module_steps_trained",
}
"""The learner's figures ``--diagnostics`` prints (ours -> the key in RLlib's learner results)."""


def summary(result: dict[str, Any]) -> dict[str, float]:
    """The figures of one ``algo.train()`` result that matter here, and the learner's (``LEARNER_FIGURES``,
    those RLlib reports)."""
    runners = result["env_runners"]
    learner = result.get("learners", {}).get("default_policy", {})
    return {
        "env_steps": runners["num_env_steps_sampled_lifetime"],
        "return": runners["episode_return_mean"],
        "success": runners[SUCCESS],
        "episode_length": runners["episode_len_mean"],
        **{name: float(learner[key]) for name, key in LEARNER_FIGURES.items() if key in learner},
    }


def train(
    config: PPOConfig, iterations: int, diagnostics: bool = False, eval_every: int = 0, eval_episodes: int = 256
) -> tuple[Algorithm, list[dict[str, Any]]]:
    """``iterations`` of ``algo.train()``; with ``diagnostics`` each line adds the learner's figures and the
    action std (``exp`` of the free log std) after the update; every ``eval_every`` iterations (0: never) the
    mean action's success on ``eval_episodes`` fresh throws (``evaluate``), as SB3's runs validate."""
    algo = config.build_algo()
    history: list[dict[str, Any]] = []
    for iteration in range(iterations):
        start = time.perf_counter()
        figures: dict[str, Any] = summary(algo.train())
        figures["seconds"] = time.perf_counter() - start
        figures["action_std"] = [float(v) for v in cast(Any, algo.get_module()).pi.log_std.detach().exp()]
        history.append(figures)
        line = (
            f"iteration {iteration + 1}: {figures['env_steps']:,.0f} throws, return {figures['return']:.3f}, "
            f"success {figures['success']:.1%} ({figures['seconds']:.1f} s)"
        )
        if diagnostics:
            line += "".join(f", {name} {figures[name]:.4g}" for name in LEARNER_FIGURES if name in figures)
            line += ", action std " + " ".join(f"{v:.3f}" for v in figures["action_std"])
        if eval_every and (iteration + 1) % eval_every == 0:
            figures["mean_action"] = evaluate(algo, eval_episodes)
            line += (
                f"; mean action: success {figures['mean_action']['success']:.1%} of "
                f"{figures['mean_action']['episodes']} throws"
            )
        print(line, flush=True)
    return algo, history


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="BoxToss-v0", choices=ENV_IDS)
    parser.add_argument("--env-config", nargs="*", default=[], metavar="KEY=VALUE", help="env kwargs")
    parser.add_argument(
        "--iterations",
        type=int,
        default=None,
        help="training iterations (default: the recipe's throws / the train batch)",
    )
    parser.add_argument("--num-envs", type=int, default=256, help="envs per env runner")
    parser.add_argument("--vectorize", default="native", choices=sorted(VECTORIZE_MODES))
    parser.add_argument("--num-env-runners", type=int, default=0, help="0: sample in the training process")
    parser.add_argument("--train-batch-size", type=int, default=None, help="default: the recipe's n_envs x n_steps")
    parser.add_argument("--eval-episodes", type=int, default=1024, help="deterministic throws at the end (0: none)")
    parser.add_argument(
        "--eval-every",
        type=int,
        default=0,
        help="iterations between evaluations of the mean action on 256 fresh throws (0: none)",
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--address", help="a running Ray cluster; default: a local Ray")
    parser.add_argument("--num-cpus", type=int, help="CPUs of the local Ray (default: all)")
    parser.add_argument(
        "--diagnostics",
        action="store_true",
        help="print the learner's figures (rate, entropy, losses, gradient norm) and the action std",
    )
    parser.add_argument(
        "--rllib-advantages",
        action="store_true",
        help="RLlib's advantage standardisation (over the batch with its artificial timesteps)",
    )
    parser.add_argument(
        "--set",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="replace settings of the recipe (recipe()'s keys, e.g. num_epochs=5)",
    )
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
    overrides = env_config_of(args.set)
    if args.train_batch_size is not None:
        overrides["train_batch_size"] = args.train_batch_size
    config = make_config(
        args.env,
        env_config,
        num_envs=args.num_envs,
        vectorize=args.vectorize,
        num_env_runners=args.num_env_runners,
        seed=args.seed,
        masked_advantages=not args.rllib_advantages,
        **overrides,
    )
    iterations = args.iterations if args.iterations is not None else iterations_of(config, args.env)
    algo, history = train(config, iterations, args.diagnostics, args.eval_every)
    if args.eval_episodes > 0:
        result = evaluate(algo, args.eval_episodes)
        print(
            f"deterministic (mean action): success {result['success']:.1%} of {result['episodes']} throws, "
            f"return {result['return']:.3f}",
            flush=True,
        )
        history.append({"evaluation": result})
    algo.stop()
    return history


if __name__ == "__main__":
    main()
