"""Gymnasium's single and batched env over the multi-throw core, for every multi-throw task.

``MultiThrowEnv`` is ``multi_throw.MultiThrowFunctional`` over a batch of one, ``MultiThrowVectorEnv`` over a batch
of ``num_envs`` (``gymnasium.make_vec``'s native batched env): a task's env subclasses them with its docstring,
its task class and its drawing (``stack.BoxTossStackEnv``, ``hidden_physics.BoxTossHiddenPhysicsEnv``). Neither
holds a copy of the engine set-up or of the step: both call the core's.

The batched env: env i behaves exactly like a single env seeded the same way (``reset(seed=s)`` seeds env i with
s + i, as Gymnasium's vector envs do; each env draws its episodes from its own stream, ``random_streams``, the
single env's ``np_random``), bit for bit, on any thread count. Episodes end at different steps; an env whose
episode ends starts its next one in the same step (``AutoresetMode.SAME_STEP``): the observation returned is the
next episode's first, the final observation and info are in ``info["final_obs"]`` and ``info["final_info"]``
(with their ``_final_obs`` / ``_final_info`` masks), the next episode's reset info under its keys.
"""

from __future__ import annotations

import inspect
import textwrap
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from box_toss_env.envs import task_columns
from box_toss_env.envs.arguments import Argument, arguments_table
from box_toss_env.envs.box_toss import check_render_mode_type
from box_toss_env.envs.box_toss_vector import MAX_NUM_ENVS, with_masks
from box_toss_env.envs.functional import first_of
from box_toss_env.envs.multi_throw import MultiThrowFunctional, SceneSimulator
from box_toss_env.envs.random_streams import RandomStreams, check_seed, check_seeds, fill_uniform
from box_toss_env.physics.simulate import check_threads
from box_toss_env.physics.validation import check_integer


@dataclass
class TriedThrows:
    """What candidate throws would do (``MultiThrowEnv.try_throws``): the reward (m,) (-inf where the engine
    diverged), the step's info of each, as (m,) arrays, and the copies' scenes once at rest (m, k, 6)."""

    reward: np.ndarray
    info: dict[str, np.ndarray]
    states: np.ndarray


