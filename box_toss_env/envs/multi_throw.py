"""The functional core of tasks of several throws an episode, written once, for a batch of any size.

``MultiThrowFunctional`` is ``functional.BoxTossFunctional``'s counterpart for episodes of several throws: the
same surface (``empty``, ``initial``, ``make_simulator``, ``launch``, ``simulate``, ``transition``,
``observation``, ``reward``, ``terminal``, ``check_finite``, ``check_bounds``, ``score``) over a batch of scenes
(``SceneBatch``) that outlive a throw. A task (``ThrowTask``: ``stack_task.StackTask``,
``hidden_physics_task.HiddenPhysicsTask``) says what is drawn, what is thrown from where, what is seen and how
a throw scores; the core does the rest, the same way for every task and every batch size:

- the engine, from the task's ``EngineConfig`` (``engine.make_engine``, the one-throw core's too);
- the scenes: env i's bodies are rows ``state[i, :k]``; a task that ``carries_bodies`` keeps what it threw (a
  throw adds row k, and the envs of a batch hold scenes of different sizes), another throws its one body again
  (row 0) each time;
- the throw: the next body leaves its release pose with the action's speed, direction and spin, and the scene
  runs until every body rests (or ``max_sim_time``): one compiled call per scene size present in the batch (the
  colliding kernel on each env's scene, whole scenes per thread, ``physics.grouped``), or one call for all bodies
  when they meet only the floor. A scene's warm start (each contact's impulses, each island's sleep) is carried
  from throw to throw, so a pile asleep at the end of a throw stays asleep until something reaches it;
- the checks: a diverged run raises the engine's ``NonFiniteStateError``, an observation outside the bounds
  energy conservation guarantees raises ``EnergyGainError``.

    core = MultiThrowFunctional(StackTask(n_boxes=4))
    batch = core.initial(np.random.default_rng(0), core.empty(64))    # 64 episodes drawn, scenes empty
    simulator = core.make_simulator(parallel=True)
    core.transition(batch, actions, simulator)                        # every env throws its next body
    reward, info = core.score(batch)                                  # (64,) and the step's info, as arrays

Env i's result depends only on its own row: the same episode and actions give the same bits at any batch size,
on any thread count, whatever the other envs' scene sizes (the single env is a batch of one).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from box_toss_env.envs import task, task_columns
from box_toss_env.envs.engine import EngineConfig, make_engine
from box_toss_env.envs.functional import EnergyGainError
from box_toss_env.physics import Simulator, check_finite_stats, layout, warm_start_memory
from box_toss_env.physics.grouped import GroupedSimulator


class ThrowTask(Protocol):
    """What a multi-throw task says; ``MultiThrowFunctional`` does the rest.

    Attributes:
        config: the task's validated arguments.
        engine_config: what the task asks of the engine (``engine.EngineConfig``).
        max_bodies: the most bodies in one env's scene.
        carries_bodies: whether the bodies thrown stay in the scene (each throw adds one) or the one body is
            thrown again each time.
        episode_size: the uniform variates an episode is drawn from (and the columns of ``SceneBatch.episodes``).
        memory_size: the numbers the task carries from throw to throw per env (``SceneBatch.memory``).
    """

    config: Any
    engine_config: EngineConfig
    max_bodies: int
    carries_bodies: bool
    episode_size: int
    memory_size: int

    def draw(self, uniforms: np.ndarray) -> np.ndarray:
        """The episodes (m, episode_size) that the variates ``uniforms`` (m, episode_size) in [0, 1) stand for."""
        ...

    def body_params(self, episodes: np.ndarray) -> np.ndarray:
        """The engine's body parameters (m, max_bodies, layout.PARAM_SIZE) of the episodes' bodies."""
        ...

    def release(self, episodes: np.ndarray, thrown: np.ndarray) -> np.ndarray:
        """(m, 3) x, y, angle of the next body's release pose, ``thrown`` (m,) throws made so far."""
        ...

    def throw_states(self, release: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """(m, 6) engine states of bodies leaving ``release`` (m, 3) with checked ``actions`` (m, 3)."""
        ...

    def observe(self, batch: SceneBatch) -> np.ndarray:
        """float32 (n, obs_size) observations of the batch."""
        ...

    def score(self, batch: SceneBatch, at_rest: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """(reward, info, terminated) of the throw just made, (n,) arrays; writes the task's ``memory``."""
        ...

    def reset_info(self, batch: SceneBatch) -> dict[str, np.ndarray]:
        """The reset's info, arrays with a leading (n,) dimension."""
        ...

    def observation_bounds(self, horizon: float) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) float32 bounds no observation leaves, for throws of ``horizon`` seconds at most."""
        ...

    def observation_names(self) -> tuple[str, ...]: ...


@dataclass
class SceneBatch:
    """``n`` episodes of a multi-throw task: what was drawn and the scenes built so far.

    Attributes:
        episodes: (n, episode_size) what ``initial`` drew (the task's columns).
        params: (n, max_bodies, layout.PARAM_SIZE) the engine's body parameters.
        state: (n, max_bodies, layout.STATE_SIZE) body states x, y, angle, vx, vy, spin (rows of bodies not thrown
            yet are zero).
        stats: (n, max_bodies, layout.STATS_SIZE) what the engine recorded of each body's last run.
        warm: (n, rows, layout.WARM_START_SIZE) each scene's warm start (contacts and sleep), carried from throw to
            throw; (n, 0, ...) when bodies meet only the floor.
        before: (n, max_bodies, 6) the states before the last throw.
        actions: (n, 3) the last throw's actions (checked and clipped; zero before the first).
        thrown: (n,) throws made in each episode.
        memory: (n, memory_size) what the task carries from throw to throw (the stack's height, ...).
        terminated: (n,) whether the last throw ended the episode.
    """

    episodes: np.ndarray
    params: np.ndarray
    state: np.ndarray
    stats: np.ndarray
    warm: np.ndarray
    before: np.ndarray
    actions: np.ndarray
    thrown: np.ndarray
    memory: np.ndarray
    terminated: np.ndarray

    @property
    def n(self) -> int:
        """The number of episodes."""
        return len(self.episodes)

    def copy(self) -> SceneBatch:
        """A deep copy (the functional way to keep a state before a method writes into it)."""
        return SceneBatch(*(getattr(self, field.name).copy() for field in dataclasses.fields(self)))

    def repeat(self, env: int, m: int) -> SceneBatch:
        """A new batch of ``m`` copies of env ``env`` (the planner's candidate throws)."""
        return SceneBatch(
            *(np.repeat(getattr(self, f.name)[env : env + 1], m, axis=0) for f in dataclasses.fields(self))
        )


class SceneSimulator:
    """The engine for a batch of scenes (``MultiThrowFunctional.make_simulator``): with box-box contact one
    grouped call per scene size (``physics.grouped``, whole scenes per thread; a single scene on the plain
    colliding kernel), without it one call of the floor-only kernel for every body. Kernels are built at their
    first run (compiled, or loaded from numba's cache)."""

    def __init__(self, flags, threads: int | None, start_interpreted: bool):
        self.flags, self.threads, self.start_interpreted = flags, threads, start_interpreted
        self._plain: Simulator | None = None
        self._grouped: dict[int, GroupedSimulator] = {}

    def plain(self) -> Simulator:
        if self._plain is None:
            self._plain = Simulator(self.flags, threads=self.threads, start_interpreted=self.start_interpreted)
        return self._plain

    def grouped(self, size: int) -> GroupedSimulator:
        if size not in self._grouped:
            self._grouped[size] = GroupedSimulator(
                self.flags, size, threads=self.threads, start_interpreted=self.start_interpreted
            )
        return self._grouped[size]

    def run(self, state, params, settings, stats, warm: np.ndarray, size: int) -> None:
        """Advance m scenes of ``size`` bodies in place: ``state`` (m * size, 6), ``params``, ``stats`` likewise,
        ``warm`` (m, rows, WARM_START_SIZE) (rows 0 without box-box contact)."""
        if not self.flags.boxes_collide:
            self.plain().run(state, params, settings, stats)
        elif len(warm) == 1 and not self.flags.parallel:
            self.plain().run(state, params, settings, stats, warm_start=warm[0])
        else:
            self.grouped(size).run(state, params, settings, stats, warm_start=warm)

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without kernels: they are loaded again (from numba's cache) at the next run."""
        return {**self.__dict__, "_plain": None, "_grouped": {}}


class MultiThrowFunctional:
    """Episodes of several throws of a task (``ThrowTask``), batch-first (module docstring).

    Attributes:
        task: the task.
        config: the task's validated arguments.
        solver, dt, max_steps, flags, settings: the engine's (``engine.make_engine``).
        observation_low, observation_high: float32 bounds no observation leaves.
    """

    def __init__(self, task: ThrowTask):
        self.task, self.config = task, task.config
        engine = make_engine(task.engine_config)
        self.solver, self.dt, self.max_steps = engine.solver, engine.dt, engine.max_steps
        self.flags, self.settings = engine.flags, engine.settings
        self.observation_low, self.observation_high = task.observation_bounds(self.max_steps * self.dt)

    # -- the batch and the engine -------------------------------------------------------------------
    def empty(self, n: int) -> SceneBatch:
        """A batch of ``n`` episodes, its arrays zero (``initial`` fills them)."""
        t = self.task
        bodies = (n, t.max_bodies)
        warm_rows = len(warm_start_memory(t.max_bodies)) if self.flags.boxes_collide else 0
        return SceneBatch(
            episodes=np.zeros((n, t.episode_size)),
            params=np.zeros((*bodies, layout.PARAM_SIZE)),
            state=np.zeros((*bodies, layout.STATE_SIZE)),
            stats=np.zeros((*bodies, layout.STATS_SIZE)),
            warm=np.zeros((n, warm_rows, layout.WARM_START_SIZE)),
            before=np.zeros((*bodies, layout.STATE_SIZE)),
            actions=np.zeros((n, task_columns.ACTION_SIZE)),
            thrown=np.zeros(n, dtype=np.int64),
            memory=np.zeros((n, t.memory_size)),
            terminated=np.zeros(n, dtype=bool),
        )

    def make_simulator(
        self, *, parallel: bool = False, threads: int | None = None, start_interpreted: bool = False
    ) -> SceneSimulator:
        """The engine for this task's scenes. ``parallel=False``: on the calling thread (the single env);
        ``parallel=True``: shares of the batch on ``threads`` threads (default: all). Results never depend on
        either."""
        return SceneSimulator(dataclasses.replace(self.flags, parallel=parallel), threads, start_interpreted)

    # -- initial: episodes drawn, scenes empty --------------------------------------------------------
    def initial(self, rng: np.random.Generator, batch: SceneBatch) -> SceneBatch:
        """Draw every episode from ``rng`` (one call, ``rng.random``): ``initial_from_uniforms`` of those variates."""
        return self.initial_from_uniforms(rng.random((batch.n, self.task.episode_size)), batch)

    def initial_from_uniforms(self, uniforms: np.ndarray, batch: SceneBatch, envs: np.ndarray | None = None):
        """The episodes that ``uniforms`` (m, episode_size) in [0, 1) stand for, written into the rows ``envs``
        (default: every row), their scenes emptied."""
        rows = slice(None) if envs is None else envs
        episodes = self.task.draw(uniforms)
        batch.episodes[rows] = episodes
        batch.params[rows] = self.task.body_params(episodes)
        for array in (
            batch.state,
            batch.warm,
            batch.before,
            batch.actions,
            batch.thrown,
            batch.memory,
            batch.terminated,
        ):
            array[rows] = 0
        return batch

    def reset_info(self, batch: SceneBatch) -> dict[str, np.ndarray]:
        """The reset's info of every env (the task's keys)."""
        return self.task.reset_info(batch)

    # -- transition: launch and simulate ----------------------------------------------------------------
    def check_actions(self, actions, shape: tuple[int, ...]) -> np.ndarray:
        """Actions as float64 (n, 3) clipped to [-1, 1]; ``shape`` is what the caller accepts ((3,) for a single
        env). A TypeError or ValueError names what is wrong (``task.check_actions``)."""
        return task.check_actions(actions, shape)

    def next_rows(self, batch: SceneBatch) -> np.ndarray:
        """(n,) the row of each env's body thrown next: row k after k throws, or row 0 for a task that throws its
        one body again."""
        return batch.thrown.copy() if self.task.carries_bodies else np.zeros(batch.n, dtype=np.int64)

    def scene_sizes(self, batch: SceneBatch) -> np.ndarray:
        """(n,) the bodies in each env's scene after its last throw."""
        return batch.thrown.copy() if self.task.carries_bodies else np.minimum(batch.thrown, 1)

    def launch(self, batch: SceneBatch, actions: np.ndarray) -> SceneBatch:
        """Each env throws its next body: it leaves its release pose with the checked ``actions`` (n, 3)."""
        batch.before[:] = batch.state
        batch.actions[:] = actions
        rows = self.next_rows(batch)
        release = self.task.release(batch.episodes, batch.thrown)
        batch.state[np.arange(batch.n), rows] = self.task.throw_states(release, actions)
        return batch

    def simulate(self, batch: SceneBatch, simulator: SceneSimulator) -> SceneBatch:
        """Run every scene until its bodies rest (or ``max_sim_time``): one engine call per scene size present;
        the states, stats and warm starts are written into the batch, and each env's throw is counted."""
        sizes = self.next_rows(batch) + 1
        for size in np.unique(sizes).tolist():
            envs = np.flatnonzero(sizes == size)
            m = len(envs)
            state = np.ascontiguousarray(batch.state[envs, :size]).reshape(m * size, layout.STATE_SIZE)
            params = np.ascontiguousarray(batch.params[envs, :size]).reshape(m * size, layout.PARAM_SIZE)
            stats = np.zeros((m * size, layout.STATS_SIZE))
            warm = np.ascontiguousarray(batch.warm[envs])
            simulator.run(state, params, self.settings, stats, warm, size)
            batch.state[envs, :size] = state.reshape(m, size, layout.STATE_SIZE)
            batch.stats[envs, :size] = stats.reshape(m, size, layout.STATS_SIZE)
            batch.warm[envs] = warm
        batch.thrown += 1
        return batch

    def transition(self, batch: SceneBatch, actions, simulator: SceneSimulator) -> SceneBatch:
        """``launch`` then ``simulate``: actions (n, 3) in [-1, 1] (clipped; checked) to the scenes at rest."""
        actions = self.check_actions(actions, (batch.n, task_columns.ACTION_SIZE))
        return self.simulate(self.launch(batch, actions), simulator)

    # -- observation, reward, the episode's end ------------------------------------------------------------
    def observation(self, batch: SceneBatch) -> np.ndarray:
        """A new float32 (n, obs_size) array of every env's observation."""
        return self.task.observe(batch)

    def scene_rows(self, batch: SceneBatch) -> np.ndarray:
        """(n, max_bodies) bool: the rows of each env's scene after its last throw."""
        return np.arange(self.task.max_bodies) < self.scene_sizes(batch)[:, None]

    def at_rest(self, batch: SceneBatch) -> np.ndarray:
        """(n,) bool: which scenes came to rest in the last throw (the others reached ``max_sim_time``)."""
        resting = ~np.isnan(batch.stats[..., layout.REST_TIME]) | ~self.scene_rows(batch)
        return resting.all(axis=1)

    def score(self, batch: SceneBatch) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The reward (n,) and the step's info as (n,) arrays of the throw just made (the task's keys); records
        whether it ended the episode (``terminal``) and what the task carries to the next throw."""
        reward, info, terminated = self.task.score(batch, self.at_rest(batch))
        batch.terminated[:] = terminated
        return reward, info

    def reward(self, batch: SceneBatch) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The reward (n,) and its named terms (the info's keys starting "reward_"), whose sum it is."""
        reward, info = self.score(batch)
        return reward, {name: value for name, value in info.items() if name.startswith("reward_")}

    def terminal(self, batch: SceneBatch) -> np.ndarray:
        """(n,) whether the last throw ended each episode (``score`` decides it)."""
        return batch.terminated.copy()

    # -- checks ------------------------------------------------------------------------------------------
    def failed(self, batch: SceneBatch) -> np.ndarray:
        """(n,) bool: scenes whose last run diverged (a body's state went non-finite)."""
        return ((batch.stats[..., layout.STATUS] != layout.STATUS_OK) & self.scene_rows(batch)).any(axis=1)

    def check_finite(self, batch: SceneBatch) -> None:
        """Raise the engine's ``NonFiniteStateError`` if a scene diverged."""
        failed = self.failed(batch)
        if failed.any():
            check_finite_stats(batch.stats[failed][self.scene_rows(batch)[failed]], self.solver)

    def outside_bounds(self, observations: np.ndarray) -> np.ndarray:
        """(n,) bool: observations that leave the observation bounds somewhere."""
        return task.outside_bounds(observations, self.observation_low, self.observation_high)

    def check_bounds(self, observations: np.ndarray, name_envs: bool = False) -> None:
        """Raise ``EnergyGainError`` for the first observation outside the bounds (its message prefixed with
        "env i: " when ``name_envs``)."""
        outside = self.outside_bounds(observations)
        if outside.any():
            i = int(np.argmax(outside))
            raise EnergyGainError((f"env {i}: " if name_envs else "") + self.bounds_message(observations[i]))

    def bounds_message(self, observation: np.ndarray) -> str:
        """What the throw that ended in ``observation`` (outside the bounds) did."""
        low, high = self.observation_low, self.observation_high
        column = int(np.argmax(np.maximum(low - observation, observation - high)))
        return (
            f"the throw ended with {self.task.observation_names()[column]} = {observation[column]:g}, outside the "
            f"observation bounds [{low[column]:g}, {high[column]:g}] that energy conservation guarantees: "
            f"solver={self.solver!r} created energy (dt={self.dt:g} s); please report these arguments"
        )
