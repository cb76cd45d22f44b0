"""The native batched ``BoxToss-Stack-v0``: ``num_envs`` stacking episodes stepped together.

    envs = gymnasium.make_vec("BoxToss-Stack-v0", num_envs=64)                   # this class
    envs = gymnasium.make_vec("BoxToss-Stack-v0", num_envs=64, vectorization_mode="sync")  # single envs

Env i behaves exactly like a single ``BoxToss-Stack-v0`` seeded the same way (``reset(seed=s)`` seeds env i with
s + i, as Gymnasium's vector envs do): it draws its hands from its own random stream (``random_streams``, the
single env's ``np_random``), with the same batch-first task functions (``stack_task``). Each env's scene holds
the boxes it has thrown so far, so the envs of a batch hold scenes of different sizes; a step runs one compiled
call per scene size present (the envs that throw their k-th box together, each env's k bodies a group of
``physics.grouped``: the single env's colliding kernel on each group in turn, whole groups per thread), and every
env's result is bit for bit the single env's (tested).

Episodes end at different steps; an env whose episode ends starts its next one in the same step
(``AutoresetMode.SAME_STEP``): the observation returned is the next episode's first, the final observation and
info are in ``info["final_obs"]`` and ``info["final_info"]`` (with their ``_final_obs`` / ``_final_info`` masks).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from box_toss_env.envs import stack_task, task
from box_toss_env.envs.box_toss import EnergyGainError
from box_toss_env.envs.box_toss_vector import MAX_NUM_ENVS, with_masks
from box_toss_env.envs.random_streams import RandomStreams, check_seeds, fill_uniform
from box_toss_env.envs.stack import BoxTossStackEnv
from box_toss_env.physics import check_finite_stats, layout, warm_start_memory
from box_toss_env.physics.grouped import GroupedSimulator
from box_toss_env.physics.simulate import check_threads
from box_toss_env.physics.validation import check_integer

STEP_INFO_KEYS = (
    *stack_task.REWARD_TERMS,
    "stack_height",
    "stack_size",
    "fell",
    "at_rest",
    "success",
    "distance",
    "final_x",
    "final_y",
    "final_angle",
    "thrown",
    "sim_time",
    "n_steps",
)
"""The single env's step ``info`` keys, each an (num_envs,) array here."""


