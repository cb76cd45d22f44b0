"""Baselines on the same targets as PPO: random throws, and an oracle that plans with the simulator.

    python -m agents.baselines random            # runs/random: uniform actions
    python -m agents.baselines oracle            # runs/oracle: cross-entropy search per target
    python -m agents.evaluate runs/oracle --env-kwargs solver=seed dt=0.0009765625   # as any run

The oracle knows everything the env draws at reset (release pose, target, dynamics) and simulates
candidate throws with the env's own engine kernel and settings before it throws once, so it bounds
what any policy can reach: each target's action is the best of a cross-entropy search over the
3-D action (``OraclePlanner``), scored by the env's reward. All targets are planned together:
every iteration simulates all candidates of all unsolved targets in one engine call.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from box_toss_env.envs import task
from box_toss_env.physics import Simulator, layout

RUNS = Path("runs")


class RandomPolicy:
    """Uniform actions in [-1, 1]^3 from a seeded generator (the same throws on every evaluation)."""

    def __init__(self, seed: int = 0):
        self.seed = seed

    def act(self, observations: np.ndarray, reset_infos, env: gym.Env) -> np.ndarray:
        return np.random.default_rng(self.seed).uniform(-1.0, 1.0, (len(observations), task.ACTION_SIZE))


class ConstantPolicy:
    """The same action for every target (e.g. [-1, 0, 0]: zero speed, the box drops from the hand)."""

    def __init__(self, action=(-1.0, 0.0, 0.0)):
        self.action = np.asarray(action, dtype=np.float64)

    def act(self, observations: np.ndarray, reset_infos, env: gym.Env) -> np.ndarray:
        return np.tile(self.action, (len(observations), 1))


def episodes_from_infos(reset_infos: list[dict[str, Any]]) -> task.Episodes:
    """The episodes (release pose, target, dynamics) that ``reset`` drew, rebuilt from its infos."""
    episodes = task.Episodes.empty(len(reset_infos))
    data = episodes.data
    for i, info in enumerate(reset_infos):
        data[i, task.EP_RELEASE] = info["release_x"], info["release_y"], info["release_angle"]
        data[i, task.EP_TARGET_X] = info["target_x"]
        data[i, task.EP_TARGET_FACES] = info["target_faces"]
        data[i, task.EP_DYNAMICS] = info["mass"], info["friction"], info["restitution"]
    return episodes


class ThrowSimulator:
    """Many throws of one env's task in one call of the env's own engine kernel and settings."""

    def __init__(self, env: gym.Env, threads: int | None = None):
        unwrapped = env.unwrapped
        self.config = unwrapped.config
        self.settings = unwrapped.engine_settings  # the env's solver settings (dt, sleep, ...): throws as the env's
        self.simulator = Simulator(dataclasses.replace(unwrapped.flags, parallel=True, record=False), threads=threads)
        self.low, self.high = unwrapped.observation_space.low, unwrapped.observation_space.high

    def rewards(self, episodes: task.Episodes, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(reward, success, distance) of throwing ``actions`` (n, 3) in ``episodes`` (n rows); a
        throw the env would refuse (non-finite state, energy gain) gets reward -inf."""
        n = len(actions)
        params = task.write_body_params(np.zeros((n, layout.PARAM_SIZE)), episodes, self.config)
        states = np.zeros((n, layout.STATE_SIZE))
        throws = task.actions_to_throws(task.check_actions(actions, (n, task.ACTION_SIZE)), self.config)
        task.write_initial_states(states, episodes, throws)
        stats = np.zeros((n, layout.STATS_SIZE))
        self.simulator.run(states, params, self.settings, stats)
        refused = stats[:, layout.STATUS] != layout.STATUS_OK
        at_rest = ~np.isnan(stats[:, layout.REST_TIME])
        with np.errstate(invalid="ignore"):
            reward, _, success, distance, _ = task.reward_terms(states, at_rest, episodes, self.config)
            refused |= task.outside_bounds(task.observe(states, episodes, self.config), self.low, self.high)
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

    def plan(self, simulator: ThrowSimulator, episodes: task.Episodes) -> np.ndarray:
        """The best action found for each episode (n, 3)."""
        s = self.settings
        rng = np.random.default_rng(s.seed)
        n = len(episodes.data)
        keep = min(s.elite, s.initial)
        # round 0: uniform candidates; the elite (n, keep, 3) holds the best throws so far, best first
        candidates = rng.uniform(-1.0, 1.0, (n, s.initial, task.ACTION_SIZE))
        elite, elite_scores, elite_settled = self._select(simulator, episodes, np.arange(n), candidates, keep)
        self.simulated = n * s.initial
        for _ in range(s.iterations):
            active = np.flatnonzero(~elite_settled[:, 0])
            if active.size == 0:
                break
            mean = elite[active].mean(axis=1, keepdims=True)
            std = np.maximum(elite[active].std(axis=1, keepdims=True), s.min_std)
            draws = np.clip(mean + std * rng.standard_normal((active.size, s.population, task.ACTION_SIZE)), -1, 1)
            self.simulated += draws.shape[0] * draws.shape[1]
            elite[active], elite_scores[active], elite_settled[active] = self._select(
                simulator, episodes, active, draws, keep, (elite[active], elite_scores[active], elite_settled[active]))
        return elite[:, 0]

    def _select(self, simulator: ThrowSimulator, episodes: task.Episodes, rows: np.ndarray, candidates: np.ndarray,
                keep: int, incumbents=None):
        """Simulate ``candidates`` (len(rows), k, 3) and keep the ``keep`` best per row, with the
        incumbents (actions, scores, settled) if given: (actions, scores, settled), best first."""
        k = candidates.shape[1]
        repeated = task.Episodes(np.repeat(episodes.data[rows], k, axis=0))
        reward, success, distance = simulator.rewards(repeated, candidates.reshape(-1, task.ACTION_SIZE))
        scores = reward.reshape(len(rows), k)
        tolerance = self.settings.settle * simulator.config.position_tolerance
        settled = (success & (distance <= tolerance)).reshape(scores.shape)
        if incumbents is not None:
            candidates = np.concatenate((incumbents[0], candidates), axis=1)
            scores = np.concatenate((incumbents[1], scores), axis=1)
            settled = np.concatenate((incumbents[2], settled), axis=1)
        order = np.argsort(-scores, axis=1, kind="stable")[:, :keep]
        return (np.take_along_axis(candidates, order[..., None], axis=1), np.take_along_axis(scores, order, axis=1),
                np.take_along_axis(settled, order, axis=1))


