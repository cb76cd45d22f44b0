"""Where an untrained policy throws: the recipe option ``initial_mean`` (``project.yml``), applied before training.

SB3 starts a policy's mean near action 0 for every observation (PPO's action layer is initialised with a gain of
0.01; SAC's and TD3's actors end in a small tanh). In the env's own actions that throw lands face 0 for every target
(docs/agents.md, "PPO in raw actions where a face counts"), so every target's throw starts at one face. The option
moves the start, and nothing else of the recipe:

    initial_mean: [a0, a1, a2]              a constant env action: the action layer's bias (its weights stay small)
    initial_mean: ballistic                 the ballistic command 0 from each first observation (a target face
                                            flat down at the target, ``envs.ballistic``), in the env's actions
    initial_mean: {ballistic: [c0, c1, c2]} the same for another command

For a ballistic start the policy's mean network is fitted by regression (mean squared error, Adam) to the env
actions of the command on ``SAMPLES`` first observations drawn from the training env's own episodes (seeded apart
from training's), normalised as training normalises them: the ``VecNormalize`` statistics start from those
observations. PPO fits its Gaussian's mean, SAC the tanh of its actor's mean, TD3 its actor (and the actor's
target copy). The log standard deviation stays the recipe's ``log_std_init``. PPO's critic is then fitted to the
rewards of throws sampled from that start (``fit_value``). A ballistic start is for a policy acting in the env's
own actions (a recipe without ``env_wrapper``). What the start scores is the benchmark's *prior* column
(``agents.benchmark``): the untrained policy's deterministic throw.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.common.base_class import BaseAlgorithm

from agents.envs import make_vector_env
from agents.recipe_options import read_initial_mean as read_option
from box_toss_env.envs.ballistic import ballistic_actions
from box_toss_env.files import write_atomic

SAMPLES = 16_384  # first observations the mean network is fitted on
FIT_STEPS = 4_000  # Adam steps of the regression
FIT_BATCH = 256
FIT_LEARNING_RATE = 1e-3
FIT_SEED_OFFSET = 1_000_003  # the fit's episodes: env seed + this, apart from training's (seed, seed + 1, ...)
TANH_LIMIT = 0.999  # targets of a tanh-squashed actor are kept inside (-1, 1)


def first_observations(env_id: str, config: dict[str, Any], seed: int, n: int = SAMPLES) -> np.ndarray:
    """``n`` first observations (n, obs) of the training env's episodes, seeded with ``seed``."""
    venv = episodes(env_id, config, seed, n)
    observations = np.asarray(cast(np.ndarray, venv.reset()), dtype=np.float64)
    venv.close()
    return observations


def episodes(env_id: str, config: dict[str, Any], seed: int, n: int = SAMPLES):
    """The training env's kind (env actions, no normaliser) over ``n`` episodes seeded with ``seed``: an SB3 VecEnv."""
    venv = make_vector_env(env_id, n, config.get("env_kwargs"), config.get("vec_env_kwargs"))
    venv.seed(seed)
    return venv


def ballistic_targets(env_id: str, config: dict[str, Any], observations: np.ndarray, command) -> np.ndarray:
    """The env actions (n, 3) of ballistic ``command`` thrown from ``observations``."""
    env = gym.make(env_id, **(config.get("env_kwargs") or {}))
    commands = np.tile(np.asarray(command, dtype=np.float64), (len(observations), 1))
    actions = ballistic_actions(observations, commands, env.unwrapped.config)[0]  # type: ignore[attr-defined]
    env.close()
    return actions


def mean_action(model: BaseAlgorithm, observations: torch.Tensor) -> torch.Tensor:
    """The policy's mean action for normalised observations, differentiable: PPO's Gaussian mean (unsquashed),
    SAC's tanh of its actor's mean, TD3's actor."""
    policy: Any = model.policy
    if hasattr(policy, "get_distribution"):  # on-policy: a Gaussian over the raw action
        return policy.get_distribution(observations).distribution.mean
    if hasattr(policy.actor, "get_action_dist_params"):  # SAC
        mean, _, _ = policy.actor.get_action_dist_params(observations)
        return torch.tanh(mean)
    return policy.actor(observations)  # TD3


def output_layer(model: BaseAlgorithm) -> torch.nn.Linear:
    """The layer that outputs the policy's mean (before any tanh)."""
    policy: Any = model.policy
    if hasattr(policy, "action_net"):
        return policy.action_net
    if isinstance(policy.actor.mu, torch.nn.Linear):  # SAC
        return policy.actor.mu
    return [m for m in policy.actor.mu if isinstance(m, torch.nn.Linear)][-1]  # TD3: Linear, then Tanh


SMALL_GAIN = 0.01
"""An actor's output weights are scaled by this for a constant start (PPO's action layer is initialised so)."""


def set_constant(model: BaseAlgorithm, action: np.ndarray) -> None:
    """Start the mean at ``action`` for every observation: the output layer's bias (atanh of it for a tanh actor),
    its weights made small (SAC's and TD3's start at PyTorch's default scale, PPO's at ``SMALL_GAIN``)."""
    squashed = not hasattr(model.policy, "action_net")
    value = np.arctanh(np.clip(action, -TANH_LIMIT, TANH_LIMIT)) if squashed else action
    layer = output_layer(model)
    with torch.no_grad():
        layer.bias.copy_(torch.as_tensor(value, dtype=torch.float32))
        if squashed:
            layer.weight.mul_(SMALL_GAIN)
    sync_target(model)


