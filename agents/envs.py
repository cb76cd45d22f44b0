"""The vector env PPO trains on, and the clock that measures the env's share of training time.

    gymnasium.make_vec(env_id, num_envs=n, **env_kwargs)   BoxToss's batched vector env (same-step autoreset)
    -> BallisticThrowsVector (with env_wrapper)            the policy acts in ballistic commands (optional)
    -> SB3VecEnvAdapter                                    SB3's VecEnv interface over it
    -> TimedVecEnv                                         seconds spent inside the env
    -> VecMonitor                                          episode rewards for the logs
    -> VecNormalize(norm_reward=False)                     running mean / std of observations

Observations are normalised (their bounds span hundreds of metres while a throw starts within
centimetres of the hand); rewards are not (every episode is one reward, already of order one).

``env_wrapper`` is RL Zoo's key: the wrapper Zoo puts around each env. We train on one batched env, so
each wrapper we accept there has a vector form (``ENV_WRAPPERS``), and a trained policy acting through
it maps its actions to the env's the same way at evaluation (``command_map``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, cast

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper, VecMonitor, VecNormalize

import box_toss_env  # noqa: F401  (registers the BoxToss envs)
from agents.env_wrappers import BALLISTIC, ENV_WRAPPERS, STACK_COMMANDS, read_env_wrapper  # noqa: F401 (re-exported)
from box_toss_env.envs.ballistic import ballistic_actions
from box_toss_env.envs.stack_commands import batch_command_actions
from box_toss_env.wrappers.ballistic import BallisticThrowsVector
from box_toss_env.wrappers.sb3_adapter import SB3VecEnvAdapter
from box_toss_env.wrappers.stack_commands import StackCommandsVector


class TimedVecEnv(VecEnvWrapper):
    """Adds up the wall time spent in the wrapped env's ``reset`` and ``step`` (``env_seconds``)."""

    def __init__(self, venv: VecEnv):
        super().__init__(venv)
        self.env_seconds = 0.0
        self.env_steps = 0

    def reset(self):
        start = time.perf_counter()
        obs = self.venv.reset()
        self.env_seconds += time.perf_counter() - start
        return obs

    def step_wait(self):
        start = time.perf_counter()
        result = self.venv.step_wait()
        self.env_seconds += time.perf_counter() - start
        self.env_steps += self.num_envs
        return result


def wrap_vector_env(vector_env: gym.vector.VectorEnv, env_wrapper: Any) -> gym.vector.VectorEnv:
    """``vector_env`` in the vector form of ``env_wrapper`` (unchanged if None)."""
    wrapper = read_env_wrapper(env_wrapper)
    if wrapper is None:
        return vector_env
    if wrapper[0] == STACK_COMMANDS:
        return StackCommandsVector(vector_env, **wrapper[1])
    return BallisticThrowsVector(vector_env, **wrapper[1])


def command_map(env_wrapper: Any) -> Callable[[np.ndarray, np.ndarray, gym.Env], np.ndarray] | None:
    """What a policy trained through ``env_wrapper`` does to its actions to get the env's:
    ``f(observations, policy_actions, env) -> env actions`` (None without a wrapper)."""
    wrapper = read_env_wrapper(env_wrapper)
    if wrapper is None:
        return None
    kwargs = wrapper[1]
    if wrapper[0] == STACK_COMMANDS:
        return lambda observations, commands, env: batch_command_actions(
            observations, commands, cast(Any, env.unwrapped).config, **kwargs
        )
    return lambda observations, commands, env: ballistic_actions(
        observations, commands, cast(Any, env.unwrapped).config, **kwargs
    )[0]


def make_vector_env(
    env_id: str,
    n_envs: int,
    env_kwargs: dict[str, Any] | None = None,
    vec_env_kwargs: dict[str, Any] | None = None,
    env_wrapper: Any = None,
) -> TimedVecEnv:
    """``n_envs`` BoxToss envs as one SB3 VecEnv (timed), from the env's own vector entry point."""
    vector_env = gym.make_vec(
        env_id, num_envs=n_envs, vectorization_mode="vector_entry_point", **(env_kwargs or {}), **(vec_env_kwargs or {})
    )
    return TimedVecEnv(SB3VecEnvAdapter(wrap_vector_env(vector_env, env_wrapper)))


def make_training_env(
    env_id: str,
    n_envs: int,
    *,
    seed: int,
    env_kwargs: dict[str, Any] | None = None,
    vec_env_kwargs: dict[str, Any] | None = None,
    normalize: dict[str, Any] | bool = True,
    statistics: VecNormalize | None = None,
    env_wrapper: Any = None,
) -> VecEnv:
    """The full training stack (module docstring), seeded; with ``statistics`` (a saved ``VecNormalize``, read
    and checked by ``agents.run_files.read_normalizer``) the observations are normalised as they were (a resume)."""
    venv: VecEnv = make_vector_env(env_id, n_envs, env_kwargs, vec_env_kwargs, env_wrapper)
    venv.seed(seed)
    venv = VecMonitor(venv)
    if statistics is not None:
        statistics.set_venv(venv)
        statistics.training = True
        venv = statistics
    elif normalize:
        options = {"norm_obs": True, "norm_reward": False, **(normalize if isinstance(normalize, dict) else {})}
        venv = VecNormalize(venv, **options)
    return venv


def find_wrapper(venv: VecEnv | None, kind: type) -> Any:
    """The first wrapper of type ``kind`` in the chain of ``venv`` (None if absent)."""
    while venv is not None:
        if isinstance(venv, kind):
            return venv
        venv = getattr(venv, "venv", None)
    return None


def normalizer_of(venv: VecEnv) -> VecNormalize | None:
    return find_wrapper(venv, VecNormalize)


def observation_normalizer(vec_normalize: VecNormalize | None):
    """A function normalising raw observations (n, obs) as training saw them (identity without
    ``VecNormalize``); it never updates the statistics."""
    if vec_normalize is None or not vec_normalize.norm_obs:
        return lambda obs: np.asarray(obs, dtype=np.float32)
    return lambda obs: cast(np.ndarray, vec_normalize.normalize_obs(np.asarray(obs, dtype=np.float32))).astype(
        np.float32
    )
