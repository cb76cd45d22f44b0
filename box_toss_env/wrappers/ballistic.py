"""Ballistic throw commands for a vector env of BoxToss (``box_toss_env.envs.ballistic`` explains
the commands: flight time, landing offset, touchdown angle):

    envs = BallisticThrowsVector(gymnasium.make_vec("BoxToss-ShortEnd-v0", num_envs=64))

Each command is turned into an env action from the observation the env last returned for that
sub-env: with ``AutoresetMode.SAME_STEP`` (the native batched env) that is the next episode's
release pose, as it should be. In ``NEXT_STEP`` mode the step after an episode ends is a reset step
whose action the env ignores, so the stale pose it is computed from does not matter either.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.vector import VectorEnv, VectorWrapper

from box_toss_env.envs import task, task_columns, task_config
from box_toss_env.envs.ballistic import (
    DEFAULT_OFFSET_RANGE,
    DEFAULT_TURN_RANGE,
    ballistic_actions,
    check_command_settings,
)


class BallisticThrowsVector(VectorWrapper):
    """A BoxToss vector env acting in ballistic commands; ``info["command_clipped"]`` (num_envs,)
    says which commands the env's limits clipped."""

    def __init__(
        self,
        env: VectorEnv,
        flight_time_range: tuple[float, float] | None = None,
        offset_range: float = DEFAULT_OFFSET_RANGE,
        turn_range: float = DEFAULT_TURN_RANGE,
    ):
        super().__init__(env)
        config = getattr(env.unwrapped, "config", None)
        if not isinstance(config, task_config.TaskConfig):
            raise TypeError(f"env must be a BoxToss vector env (with a task config), got {env!r}")
        self.config = config
        self.settings = check_command_settings(config, flight_time_range, offset_range, turn_range)
        self._observations: np.ndarray | None = None

    def reset(self, *, seed=None, options=None) -> tuple[Any, dict[str, Any]]:
        observations, info = self.env.reset(seed=seed, options=options)
        self._observations = np.asarray(observations)
        return observations, info

    def step(self, actions) -> tuple[Any, Any, Any, Any, dict[str, Any]]:
        if self._observations is None:
            raise ResetNeeded("call reset() before step()")
        commands = task.check_actions(actions, (self.num_envs, task_columns.ACTION_SIZE))
        env_actions, clipped = ballistic_actions(self._observations, commands, self.config, *self.settings)
        observations, rewards, terminations, truncations, info = self.env.step(env_actions)
        self._observations = np.asarray(observations)
        return observations, rewards, terminations, truncations, {**info, "command_clipped": clipped}