def sync_target(model: BaseAlgorithm) -> None:
    """TD3's target actor made the actor again (it starts as a copy)."""
    policy: Any = model.policy
    if getattr(policy, "actor_target", None) is not None:
        policy.actor_target.load_state_dict(policy.actor.state_dict())


def fit(model: BaseAlgorithm, observations: np.ndarray, targets: np.ndarray, seed: int) -> dict[str, float]:
    """Regress the policy's mean on ``targets`` (n, 3) at normalised ``observations`` (n, obs); returns the fit's
    mean absolute error and its largest error per sample (the largest over the action's dimensions), in action
    units."""
    squashed = not hasattr(model.policy, "action_net")
    goal = torch.as_tensor(np.clip(targets, -TANH_LIMIT, TANH_LIMIT) if squashed else targets, dtype=torch.float32)
    inputs = torch.as_tensor(observations, dtype=torch.float32)
    optimizer = torch.optim.Adam(model.policy.parameters(), lr=FIT_LEARNING_RATE)
    decay = torch.optim.lr_scheduler.LambdaLR(optimizer, lambda step: 1.0 - step / FIT_STEPS)  # linear, to 0
    generator = torch.Generator().manual_seed(seed)
    model.policy.set_training_mode(True)
    for _ in range(FIT_STEPS):
        batch = torch.randint(len(inputs), (FIT_BATCH,), generator=generator)
        loss = torch.mean((mean_action(model, inputs[batch]) - goal[batch]) ** 2)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        decay.step()
    model.policy.set_training_mode(False)
    sync_target(model)
    with torch.no_grad():
        error = (mean_action(model, inputs) - goal).abs()
    return {"mean_abs_error": float(error.mean()), "max_abs_error": float(error.max(dim=1).values.max())}


def fit_value(model: BaseAlgorithm, venv, observations: np.ndarray, seed: int) -> dict[str, float]:
    """An actor-critic's value function fitted to the rewards of its own (fitted) policy: one action sampled from
    the policy per first observation of ``venv`` (``observations``, normalised), thrown, and V regressed on the
    rewards (every episode is one throw: V(s) is the expected reward). Without it the first updates' advantages are
    the raw rewards, whose noise moves a fitted mean by more than its narrow spread. Returns the share of the
    rewards' variance V explains."""
    policy: Any = model.policy
    inputs = torch.as_tensor(observations, dtype=torch.float32)
    with torch.no_grad():
        actions = policy.get_distribution(inputs).sample().numpy()
    low, high = model.action_space.low, model.action_space.high  # type: ignore[attr-defined]
    _, rewards, _, _ = venv.step(np.clip(actions, low, high))
    goal = torch.as_tensor(rewards, dtype=torch.float32)[:, None]
    optimizer = torch.optim.Adam(policy.parameters(), lr=FIT_LEARNING_RATE)
    decay = torch.optim.lr_scheduler.LambdaLR(optimizer, lambda step: 1.0 - step / FIT_STEPS)
    generator = torch.Generator().manual_seed(seed + 1)
    policy.set_training_mode(True)
    for _ in range(FIT_STEPS):
        batch = torch.randint(len(inputs), (FIT_BATCH,), generator=generator)
        loss = torch.mean((policy.predict_values(inputs[batch]) - goal[batch]) ** 2)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        decay.step()
    policy.set_training_mode(False)
    with torch.no_grad():
        residual = float(torch.var(policy.predict_values(inputs) - goal))
    return {"value_explained_variance": 1.0 - residual / max(float(torch.var(goal)), 1e-12)}


def apply(model: BaseAlgorithm, config: dict[str, Any], env_id: str, seed: int, run_dir: Path | None = None) -> None:
    """Move ``model``'s starting mean as ``config["initial_mean"]`` says (nothing without it); with ``run_dir``,
    what the fit reached is written to ``initial_mean.json`` there."""
    option = read_option(config.get("initial_mean"))
    if option is None:
        return
    kind, vector = option
    torch.manual_seed(seed)
    if kind == "constant":
        set_constant(model, vector)
        report: dict[str, Any] = {"initial_mean": vector.tolist()}
    else:
        venv = episodes(env_id, config, seed + FIT_SEED_OFFSET)
        observations = np.asarray(venv.reset(), dtype=np.float64)
        targets = ballistic_targets(env_id, config, observations, vector)
        normalizer = model.get_vec_normalize_env()
        if normalizer is not None and normalizer.norm_obs:
            normalizer.obs_rms.update(observations)  # training's statistics start from these observations
            observations = cast(np.ndarray, normalizer.normalize_obs(observations.astype(np.float32)))
        report = {"initial_mean": {"ballistic": vector.tolist()}, "samples": len(targets)}
        report.update(fit(model, observations, targets, seed))
        if hasattr(model.policy, "predict_values"):  # an actor-critic (PPO): its critic learns the start's rewards
            report.update(fit_value(model, venv, observations, seed))
        venv.close()
    if run_dir is not None:
        write_atomic(Path(run_dir) / "initial_mean.json", json.dumps(report, indent=2))
