"""Ballistic throw commands: a prior that lands a target face flat on the target, and a command
that says how to depart from it (flight time, landing offset, lean), instead of speed, launch angle
and spin.

A policy that stands the box on an end in the env's own action space must hit a precise spin, and
which spin that is depends on the release angle and on how long the box flies. Free flight has a
closed form, so that dependence can be taken out of what is learned: a *command* c in [-1, 1]^3 names

    T   = T_lo + (T_hi - T_lo) (c0 + 1) / 2     flight time of the centre until touchdown [s]
    x*  = target_x + offset_range c1            where the centre should touch down [m]
    phi = phi_face + turn_range c2              the box's angle at touchdown [rad]

where phi_face is the angle nearest the release angle theta0 at which a target face points flat
down (face f is down at angle -f pi/2, modulo 2 pi; the target faces are in the observation). The
throw that does it follows from the parabola and the constant spin of free flight, from the release
pose (x0, y0, theta0) in the observation:

    h(phi) = (L/2) |sin phi| + (W/2) |cos phi|  height of the centre when its lowest corner touches
    vx = (x* - x0) / T,   vy = (h(phi) - y0) / T + g T / 2,   spin = (phi - theta0) / T
    speed = sqrt(vx^2 + vy^2),   launch angle = atan2(vy, vx).

With a base box to land on (``BoxToss-OnBox-v0``) the touchdown is on the base's top rather than on the
floor: the height h(phi) is raised by the top's height y_top (from the base's pose and size in the
observation: y_base + (L_b/2) |sin theta_b| + (H_b/2) |cos theta_b|), and x* is measured from the base's
centre, which is the target x.

Those are mapped to env actions as ``task.throws_to_actions`` does, and a throw beyond the env's
limits (speed above ``max_speed``, a launch angle outside its range, spin above ``max_spin``) is
clipped to the limit, each component on its own; ``info["command_clipped"]`` says whether it was.
The command c = 0 is the prior's own throw: a target face flat down, touching down at the target.
What is left to learn is smooth: standing the box on an end, for instance, takes a small lean
against the slide that changes slowly with the flight time, whatever the release angle. Touchdown is
where the centre's parabola meets h(phi), before bounces and slides, which the command's offset and
lean learn to allow for.

``BallisticThrows`` wraps one env; ``box_toss_env.wrappers.ballistic.BallisticThrowsVector`` wraps a vector env;
``ballistic_actions`` is the mapping itself, batch-first, for policies that act on raw observations.
"""

from __future__ import annotations

import math
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np

from box_toss_env.envs import task, task_columns, task_config
from box_toss_env.physics.ranges import Range

MIN_FLIGHT_TIME = 0.2  # [s] default lower end of T: below it a half turn needs more than 15 rad/s
DEFAULT_OFFSET_RANGE = 0.5  # [m] x* - target_x in [-offset_range, offset_range]
DEFAULT_TURN_RANGE = 0.25 * math.pi  # [rad] phi - phi_face in [-turn_range, turn_range]: leans up to 45 degrees
# (a range of pi/2 reaches the neighbouring faces too, where PPO found a poorer optimum: 22 % on short ends)
_FACE_DOWN_ANGLES = -task_columns.QUARTER_TURN * np.arange(4.0)  # face f points down at angle -f pi/2


def check_command_settings(
    config: task_config.TaskConfig, flight_time_range, offset_range, turn_range
) -> tuple[tuple[float, float], float, float]:
    """Validated (flight_time_range, offset_range, turn_range); None takes the default
    (T in [0.2 s, 2 max_speed / g]: the flight of the steepest, fastest throw)."""
    if flight_time_range is None:
        flight_time_range = (MIN_FLIGHT_TIME, max(2.0 * config.max_speed / config.gravity, 2 * MIN_FLIGHT_TIME))
    low, high = task_config.check_interval("flight_time_range", flight_time_range, Range(0.0, 1e3, "s", low_open=True))
    if low >= high:
        raise ValueError(f"flight_time_range must have low < high, got {flight_time_range!r}")
    offset_range = Range(0.0, 1e3, "m").check("offset_range", offset_range)
    turn_range = Range(0.0, 4.0 * math.pi, "rad").check("turn_range", turn_range)
    return (low, high), offset_range, turn_range


def face_angles(theta0: np.ndarray, target_faces: np.ndarray) -> np.ndarray:
    """(n,) the angle nearest each ``theta0`` at which one of its target faces (n, 4 flags) points
    flat down: -f pi/2 + 2 pi k, over target faces f and integers k (the lowest f on a tie)."""
    turns = np.round((theta0[:, None] - _FACE_DOWN_ANGLES) / (2.0 * math.pi))
    candidates = _FACE_DOWN_ANGLES + 2.0 * math.pi * turns  # (n, 4) nearest angle of each face
    distance = np.where(target_faces > 0.5, np.abs(candidates - theta0[:, None]), np.inf)
    return candidates[np.arange(len(theta0)), np.argmin(distance, axis=1)]


