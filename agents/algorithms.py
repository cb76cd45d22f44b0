"""The Stable-Baselines3 algorithms that ``agents/`` trains, by the names RL Baselines3 Zoo uses.

Every BoxToss episode is one throw, so on-policy (PPO) and off-policy (SAC, TD3) learners see the
same thing: a contextual bandit with a continuous 3-D action. Hyperparameters are in
``agents/hyperparams/<name>.yml`` (RL Zoo's format), keyed by env id.
"""

from __future__ import annotations

import inspect

from stable_baselines3 import PPO, SAC, TD3
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm

ALGORITHMS: dict[str, type[BaseAlgorithm]] = {"ppo": PPO, "sac": SAC, "td3": TD3}
# constructor arguments a run sets itself rather than the hyperparameter file
_SET_BY_THE_RUN = {"self", "env", "verbose", "seed", "device", "tensorboard_log", "_init_setup_model"}


def algorithm_class(name: str) -> type[BaseAlgorithm]:
    """The SB3 class of the algorithm ``name`` ("ppo", "sac" or "td3")."""
    if name not in ALGORITHMS:
        raise ValueError(f"algo must be one of {sorted(ALGORITHMS)}, got {name!r}")
    return ALGORITHMS[name]


def constructor_keys(name: str) -> set[str]:
    """The hyperparameters the algorithm's constructor takes (``policy``, ``learning_rate``, ...)."""
    return set(inspect.signature(algorithm_class(name).__init__).parameters) - _SET_BY_THE_RUN


def is_off_policy(name: str) -> bool:
    """Whether the algorithm learns from a replay buffer (saved with its checkpoints)."""
    return issubclass(algorithm_class(name), OffPolicyAlgorithm)
