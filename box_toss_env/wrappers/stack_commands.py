"""Throw commands for the batched ``BoxToss-Stack-v0`` (``box_toss_env.envs.stack_commands`` explains them:
flight time, touchdown offset, lean, aimed at the stack's top), the vector form of ``StackCommands``:

    envs = StackCommandsVector(gymnasium.make_vec("BoxToss-Stack-v0", num_envs=8))

Each command is turned into an env action from the observation the env last returned for that env: with the
batched env's same-step autoreset that is the next episode's first observation, as it should be.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.vector import VectorEnv, VectorWrapper

from box_toss_env.envs import stack_task, task, task_columns
from box_toss_env.envs.stack_commands import (
    FLIGHT_TIME_RANGE,
    OFFSET_RANGE,
    TURN_RANGE,
    batch_command_actions,
    check_stack_command_settings,
)


class StackCommandsVector(VectorWrapper):
    """A batched ``BoxToss-Stack-v0`` acting in throw commands; observations and rewards are the env's."""

    def __init__(
        self,
        env: VectorEnv,
        flight_time_range: tuple[float, float] = FLIGHT_TIME_RANGE,
        offset_range: float = OFFSET_RANGE,
        turn_range: float = TURN_RANGE,
    ):
        super().__init__(env)
        config = getattr(env.unwrapped, "config", None)
        if not isinstance(config, stack_task.StackConfig):
            raise TypeError(f"env must be a BoxToss-Stack vector env (with a stack config), got {env!r}")
        self.config = config
        self.settings = check_stack_command_settings(flight_time_range, offset_range, turn_range)
        self._observations: np.ndarray | None = None

    def reset(self, *, seed=None, options=None) -> tuple[Any, dict[str, Any]]:
        observations, info = self.env.reset(seed=seed, options=options)
        self._observations = np.asarray(observations)
        return observations, info

    def step(self, actions) -> tuple[Any, Any, Any, Any, dict[str, Any]]:
        if self._observations is None:
            raise ResetNeeded("call reset() before step()")
        commands = task.check_actions(actions, (self.num_envs, task_columns.ACTION_SIZE))
        env_actions = batch_command_actions(self._observations, commands, self.config, *self.settings)
        observations, rewards, terminations, truncations, info = self.env.step(env_actions.astype(np.float32))
        self._observations = np.asarray(observations)
        return observations, rewards, terminations, truncations, info
