"""A curriculum, the recipe option ``curriculum`` (``project.yml``): the env's arguments changed in stages while the
policy trains, ending on the recipe's own env.

    curriculum:
      - {until: 300000, env_kwargs: {box_length: 0.25}}   # throws 0 - 300k: a box of 0.25 x 0.2 m
      - {until: 600000, env_kwargs: {box_length: 0.32}}   # then 0.32 x 0.2 m, up to 600k throws
                                                          # then the recipe's env (0.4 x 0.2 m) to n_timesteps

Each stage's ``env_kwargs`` update the recipe's. Training starts on the stage its first throw falls in (a resumed run
too) and ``CurriculumCallback`` moves to the next at the first rollout past a stage's ``until``: the batched env
inside the training stack is replaced by one of the next stage's arguments (seeded with the run's seed plus the
throws so far, so each stage draws fresh episodes), the observation statistics carry on, and the policy's next
action is taken from the new env's first observations. Validation, the test targets and the learning-rate schedule
are the recipe's throughout: what the curves show is the final task. The stages' observations must have the
recipe's shape (a stage changes what is thrown, not what is observed).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
from stable_baselines3.common.callbacks import BaseCallback

from agents.envs import find_wrapper, wrap_vector_env
from agents.recipe_options import read_stages
from box_toss_env.wrappers.sb3_adapter import SB3VecEnvAdapter


def env_kwargs_at(config: dict[str, Any], timesteps: int) -> dict[str, Any]:
    """The env's arguments while training at ``timesteps`` throws: the stage's over the recipe's."""
    base = dict(config.get("env_kwargs") or {})
    for until, kwargs in read_stages(config.get("curriculum")):
        if timesteps < until:
            return {**base, **kwargs}
    return base


class CurriculumCallback(BaseCallback):
    """Moves training to the next stage's env at the first rollout past a stage's end (module docstring)."""

    def __init__(self, env_id: str, config: dict[str, Any], seed: int):
        super().__init__()
        self.env_id, self.config, self.seed = env_id, config, seed
        self.current = env_kwargs_at(config, 0)

    def _on_training_start(self) -> None:
        self.current = env_kwargs_at(self.config, self.model.num_timesteps)

    def _on_rollout_start(self) -> None:
        wanted = env_kwargs_at(self.config, self.model.num_timesteps)
        if wanted == self.current:
            return
        adapter = find_wrapper(self.model.get_env(), SB3VecEnvAdapter)
        vector_env = gym.make_vec(
            self.env_id,
            num_envs=adapter.num_envs,
            vectorization_mode="vector_entry_point",
            **wanted,
            **(self.config.get("vec_env_kwargs") or {}),
        )
        adapter.vector_env.close()
        adapter.vector_env = wrap_vector_env(vector_env, self.config.get("env_wrapper"))
        env = self.model.get_env()
        if env is None:
            raise RuntimeError("curriculum: the model has no env to change")
        env.seed(self.seed + self.model.num_timesteps)
        self.model._last_obs = env.reset()  # type: ignore[assignment]  # the new stage's first observations
        if getattr(self.model, "_last_episode_starts", None) is not None:
            self.model._last_episode_starts[:] = True  # type: ignore[index]
        if hasattr(self.model, "_last_original_obs") and hasattr(env, "get_original_obs"):
            self.model._last_original_obs = env.get_original_obs()
        self.current = wanted
        print(f"curriculum: {self.model.num_timesteps:,} throws, env {wanted}", flush=True)

    def _on_step(self) -> bool:
        return True
