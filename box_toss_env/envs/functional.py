"""BoxToss's functional API: one throw, written once, for a batch of any size.

``BoxTossFunctional`` is the whole BoxToss step as functions of a batch of throws (``ThrowBatch``),
in the spirit of Gymnasium's functional envs (``gymnasium.experimental.functional.FuncEnv``:
``initial``, ``transition``, ``observation``, ``reward``, ``terminal``). ``BoxTossEnv`` is it over a
batch of one, ``BoxTossVectorEnv`` over a batch of ``num_envs``, and the oracle (``agents.oracle``)
over its candidate throws; they hold no other copy of the task or of the step.

    core = BoxTossFunctional(target_face="long_side")       # BoxTossEnv's arguments, less rendering
    batch = core.initial(np.random.default_rng(0), core.empty(256))   # 256 boxes in the hand
    simulator = core.make_simulator(parallel=True)           # the env's compiled engine kernel
    core.transition(batch, actions, simulator)               # actions (256, 3) in [-1, 1]
    reward, info = core.score(batch)                         # (256,) and the step's info, as arrays

A step is five stages, each a method with one job:

1. ``initial``: draw the episodes (release pose, target, dynamics, base box) and put each box in the hand;
2. ``launch``: map actions to launch speed, direction and spin, and write the initial states;
3. ``simulate``: run the engine until every box rests (or ``max_sim_time``);
4. ``observation``, ``landing`` / ``reward``: observe the final state and score it (``task``);
5. ``check_finite``, ``check_bounds``, ``score``: refuse a diverged throw or one that left the
   observation bounds, and gather the step's info.

The arrays live in the batch and are written in place (numpy, not JAX: the envs allocate them once, so a
throw allocates almost nothing); every method returns what it wrote. A throw's result depends only on its
own row: the same episode and action give the same bits at any batch size and on any thread count.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from box_toss_env.envs import task, task_columns, task_config
from box_toss_env.envs.arguments import CORE_ARGUMENTS, apply_split, with_defaults
from box_toss_env.envs.engine import EngineConfig, make_engine
from box_toss_env.physics import Simulator, check_finite_stats, layout
from box_toss_env.physics.grouped import GroupedSimulator
from box_toss_env.physics.grouped import make_simulator as make_grouped_simulator


# the columns the reset's and the step's info read
def _columns(*pairs: tuple[str, int]) -> tuple[tuple[str, ...], np.ndarray]:
    return tuple(name for name, _ in pairs), np.array([column for _, column in pairs], dtype=np.intp)


RESET_INFO = _columns(
    ("target_x", task_columns.EP_TARGET_X),
    ("release_x", task_columns.EP_RELEASE_X),
    ("release_y", task_columns.EP_RELEASE_Y),
    ("release_angle", task_columns.EP_RELEASE_ANGLE),
    ("mass", task_columns.EP_MASS),
    ("friction", task_columns.EP_FRICTION),
    ("restitution", task_columns.EP_RESTITUTION),
)
RESET_INFO_WITH_BASE = _columns(
    *zip(*RESET_INFO, strict=True),
    ("base_length", task_columns.EP_BASE_LENGTH),
    ("base_height", task_columns.EP_BASE_HEIGHT),
)
BOX_SIZE_INFO = ("box_length", "box_width")  # with a drawn box size: after all the others
STEP_STATS = np.array(
    [layout.FIRST_CONTACT_TIME, layout.END_TIME, layout.MAX_PENETRATION, layout.N_IMPACTS, layout.N_STEPS],
    dtype=np.intp,
)
STEP_EPISODE = np.array(
    [task_columns.EP_TARGET_X, task_columns.EP_MASS, task_columns.EP_FRICTION, task_columns.EP_RESTITUTION],
    dtype=np.intp,
)


class EnergyGainError(FloatingPointError):
    """A throw ended outside the observation bounds: the solver created energy or let the box sink
    through the floor (``solver="seed"`` with a time step too large for the penalty stiffness, or no
    penalty at all). The message says which. Nothing is clipped."""


@dataclass
class ThrowBatch:
    """The state of ``n`` throws of one task: what was drawn and where the bodies are.

    The engine arrays hold ``n * bodies_per_env`` rows: throw i's thrown box in row
    ``i * bodies_per_env``, with a base box that box in the next row.

    Attributes:
        episodes: what ``initial`` drew, one row per throw (``task_config.Episodes``).
        params: (n * bodies_per_env, layout.PARAM_SIZE) the engine's body parameters.
        state: (n * bodies_per_env, layout.STATE_SIZE) body states x, y, angle, vx, vy, spin.
        stats: (n * bodies_per_env, layout.STATS_SIZE) what the engine recorded of the last run.
        params_written: whether ``params`` hold the parameters of every body (the envs write them
            once, or per episode when the dynamics or the base box are drawn).
    """

    episodes: task_config.Episodes
    params: np.ndarray
    state: np.ndarray
    stats: np.ndarray
    params_written: bool = False

    @property
    def n(self) -> int:
        """The number of throws."""
        return len(self.episodes.data)

    @functools.cached_property
    def bodies_per_throw(self) -> int:
        """Engine bodies per throw: the thrown box, and the base box where there is one."""
        return len(self.state) // self.n

    @functools.cached_property
    def thrown_state(self) -> np.ndarray:
        """(n, 6) the thrown boxes' states: a view of ``state``."""
        return self.state[:: self.bodies_per_throw]

    @functools.cached_property
    def base_state(self) -> np.ndarray | None:
        """(n, 6) the base boxes' states (a view of ``state``), or None without base boxes."""
        return self.state[1::2] if self.bodies_per_throw == 2 else None

    @functools.cached_property
    def thrown_stats(self) -> np.ndarray:
        """(n, layout.STATS_SIZE) what the engine recorded of the thrown boxes: a view of ``stats``."""
        return self.stats[:: self.bodies_per_throw]

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the cached views: they are views of ``state`` and ``stats`` again after unpickling."""
        return {field.name: getattr(self, field.name) for field in dataclasses.fields(self)}

    def copy(self) -> ThrowBatch:
        """A deep copy (the functional way to keep a state before a method writes into it)."""
        return ThrowBatch(
            task_config.Episodes(self.episodes.data.copy()),
            self.params.copy(),
            self.state.copy(),
            self.stats.copy(),
            self.params_written,
        )


class BoxTossFunctional:
    """The BoxToss throw, batch-first; keyword arguments are ``BoxTossEnv``'s but the rendering ones.

    Every argument is validated here (``arguments.ENV_ARGUMENTS``, ``task_config.make_task_config`` and the
    engine's ``Scene``): a TypeError names one of the wrong type, a ValueError one outside its range.

    Attributes:
        arguments: every argument's value, defaults filled in.
        config: the validated task (``task_config.TaskConfig``).
        solver, dt: the engine's solver and time step [s].
        max_steps: the most time steps of a throw (``max_sim_time`` in whole steps).
        flags: the compile-time switches of the engine kernel (``physics.KernelFlags``).
        settings: the engine's settings array (dt, gravity, sleep, ...; ``physics.layout``).
        engine_config: what the task asks of the engine (``engine.make_engine`` made the four above from it).
        observation_low, observation_high: float32 bounds no observation leaves (``task.observation_bounds``).
    """

    def __init__(self, **kwargs: Any):
        self.arguments = args = apply_split(with_defaults(kwargs, CORE_ARGUMENTS, type(self).__name__))
        task_names = [name for name in CORE_ARGUMENTS if name not in ("solver", "dt", "split")]
        self.config = config = task_config.make_task_config(**{name: args[name] for name in task_names})
        # the engine validates the solver settings (dt, solver, material) and names what is wrong; it is
        # sized for the largest box drawn
        largest_box = (config.box_length_range[1], config.box_width_range[1])
        self.engine_config = engine_config(config, *largest_box, args["solver"], args["dt"])
        engine = make_engine(self.engine_config)
        self.solver, self.dt, self.max_steps = engine.solver, engine.dt, engine.max_steps
        self.flags, self.settings = engine.flags, engine.settings
        self.observation_low, self.observation_high = task.observation_bounds(config, self.max_steps * self.dt)

    # -- the batch and the engine -------------------------------------------------------------------
    def empty(self, n: int) -> ThrowBatch:
        """A batch of ``n`` throws, its arrays zero (``initial`` or ``for_episodes`` fills them)."""
        bodies = n * self.config.bodies_per_env
        return ThrowBatch(
            task_config.Episodes.empty(n, self.config.episode_size),
            np.zeros((bodies, layout.PARAM_SIZE)),
            np.zeros((bodies, layout.STATE_SIZE)),
            np.zeros((bodies, layout.STATS_SIZE)),
        )

    def for_episodes(self, episodes: task_config.Episodes) -> ThrowBatch:
        """A new batch of the given episodes (n rows), the boxes in the hand: to throw from episodes
        drawn elsewhere (the oracle plans from what ``reset`` returned)."""
        batch = self.empty(len(episodes.data))
        batch.episodes.data[:] = episodes.data
        return self.place(batch)

    def make_simulator(
        self,
        *,
        parallel: bool = False,
        threads: int | None = None,
        record: bool = False,
        start_interpreted: bool = False,
    ) -> Simulator | GroupedSimulator:
        """The engine for this task's throws. ``parallel=False``: one throw's scene per call (the single
        env; ``record`` keeps its trajectory). ``parallel=True``: any batch, on ``threads`` threads (with a
        base box each throw's two boxes stepped together, ``physics.grouped``). The compiled kernel is
        shared by every simulator of the same flags (numba's cache)."""
        if not parallel:
            return Simulator(
                dataclasses.replace(self.flags, record=record), threads=threads, start_interpreted=start_interpreted
            )
        return make_grouped_simulator(
            dataclasses.replace(self.flags, parallel=True, record=record),
            self.config.bodies_per_env,
            threads=threads,
            start_interpreted=start_interpreted,
        )

    # -- 1. initial: episodes drawn, boxes in the hand ---------------------------------------------
    def initial(self, rng: np.random.Generator, batch: ThrowBatch) -> ThrowBatch:
        """Draw every throw's episode from ``rng`` (one call, ``rng.random``) and put the boxes in the
        hand: ``initial_from_uniforms`` of those variates."""
        return self.initial_from_uniforms(rng.random(batch.episodes.data.shape), batch)

    def initial_from_uniforms(self, uniforms: np.ndarray, batch: ThrowBatch) -> ThrowBatch:
        """The episodes that the variates ``uniforms`` (n, episode_size) in [0, 1) stand for
        (``task.episodes_from_uniforms``), the boxes at rest in the hand."""
        task.episodes_from_uniforms(uniforms, self.config, batch.episodes)
        return self.place(batch)

    def place(self, batch: ThrowBatch) -> ThrowBatch:
        """Write the bodies' parameters (when drawn, or not yet written) and put every box in the hand,
        at rest (and the base boxes on the floor)."""
        if not batch.params_written or self.config.draws_body_params:
            task.write_body_params(batch.params, batch.episodes, self.config)
            batch.params_written = True
        return self._write_states(batch, None)

    def _write_states(self, batch: ThrowBatch, throws: np.ndarray | None) -> ThrowBatch:
        task.write_initial_states(batch.thrown_state, batch.episodes, throws)
        if batch.base_state is not None:
            task.write_base_states(batch.base_state, batch.episodes)
        return batch

    def reset_info(self, batch: ThrowBatch) -> dict[str, np.ndarray]:
        """The reset's info as (n,) arrays (``target_faces`` (n, 4) int8): ``BoxTossEnv.reset``'s keys."""
        data = batch.episodes.data
        names, columns = RESET_INFO_WITH_BASE if self.config.base_box else RESET_INFO
        if self.config.draws_box_size:
            names, columns = (*names, *BOX_SIZE_INFO), np.concatenate([columns, self.config.box_size_columns])
        rows = data.take(columns, axis=1).T  # one copy, a row per key
        info = {"target_x": rows[0], "target_faces": data[:, task_columns.EP_TARGET_FACES].astype(np.int8)}
        info.update(zip(names[1:], rows[1:], strict=True))
        return info

    # -- 2. and 3. transition: launch and simulate ------------------------------------------------
    def check_actions(self, actions, shape: tuple[int, ...]) -> np.ndarray:
        """Actions as float64 (n, 3) clipped to [-1, 1]; ``shape`` is what the caller accepts ((3,) for a
        single env). A TypeError or ValueError names what is wrong (``task.check_actions``)."""
        return task.check_actions(actions, shape)

    def launch(self, batch: ThrowBatch, actions: np.ndarray) -> ThrowBatch:
        """Throw: each box leaves the hand with the launch speed, direction and spin of its action
        (checked actions (n, 3), ``task.actions_to_throws``); base boxes stand where they were placed."""
        return self._write_states(batch, task.actions_to_throws(actions, self.config))

    def simulate(
        self,
        batch: ThrowBatch,
        simulator: Simulator | GroupedSimulator,
        trajectory: np.ndarray | None = None,
        events: np.ndarray | None = None,
    ) -> ThrowBatch:
        """Run every throw until its box rests or ``max_sim_time`` (``make_simulator``); the final states
        and the engine's stats are written into the batch."""
        simulator.run(batch.state, batch.params, self.settings, batch.stats, trajectory, events)
        return batch

    def transition(self, batch: ThrowBatch, actions, simulator: Simulator | GroupedSimulator) -> ThrowBatch:
        """``launch`` then ``simulate``: actions (n, 3) in [-1, 1] (clipped; checked) to final states."""
        actions = self.check_actions(actions, (batch.n, task_columns.ACTION_SIZE))
        return self.simulate(self.launch(batch, actions), simulator)

    # -- 4. observation and reward ------------------------------------------------------------------
    def observation(self, batch: ThrowBatch) -> np.ndarray:
        """A new float32 (n, obs_size) array of every throw's observation (``task.observe``)."""
        return task.observe(batch.thrown_state, batch.episodes, self.config, batch.base_state)

    def at_rest(self, batch: ThrowBatch) -> np.ndarray:
        """(n,) bool: which boxes came to rest (the others reached ``max_sim_time``)."""
        return ~np.isnan(batch.thrown_stats[:, layout.REST_TIME])

    def landing(self, batch: ThrowBatch, at_rest: np.ndarray | None = None):
        """(reward, terms, success, distance, orientation error) of where the boxes are, (n,) arrays
        (``task.reward_terms``); ``at_rest`` defaults to what the engine recorded."""
        at_rest = self.at_rest(batch) if at_rest is None else at_rest
        return task.reward_terms(batch.thrown_state, at_rest, batch.episodes, self.config, batch.base_state)

    def reward(self, batch: ThrowBatch) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The reward (n,) and its named terms (``task.REWARD_TERMS``), whose sum it is."""
        reward, terms, *_ = self.landing(batch)
        return reward, terms

    def terminal(self, batch: ThrowBatch) -> np.ndarray:
        """(n,) True: every throw ends its episode."""
        return np.ones(batch.n, dtype=bool)

    # -- 5. checks and the step's info --------------------------------------------------------------
    def failed(self, batch: ThrowBatch) -> np.ndarray:
        """(n,) bool: throws whose engine run diverged (a body's state went non-finite)."""
        return (batch.stats[:, layout.STATUS] != layout.STATUS_OK).reshape(batch.n, -1).any(axis=1)

    def check_finite(self, batch: ThrowBatch) -> None:
        """Raise the engine's ``NonFiniteStateError`` if a throw diverged."""
        if (batch.stats[:, layout.STATUS] != layout.STATUS_OK).any():
            check_finite_stats(batch.stats, self.solver)

    def outside_bounds(self, observations: np.ndarray) -> np.ndarray:
        """(n,) bool: observations that leave the observation bounds somewhere."""
        return task.outside_bounds(observations, self.observation_low, self.observation_high)

    def check_bounds(self, observations: np.ndarray, name_envs: bool = False) -> None:
        """Raise ``EnergyGainError`` for the first observation outside the bounds (its message prefixed
        with "env i: " when ``name_envs``)."""
        outside = self.outside_bounds(observations)
        if outside.any():
            i = int(np.argmax(outside))
            raise EnergyGainError((f"env {i}: " if name_envs else "") + self.bounds_message(observations[i]))

    def score(self, batch: ThrowBatch) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The reward (n,) and the step's info as (n,) arrays: ``BoxTossEnv.step``'s keys, in its order."""
        at_rest = self.at_rest(batch)
        reward, terms, success, distance, orientation_error = self.landing(batch, at_rest)
        # a few grouped copies (a row per key), not one numpy call per key: the single env pays each call
        x, y, angle = batch.thrown_state[:, layout.X : layout.ANGLE + 1].T.copy()
        first_contact, end_time, penetration, impacts, steps = batch.thrown_stats.take(STEP_STATS, axis=1).T
        target_x, mass, friction, restitution = batch.episodes.data.take(STEP_EPISODE, axis=1).T
        info = {
            "final_x": x,
            "final_y": y,
            "final_angle": task.wrap_angles(angle),
            "face_down": task.faces_down(angle),
            "at_rest": at_rest,
            "success": success,
            "distance": distance,
            "orientation_error": orientation_error,
            "flight_time": np.where(np.isnan(first_contact), end_time, first_contact),
            "n_impacts": impacts.astype(np.int64),
            "n_steps": steps.astype(np.int64),
            "max_penetration": penetration,
            "sim_time": end_time,
            **terms,
            "target_x": target_x,
            "mass": mass,
            "friction": friction,
            "restitution": restitution,
        }
        if batch.base_state is not None:
            info.update(base_landing_info(batch.base_state, batch.thrown_state, batch.episodes, self.config))
        return reward, info

    def bounds_message(self, observation: np.ndarray) -> str:
        """What the throw that ended in ``observation`` (outside the bounds) did, for the solver that ran."""
        low, high = self.observation_low, self.observation_high
        column = int(np.argmax(np.maximum(low - observation, observation - high)))
        where = (
            f"the throw ended with {task.observation_names(self.config)[column]} = {observation[column]:g}, "
            f"outside the observation bounds [{low[column]:g}, {high[column]:g}]"
        )
        stiffness = self.config.penalty_stiffness
        if column == task_columns.OBS_Y and observation[column] < low[column]:
            what = (
                f"{where}: the box sank through the floor (its centre more than a corner radius below it) "
                f"with solver={self.solver!r}. "
            )
            if self.solver == "robust":
                return what + "The robust solver should never let a box through: please report these arguments"
            if stiffness == 0.0:
                return what + (
                    "With penalty_stiffness=0 the seed scheme has nothing that pushes a corner back out "
                    "of the floor: give penalty_stiffness > 0, or use solver='robust'"
                )
            return what + (
                f"The seed scheme's penalty spring (penalty_stiffness={stiffness:g} N/m) was too soft to "
                "hold it: use a stiffer one (with a dt small enough for it), or solver='robust'"
            )
        what = f"{where} that energy conservation guarantees: solver={self.solver!r} created energy. "
        if self.solver == "robust":
            return what + "The robust solver should never create energy: please report these arguments"
        return what + (
            f"The seed scheme's explicit penalty spring gains energy when dt is too large for its "
            f"stiffness (dt={self.dt:g} s with penalty_stiffness={stiffness:g} N/m): use a smaller dt "
            "(e.g. 1/1024 s for 1e5 N/m), a softer penalty_stiffness, or solver='robust'"
        )


def engine_config(
    config: task_config.TaskConfig, box_length: float, box_width: float, solver: str, dt: float
) -> EngineConfig:
    """What a one-throw task asks of the engine: its box, the largest mass, friction and restitution it draws,
    the solver and step; with a base box the thrown box and the base are one scene of colliding boxes (the
    colliding kernel), without one the floor-only kernel."""
    return EngineConfig(
        box_size=(box_length, box_width),
        mass=config.mass_range[1],
        release=(config.release_x_range[0], config.release_height_range[0]),
        gravity=config.gravity,
        restitution=config.restitution_range[1],
        friction=config.friction_range[1],
        penalty_stiffness=config.penalty_stiffness,
        solver=solver,
        dt=dt,
        max_sim_time=config.max_sim_time,
        boxes_collide=config.base_box,
    )


def base_landing_info(
    base_states: np.ndarray, states: np.ndarray, episodes: task_config.Episodes, config: task_config.TaskConfig
) -> dict[str, np.ndarray]:
    """The step info of a task with a base box, (n,) arrays: where the base ended (``base_x``, ``base_y``
    [m], ``base_angle`` [rad, wrapped to [-pi, pi)]), the thrown box's lowest point above the base's top
    (``height_above_base`` [m]) and whether it rests on it (``on_base``: within ``task.SUPPORT_TOLERANCE``
    of the top, its centre over the top face)."""
    _, dy = task.landing_offsets(states, episodes, config, base_states)
    top_x, _, half_top = task.base_top(base_states, episodes)
    on_base = (np.abs(dy) <= task.SUPPORT_TOLERANCE) & (np.abs(states[:, layout.X] - top_x) <= half_top)
    return {
        "base_x": base_states[:, layout.X].copy(),
        "base_y": base_states[:, layout.Y].copy(),
        "base_angle": task.wrap_angles(base_states[:, layout.ANGLE]),
        "height_above_base": dy,
        "on_base": on_base,
    }


def episodes_from_reset_infos(reset_infos: list[dict[str, Any]]) -> task_config.Episodes:
    """The episodes (release pose, target, dynamics, and the base box's size where there is one) that
    ``reset`` drew, rebuilt from its infos (one per throw, each as ``BoxTossEnv.reset`` returns it):
    the inverse of ``BoxTossFunctional.reset_info``."""
    base_box = bool(reset_infos) and "base_length" in reset_infos[0]
    names, columns = RESET_INFO_WITH_BASE if base_box else RESET_INFO
    size = task_columns.EPISODE_SIZE_WITH_BASE if base_box else task_columns.EPISODE_SIZE
    if reset_infos and "box_length" in reset_infos[0]:  # a drawn box size: its columns after all the others
        names, columns = (*names, *BOX_SIZE_INFO), np.concatenate([columns, [size, size + 1]])
        size += len(BOX_SIZE_INFO)
    episodes = task_config.Episodes.empty(len(reset_infos), size)
    for row, info in zip(episodes.data, reset_infos, strict=True):
        row[columns] = [info[name] for name in names]
        row[task_columns.EP_TARGET_FACES] = info["target_faces"]
    return episodes


def first_of(info: dict[str, np.ndarray]) -> dict[str, Any]:
    """One throw's info from a batch's: Python scalars (the first row of an array of rows)."""
    return {key: value.item(0) if value.ndim == 1 else value[0] for key, value in info.items()}
