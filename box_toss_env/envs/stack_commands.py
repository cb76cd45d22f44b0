"""Throw commands for ``BoxToss-Stack-v0``: a throw that touches down flat on the stack's top at the target, and
a command that says how to depart from it (flight time, touchdown offset, lean), instead of speed, direction
and spin (as ``envs.ballistic`` does for one throw).

A command c in [-1, 1]^3 names the flight time T = T_lo + (T_hi - T_lo) (c0 + 1) / 2, the touchdown x
x* = target_x + offset_range c1 and the touchdown angle phi = phi_flat + turn_range c2, phi_flat the angle
nearest the release angle theta0 at which a long side is down. The centre touches down at the stack's height H
(in the observation) plus h(phi) = (L/2) |sin phi| + (W/2) |cos phi|, the free-flight throw that does it being

    vx = (x* - x0) / T,   vy = (H + h(phi) - y0) / T + g T / 2,   spin = (phi - theta0) / T

from the release pose (x0, y0, theta0) of the box in the hand; a throw beyond the env's limits is clipped to
them. The command c = 0 is the prior's throw: flat onto the stack's top, centred on the target.
"""

from __future__ import annotations

import math
from typing import Any, SupportsFloat, cast

import gymnasium as gym
import numpy as np

from box_toss_env.envs import stack_task, task, task_columns

FLIGHT_TIME_RANGE = (0.3, 1.6)  # [s]
OFFSET_RANGE = 0.3  # [m]
TURN_RANGE = 0.25 * math.pi  # [rad]


def command_actions(
    observation: np.ndarray,
    commands: np.ndarray,
    config: stack_task.StackConfig,
    flight_time_range: tuple[float, float] = FLIGHT_TIME_RANGE,
    offset_range: float = OFFSET_RANGE,
    turn_range: float = TURN_RANGE,
) -> np.ndarray:
    """The env actions (m, 3) of ``commands`` (m, 3) in [-1, 1] from one ``observation`` (module docstring)."""
    tail = np.asarray(observation, dtype=np.float64)[stack_task.BODY_SIZE * config.n_boxes :]
    x0, y0 = tail[stack_task.H_X], tail[stack_task.H_Y]
    theta0 = math.atan2(tail[stack_task.H_SIN], tail[stack_task.H_COS])
    half_length, half_width = 0.5 * tail[stack_task.H_LENGTH], 0.5 * tail[stack_task.H_WIDTH]
    t_low, t_high = flight_time_range
    commands = np.asarray(commands, dtype=np.float64)
    flight_time = t_low + (t_high - t_low) * 0.5 * (commands[:, 0] + 1.0)
    landing_x = tail[stack_task.G_TARGET_X] + offset_range * commands[:, 1]
    phi = round(theta0 / math.pi) * math.pi + turn_range * commands[:, 2]
    height = tail[stack_task.G_HEIGHT] + half_length * np.abs(np.sin(phi)) + half_width * np.abs(np.cos(phi))
    vx = (landing_x - x0) / flight_time
    vy = (height - y0) / flight_time + 0.5 * config.gravity * flight_time
    spin = (phi - theta0) / flight_time
    return stack_task.actions_of_throws(np.hypot(vx, vy), np.arctan2(vy, vx), spin, config)


class StackCommands(gym.Wrapper):
    """``BoxToss-Stack-v0`` acting in throw commands (module docstring); observations and rewards are the env's.
    Loads in RL Baselines3 Zoo as ``env_wrapper: box_toss_env.envs.stack_commands.StackCommands``."""

    def __init__(
        self,
        env: gym.Env,
        flight_time_range: tuple[float, float] = FLIGHT_TIME_RANGE,
        offset_range: float = OFFSET_RANGE,
        turn_range: float = TURN_RANGE,
    ):
        super().__init__(env)
        self.config: stack_task.StackConfig = env.unwrapped.config  # type: ignore[attr-defined]  # BoxToss-Stack
        self.settings = (cast(tuple[float, float], tuple(flight_time_range)), float(offset_range), float(turn_range))
        self._observation: np.ndarray | None = None

    def reset(self, **kwargs) -> tuple[Any, dict[str, Any]]:
        observation, info = self.env.reset(**kwargs)
        self._observation = np.asarray(observation)
        return observation, info

    def step(self, action) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        if self._observation is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        command = task.check_actions(action, (task_columns.ACTION_SIZE,))
        env_action = command_actions(self._observation, command, self.config, *self.settings)[0]
        observation, reward, terminated, truncated, info = self.env.step(env_action.astype(np.float32))
        self._observation = np.asarray(observation)
        return observation, reward, terminated, truncated, info


def batch_command_actions(
    observations: np.ndarray,
    commands: np.ndarray,
    config: stack_task.StackConfig,
    flight_time_range: tuple[float, float] = FLIGHT_TIME_RANGE,
    offset_range: float = OFFSET_RANGE,
    turn_range: float = TURN_RANGE,
) -> np.ndarray:
    """The env actions (n, 3) of one command per env: ``commands`` (n, 3) from ``observations`` (n, obs), row by
    row as ``command_actions`` (a vector env's, or a policy's batch)."""
    observations, commands = np.asarray(observations), np.asarray(commands, dtype=np.float64).reshape(-1, 3)
    return np.concatenate(
        [
            command_actions(observations[i], commands[i : i + 1], config, flight_time_range, offset_range, turn_range)
            for i in range(len(commands))
        ]
    )


def check_stack_command_settings(
    flight_time_range=FLIGHT_TIME_RANGE, offset_range=OFFSET_RANGE, turn_range=TURN_RANGE
) -> tuple[tuple[float, float], float, float]:
    """The command settings, checked: a ValueError naming the first that is out of range."""
    low, high = (float(v) for v in flight_time_range)
    if not (0.0 < low < high and math.isfinite(high)):
        raise ValueError(f"flight_time_range must be (low, high) with 0 < low < high, got {flight_time_range!r}")
    for name, value in (("offset_range", offset_range), ("turn_range", turn_range)):
        if not (math.isfinite(float(value)) and float(value) >= 0.0):
            raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return (low, high), float(offset_range), float(turn_range)
