"""BoxToss for RLlib: every BoxToss env id registered with an env creator that honours ``env_config``.

    register_rllib_envs()
    PPOConfig().environment("BoxToss-ShortEnd-v0", env_config={"max_spin": 10})   # env kwargs
        .env_runners(num_envs_per_env_runner=64, gym_env_vectorize_mode="vector_entry_point")

``env_config`` holds the env's keyword arguments (those of ``gymnasium.make``), plus ``threads``, the
engine threads of the batched env, and ``ballistic`` (True: act in ballistic commands, ``BallisticThrows``
or ``BallisticThrowsVector``, as ``agents/hyperparams/ppo.yml`` does where a face counts). RLlib calls the
creator once per env (its default vectorisation, ``gym_env_vectorize_mode="sync"``: a ``SyncVectorEnv``
of single envs), or once per env runner with ``num_envs`` added (``"vector_entry_point"``): then the
creator returns the native batched env, seen with ``NEXT_STEP`` autoreset
(``box_toss_env.wrappers.next_step``), which RLlib's env runners expect.
"""

from __future__ import annotations

import functools
from typing import Any

import gymnasium as gym
from ray.tune.registry import register_env

import box_toss_env  # noqa: F401  (registers the BoxToss envs with Gymnasium)
from box_toss_env.envs.ballistic import BallisticThrows
from box_toss_env.wrappers.ballistic import BallisticThrowsVector
from box_toss_env.wrappers.next_step import NextStepAutoreset

ENV_IDS = (
    "BoxToss-v0",
    "BoxToss-LongSide-v0",
    "BoxToss-ShortEnd-v0",
    "BoxToss-ThisSideUp-v0",
    "BoxToss-Mixed-v0",
    "BoxToss-OnBox-v0",
)
VECTORIZE_MODES = {"native": "vector_entry_point", "sync": "sync"}  # ours -> RLlib's gym_env_vectorize_mode
BALLISTIC = "box_toss_env.envs.ballistic.BallisticThrows"  # ppo.yml's env_wrapper; env_config["ballistic"]


def make_env(env_id: str, env_config: dict[str, Any]) -> gym.Env | gym.vector.VectorEnv:
    """The env ``env_id`` with ``env_config`` as its kwargs: a single env, or with ``num_envs`` the
    native batched env (``threads`` engine threads) under ``NEXT_STEP`` autoreset."""
    kwargs = dict(env_config)  # RLlib's EnvContext is a dict (worker index and the like are attributes)
    num_envs = kwargs.pop("num_envs", None)
    threads = kwargs.pop("threads", None)
    ballistic = bool(kwargs.pop("ballistic", False))
    if num_envs is None:
        env = gym.make(env_id, **kwargs)
        return BallisticThrows(env) if ballistic else env
    envs = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point", threads=threads, **kwargs)
    return NextStepAutoreset(BallisticThrowsVector(envs) if ballistic else envs)


def register_rllib_envs(env_ids: tuple[str, ...] = ENV_IDS) -> None:
    """Register each BoxToss env id in Ray's registry (the same name RLlib's ``environment()`` takes)."""
    for env_id in env_ids:
        register_env(env_id, functools.partial(make_env, env_id))
