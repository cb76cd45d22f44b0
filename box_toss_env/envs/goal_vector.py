"""The native batched ``BoxToss-Goal-v0``: ``num_envs`` goal-conditioned throws simulated in one engine call.

    envs = gymnasium.make_vec("BoxToss-Goal-v0", num_envs=64)            # this class (vector_entry_point)
    envs = gymnasium.make_vec("BoxToss-Goal-v0", num_envs=64, threads=1)  # one engine thread

Env i is exactly a single ``BoxToss-Goal-v0`` seeded the same way: its throws are the batched ``BoxToss-v0``'s
(``BoxTossVectorEnv``: the same arguments, checked the same way, ``num_envs`` in [1, ``MAX_NUM_ENVS``], every seed
of a list checked before any env is seeded, naming the index of a bad one), and its observations, rewards and goal
functions those of ``BoxTossGoalEnv``: a Dict of ``observation``, ``achieved_goal`` and ``desired_goal``, batched,
the reward ``compute_reward`` of the goals. Episodes are one throw, so envs reset in the step they end
(``AutoresetMode.SAME_STEP``): the final Dict observations are in ``info["final_obs"]``, the final infos (with
``is_success``) in ``info["final_info"]``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from box_toss_env.envs.box_toss_vector import BoxTossVectorEnv
from box_toss_env.envs.goal import BoxTossGoalEnv, achieved_goals, desired_goals, refuse_base_box


class BoxTossGoalVectorEnv(VectorEnv):
    """``num_envs`` ``BoxToss-Goal-v0`` envs stepped together; keyword arguments are ``BoxTossVectorEnv``'s
    (``threads``, ``render_mode``) and the goal env's (``BoxTossEnv``'s, less ``base_box``)."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, num_envs: int = 1, *, threads: int | None = None, render_mode: str | None = None, **kwargs):
        refuse_base_box(kwargs)
        self.throws = BoxTossVectorEnv(num_envs, threads=threads, render_mode=render_mode, **kwargs)
        self.goals = BoxTossGoalEnv(**kwargs)  # the single env's spaces and goal functions
        self.num_envs = self.throws.num_envs
        self.render_mode = self.throws.render_mode
        self.metadata = {**self.metadata, "render_fps": self.throws.metadata["render_fps"]}
        self.single_observation_space = self.goals.observation_space
        self.single_action_space = self.goals.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._desired: np.ndarray | None = None

    @property  # type: ignore[misc]  # a generator per env, where Gymnasium's vector envs have one
    def np_random(self) -> list[np.random.Generator]:  # type: ignore[override]
        """Each env's random generator (``BoxTossVectorEnv.np_random``)."""
        return self.throws.np_random

    def _observations(self, observation: np.ndarray) -> dict[str, np.ndarray]:
        """The Dict observations of the envs' current episodes (the boxes in the hand)."""
        episodes = self.throws._episodes
        release = episodes.release
        self._desired = desired_goals(episodes)
        achieved = achieved_goals(release[:, 0], release[:, 2], np.zeros(self.num_envs))
        return {"observation": observation, "achieved_goal": achieved, "desired_goal": self._desired}

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        """As ``BoxTossVectorEnv.reset``, observed as goals."""
        observation, info = self.throws.reset(seed=seed, options=options)
        return self._observations(observation), info

    def step(self, actions):
        """Throw every box (``BoxTossVectorEnv.step``); each reward is ``compute_reward`` of the throw's goals."""
        desired = self._desired
        observation, _, terminated, truncated, info = self.throws.step(actions)
        assert desired is not None  # step refuses before a reset (ResetNeeded)
        final = info["final_info"]
        achieved = achieved_goals(final["final_x"], final["final_angle"], final["at_rest"])
        reward = self.compute_reward(achieved, desired, final)
        final["is_success"] = self.compute_success(achieved, desired)
        final["_is_success"] = np.ones(self.num_envs, dtype=bool)
        info["final_obs"] = {"observation": info["final_obs"], "achieved_goal": achieved, "desired_goal": desired}
        return self._observations(observation), reward, terminated, truncated, info

    # -- goal functions: the single goal env's, vectorised over leading dimensions ----------------------
    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray:
        """``BoxTossGoalEnv.compute_reward``."""
        return self.goals.compute_reward(achieved_goal, desired_goal, info)

    def compute_success(self, achieved_goal, desired_goal) -> np.ndarray:
        """``BoxTossGoalEnv.compute_success``."""
        return self.goals.compute_success(achieved_goal, desired_goal)

    def compute_terminated(self, achieved_goal, desired_goal, info) -> np.ndarray:
        """True for any goals: every episode is one throw."""
        return self.goals.compute_terminated(achieved_goal, desired_goal, info)

    def compute_truncated(self, achieved_goal, desired_goal, info) -> np.ndarray:
        """False for any goals."""
        return self.goals.compute_truncated(achieved_goal, desired_goal, info)

    def render(self) -> tuple[np.ndarray, ...] | None:
        """``BoxTossVectorEnv.render``: one frame per env."""
        return self.throws.render()

    def close_extras(self, **kwargs) -> None:
        for name in ("throws", "goals"):
            env = self.__dict__.get(name)  # absent when __init__ refused its arguments
            if env is not None:
                env.close()
