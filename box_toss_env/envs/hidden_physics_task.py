"""The hidden-physics task (``BoxToss-HiddenPhysics-v0``) for the multi-throw core: one box thrown again and again
at one target, its mass, friction and restitution drawn wide and never observed.

An episode is a one-throw episode of ``BoxToss-v0`` (release pose, target, target faces, dynamics: ``task``'s
draws, with the dynamics ranges wide) thrown up to ``max_throws`` times: after each throw the box is picked up
and thrown again from the same release pose. Each throw is exactly ``BoxToss-v0``'s throw of that episode (the
one-throw core's launch, engine and score, ``functional.BoxTossFunctional``), so a planner told the dynamics can
plan it with the one-throw tools (the oracle). The agent sees where each throw landed and how it threw it, never
the dynamics: it must infer them from the landings.

Observation columns (``OBSERVATION_NAMES``): the box in the hand (release x, y, cos, sin), the target x and the four
target-face flags; the last landing (x, y, cos, sin of the box once the throw ended, 1 if it came to rest; zeros
before the first throw) and the last action; the throws made so far.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from box_toss_env.envs import task, task_columns, task_config
from box_toss_env.envs.arguments import ARGUMENTS, Argument
from box_toss_env.envs.functional import BoxTossFunctional, ThrowBatch
from box_toss_env.physics import layout
from box_toss_env.physics.validation import check_integer

MAX_THROWS = 64
"""The most throws one episode may allow."""

HIDDEN_DEFAULTS: dict[str, Any] = {
    "target_face": "long_side",
    "mass_range": (0.5, 5.0),
    "friction_range": (0.1, 1.0),
    "restitution_range": (0.0, 0.6),
}
"""Where ``BoxToss-HiddenPhysics-v0``'s defaults differ from ``BoxToss-v0``'s: the pose asked for (near the target,
a long side down) and the dynamics, drawn wide per episode."""

_LEFT_OUT: tuple[str, ...] = ("mass", "friction", "restitution", "observe_dynamics", "base_box")
_LEFT_OUT += ("base_length_range", "base_height_range", "base_mass", "render_fps")
_LEFT_OUT += ("observation_mode", "pixel_size", "split", "box_length_range", "box_width_range")  # one-throw only


def _argument(name: str) -> Argument:
    a = ARGUMENTS[name]
    if name not in HIDDEN_DEFAULTS:
        return a
    return Argument(name, a.type.replace(" | None", ""), HIDDEN_DEFAULTS[name], a.doc, a.allowed, "", a.group)


HIDDEN_ARGUMENTS: tuple[Argument, ...] = (
    Argument("max_throws", "int", 5, f"throws an episode allows, in [1, {MAX_THROWS}]"),
    *(_argument(name) for name in ARGUMENTS if name not in _LEFT_OUT),
)
"""The keyword arguments of ``BoxToss-HiddenPhysics-v0``: ``max_throws`` and ``BoxToss-v0``'s (less the fixed
dynamics, the dynamics' observation and the base box), with ``HIDDEN_DEFAULTS``."""

HAND_NAMES = ("hand x", "hand y", "hand cos(angle)", "hand sin(angle)", "target x")
FACE_NAMES = ("target face 0", "target face 1", "target face 2", "target face 3")
LANDING_NAMES = ("landing x", "landing y", "landing cos(angle)", "landing sin(angle)", "landing at rest")
ACTION_NAMES = ("last action 0", "last action 1", "last action 2")
OBSERVATION_NAMES = (*HAND_NAMES, *FACE_NAMES, *LANDING_NAMES, *ACTION_NAMES, "throws made")
O_HAND_X, O_HAND_Y, O_HAND_COS, O_HAND_SIN, O_TARGET_X = range(5)
O_FACES, O_LANDING, O_AT_REST, O_ACTION, O_THROWS = 5, 9, 13, 14, 17


