"""The oracle: a policy that plans each throw with the simulator (the ceiling agents are measured against).

The oracle knows everything the env draws at reset (release pose, target, dynamics) and simulates
candidate throws with the env's own engine kernel and settings before it throws once, so it bounds
what any policy can reach: each target's action is the best of a cross-entropy search over the
3-D action (``OraclePlanner``), scored by the env's reward. All targets are planned together:
every iteration simulates all candidates of all unsolved targets in one engine call.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, cast

import gymnasium as gym
import numpy as np

from box_toss_env.envs import task_columns, task_config
from box_toss_env.envs.functional import BoxTossFunctional, episodes_from_reset_infos

episodes_from_infos = episodes_from_reset_infos
"""The episodes that ``reset`` drew, rebuilt from its infos (``envs.functional.episodes_from_reset_infos``)."""


class ThrowSimulator:
    """Many throws of one env's task in one engine call: the env's own throw (``env.unwrapped.core``,
    ``envs.functional.BoxTossFunctional``) over a batch of candidates, on its compiled kernel and settings."""

    def __init__(self, env: gym.Env, threads: int | None = None):
        self.core: BoxTossFunctional = cast(Any, env.unwrapped).core
        self.config = self.core.config
        self.settings = self.core.settings  # the env's solver settings (dt, sleep, ...): throws as the env's
        self.simulator = self.core.make_simulator(parallel=True, threads=threads)
        self.low, self.high = self.core.observation_low, self.core.observation_high

    def rewards(self, episodes: task_config.Episodes, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(reward, success, distance) of throwing ``actions`` (n, 3) in ``episodes`` (n rows); a
        throw the env would refuse (non-finite state, energy gain) gets reward -inf."""
        core = self.core
        batch = core.transition(core.for_episodes(episodes), actions, self.simulator)
        refused = core.failed(batch)
        with np.errstate(invalid="ignore"):
            reward, _, success, distance, _ = core.landing(batch)
            refused |= core.outside_bounds(core.observation(batch))
        reward[refused] = -np.inf
        success[refused] = False
        return reward, success, distance


@dataclass(frozen=True)
class OracleSettings:
    """Cross-entropy search over the action, per target: ``initial`` uniform candidates, then up to
    ``iterations`` rounds of ``population`` candidates drawn around the ``elite`` best so far; a
    target stops once it has a success within ``settle`` times the position tolerance."""

    initial: int = 128
    population: int = 32
    elite: int = 8
    iterations: int = 12
    min_std: float = 0.005
    settle: float = 0.05
    seed: int = 0
    threads: int | None = None


class OraclePlanner:
    """For each target, the best throw a cross-entropy search over the simulator finds."""

    def __init__(self, settings: OracleSettings | None = None):
        self.settings = settings or OracleSettings()
        self.simulated = 0  # throws simulated by the last plan

    def act(self, observations: np.ndarray, reset_infos: list[dict[str, Any]], env: gym.Env) -> np.ndarray:
        return self.plan(ThrowSimulator(env, self.settings.threads), episodes_from_infos(reset_infos))

    def plan(self, simulator: ThrowSimulator, episodes: task_config.Episodes) -> np.ndarray:
        """The best action found for each episode (n, 3)."""
        s = self.settings
        rng = np.random.default_rng(s.seed)
        n = len(episodes.data)
        keep = min(s.elite, s.initial)
        # round 0: uniform candidates; the elite (n, keep, 3) holds the best throws so far, best first
        candidates = rng.uniform(-1.0, 1.0, (n, s.initial, task_columns.ACTION_SIZE))
        elite, elite_scores, elite_settled = self._select(simulator, episodes, np.arange(n), candidates, keep)
        self.simulated = n * s.initial
        for _ in range(s.iterations):
            active = np.flatnonzero(~elite_settled[:, 0])
            if active.size == 0:
                break
            mean = elite[active].mean(axis=1, keepdims=True)
            std = np.maximum(elite[active].std(axis=1, keepdims=True), s.min_std)
            draws = np.clip(
                mean + std * rng.standard_normal((active.size, s.population, task_columns.ACTION_SIZE)), -1, 1
            )
            self.simulated += draws.shape[0] * draws.shape[1]
            elite[active], elite_scores[active], elite_settled[active] = self._select(
                simulator, episodes, active, draws, keep, (elite[active], elite_scores[active], elite_settled[active])
            )
        return elite[:, 0]

    def _select(
        self,
        simulator: ThrowSimulator,
        episodes: task_config.Episodes,
        rows: np.ndarray,
        candidates: np.ndarray,
        keep: int,
        incumbents=None,
    ):
        """Simulate ``candidates`` (len(rows), k, 3) and keep the ``keep`` best per row, with the
        incumbents (actions, scores, settled) if given: (actions, scores, settled), best first."""
        k = candidates.shape[1]
        repeated = task_config.Episodes(np.repeat(episodes.data[rows], k, axis=0))
        reward, success, distance = simulator.rewards(repeated, candidates.reshape(-1, task_columns.ACTION_SIZE))
        scores = reward.reshape(len(rows), k)
        tolerance = self.settings.settle * simulator.config.position_tolerance
        settled = (success & (distance <= tolerance)).reshape(scores.shape)
        if incumbents is not None:
            candidates = np.concatenate((incumbents[0], candidates), axis=1)
            scores = np.concatenate((incumbents[1], scores), axis=1)
            settled = np.concatenate((incumbents[2], settled), axis=1)
        order = np.argsort(-scores, axis=1, kind="stable")[:, :keep]
        return (
            np.take_along_axis(candidates, order[..., None], axis=1),
            np.take_along_axis(scores, order, axis=1),
            np.take_along_axis(settled, order, axis=1),
        )
