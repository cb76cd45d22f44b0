"""``BoxToss-Goal-v0``: BoxToss in gymnasium-robotics' goal-conditioned form, for SB3's ``HerReplayBuffer``."""

from __future__ import annotations

from typing import Any, cast

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from box_toss_env.envs import task, task_columns, task_config
from box_toss_env.envs.box_toss import BoxTossEnv
from box_toss_env.envs.random_streams import check_seed

# -- goal columns: achieved and desired goals share this layout ------------------------------------
GOAL_X, GOAL_AT_REST, GOAL_TILT = 0, 1, 2
GOAL_FACES = slice(3, 7)
GOAL_SIZE = 7
MAX_TILT = 0.5 * task_columns.QUARTER_TURN  # [rad] |tilt| <= pi/4: the face down is the one nearest to flat


def achieved_goals(x: np.ndarray, angles: np.ndarray, at_rest: np.ndarray) -> np.ndarray:
    """Achieved goals (n, 7) float32 of boxes with centre x [m], angle [rad] and at-rest flags (n,):
    x, at rest (0 or 1), the tilt ``wrap(angle + k pi/2)`` in [-pi/4, pi/4] of the face k down
    (``task.faces_down``) from lying flat, and the one-hot of k."""
    angles = np.asarray(angles, dtype=np.float64).reshape(-1)
    faces = task.faces_down(angles)
    goals = np.zeros((len(angles), GOAL_SIZE), dtype=np.float32)
    goals[:, GOAL_X] = x
    goals[:, GOAL_AT_REST] = at_rest
    goals[:, GOAL_TILT] = task.wrap_angles(angles + task_columns.QUARTER_TURN * faces)
    goals[np.arange(len(angles)), GOAL_FACES.start + faces] = 1.0
    return goals


def desired_goals(episodes: task_config.Episodes) -> np.ndarray:
    """Desired goals (n, 7) float32 of the episodes: the target x, at rest (1), flat (tilt 0) and the
    target-face mask."""
    goals = np.zeros((len(episodes.data), GOAL_SIZE), dtype=np.float32)
    goals[:, GOAL_X] = episodes.target_x
    goals[:, GOAL_AT_REST] = 1.0
    goals[:, GOAL_FACES] = episodes.target_faces
    return goals


def goal_observations(observations: np.ndarray) -> dict[str, np.ndarray]:
    """The Dict observations (``observation``, ``achieved_goal``, ``desired_goal``) that ``BoxTossGoalEnv.reset``
    returns, from ``BoxTossEnv``'s first observations (n, 12) of the same seeds: the achieved goal is the box in
    the hand (its x and angle, at rest 0), the desired goal the observation's target x and target-face mask. So a
    policy trained on the goal env throws at ``BoxToss-v0``'s targets (the evaluation's)."""
    observations = np.asarray(observations, dtype=np.float32).reshape(-1, np.shape(observations)[-1])
    angles = np.arctan2(observations[:, task_columns.OBS_SIN], observations[:, task_columns.OBS_COS])
    achieved = achieved_goals(observations[:, task_columns.OBS_X], angles, np.zeros(len(observations)))
    desired = np.zeros((len(observations), GOAL_SIZE), dtype=np.float32)
    desired[:, GOAL_X] = observations[:, task_columns.OBS_TARGET_X]
    desired[:, GOAL_AT_REST] = 1.0
    desired[:, GOAL_FACES] = observations[:, task_columns.OBS_TARGET_FACES]
    return {"observation": observations, "achieved_goal": achieved, "desired_goal": desired}


def refuse_base_box(kwargs: dict[str, Any]) -> None:
    """A ValueError if ``kwargs`` ask for a base box, which the goal cannot describe."""
    if kwargs.get("base_box"):
        raise ValueError(
            "BoxToss-Goal-v0 does not take base_box=True: the goal (x, at rest, tilt, face) "
            "does not hold where the base box ended, which the distance depends on"
        )