class HiddenPhysicsTask:
    """``BoxToss-HiddenPhysics-v0`` for the multi-throw core (module docstring): ``episodes`` rows are one-throw
    episodes (``task_config.Episodes``' columns); the scene is the one box, thrown again each time. Keyword arguments:
    ``HIDDEN_ARGUMENTS``' but the rendering ones."""

    carries_bodies = False
    max_bodies = 1
    memory_size = 0

    def __init__(self, **kwargs: Any):
        names = [a.name for a in HIDDEN_ARGUMENTS if a.group != "render"]
        unknown = [name for name in kwargs if name not in names]
        if unknown:
            raise TypeError(f"BoxTossHiddenPhysicsEnv() got an unexpected keyword argument {unknown[0]!r}")
        values = {a.name: kwargs.get(a.name, a.default) for a in HIDDEN_ARGUMENTS if a.group != "render"}
        self.max_throws = check_integer("max_throws", values.pop("max_throws"), 1, MAX_THROWS)
        self.throw = BoxTossFunctional(**values)  # one throw of the episode: BoxToss-v0's, validated there
        self.config = self.throw.config
        self.engine_config = self.throw.engine_config
        self.episode_size = self.config.episode_size

    def one_throw_arguments(self) -> dict[str, Any]:
        """The ``BoxToss-v0`` arguments whose throws are this task's (the ceiling's planner plans with them)."""
        return dict(self.throw.arguments)

    def throw_batch(self, batch) -> ThrowBatch:
        """The batch's last throws as the one-throw core's batch (views of its arrays)."""
        arrays = (batch.params[:, 0], batch.state[:, 0], batch.stats[:, 0])
        return ThrowBatch(task_config.Episodes(batch.episodes), *arrays, params_written=True)

    def draw(self, uniforms: np.ndarray) -> np.ndarray:
        episodes = task_config.Episodes.empty(len(uniforms), self.episode_size)
        return task.episodes_from_uniforms(uniforms, self.config, episodes).data

    def body_params(self, episodes: np.ndarray) -> np.ndarray:
        params = np.zeros((len(episodes), layout.PARAM_SIZE))
        return task.write_body_params(params, task_config.Episodes(episodes), self.config)[:, None]

    def release(self, episodes: np.ndarray, thrown: np.ndarray) -> np.ndarray:
        return episodes[:, task_columns.EP_RELEASE]

    def throw_states(self, release: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """The one-throw core's launch (``task.write_initial_states``) from ``release``."""
        episodes = task_config.Episodes.empty(len(release), self.episode_size)
        episodes.data[:, task_columns.EP_RELEASE] = release
        states = np.empty((len(release), layout.STATE_SIZE))
        return task.write_initial_states(states, episodes, task.actions_to_throws(actions, self.config))

    def observe(self, batch) -> np.ndarray:
        landed = batch.thrown > 0
        hand = batch.episodes[:, task_columns.EP_RELEASE]
        landing = batch.state[:, 0]
        at_rest = ~np.isnan(batch.stats[:, 0, layout.REST_TIME]) & landed
        parts = [
            hand[:, :2],
            np.cos(hand[:, 2:3]),
            np.sin(hand[:, 2:3]),
            batch.episodes[:, task_columns.EP_TARGET_X : task_columns.EP_TARGET_X + 1],
            batch.episodes[:, task_columns.EP_TARGET_FACES],
            landing[:, layout.X : layout.Y + 1],
            np.where(landed, np.cos(landing[:, layout.ANGLE]), 0.0)[:, None],
            np.sin(landing[:, layout.ANGLE : layout.ANGLE + 1]),
            at_rest[:, None],
            batch.actions,
            batch.thrown[:, None],
        ]
        return np.concatenate(parts, axis=1, dtype=np.float32)

    def score(self, batch, at_rest: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """The one-throw core's reward and info of each throw (``BoxTossFunctional.score``) and the throws made;
        terminated on success or once ``max_throws`` are made."""
        reward, info = self.throw.score(self.throw_batch(batch))
        info["thrown"] = batch.thrown.copy()
        return reward, info, info["success"] | (batch.thrown >= self.max_throws)

    def reset_info(self, batch) -> dict[str, np.ndarray]:
        """The one-throw reset's info (target, faces, release pose and the hidden dynamics, for analysis and for
        planners told them)."""
        throw_batch = ThrowBatch(
            task_config.Episodes(batch.episodes), batch.params[:, 0], batch.state[:, 0], batch.stats[:, 0]
        )
        return self.throw.reset_info(throw_batch)

    def observation_bounds(self, horizon: float) -> tuple[np.ndarray, np.ndarray]:
        """The hand's bounds from its ranges, the landing's from ``task.observation_bounds`` (energy), widened to
        hold the zeros before the first throw."""
        config = self.config
        one_low, one_high = task.observation_bounds(config, horizon)
        landing = slice(task_columns.OBS_X, task_columns.OBS_SIN + 1)
        target = task_columns.OBS_TARGET_X
        low = [config.release_x_range[0], config.release_height_range[0], -1.0, -1.0, one_low[target]]
        high = [config.release_x_range[1], config.release_height_range[1], 1.0, 1.0, one_high[target]]
        low += [0.0] * 4 + [min(v, 0.0) for v in one_low[landing]] + [0.0] + [-1.0] * 3 + [0.0]
        high += [1.0] * 4 + [max(v, 0.0) for v in one_high[landing]] + [1.0] + [1.0] * 3 + [self.max_throws]
        lows, highs = np.array(low, dtype=np.float32), np.array(high, dtype=np.float32)
        fixed = lows == highs
        lows[fixed] = np.nextafter(lows[fixed], np.float32(-np.inf))
        highs[fixed] = np.nextafter(highs[fixed], np.float32(np.inf))
        return lows, highs

    def observation_names(self) -> tuple[str, ...]:
        return OBSERVATION_NAMES
