"""BoxToss-Goal-v0: BoxToss in gymnasium-robotics' goal-conditioned form (for SB3's HerReplayBuffer)."""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces

from box_toss_env.envs import task
from box_toss_env.envs.box_toss import BoxTossEnv


class BoxTossGoalEnv(BoxTossEnv):
    """
    ## Description
    BoxToss (one throw per episode) with Dict observations {"observation", "achieved_goal", "desired_goal"}
    and a vectorised ``compute_reward``, so HER can relabel a throw as a success for where it landed.

    Goal encoding (6 floats): ``(x, at_rest, face_0..face_3)``. desired_goal = (target x, 1, the target-face
    mask of task.py); achieved_goal = (the box's x, 1 if at rest, one-hot of the face down) after the
    throw, and where it is in the hand (at_rest 0) after reset. A face mask rather than an angle keeps
    the goal what the task scores and lets HER relabel (achieved and desired share one encoding); the
    orientation term uses the face down rather than the exact rest angle, so it equals BoxTossEnv's term
    for a box resting flat and differs by the small tilt otherwise (pi when not at rest).

    ## Action Space
    As ``BoxTossEnv`` (the throw, ``Box(-1, 1, (3,))``).

    ## Observation Space
    | key             | shape | meaning                                                      |
    |-----------------|-------|--------------------------------------------------------------|
    | observation     | as BoxTossEnv | BoxTossEnv's observation                             |
    | achieved_goal   | (6,)  | (box x, at rest 0/1, one-hot of the face down)               |
    | desired_goal    | (6,)  | (target x, 1, target-face mask)                              |

    ## Rewards
    ``compute_reward(achieved, desired, info)``: task.py's distance, orientation (``task.orientation_errors``
    of the face down; pi when not at rest) and success terms computed from the goals alone, over any leading
    batch dimensions; ``step`` returns exactly ``compute_reward`` of its own goals.

    ## Starting State
    As ``BoxTossEnv``; the achieved goal is the box in the hand (at rest 0, no face).

    ## Episode End
    One throw: terminated after the step, as ``BoxTossEnv``.

    ## Arguments
    ``BoxTossEnv``'s keyword arguments, except ``base_box`` (not supported yet).

    ## Version history
    - v0: first version (no base box).
    """

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        config = self.config
        if config.base_box:
            raise ValueError("BoxToss-Goal-v0 does not support a base box yet")
        low, high = self.observation_space.low, self.observation_space.high
        glow = np.array([low[task.OBS_X], 0, 0, 0, 0, 0], dtype=np.float32)
        ghigh = np.array([high[task.OBS_X], 1, 1, 1, 1, 1], dtype=np.float32)
        goal = spaces.Box(glow, ghigh, dtype=np.float32)
        self._flat_space = self.observation_space  # BoxTossEnv.step checks its observation against it
        self.observation_space = spaces.Dict(
            {"observation": self.observation_space, "achieved_goal": goal, "desired_goal": goal})

    def _goals(self, x: float, angle: float, at_rest: bool):
        unwrapped = self
        faces = unwrapped._episodes.data[0, task.EP_TARGET_FACES]
        achieved = np.zeros(6, dtype=np.float32)
        achieved[0], achieved[1] = x, float(at_rest)
        if at_rest:
            achieved[2 + int(task.faces_down(np.array([angle]))[0])] = 1.0
        desired = np.concatenate([[unwrapped._episodes.data[0, task.EP_TARGET_X], 1.0], faces]).astype(np.float32)
        return achieved, desired

    def reset(self, *, seed=None, options=None):
        obs, info = super().reset(seed=seed, options=options)
        achieved, desired = self._goals(float(obs[task.OBS_X]), 0.0, False)
        return {"observation": obs, "achieved_goal": achieved, "desired_goal": desired}, info

    def step(self, action):
        dict_space, self.observation_space = self.observation_space, self._flat_space
        try:
            obs, _, terminated, truncated, info = super().step(action)
        finally:
            self.observation_space = dict_space
        achieved, desired = self._goals(info["final_x"], info["final_angle"], info["at_rest"])
        reward = float(self.compute_reward(achieved, desired, info))
        info["is_success"] = bool(self.compute_success(achieved, desired))
        return ({"observation": obs, "achieved_goal": achieved, "desired_goal": desired},
                reward, terminated, truncated, info)

    def compute_success(self, achieved_goal, desired_goal):
        a, d = np.asarray(achieved_goal), np.asarray(desired_goal)
        config = self.config
        face_ok = (a[..., 2:] * d[..., 2:]).sum(axis=-1) > 0.5
        return (a[..., 1] > 0.5) & (np.abs(a[..., 0] - d[..., 0]) <= config.position_tolerance) & face_ok

    def compute_reward(self, achieved_goal, desired_goal, info):
        """task.py's reward terms from the goals alone, over any leading batch dimensions: distance
        |x - target x|, orientation error (``task.orientation_errors``) of the face down (pi when the box is
        not at rest on a face) and the success bonus."""
        a, d = np.asarray(achieved_goal, dtype=np.float64), np.asarray(desired_goal, dtype=np.float64)
        config = self.config
        shape = a.shape[:-1]
        faces_a, faces_d = a[..., 2:].reshape(-1, 4), d[..., 2:].reshape(-1, 4)
        angles = -task.QUARTER_TURN * np.argmax(faces_a, axis=1)
        errors = np.where(faces_a.max(axis=1) > 0.5, task.orientation_errors(angles, faces_d), math.pi).reshape(shape)
        success = self.compute_success(a, d)
        return (-config.distance_weight * np.abs(a[..., 0] - d[..., 0]) - config.orientation_weight * errors
                + config.success_bonus * success)
