"""Training configuration: hyperparameters from a YAML file keyed by env id, command-line overrides.

A configuration is a plain dict (what ``config.yml`` in a run folder holds). Overrides are
``key=value`` strings; the key may be dotted (``policy_kwargs.net_arch=[64, 64]``) and the value is
read with ``yaml.safe_load`` (numbers, lists, dicts, booleans, strings), never evaluated as code.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import yaml

HYPERPARAMS = Path(__file__).parent / "hyperparams" / "ppo.yml"

# keys of a configuration that are not PPO constructor arguments
RUN_KEYS = {
    "n_timesteps": "env steps (throws) to train for",
    "n_envs": "envs stepped together",
    "normalize": "VecNormalize kwargs, or false",
    "env_kwargs": "kwargs of gymnasium.make_vec and gymnasium.make",
    "vec_env_kwargs": "kwargs of gymnasium.make_vec only",
    "torch_threads": "torch.set_num_threads",
    "eval_freq": "env steps between evaluations (0: never)",
    "eval_targets": "validation targets per evaluation",
    "checkpoint_freq": "env steps between checkpoints (0: never)",
}
PPO_KEYS = {"policy", "learning_rate", "n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda", "clip_range",
            "clip_range_vf", "normalize_advantage", "ent_coef", "vf_coef", "max_grad_norm", "use_sde",
            "sde_sample_freq", "target_kl", "policy_kwargs", "stats_window_size"}
ACTIVATIONS = ("tanh", "relu", "elu", "leaky_relu", "gelu", "silu")


def load_hyperparams(env_id: str, path: str | Path = HYPERPARAMS) -> dict[str, Any]:
    """The hyperparameters of ``env_id`` in the YAML file ``path`` (a deep copy)."""
    with open(path) as file:
        table = yaml.safe_load(file) or {}
    if env_id not in table:
        raise KeyError(f"{path} has no entry for {env_id!r}; it has {sorted(table)}")
    return coerce_numbers(copy.deepcopy(table[env_id]))


def coerce_numbers(value: Any) -> Any:
    """``value`` with every string that reads as a number (``1e-3``) made that number, recursively."""
    if isinstance(value, dict):
        return {key: coerce_numbers(item) for key, item in value.items()}
    if isinstance(value, list):
        return [coerce_numbers(item) for item in value]
    if isinstance(value, str):
        return read_value(value)
    return value


def parse_override(text: str) -> tuple[list[str], Any]:
    """``"a.b=value"`` as (["a", "b"], yaml.safe_load("value"))."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise ValueError(f"an override must look like key=value (e.g. n_timesteps=100000), got {text!r}")
    return key.strip().split("."), read_value(value)


def read_value(text: str) -> Any:
    """``yaml.safe_load(text)``, except that numbers YAML 1.1 reads as strings (``1e-3``, ``3E5``)
    are numbers."""
    value = yaml.safe_load(text)
    if isinstance(value, str):
        try:
            number = float(value)
        except ValueError:
            return value
        return int(number) if number.is_integer() and "." not in value and "e-" not in value.lower() else number
    return value


def apply_overrides(config: dict[str, Any], overrides: list[str] | None) -> dict[str, Any]:
    """A copy of ``config`` with each ``key=value`` override applied (dotted keys reach into dicts).
    Unknown top-level keys raise a ValueError naming them, so a typo does not pass silently."""
    config = copy.deepcopy(config)
    for text in overrides or ():
        keys, value = parse_override(text)
        if keys[0] not in RUN_KEYS and keys[0] not in PPO_KEYS:
            raise ValueError(f"unknown hyperparameter {keys[0]!r} in {text!r}; known: "
                             f"{sorted(RUN_KEYS) + sorted(PPO_KEYS)}")
        node = config
        for key in keys[:-1]:
            child = node.get(key)
            if not isinstance(child, dict):
                child = node[key] = {}
            node = child
        node[keys[-1]] = value
    return config


def check_config(config: dict[str, Any]) -> None:
    """A ValueError naming the first key that is unknown or out of range."""
    for key in config:
        if key not in RUN_KEYS and key not in PPO_KEYS:
            raise ValueError(f"unknown hyperparameter {key!r}; known: {sorted(RUN_KEYS) + sorted(PPO_KEYS)}")
    for key in ("n_timesteps", "n_envs"):
        if not isinstance(config.get(key), int) or config[key] < 1:
            raise ValueError(f"{key} must be an integer >= 1, got {config.get(key)!r}")
    activation = config.get("policy_kwargs", {}).get("activation_fn", "tanh")
    if activation not in ACTIVATIONS:
        raise ValueError(f"policy_kwargs.activation_fn must be one of {ACTIVATIONS}, got {activation!r}")


def ppo_kwargs(config: dict[str, Any]) -> dict[str, Any]:
    """The PPO constructor arguments of ``config``, with the activation's name made a torch class."""
    import torch.nn

    kwargs = {key: copy.deepcopy(value) for key, value in config.items() if key in PPO_KEYS}
    policy_kwargs = kwargs.setdefault("policy_kwargs", {})
    name = policy_kwargs.get("activation_fn", "tanh")
    classes = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU, "elu": torch.nn.ELU, "leaky_relu": torch.nn.LeakyReLU,
               "gelu": torch.nn.GELU, "silu": torch.nn.SiLU}
    policy_kwargs["activation_fn"] = classes[name]
    for key in ("learning_rate", "clip_range"):
        if isinstance(kwargs.get(key), str):
            kwargs[key] = schedule(key, kwargs[key])
    return kwargs


def schedule(name: str, text: str):
    """``"lin_X"``: a value decaying linearly from X at the start of training to 0 at its end
    (SB3 calls schedules with the fraction of training remaining, 1 -> 0, and below 0 in the last
    rollout when the budget is not a multiple of the rollout size)."""
    prefix, _, value = text.partition("_")
    start = read_value(value)
    if prefix != "lin" or not isinstance(start, (int, float)):
        raise ValueError(f"{name} must be a number or 'lin_<number>' (linear decay to 0), got {text!r}")
    return LinearSchedule(float(start))


class LinearSchedule:
    """X * (fraction of training remaining); a class rather than a lambda, so saved models load anywhere."""

    def __init__(self, start: float):
        self.start = start

    def __call__(self, progress_remaining: float) -> float:
        return self.start * max(progress_remaining, 0.0)  # SB3 may overshoot the budget by part of a rollout

    def __repr__(self) -> str:
        return f"lin_{self.start:g}"


def save_yaml(data: Any, path: str | Path) -> None:
    with open(path, "w") as file:
        yaml.safe_dump(data, file, sort_keys=False)


def load_yaml(path: str | Path) -> Any:
    with open(path) as file:
        return yaml.safe_load(file)
