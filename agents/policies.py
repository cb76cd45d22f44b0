"""Policies that evaluation throws with: random and constant actions, and trained SB3 models.

A policy answers a batch of first observations (n, obs) and their reset infos with actions (n, 3)
in [-1, 1]; ``env`` is the env the throws will be made in (a planner may simulate with it). The
oracle, which plans with the simulator, is in ``agents.oracle``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Protocol

import gymnasium as gym
import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import VecNormalize

from agents import algorithms
from agents.envs import command_map, observation_normalizer
from agents.run_files import check_model_file, read_normalizer
from box_toss_env.envs import task_columns
from box_toss_env.envs.goal import goal_observations
from box_toss_env.files import DamagedFileError


class UnreadableModelError(DamagedFileError):
    """A saved model that is missing, truncated or not a model of the algorithm."""


def load_model(algo: str, path: Path, **kwargs) -> BaseAlgorithm:
    """``algo``'s model saved at ``path`` (CPU); an UnreadableModelError naming the file if it is missing or
    damaged (``check_model_file``), or if SB3 cannot load it as a model of ``algo``."""
    if not path.exists():
        raise UnreadableModelError(f"{path} does not exist (did the run finish? --resume it)")
    try:
        check_model_file(path)
    except DamagedFileError as error:
        raise UnreadableModelError(f"{error}; retrain, or --resume from a checkpoint") from None
    try:
        return algorithms.algorithm_class(algo).load(path, device="cpu", **kwargs)
    except OSError:
        raise
    except Exception as error:  # the file is whole (checked above) but not a model SB3 loads as algo's
        message = " ".join(str(error).split())[:200]
        raise UnreadableModelError(
            f"{path} cannot be read as a {algo.upper()} model ({type(error).__name__}: {message})"
        ) from None


class Policy(Protocol):
    def act(self, observations: np.ndarray, reset_infos: list[dict[str, Any]], env: gym.Env) -> np.ndarray: ...


class RandomPolicy:
    """Uniform actions in [-1, 1]^3 from a generator seeded at construction (the same throws on every evaluation
    with a new policy); each call draws new actions (the throws of an episode of several steps differ)."""

    def __init__(self, seed: int = 0):
        self.seed = seed
        self.rng = np.random.default_rng(seed)

    def act(self, observations: np.ndarray, reset_infos, env: gym.Env) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, (len(observations), task_columns.ACTION_SIZE))


class ConstantPolicy:
    """The same action for every target (e.g. [-1, 0, 0]: zero speed, the box drops from the hand)."""

    def __init__(self, action=(-1.0, 0.0, 0.0)):
        self.action = np.asarray(action, dtype=np.float64)

    def act(self, observations: np.ndarray, reset_infos, env: gym.Env) -> np.ndarray:
        return np.tile(self.action, (len(observations), 1))


class GoalPolicy:
    """A model trained on ``BoxToss-Goal-v0`` (Dict observations) throwing at ``BoxToss-v0``'s targets: each
    first observation is made the goal env's Dict of the same seed (``goal_observations``), the model answers
    with its deterministic action (no normalisation), mapped to env actions as ``env_wrapper`` does (ballistic
    commands) if it was trained through one."""

    def __init__(self, model: BaseAlgorithm, env_wrapper: Any = None):
        self.model = model
        self.commands_to_actions = command_map(env_wrapper)

    def act(self, observations: np.ndarray, reset_infos, env: gym.Env) -> np.ndarray:
        actions, _ = self.model.predict(goal_observations(observations), deterministic=True)
        if self.commands_to_actions is not None:
            actions = self.commands_to_actions(observations, actions, env)
        return actions


class TrainedPolicy:
    """A trained SB3 model's deterministic action on observations normalised as in training; a model
    trained through an ``env_wrapper`` (ballistic commands) has its actions mapped as that wrapper does."""

    def __init__(self, model: BaseAlgorithm, vec_normalize: VecNormalize | None = None, env_wrapper: Any = None):
        self.model = model
        self.normalize = observation_normalizer(vec_normalize)
        self.commands_to_actions = command_map(env_wrapper)

    def act(self, observations: np.ndarray, reset_infos, env: gym.Env) -> np.ndarray:
        actions, _ = self.model.predict(self.normalize(observations), deterministic=True)
        if self.commands_to_actions is not None:
            actions = self.commands_to_actions(observations, actions, env)
        return actions

    @classmethod
    def load(
        cls, run_dir: Path, algo: str, which: str = "final", env_wrapper: Any = None, normalized: bool = False
    ) -> TrainedPolicy:
        """The final model of a run folder (``which="best"``: the best by validation success); a model
        trained on ``normalized`` observations refuses to load without its statistics."""
        prefix = "" if which == "final" else "best_"
        model = load_model(algo, Path(run_dir) / f"{prefix}model.zip")
        stats = Path(run_dir) / f"{prefix}vecnormalize.pkl"
        vec_normalize = None
        if normalized and not stats.exists():
            raise UnreadableModelError(
                f"{stats} is missing: the model was trained on normalised observations and "
                f"acts at random without their statistics"
            )
        if stats.exists():  # the statistics only (SB3 pickles them without their venv)
            vec_normalize = read_normalizer(stats, model.observation_space.shape)
        return cls(model, vec_normalize, env_wrapper)
