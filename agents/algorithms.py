"""The Stable-Baselines3 algorithms that ``agents/`` trains, by the names RL Baselines3 Zoo uses.

Every BoxToss episode is one throw, so on-policy (PPO) and off-policy (SAC, TD3) learners see the
same thing: a contextual bandit with a continuous 3-D action. Hyperparameters are in
``agents/hyperparams/<name>.yml`` (RL Zoo's format), keyed by env id.

Stable-Baselines3 (and torch) are imported on the first call that needs a class, not with this module, so that
the commands parse their options (and answer ``--help``) without loading them.
"""

from __future__ import annotations

import inspect
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm

ALGORITHMS: dict[str, str] = {"ppo": "PPO", "sac": "SAC", "td3": "TD3"}
"""The algorithms' names, and their classes' names in ``stable_baselines3``."""
# constructor arguments a run sets itself rather than the hyperparameter file
SET_BY_THE_RUN = {"self", "env", "verbose", "seed", "device", "tensorboard_log", "_init_setup_model", "action_noise"}


def algorithm_class(name: str) -> type[BaseAlgorithm]:
    """The SB3 class of the algorithm ``name`` ("ppo", "sac" or "td3")."""
    if name not in ALGORITHMS:
        raise ValueError(f"algo must be one of {sorted(ALGORITHMS)}, got {name!r}")
    import stable_baselines3

    return getattr(stable_baselines3, ALGORITHMS[name])


def constructor_parameters(name: str) -> dict[str, inspect.Parameter]:
    """The hyperparameters the algorithm's constructor takes (``policy``, ``learning_rate``, ...), with their
    annotations and defaults; those a run sets itself (``SET_BY_THE_RUN``: the env, the seed, the device, the
    action noise, which ``noise_type`` and ``noise_std`` set) are left out."""
    parameters = inspect.signature(algorithm_class(name).__init__).parameters
    return {key: parameter for key, parameter in parameters.items() if key not in SET_BY_THE_RUN}


def constructor_keys(name: str) -> set[str]:
    """The names of ``constructor_parameters``."""
    return set(constructor_parameters(name))


def is_off_policy(name: str) -> bool:
    """Whether the algorithm learns from a replay buffer (saved with its checkpoints)."""
    from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm

    return issubclass(algorithm_class(name), OffPolicyAlgorithm)