class BoxTossStackVectorEnv(VectorEnv):
    """``num_envs`` BoxToss-Stack envs stepped together; keyword arguments are ``BoxTossStackEnv``'s.

    Args:
        num_envs: number of envs, in [1, MAX_NUM_ENVS].
        threads: engine threads, in [1, numba.config.NUMBA_NUM_THREADS] (default: all). It changes the speed,
            never the results.
        **kwargs: the single env's arguments (see ``BoxTossStackEnv``), validated the same way.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, num_envs: int = 1, *, threads: int | None = None, **kwargs):
        num_envs = check_integer("num_envs", num_envs, 1, MAX_NUM_ENVS)
        self.threads = None if threads is None else check_threads(threads)
        self.env = BoxTossStackEnv(**kwargs)  # the definition of one env: validated arguments, spaces, settings
        self.config = config = self.env.config
        self.num_envs = int(num_envs)
        self.single_observation_space = self.env.observation_space
        self.single_action_space = self.env.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.render_mode = None
        n, boxes = self.num_envs, config.n_boxes
        self._hands = np.zeros((n, boxes, stack_task.EPISODE_COLUMNS))
        self._targets = np.zeros(n)
        self._params = np.zeros((n, boxes, layout.PARAM_SIZE))
        self._state = np.zeros((n, boxes, layout.STATE_SIZE))
        self._warm = np.zeros((n, *warm_start_memory(boxes).shape))  # each env's warm start (its pile's sleep)
        self._thrown = np.zeros(n, dtype=np.int64)
        self._height = np.zeros(n)
        self._uniforms = np.zeros((n, stack_task.uniforms_per_episode(config)))
        self._streams = RandomStreams(n)
        self._settings = self.env.engine_settings
        self._simulators: dict[int, GroupedSimulator] = {}
        self._needs_reset = True

    def _simulator(self, size: int) -> GroupedSimulator:
        """The grouped colliding kernel for scenes of ``size`` bodies (compiled or loaded at its first run)."""
        if size not in self._simulators:
            flags = dataclasses.replace(self.env.flags, parallel=True)
            self._simulators[size] = GroupedSimulator(flags, size, threads=self.threads, start_interpreted=True)
        return self._simulators[size]

    # -- episodes -----------------------------------------------------------------------------------------
    def _new_episodes(self, envs: np.ndarray) -> None:
        """Draw the next episode of each env in ``envs`` (each from its own stream); their scenes are empty."""
        states, uniforms = self._streams.states[envs], self._uniforms[envs]
        fill_uniform(states, uniforms)
        self._streams.states[envs] = states
        hands, targets = stack_task.episode_from_uniforms(uniforms, self.config)
        self._hands[envs], self._targets[envs] = hands, targets
        self._params[envs] = stack_task.body_params(hands, self.config)
        self._state[envs] = 0.0
        self._warm[envs] = 0.0
        self._thrown[envs] = 0
        self._height[envs] = 0.0

    def _reset_info(self, envs: np.ndarray) -> dict[str, np.ndarray]:
        hands = self._hands
        return {
            "target_x": self._targets.copy(),
            "box_lengths": hands[..., stack_task.E_LENGTH].copy(),
            "box_widths": hands[..., stack_task.E_WIDTH].copy(),
            "box_masses": hands[..., stack_task.E_MASS].copy(),
        }

    def _observe(self) -> np.ndarray:
        return stack_task.observe(self._state, self._hands, self._thrown, self._targets, self._height, self.config)

    # -- the Gymnasium API --------------------------------------------------------------------------------
    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        """Seed every env's stream (``random_streams.check_seeds``) and draw every env's hand and target."""
        self._streams.seed_all(check_seeds(seed, self.num_envs))
        everyone = np.arange(self.num_envs)
        self._new_episodes(everyone)
        self._needs_reset = False
        return self._observe(), with_masks(self._reset_info(everyone), self.num_envs)

    def step(self, actions):
        """Throw every env's next box; simulate every scene until it rests; start the next episode of each env
        whose episode ended."""
        if self._needs_reset:
            raise ResetNeeded("call reset() before the first step()")
        actions = task.check_actions(actions, self.action_space.shape)
        config, n = self.config, self.num_envs
        everyone = np.arange(n)
        k = self._thrown
        release = self._hands[everyone, k, stack_task.E_RELEASE_X :]
        self._state[everyone, k] = stack_task.thrown_states(release, actions, config)
        info = {key: np.zeros(n) for key in STEP_INFO_KEYS}
        reward = np.zeros(n)
        for size in np.unique(k + 1):  # the envs throwing their size-th box: scenes of size bodies
            envs = np.flatnonzero(k + 1 == size)
            self._throw(envs, int(size), reward, info)
        self._thrown += 1
        self._height = info["stack_height"].copy()
        fell = info["fell"].astype(bool)
        terminated = fell | (self._thrown == config.n_boxes)
        observations = self._observe()
        space = self.single_observation_space
        outside = np.any((observations < space.low) | (observations > space.high), axis=1)
        if outside.any():
            raise EnergyGainError(
                f"env {int(np.argmax(outside))}: a throw ended outside the observation bounds "
                "energy conservation guarantees; please report these arguments"
            )
        for key in ("stack_size", "thrown", "n_steps"):
            info[key] = info[key].astype(np.int64)
        for key in ("fell", "at_rest", "success"):
            info[key] = info[key].astype(bool)
        info = with_masks(info, n)
        ended = np.flatnonzero(terminated)
        if ended.size:
            info["final_obs"] = observations.copy()
            info["_final_obs"] = terminated.copy()
            info["final_info"] = {**info, **{f"_{key}": terminated.copy() for key in STEP_INFO_KEYS}}
            info["_final_info"] = terminated.copy()
            self._new_episodes(ended)
            observations = self._observe()
            reset_info = self._reset_info(ended)
            for key, value in reset_info.items():
                info[key], info[f"_{key}"] = value, terminated.copy()
        return observations, reward, terminated, np.zeros(n, dtype=bool), info

    def _throw(self, envs: np.ndarray, size: int, reward: np.ndarray, info: dict[str, np.ndarray]) -> None:
        """Simulate the scenes of ``envs`` (``size`` bodies each, the last one just thrown) in one grouped call
        and score them into ``reward`` and ``info``."""
        m = len(envs)
        before = self._state[envs, : size - 1].copy()
        scenes = np.ascontiguousarray(self._state[envs, :size]).reshape(m * size, layout.STATE_SIZE)
        params = np.ascontiguousarray(self._params[envs, :size]).reshape(m * size, layout.PARAM_SIZE)
        stats: np.ndarray = np.zeros((m * size, layout.STATS_SIZE))
        warm = np.ascontiguousarray(self._warm[envs])
        self._simulator(size).run(scenes, params, self._settings, stats, warm_start=warm)
        self._warm[envs] = warm
        if np.any(stats[:, layout.STATUS] != layout.STATUS_OK):
            check_finite_stats(stats, "robust")
        after = scenes.reshape(m, size, layout.STATE_SIZE)
        self._state[envs, :size] = after
        stats = stats.reshape(m, size, layout.STATS_SIZE)
        at_rest: np.ndarray = ~np.isnan(stats[..., layout.REST_TIME]).any(axis=1)
        half = self._params[envs, :size, layout.HALF_LENGTH : layout.HALF_WIDTH + 1]
        outcome = stack_task.score_throws(before, after, half, at_rest, self._targets[envs], self.config)
        reward[envs] = outcome.reward
        thrown = after[:, size - 1]
        for name, value in outcome.terms.items():
            info[name][envs] = value
        info["stack_height"][envs] = outcome.height
        info["stack_size"][envs] = outcome.on_target.sum(axis=1)
        info["fell"][envs] = outcome.fell
        info["at_rest"][envs] = at_rest
        info["success"][envs] = outcome.success
        info["distance"][envs] = outcome.distance
        info["final_x"][envs], info["final_y"][envs] = thrown[:, layout.X], thrown[:, layout.Y]
        info["final_angle"][envs] = (thrown[:, layout.ANGLE] + math.pi) % (2.0 * math.pi) - math.pi
        info["thrown"][envs] = size
        info["sim_time"][envs] = stats[:, 0, layout.END_TIME]
        info["n_steps"][envs] = stats[..., layout.N_STEPS].max(axis=1)

    def close_extras(self, **kwargs) -> None:
        env = self.__dict__.get("env")
        if env is not None:
            env.close()

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_simulators"] = {}  # compiled kernels are loaded again from numba's cache after unpickling
        return state
