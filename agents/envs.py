"""The vector env PPO trains on, and the clock that measures the env's share of training time.

    gymnasium.make_vec(env_id, num_envs=n, **env_kwargs)   BoxToss's batched vector env (same-step autoreset)
    -> SB3VecEnvAdapter                                    SB3's VecEnv interface over it
    -> TimedVecEnv                                         seconds spent inside the env
    -> VecMonitor                                          episode rewards for the logs
    -> VecNormalize(norm_reward=False)                     running mean / std of observations

Observations are normalised (their bounds span hundreds of metres while a throw starts within
centimetres of the hand); rewards are not (every episode is one reward, already of order one).
"""

from __future__ import annotations

import time
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper, VecMonitor, VecNormalize

import box_toss_env  # noqa: F401  (registers the BoxToss envs)
from box_toss_env.vector.sb3_adapter import SB3VecEnvAdapter


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


def make_vector_env(env_id: str, n_envs: int, env_kwargs: dict[str, Any] | None = None,
                    vec_env_kwargs: dict[str, Any] | None = None) -> TimedVecEnv:
    """``n_envs`` BoxToss envs as one SB3 VecEnv (timed), from the env's own vector entry point."""
    vector_env = gym.make_vec(env_id, num_envs=n_envs, vectorization_mode="vector_entry_point",
                              **(env_kwargs or {}), **(vec_env_kwargs or {}))
    return TimedVecEnv(SB3VecEnvAdapter(vector_env))


def make_training_env(env_id: str, n_envs: int, *, seed: int, env_kwargs: dict[str, Any] | None = None,
                      vec_env_kwargs: dict[str, Any] | None = None, normalize: dict[str, Any] | bool = True,
                      normalize_path: str | None = None) -> VecEnv:
    """The full training stack (module docstring), seeded; with ``normalize_path`` the observation
    statistics are loaded from a saved ``VecNormalize`` (to resume training)."""
    venv: VecEnv = make_vector_env(env_id, n_envs, env_kwargs, vec_env_kwargs)
    venv.seed(seed)
    venv = VecMonitor(venv)
    if normalize_path is not None:
        venv = VecNormalize.load(normalize_path, venv)
        venv.training = True
    elif normalize:
        options = {"norm_obs": True, "norm_reward": False, **(normalize if isinstance(normalize, dict) else {})}
        venv = VecNormalize(venv, **options)
    return venv


def find_wrapper(venv: VecEnv, kind: type) -> Any:
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
    return lambda obs: vec_normalize.normalize_obs(np.asarray(obs, dtype=np.float32)).astype(np.float32)