def make_baseline(algo: str, settings: dict[str, Any] | None = None):
    """The baseline policy named ``algo`` ("random", "oracle" or "constant") with its settings."""
    settings = settings or {}
    if algo == "random":
        return RandomPolicy(**settings)
    if algo == "oracle":
        return OraclePlanner(OracleSettings(**settings))
    if algo == "constant":
        return ConstantPolicy(**settings)
    raise ValueError(f"unknown baseline {algo!r}; choose random, oracle or constant")


def make_baseline_run(algo: str, run_dir: Path, env_id: str = "BoxToss-v0", env_kwargs: dict[str, Any] | None = None,
                      settings: dict[str, Any] | None = None, command: str | None = None) -> Path:
    """A run folder for a baseline (config.yml, command.txt), evaluated like any run."""
    from agents.config import save_yaml

    run_dir.mkdir(parents=True, exist_ok=True)
    save_yaml({"algo": algo, "env_id": env_id, "env_kwargs": env_kwargs or {}, "baseline": settings or {}},
              run_dir / "config.yml")
    if command:
        (run_dir / "command.txt").write_text(command + "\n")
    return run_dir


def main(argv: list[str] | None = None) -> None:
    import shlex

    from agents.evaluate import TEST_TARGETS, evaluate_run, parse_kwargs

    argv = sys.argv[1:] if argv is None else list(argv)
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("algo", choices=("random", "oracle"))
    parser.add_argument("--env", default="BoxToss-v0")
    parser.add_argument("--env-kwargs", nargs="*", default=[], metavar="KEY=VALUE")
    parser.add_argument("--set", nargs="*", default=[], action="extend", metavar="KEY=VALUE", dest="settings",
                        help="baseline settings, e.g. seed=1 (random) or population=128 iterations=8 (oracle)")
    parser.add_argument("--name", help="run folder name (default: the baseline's name)")
    parser.add_argument("--runs-dir", type=Path, default=RUNS)
    parser.add_argument("--targets", type=int, default=TEST_TARGETS)
    args = parser.parse_args(argv)
    run_dir = make_baseline_run(args.algo, args.runs_dir / (args.name or args.algo), args.env,
                                parse_kwargs(args.env_kwargs), parse_kwargs(args.settings),
                                shlex.join(["python", "-m", "agents.baselines", *argv]))
    results = evaluate_run(run_dir, n_targets=args.targets)
    print(f"{args.algo}: acted on {args.targets} targets in {results['act_seconds']:.1f} s")


if __name__ == "__main__":
    main()