def observed_base_top(observations: np.ndarray) -> np.ndarray:
    """(n,) height [m] of the top of the base box in observations (n, obs) of a task with a base box:
    y_base + (L_b/2) |sin theta_b| + (H_b/2) |cos theta_b|."""
    obs = np.asarray(observations, dtype=np.float64)
    return (
        obs[:, task_columns.OBS_BASE_Y]
        + 0.5 * obs[:, task_columns.OBS_BASE_LENGTH] * np.abs(obs[:, task_columns.OBS_BASE_SIN])
        + 0.5 * obs[:, task_columns.OBS_BASE_HEIGHT] * np.abs(obs[:, task_columns.OBS_BASE_COS])
    )


def ballistic_throws(
    observations: np.ndarray,
    commands: np.ndarray,
    config: task_config.TaskConfig,
    flight_time_range: tuple[float, float],
    offset_range: float,
    turn_range: float,
) -> np.ndarray:
    """(n, 3) speed [m/s], launch angle [rad] and spin [rad/s] that carry out ``commands`` (n, 3)
    from the release poses in ``observations`` (n, obs), by the formulas of the module docstring."""
    obs = np.asarray(observations, dtype=np.float64)
    c = np.asarray(commands, dtype=np.float64)
    x0, y0 = obs[:, task_columns.OBS_X], obs[:, task_columns.OBS_Y]
    theta0 = np.arctan2(obs[:, task_columns.OBS_SIN], obs[:, task_columns.OBS_COS])
    t_low, t_high = flight_time_range
    flight_time = t_low + (t_high - t_low) * 0.5 * (c[:, 0] + 1.0)
    landing_x = obs[:, task_columns.OBS_TARGET_X] + offset_range * c[:, 1]
    phi = face_angles(theta0, obs[:, task_columns.OBS_TARGET_FACES]) + turn_range * c[:, 2]
    if config.draws_box_size:  # the episode's box, observed
        half_length, half_width = (0.5 * obs[:, column] for column in config.box_size_observed)
    else:
        half_length, half_width = np.full(len(obs), config.half_length), np.full(len(obs), config.half_width)
    height = half_length * np.abs(np.sin(phi)) + half_width * np.abs(np.cos(phi))
    if config.base_box:  # touch down on the base box's top
        height = height + observed_base_top(obs)
    vx = (landing_x - x0) / flight_time
    vy = (height - y0) / flight_time + 0.5 * config.gravity * flight_time
    spin = (phi - theta0) / flight_time
    return np.stack((np.hypot(vx, vy), np.arctan2(vy, vx), spin), axis=1)


def ballistic_actions(
    observations: np.ndarray,
    commands: np.ndarray,
    config: task_config.TaskConfig,
    flight_time_range: tuple[float, float] | None = None,
    offset_range: float = DEFAULT_OFFSET_RANGE,
    turn_range: float = DEFAULT_TURN_RANGE,
) -> tuple[np.ndarray, np.ndarray]:
    """Env actions (n, 3) for ``commands`` (n, 3) in [-1, 1] thrown from the release poses in
    ``observations`` (n, obs), and (n,) bool: which were clipped to the env's limits."""
    settings = check_command_settings(config, flight_time_range, offset_range, turn_range)
    commands = task.check_actions(commands, np.shape(commands))
    actions = task.throws_to_actions(ballistic_throws(observations, commands, config, *settings), config)
    clipped = (np.abs(actions) > 1.0).any(axis=1)
    return np.clip(actions, -1.0, 1.0), clipped


def _throw_observation(observation: Any) -> np.ndarray:
    """The throw env's observation: ``observation`` itself, or a goal env's ``observation["observation"]``."""
    return np.asarray(observation["observation"] if isinstance(observation, dict) else observation)


class BallisticThrows(gym.Wrapper):
    """BoxToss acting in ballistic commands (module docstring): the action is (flight time,
    landing offset, touchdown angle), each in [-1, 1]; observations and rewards are the env's. Around
    ``BoxToss-Goal-v0`` the commands are computed from the Dict's ``"observation"`` (the throw env's).

    Also loads in RL Baselines3 Zoo as ``env_wrapper: box_toss_env.envs.ballistic.BallisticThrows``.
    """

    def __init__(
        self,
        env: gym.Env,
        flight_time_range: tuple[float, float] | None = None,
        offset_range: float = DEFAULT_OFFSET_RANGE,
        turn_range: float = DEFAULT_TURN_RANGE,
    ):
        super().__init__(env)
        self.config: task_config.TaskConfig = env.unwrapped.config  # type: ignore[attr-defined]  # a BoxToss env
        self.settings = check_command_settings(self.config, flight_time_range, offset_range, turn_range)
        self._observation: np.ndarray | None = None

    def reset(self, **kwargs) -> tuple[Any, dict[str, Any]]:
        observation, info = self.env.reset(**kwargs)
        self._observation = _throw_observation(observation)
        return observation, info

    def step(self, action) -> tuple[Any, SupportsFloat, bool, bool, dict[str, Any]]:
        if self._observation is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        command = task.check_actions(action, (task_columns.ACTION_SIZE,))
        actions, clipped = ballistic_actions(self._observation[None], command, self.config, *self.settings)
        observation, reward, terminated, truncated, info = self.env.step(actions[0])
        self._observation = _throw_observation(observation)
        info["command_clipped"] = bool(clipped[0])
        return observation, reward, terminated, truncated, info
