"""The native batched ``BoxToss-v0``: ``num_envs`` throws simulated in one parallel engine call.

    envs = gymnasium.make_vec("BoxToss-v0", num_envs=256)            # this class (vector_entry_point)
    envs = gymnasium.make_vec("BoxToss-v0", num_envs=256, threads=1)  # one engine thread

Env i behaves exactly like a single ``BoxToss-v0`` seeded the same way: it owns its own random
stream (``reset(seed=s)`` seeds env i with s + i, as Gymnasium's vector envs do; ``random_streams``
keeps all of them in one array), and its throws are the single env's throw over a batch of
``num_envs`` (``functional.BoxTossFunctional``, ``self.core``, the same object as ``self.env.core``): all
throws go through the single env's compiled engine kernel, run over shares of the batch on ``threads``
threads at once (default: ``numba.config.NUMBA_NUM_THREADS``, the cores available); results do not depend on
the thread count. The task logic, the reward, the drawing and the compiled code are the single env's, not a
copy: whichever of the two throws first compiles
the kernel (or loads it from numba's cache) for both. With a base box (``BoxToss-OnBox-v0``) each env is a
scene of two colliding boxes, rows 2i and 2i + 1 of the engine's arrays, and the batch runs the single env's
colliding kernel on each env's pair in one compiled call (``physics.grouped``, whole envs per thread).

Episodes are one step long, so envs reset in the step they end (``AutoresetMode.SAME_STEP``): the
observation returned by ``step`` is the next episode's first one, and the final observation and info
are in ``info["final_obs"]`` and ``info["final_info"]`` (with their ``_final_obs``/``_final_info``
masks). With Gymnasium's default ``NEXT_STEP`` every other step would be an empty reset step.
For Stable-Baselines3 wrap it in ``box_toss_env.wrappers.sb3_adapter.SB3VecEnvAdapter``.

The engine's threads are Python threads running the compiled kernel without the GIL; numba's own
threading layer (OpenMP or TBB) is not used.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from box_toss_env.envs import task
from box_toss_env.envs.box_toss import BoxTossEnv, check_render_mode_type
from box_toss_env.envs.random_streams import RandomStreams, check_seeds
from box_toss_env.physics import Simulator
from box_toss_env.physics.grouped import GroupedSimulator
from box_toss_env.physics.simulate import check_threads
from box_toss_env.physics.validation import check_integer

MAX_NUM_ENVS = 2**20
"""The most envs one batch may hold: about 2 KB each (state, episodes, info arrays), so 2 GB at most."""


class BoxTossVectorEnv(VectorEnv):
    """``num_envs`` BoxToss envs stepped together; keyword arguments are ``BoxTossEnv``'s.

    Args:
        num_envs: number of envs, in [1, MAX_NUM_ENVS].
        threads: engine threads for the batch, in [1, numba.config.NUMBA_NUM_THREADS] (default:
            all of them, the cores available). It changes the speed, never the results.
        render_mode: None or "rgb_array" (``render()`` returns one frame per env).
        **kwargs: the single env's arguments (see ``BoxTossEnv``), validated the same way.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, num_envs: int = 1, *, threads: int | None = None, render_mode: str | None = None, **kwargs):
        num_envs = check_integer("num_envs", num_envs, 1, MAX_NUM_ENVS)
        threads = None if threads is None else check_threads(threads)
        check_render_mode_type(render_mode)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        # the definition of one env: its validated arguments, spaces, solver settings and drawing
        self.env = BoxTossEnv(render_mode="rgb_array" if render_mode else None, **kwargs)
        self.config = self.env.config
        self.num_envs = int(num_envs)
        self.threads = threads
        self.single_observation_space = self.env.observation_space
        self.single_action_space = self.env.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.metadata = {**self.metadata, "render_fps": self.env.render_fps}

        n = self.num_envs
        self.core = self.env.core  # the throw, batch-first: the single env's, over a batch of num_envs
        # env i's bodies: consecutive rows of the batch's engine arrays, its thrown box first
        self._batch = self.core.empty(n)
        self._episodes, self._params, self._state, self._stats = (
            self._batch.episodes,
            self._batch.params,
            self._batch.state,
            self._batch.stats,
        )
        self._streams = RandomStreams(n)  # env i's random stream: np_random of a single env
        self._settings = self.env.engine_settings
        self._needs_reset = True
        self._simulator: Simulator | GroupedSimulator | None = None

    @property
    def simulator(self) -> Simulator | GroupedSimulator:
        """The engine kernel for the whole batch (the single env's kernel, run on threads; with a base
        box the single env's colliding kernel run on each env's pair of boxes, ``physics.grouped``),
        compiled or loaded at its first run."""
        if self._simulator is None:
            self._simulator = self.core.make_simulator(parallel=True, threads=self.threads, start_interpreted=True)
        return self._simulator

    @property
    def _thrown_state(self) -> np.ndarray:
        return task.thrown_rows(self._state, self.config)

    @property
    def _base_state(self) -> np.ndarray:
        return task.base_rows(self._state, self.config)

    @property  # type: ignore[misc]  # a generator per env, where Gymnasium's vector envs have one
    def np_random(self) -> list[np.random.Generator]:  # type: ignore[override]
        """Each env's random generator, at its current position (copies: drawing from them does not
        advance the envs' streams)."""
        return [self._streams.generator(i) for i in range(self.num_envs)]

    # -- episodes ---------------------------------------------------------------------------------
    def _seed(self, seed: int | list[int | None] | None) -> None:
        """Every env's stream seeded at once (``random_streams.check_seeds``: the whole list is checked,
        naming the index of a bad seed, before any stream is touched)."""
        self._streams.seed_all(check_seeds(seed, self.num_envs))

    def _new_episodes(self) -> dict[str, np.ndarray]:
        """Draw every env's next episode (each from its own stream); the boxes are in the hand."""
        # the uniform variates each episode is drawn from, drawn in place (no second batch-sized array)
        self.core.initial_from_uniforms(self._streams.fill_uniform(self._episodes.data), self._batch)
        return self.core.reset_info(self._batch)

    def _observe(self) -> np.ndarray:
        """Every env's state observation (n, obs); ``_seen`` makes it what the agents observe."""
        return self.core.observation(self._batch)

    def _seen(self, state: np.ndarray) -> np.ndarray:
        """What the agents observe: the state observations, or with ``observation_mode="pixels"`` the images of
        every env's scene as it is now (``envs.pixels``, one compiled call for the batch)."""
        return state if self.env.pixels is None else self.env.pixels.draw(self._batch)

    # -- the Gymnasium API ------------------------------------------------------------------------
    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        """Draw every env's release pose, target and dynamics. ``options`` is unused."""
        self._seed(seed)
        info = self._new_episodes()
        self._needs_reset = False
        return self._seen(self._observe()), with_masks(info, self.num_envs)

    def step(self, actions):
        """Throw every box, simulate all throws together until each rests (or ``max_sim_time``),
        then start every env's next episode (all episodes end in this step)."""
        if self._needs_reset:
            raise ResetNeeded("call reset() before the first step()")
        core, batch = self.core, self._batch
        core.launch(batch, core.check_actions(actions, self.action_space.shape))
        core.simulate(batch, self.simulator)
        core.check_finite(batch)  # raises NonFiniteStateError
        final_obs = self._observe()
        core.check_bounds(final_obs, name_envs=True)  # raises EnergyGainError
        final_obs = self._seen(final_obs)
        reward, final_info = core.score(batch)
        # every episode ended: start the next ones
        info = self._new_episodes()
        observations = self._seen(self._observe())
        n = self.num_envs
        info = with_masks(info, n)
        info["final_obs"] = final_obs
        info["_final_obs"] = np.ones(n, dtype=bool)
        info["final_info"] = with_masks(final_info, n)
        info["_final_info"] = np.ones(n, dtype=bool)
        return observations, reward, np.ones(n, dtype=bool), np.zeros(n, dtype=bool), info

    def render(self) -> tuple[np.ndarray, ...] | None:
        """One frame per env of its current state (the box in the hand after a step, since envs
        reset in the step they end)."""
        if self.render_mode is None:
            return None
        renderer = self.env._renderer_for_env()
        bodies = self.config.bodies_per_env
        frames = []
        for i in range(self.num_envs):
            if self.config.base_box:  # env i's base box is drawn too
                renderer.other_boxes = 0.5 * self._episodes.base_size[i : i + 1]
            if self.config.draws_box_size:  # env i's box
                renderer.half_extents = task.box_half_sizes(self._episodes, self.config)[i].copy()
            state = self._state[bodies * i : bodies * (i + 1)] if self.config.base_box else self._state[i]
            frames.append(
                renderer.frame(state, float(self._episodes.target_x[i]), self._episodes.target_faces[i], f"env {i}")
            )
        return tuple(frames)

    def close_extras(self, **kwargs) -> None:
        env = self.__dict__.get("env")  # absent when __init__ refused its arguments
        if env is not None:
            env.close()

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_simulator"] = None  # compiled kernels are rebuilt (loaded from numba's cache) after unpickling
        return state


def with_masks(info: dict[str, np.ndarray], num_envs: int) -> dict[str, np.ndarray]:
    """Gymnasium's vector info layout: each key's array of values next to a ``_key`` mask of the
    envs that set it (here every env sets every key)."""
    mask = np.ones(num_envs, dtype=bool)
    return {**info, **{f"_{key}": mask for key in info}}