class BoxTossGoalEnv(gym.Env):
    r"""BoxToss with gymnasium-robotics' goal-conditioned interface, so that HER can relabel each throw as
    a success for where it came to rest.

    ## Description

    The task and the physics are ``BoxToss-v0``'s (see ``BoxTossEnv``): one throw per episode, rewarded
    for coming to rest at a target x on a target face. This env holds a ``BoxTossEnv`` (``throw_env``),
    throws with it and reports each observation as the Dict that goal-conditioned agents expect,
    ``{"observation", "achieved_goal", "desired_goal"}``, with ``compute_reward(achieved_goal,
    desired_goal, info)`` vectorised over any leading batch dimensions (SB3's ``HerReplayBuffer``
    recomputes the rewards of relabelled goals with it). An episode is one step, so HER's ``"future"``
    strategy relabels a throw with the achieved goal of its own landing.

    ## Action Space

    As ``BoxTossEnv``: ``Box(-1, 1, (3,), float32)``, launch speed, direction and spin.

    ## Observation Space

    ``Dict`` of three ``Box`` spaces, float32:

    | Key             | Shape | Meaning                                                                 |
    |-----------------|-------|-------------------------------------------------------------------------|
    | observation     | (12,) | ``BoxTossEnv``'s observation ((15,) with ``observe_dynamics``)          |
    | achieved_goal   | (7,)  | where the box is: centre x, at rest, tilt, one-hot of the face down     |
    | desired_goal    | (7,)  | the task: target x, 1 (at rest), 0 (flat), the target-face mask         |

    Goal columns (achieved and desired share the layout, so either can stand for the other):

    | Num | Goal column | Achieved goal                                        | Desired goal                  | Unit |
    |-----|-------------|------------------------------------------------------|-------------------------------|------|
    | 0   | x           | the box's centre x                                   | target x                      | m    |
    | 1   | at rest     | 1 if the throw came to rest (0 in the hand)          | 1                             |      |
    | 2   | tilt        | ``wrap(angle + k pi/2)`` in [-pi/4, pi/4], k the face down | 0                       | rad  |
    | 3-6 | faces       | one-hot of the face k down                           | 1 for each target face        |      |

    The x bounds are those of the observation's x and target-x columns together.

    ## Rewards

    ``step`` returns ``compute_reward(achieved_goal, desired_goal, info)`` of its own goals, and that is
    ``BoxTossEnv``'s reward computed from the goals: the box's angle is ``tilt - k pi/2``, so

        reward = -distance_weight * |x_a - x_d| - orientation_weight * orientation_error + success_bonus * success

    with ``orientation_error`` the turn to the nearest face of the desired mask lying flat
    (``task.orientation_errors``) and ``success`` = achieved at rest, ``|x_a - x_d| <= position_tolerance``
    and ``orientation_error < pi/4``. It equals ``BoxToss-v0``'s reward for the same seed and throw up to
    the float32 rounding of the goals (``tests/envs/test_goal.py`` checks it over 300 throws). ``info`` is
    ``BoxTossEnv``'s, with ``is_success`` (``compute_success`` of the goals) added for SB3's logs.
    ``compute_reward`` ignores ``info``.

    ## Starting State

    As ``BoxTossEnv`` (the same draws from the same seed); the achieved goal is the box in the hand (at
    rest 0, its release x and angle).

    ## Episode End

    As ``BoxTossEnv``: every episode is one throw, ``terminated`` after the step (``compute_terminated``
    is True for any goals, ``compute_truncated`` False).

    ## Arguments

    ``gymnasium.make("BoxToss-Goal-v0", **kwargs)`` takes ``BoxTossEnv``'s keyword arguments (e.g.
    ``target_face="mixed"``), except ``base_box`` (a ``ValueError``: with a base box the distance depends
    on where the base ended, which the goal does not hold). ``render_mode`` renders as ``BoxTossEnv``.

    ## Version History

    * v0: initial version.
    """

    metadata = BoxTossEnv.metadata

    def __init__(self, render_mode: str | None = None, **kwargs):
        refuse_base_box(kwargs)
        self.throw_env = BoxTossEnv(render_mode=render_mode, **kwargs)
        self.render_mode = self.throw_env.render_mode
        self.config = self.throw_env.config
        self.action_space = self.throw_env.action_space
        inner = cast(spaces.Box, self.throw_env.observation_space)
        x_low = min(inner.low[task_columns.OBS_X], inner.low[task_columns.OBS_TARGET_X])
        x_high = max(inner.high[task_columns.OBS_X], inner.high[task_columns.OBS_TARGET_X])
        low = np.array([x_low, 0.0, -MAX_TILT, 0.0, 0.0, 0.0, 0.0], dtype=np.float32)
        high = np.array([x_high, 1.0, MAX_TILT, 1.0, 1.0, 1.0, 1.0], dtype=np.float32)
        self.observation_space = spaces.Dict(
            {
                "observation": inner,
                "achieved_goal": spaces.Box(low, high, dtype=np.float32),
                "desired_goal": spaces.Box(low, high, dtype=np.float32),
            }
        )

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """As ``BoxTossEnv.reset``: the throw env draws from this env's ``np_random``."""
        super().reset(seed=check_seed(seed))
        self.throw_env.np_random = self.np_random
        observation, info = self.throw_env.reset(options=options)
        release = self.throw_env._episodes.release[0]
        achieved = achieved_goals(release[:1], release[2:3], np.zeros(1))[0]
        return self._dict(observation, achieved), info

    def step(self, action):
        """Throw with ``BoxTossEnv.step``; the reward is ``compute_reward`` of the goals."""
        observation, _, _, _, info = self.throw_env.step(action)
        achieved = achieved_goals(
            np.array([info["final_x"]]), np.array([info["final_angle"]]), np.array([info["at_rest"]])
        )[0]
        obs = self._dict(observation, achieved)
        reward = float(self.compute_reward(achieved, obs["desired_goal"], info))
        info["is_success"] = bool(self.compute_success(achieved, obs["desired_goal"]))
        terminated = bool(self.compute_terminated(achieved, obs["desired_goal"], info))
        truncated = bool(self.compute_truncated(achieved, obs["desired_goal"], info))
        return obs, reward, terminated, truncated, info

    def _dict(self, observation: np.ndarray, achieved: np.ndarray) -> dict[str, np.ndarray]:
        return {
            "observation": observation,
            "achieved_goal": achieved,
            "desired_goal": desired_goals(self.throw_env._episodes)[0],
        }

    # -- goal functions, vectorised over leading dimensions -----------------------------------------
    def _terms(self, achieved_goal, desired_goal):
        """(distance, orientation error, success) of goals (..., 7), each of the leading shape."""
        achieved = np.asarray(achieved_goal, dtype=np.float64)
        desired = np.asarray(desired_goal, dtype=np.float64)
        shape = np.broadcast_shapes(achieved.shape, desired.shape)
        achieved = np.broadcast_to(achieved, shape).reshape(-1, GOAL_SIZE)
        desired = np.broadcast_to(desired, shape).reshape(-1, GOAL_SIZE)
        distance = np.abs(achieved[:, GOAL_X] - desired[:, GOAL_X])
        angles = achieved[:, GOAL_TILT] - task_columns.QUARTER_TURN * np.argmax(achieved[:, GOAL_FACES], axis=1)
        orientation_error = task.orientation_errors(angles, desired[:, GOAL_FACES])
        success = (
            (achieved[:, GOAL_AT_REST] > 0.5)
            & (distance <= self.config.position_tolerance)
            & (orientation_error < MAX_TILT)
        )
        return tuple(value.reshape(shape[:-1]) for value in (distance, orientation_error, success))

    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray:
        """The reward (see Rewards) of goals (..., 7), of the leading shape; ``info`` is not used."""
        config = self.config
        distance, orientation_error, success = self._terms(achieved_goal, desired_goal)
        return (
            (0.0 - config.distance_weight * distance)
            + (0.0 - config.orientation_weight * orientation_error)
            + config.success_bonus * success
        )

    def compute_success(self, achieved_goal, desired_goal) -> np.ndarray:
        """Whether goals (..., 7) are a success: at rest, within ``position_tolerance`` of the desired x,
        a desired face down."""
        return self._terms(achieved_goal, desired_goal)[2]

    def compute_terminated(self, achieved_goal, desired_goal, info) -> np.ndarray:
        """True for any goals (of the leading shape): every episode is one throw."""
        return np.ones(np.shape(achieved_goal)[:-1], dtype=bool)

    def compute_truncated(self, achieved_goal, desired_goal, info) -> np.ndarray:
        """False for any goals: a throw is never cut by a time limit."""
        return np.zeros(np.shape(achieved_goal)[:-1], dtype=bool)

    # -- rendering: the throw env's -----------------------------------------------------------------
    def render(self):
        """As ``BoxTossEnv.render``."""
        return self.throw_env.render()

    def close(self):
        """Close the throw env's window if one is open."""
        self.throw_env.close()