class MultiThrowEnv(gym.Env):
    """A multi-throw task's single env (module docstring). Subclasses set ``task_class`` (the task, made from
    the env's keyword arguments but the rendering ones), ``metadata`` and ``drawn_scene``."""

    task_class: type
    window_title = "BoxToss"

    def __init__(self, render_mode: str | None = None, **kwargs: Any):
        check_render_mode_type(render_mode)
        modes = tuple(self.metadata["render_modes"])
        if render_mode is not None and render_mode not in modes:
            raise ValueError(f"render_mode must be None or one of {modes}, got {render_mode!r}")
        self.render_mode = render_mode
        self.render_size = (
            check_integer("render_width", kwargs.pop("render_width", 600), 16, 8192),
            check_integer("render_height", kwargs.pop("render_height", 400), 16, 8192),
        )
        self.core = core = MultiThrowFunctional(self.task_class(**kwargs))
        self.config, self.dt, self.max_steps, self.flags = core.config, core.dt, core.max_steps, core.flags
        self.action_space = spaces.Box(-1.0, 1.0, shape=(task_columns.ACTION_SIZE,), dtype=np.float32)
        self.observation_space = spaces.Box(core.observation_low, core.observation_high, dtype=np.float32)
        self._batch = core.empty(1)
        self._needs_reset = True
        self._simulator: SceneSimulator | None = None  # built at the first throw: making an env compiles nothing
        self._renderer: Any = None
        self._score = 0.0  # the return so far
        self._last_info: dict[str, Any] | None = None

    @property
    def engine_settings(self) -> np.ndarray:
        """The engine's settings array of this env's throws (a copy)."""
        return self.core.settings.copy()

    @property
    def thrown(self) -> int:
        """How many throws this episode has made."""
        return int(self._batch.thrown[0])

    @property
    def scene(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the engine's state (k, 6) and body parameters (k, 7) of the k bodies in the scene."""
        k = int(self.core.scene_sizes(self._batch)[0])
        return self._batch.state[0, :k].copy(), self._batch.params[0, :k].copy()

    # -- the Gymnasium API ------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Draw an episode; the scene is empty. ``options`` is unused."""
        super().reset(seed=check_seed(seed))
        self.core.initial(self.np_random, self._batch)
        self._needs_reset, self._score, self._last_info = False, 0.0, None
        if self.render_mode == "human":
            self.render()
        return self.core.observation(self._batch)[0], first_of(self.core.reset_info(self._batch))

    def step(self, action):
        """Throw the next body with ``action``; simulate the scene until everything rests."""
        if self._needs_reset:
            raise ResetNeeded("the episode has ended (or not started): call reset() before step()")
        core, batch = self.core, self._batch
        core.launch(batch, core.check_actions(action, self.action_space.shape))
        if self._simulator is None:
            self._simulator = core.make_simulator(start_interpreted=True)
        core.simulate(batch, self._simulator)
        core.check_finite(batch)  # raises NonFiniteStateError
        rewards, infos = core.score(batch)
        terminated = bool(core.terminal(batch)[0])
        self._needs_reset = terminated
        observation = core.observation(batch)
        core.check_bounds(observation)  # raises EnergyGainError
        reward, info = float(rewards[0]), first_of(infos)
        self._score += reward
        self._last_info = info
        if self.render_mode == "human":
            self.render()
        return observation[0], reward, terminated, False, info

    # -- a planner's search: candidate throws onto copies of the scene -------------------------------------
    def try_throws(self, actions: np.ndarray, threads: int | None = 1) -> TriedThrows:
        """What throwing the next body with each of ``actions`` (m, 3) would do, without doing it: m copies of the
        scene, each with one candidate throw, simulated in one engine call on ``threads`` threads (each copy's
        result bit for bit what ``step`` gives)."""
        if self._needs_reset:
            raise ResetNeeded("call reset() before try_throws()")
        core = self.core
        actions = core.check_actions(actions, np.shape(actions))
        copies = self._batch.repeat(0, len(actions))
        core.transition(copies, actions, core.make_simulator(parallel=threads != 1, threads=threads))
        failed = core.failed(copies)
        with np.errstate(invalid="ignore"):
            reward, info = core.score(copies)
        states = copies.state[:, : int(core.scene_sizes(copies)[0])]
        return TriedThrows(np.where(failed, -np.inf, reward), info, states)

    # -- rendering ------------------------------------------------------------------------------------------
    def drawn_scene(self) -> dict[str, Any]:
        """The keyword arguments of ``rendering.SceneRenderer.render_rgb`` for the current state."""
        raise NotImplementedError

    def render(self):
        """A frame of the scene ("rgb_array") or the window ("human")."""
        if self.render_mode is None:
            gym.logger.warn('render() was called without a render_mode; make the env with render_mode="rgb_array"')
            return None
        scene = self.drawn_scene()
        if self._renderer is None:
            from box_toss_env.rendering import SceneRenderer

            self._renderer = SceneRenderer(*self.render_size, window_title=self.window_title)
        if self.render_mode == "rgb_array":
            return self._renderer.render_rgb(**scene)
        if not self._renderer.show(**scene, fps=self.metadata["render_fps"]):
            self.close()
        return None

    def close(self):
        """Close the window if one is open; safe to call more than once."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self):
        return {**self.__dict__, "_simulator": None, "_renderer": None}


class MultiThrowVectorEnv(VectorEnv):
    """``num_envs`` episodes of a multi-throw task stepped together (module docstring); subclasses set
    ``env_class``, whose keyword arguments these are.

    Args:
        num_envs: number of envs, in [1, MAX_NUM_ENVS].
        threads: engine threads, in [1, numba.config.NUMBA_NUM_THREADS] (default: all). It changes the speed,
            never the results.
        **kwargs: the single env's arguments, validated the same way.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}
    env_class: type[MultiThrowEnv]

    def __init__(self, num_envs: int = 1, *, threads: int | None = None, **kwargs):
        self.num_envs = n = check_integer("num_envs", num_envs, 1, MAX_NUM_ENVS)
        self.threads = None if threads is None else check_threads(threads)
        self.env = self.env_class(**kwargs)  # the definition of one env: validated arguments, spaces, the core
        self.core, self.config, self.render_mode = self.env.core, self.env.config, None
        self.single_observation_space = self.env.observation_space
        self.single_action_space = self.env.action_space
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self._batch = self.core.empty(n)
        self._uniforms = np.zeros((n, self.core.task.episode_size))
        self._streams = RandomStreams(n)
        self._simulator: SceneSimulator | None = None
        self._needs_reset = True

    @property
    def simulator(self) -> SceneSimulator:
        """The engine for the whole batch, its kernels built at their first run."""
        if self._simulator is None:
            self._simulator = self.core.make_simulator(parallel=True, threads=self.threads, start_interpreted=True)
        return self._simulator

    def _new_episodes(self, envs: np.ndarray) -> None:
        """Draw the next episode of each env in ``envs`` (each from its own stream); their scenes are empty."""
        states, uniforms = self._streams.states[envs], self._uniforms[envs]
        fill_uniform(states, uniforms)
        self._streams.states[envs] = states
        self.core.initial_from_uniforms(uniforms, self._batch, envs)

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        """Seed every env's stream (``random_streams.check_seeds``) and draw every env's episode."""
        self._streams.seed_all(check_seeds(seed, self.num_envs))
        self._new_episodes(np.arange(self.num_envs))
        self._needs_reset = False
        return self.core.observation(self._batch), with_masks(self.core.reset_info(self._batch), self.num_envs)

    def step(self, actions):
        """Every env throws its next body; every scene runs until it rests; each env whose episode ended starts
        its next one."""
        if self._needs_reset:
            raise ResetNeeded("call reset() before the first step()")
        core, batch, n = self.core, self._batch, self.num_envs
        core.launch(batch, core.check_actions(actions, self.action_space.shape))
        core.simulate(batch, self.simulator)
        core.check_finite(batch)  # raises NonFiniteStateError
        reward, step_info = core.score(batch)
        terminated = core.terminal(batch)
        observations = core.observation(batch)
        core.check_bounds(observations, name_envs=True)  # raises EnergyGainError
        info = with_masks(step_info, n)
        if terminated.any():
            info["final_obs"], info["_final_obs"] = observations.copy(), terminated.copy()
            info["final_info"] = {**info, **{f"_{key}": terminated.copy() for key in step_info}}
            info["_final_info"] = terminated.copy()
            self._new_episodes(np.flatnonzero(terminated))
            observations = core.observation(batch)
            for key, value in core.reset_info(batch).items():
                info[key], info[f"_{key}"] = value, terminated.copy()
        return observations, reward, terminated, np.zeros(n, dtype=bool), info

    def close_extras(self, **kwargs) -> None:
        env = self.__dict__.get("env")  # absent when __init__ refused its arguments
        if env is not None:
            env.close()

    def __getstate__(self):
        return {**self.__dict__, "_simulator": None}  # kernels are loaded again from numba's cache


def document_arguments(env_class: type, arguments: tuple[Argument, ...]) -> None:
    """Write ``arguments``' table into the env's docstring (its ``ARGUMENTS_TABLE`` line) and give ``__init__``
    their signature (what ``help()`` and ``inspect.signature`` show)."""
    if env_class.__doc__:  # None under python -OO
        table = textwrap.indent(arguments_table(arguments), "    ")
        env_class.__doc__ = env_class.__doc__.replace("    ARGUMENTS_TABLE", table)
    parameters = [
        inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD),
        inspect.Parameter("render_mode", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=None),
    ]
    parameters += [inspect.Parameter(a.name, inspect.Parameter.KEYWORD_ONLY, default=a.default) for a in arguments]
    env_class.__init__.__signature__ = inspect.Signature(parameters)  # type: ignore[misc]
