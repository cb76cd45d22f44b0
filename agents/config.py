"""Training configuration: RL Baselines3 Zoo hyperparameter files, our own settings, overrides.

Two files, both keyed by env id:

- ``agents/hyperparams/<algo>.yml`` is in RL Zoo's format and loads unchanged with
  ``python -m rl_zoo3.train --algo <algo> --env <id> --gym-packages box_toss_env --conf-file ...``:
  the algorithm's constructor arguments plus Zoo's own keys (``n_timesteps``, ``n_envs``,
  ``normalize``, ``env_kwargs``, ``env_wrapper``, ``noise_type``, ``noise_std``); ``policy_kwargs`` and a dict
  ``normalize`` are Python expressions in strings (``"dict(net_arch=[64, 64], activation_fn=nn.Tanh)"``).
- ``agents/hyperparams/project.yml`` holds what only our scripts use (engine threads, torch threads,
  validation and checkpoint frequency): ``defaults`` for every run, then per algorithm and env id.

``agents/hyperparams/raw/<algo>.yml`` (``RAW_HYPERPARAMS``, RL Zoo's format too) holds the recipes of the raw tier
(the env's own actions, no ``env_wrapper``) where they differ from the file above without its wrapper; a folder
without its own ``project.yml`` uses its parent's.

A configuration is one plain dict of both (what ``config.yml`` in a run folder holds), with Zoo's
expression strings read into dicts (``activation_fn: nn.Tanh`` stays a name). Expressions are read
with ``ast``, never evaluated: only ``dict(...)``, literals and ``nn.<Name>`` are accepted.
Overrides are ``key=value`` strings; the key may be dotted (``policy_kwargs.net_arch=[64, 64]``) and
the value is read with ``yaml.safe_load``.
"""

from __future__ import annotations

import argparse
import ast
import copy
import math
from pathlib import Path
from typing import Any

import numba
import numpy as np
import torch.nn
import yaml
from stable_baselines3.common.noise import NormalActionNoise

from agents import algorithms
from agents.envs import read_env_wrapper
from box_toss_env.files import write_atomic

HYPERPARAMS = Path(__file__).parent / "hyperparams"
RAW_HYPERPARAMS = HYPERPARAMS / "raw"
PROJECT_FILE = "project.yml"

ZOO_KEYS = {
    "n_timesteps": "env steps (throws) to train for",
    "n_envs": "envs stepped together",
    "normalize": "VecNormalize kwargs (a dict, or true), or false",
    "env_kwargs": "kwargs of gymnasium.make_vec and gymnasium.make",
    "noise_type": "action noise of off-policy algorithms: 'normal'",
    "noise_std": "standard deviation of that noise, in action units",
    "env_wrapper": "wrapper of each env: box_toss_env.envs.ballistic.BallisticThrows (ballistic commands), "
    "box_toss_env.envs.stack_commands.StackCommands (BoxToss-Stack-v0's), null: the env's own actions",
}
PROJECT_KEYS = {
    "vec_env_kwargs": "kwargs of gymnasium.make_vec only (engine threads)",
    "torch_threads": "torch.set_num_threads",
    "eval_freq": "env steps between evaluations (0: never)",
    "eval_targets": "validation targets per evaluation",
    "checkpoint_freq": "env steps between checkpoints (0: never)",
}
EXPRESSION_KEYS = ("policy_kwargs", "normalize", "replay_buffer_kwargs")  # Zoo evaluates these strings


class ConfigError(ValueError):
    """A configuration that cannot run; the message names the key and what is allowed."""


class OneLineParser(argparse.ArgumentParser):
    """A parser whose errors are one line, exit code 2 (argparse would print the whole usage first)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


# -- reading files -------------------------------------------------------------------------------
def hyperparams_path(algo: str, directory: str | Path = HYPERPARAMS) -> Path:
    algorithms.algorithm_class(algo)  # a ValueError for an unknown name
    return Path(directory) / f"{algo}.yml"


def load_hyperparams(algo: str, env_id: str, directory: str | Path = HYPERPARAMS) -> dict[str, Any]:
    """The configuration of ``algo`` on ``env_id``: its entry in ``<algo>.yml`` (Zoo format, read
    into plain values) with our settings from ``project.yml``."""
    path = hyperparams_path(algo, directory)
    table = read_mapping(path)
    if env_id not in table:
        raise ConfigError(f"{path} has no entry for {env_id!r}; it has {sorted(table)}")
    config = read_zoo_entry(table[env_id], f"{path}: {env_id}")
    config.update(project_settings(algo, env_id, project_path(directory)))
    return config


def project_path(directory: str | Path) -> Path:
    """``project.yml`` of ``directory``, or of its parent if it has none (``raw/`` shares the recipes' settings)."""
    path = Path(directory) / PROJECT_FILE
    parent = Path(directory).parent / PROJECT_FILE
    return parent if not path.exists() and parent.exists() else path


def has_entry(algo: str, env_id: str, directory: str | Path) -> bool:
    """Whether ``directory``'s ``<algo>.yml`` exists and has an entry for ``env_id``."""
    path = hyperparams_path(algo, directory)
    return path.exists() and env_id in read_mapping(path)


def read_mapping(path: Path) -> dict[str, Any]:
    """A YAML file that must hold a mapping (a ConfigError naming the file otherwise)."""
    try:
        with open(path) as file:
            data = yaml.safe_load(file)
    except FileNotFoundError:
        raise ConfigError(f"no hyperparameter file {path}") from None
    except yaml.YAMLError as error:
        raise ConfigError(f"{path} is not valid YAML: {error}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path} must hold a mapping of env ids to hyperparameters, got a {type(data).__name__}")
    return data


def project_settings(algo: str, env_id: str, path: Path) -> dict[str, Any]:
    """``defaults`` of project.yml, updated by its ``<algo>: <env_id>:`` entry if any."""
    table = read_mapping(path) if path.exists() else {}
    settings = copy.deepcopy(table.get("defaults") or {})
    settings.update(copy.deepcopy((table.get(algo) or {}).get(env_id) or {}))
    return settings


def read_zoo_entry(entry: Any, where: str) -> dict[str, Any]:
    """A Zoo hyperparameter entry with its expression strings read into plain values."""
    if not isinstance(entry, dict):
        raise ConfigError(f"{where} must be a mapping of hyperparameters, got {entry!r}")
    config = {key: coerce_numbers(value) for key, value in copy.deepcopy(entry).items()}
    for key in EXPRESSION_KEYS:
        if isinstance(config.get(key), str):
            config[key] = read_expression(config[key], key)
    return config


def read_expression(text: str, key: str) -> Any:
    """Zoo's Python expression ``text`` (``"dict(net_arch=[64], activation_fn=nn.Tanh)"``) as plain
    values, read with ``ast`` and never evaluated: ``nn.Tanh`` becomes the string "nn.Tanh"."""

    def value(node: ast.AST) -> Any:
        if isinstance(node, ast.Constant):
            return node.value
        if isinstance(node, (ast.List, ast.Tuple)):
            return [value(item) for item in node.elts]
        if isinstance(node, ast.Dict) and all(k is not None for k in node.keys):
            return {value(k): value(v) for k, v in zip(node.keys, node.values, strict=True) if k is not None}
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "dict" and not node.args:
            return {item.arg: value(item.value) for item in node.keywords}
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "nn":
            return f"nn.{node.attr}"
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            return -value(node.operand)
        raise ConfigError(f"{key}: {text!r} may hold only dict(...), numbers, strings, lists and nn.<Name>")

    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError:
        raise ConfigError(f"{key}: {text!r} is not a Python expression") from None
    return value(tree.body)


def coerce_numbers(value: Any) -> Any:
    """``value`` with every string that reads as a number (``1e-3``) made that number, recursively."""
    if isinstance(value, dict):
        return {key: coerce_numbers(item) for key, item in value.items()}
    if isinstance(value, list):
        return [coerce_numbers(item) for item in value]
    if isinstance(value, str):
        return read_value(value)
    return value


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


# -- writing files -------------------------------------------------------------------------------
def zoo_entry(config: dict[str, Any]) -> dict[str, Any]:
    """The Zoo-format part of ``config`` (what ``<algo>.yml`` holds for one env id): our own
    settings left out, dicts of expression keys written as Zoo's strings."""
    entry = {key: copy.deepcopy(value) for key, value in config.items() if key not in PROJECT_KEYS}
    for key in EXPRESSION_KEYS:
        if isinstance(entry.get(key), dict):
            entry[key] = expression(entry[key])
    return entry


def expression(value: Any) -> str:
    """The Python expression Zoo reads back as ``value`` (inverse of ``read_expression``)."""
    if isinstance(value, dict):
        return "dict(" + ", ".join(f"{key}={expression(item)}" for key, item in value.items()) + ")"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(expression(item) for item in value) + "]"
    if isinstance(value, str) and value.startswith("nn."):
        return value
    return repr(value)


def save_yaml(data: Any, path: str | Path) -> None:
    write_atomic(path, yaml.safe_dump(data, sort_keys=False))


def load_yaml(path: str | Path) -> Any:
    with open(path) as file:
        return yaml.safe_load(file)


# -- overrides and checks ------------------------------------------------------------------------
def known_keys(algo: str) -> list[str]:
    return sorted(set(ZOO_KEYS) | set(PROJECT_KEYS) | algorithms.constructor_keys(algo))


def parse_override(text: str) -> tuple[list[str], Any]:
    """``"a.b=value"`` as (["a", "b"], yaml.safe_load("value"))."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise ConfigError(f"an override must look like key=value (e.g. n_timesteps=100000), got {text!r}")
    return key.strip().split("."), read_value(value)


def apply_overrides(config: dict[str, Any], overrides: list[str] | None, algo: str = "ppo") -> dict[str, Any]:
    """A copy of ``config`` with each ``key=value`` override applied (dotted keys reach into dicts).
    Unknown top-level keys raise a ConfigError naming them, so a typo does not pass silently."""
    config = copy.deepcopy(config)
    for text in overrides or ():
        keys, value = parse_override(text)
        if keys[0] not in known_keys(algo):
            raise ConfigError(f"unknown hyperparameter {keys[0]!r} in {text!r} for {algo}; known: {known_keys(algo)}")
        node = config
        for key in keys[:-1]:
            child = node.get(key)
            if not isinstance(child, dict):
                child = node[key] = {}
            node = child
        node[keys[-1]] = value
    return config


def check_config(config: dict[str, Any], algo: str = "ppo") -> None:
    """A ConfigError naming the first key that is unknown, missing or out of range."""
    if not isinstance(config, dict):
        raise ConfigError(f"a configuration must be a mapping, got {config!r}")
    for key in config:
        if key not in known_keys(algo):
            raise ConfigError(f"unknown hyperparameter {key!r} for {algo}; known: {known_keys(algo)}")
    if not isinstance(config.get("policy"), str):
        raise ConfigError(f"policy must be given, e.g. policy: MlpPolicy (got {config.get('policy')!r})")
    for key in ("n_timesteps", "n_envs"):
        if not isinstance(config.get(key), int) or isinstance(config.get(key), bool) or config[key] < 1:
            raise ConfigError(f"{key} must be an integer >= 1, got {config.get(key)!r}")
    check_schema(config, algo)
    policy_kwargs = config.get("policy_kwargs", {})
    if not isinstance(policy_kwargs, dict):
        raise ConfigError(f"policy_kwargs must be a mapping, got {policy_kwargs!r}")
    activation = policy_kwargs.get("activation_fn", "nn.Tanh")
    if not (
        isinstance(activation, str)
        and activation.startswith("nn.")
        and isinstance(getattr(torch.nn, activation[3:], None), type)
    ):
        raise ConfigError(
            f"policy_kwargs.activation_fn must name a torch.nn activation (nn.Tanh, nn.ReLU, ...), got {activation!r}"
        )
    try:
        read_env_wrapper(config.get("env_wrapper"))
    except ValueError as error:
        raise ConfigError(str(error)) from None
    if config.get("noise_type") not in (None, "normal"):
        raise ConfigError(f"noise_type must be 'normal' (or absent), got {config['noise_type']!r}")
    for key in ("learning_rate", "clip_range"):
        if isinstance(config.get(key), str):
            schedule(key, config[key])


# -- the schema: every option's type and range, checked at once before anything is made -----------
class Rule:
    """What one configuration key accepts: an integer or a number in [low, high], a boolean, one of
    ``choices``, a ``lin_<number>`` schedule (``schedule=True``), a list of layer sizes, or a mapping
    (checked by ``mapping`` rules); ``allowed`` says it in words for the error message."""

    def __init__(
        self,
        kind: str,
        low: float | None = None,
        high: float | None = None,
        *,
        choices: tuple = (),
        schedule: bool = False,
        mapping: dict[str, Rule] | None = None,
        above: bool = False,
    ):
        self.kind, self.low, self.high, self.choices = kind, low, high, choices
        self.schedule, self.mapping, self.above = schedule, mapping or {}, above

    @property
    def allowed(self) -> str:
        if self.kind == "bool":
            return "true or false"
        if self.kind == "layers":
            return "a list of layer sizes >= 1 (e.g. [64, 64]), or dict(pi=[...], vf=[...])"
        if self.kind == "mapping":
            return f"a mapping of {sorted(self.mapping)}" if self.mapping else "a mapping"
        noun = "an integer" if self.kind == "int" else "a number"
        bounds = []
        if self.low is not None:
            bounds.append(f"{'>' if self.above else '>='} {self.low:g}")
        if self.high is not None:
            bounds.append(f"<= {self.high:g}")
        words = f"{noun} {' and '.join(bounds)}".strip()
        extra = [repr(choice) for choice in self.choices] + (["'lin_<number>'"] if self.schedule else [])
        return " or ".join([words, *extra])

    def ok(self, value: Any) -> bool:
        if value in self.choices and not isinstance(value, bool):
            return True
        if self.schedule and isinstance(value, str):
            prefix, _, start = value.partition("_")
            number = read_value(start)
            return (
                prefix == "lin"
                and isinstance(number, (int, float))
                and not isinstance(number, bool)
                and math.isfinite(number)
                and number > 0
            )
        if self.kind == "bool":
            return isinstance(value, bool)
        if self.kind == "layers":
            if isinstance(value, dict):
                return bool(value) and set(value) <= {"pi", "vf", "qf"} and all(map(layer_sizes, value.values()))
            return layer_sizes(value)
        if self.kind == "mapping":
            return isinstance(value, dict)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return False
        if self.kind == "int" and not isinstance(value, int):
            return False
        if not math.isfinite(value):
            return False
        if self.low is not None and (value <= self.low if self.above else value < self.low):
            return False
        return self.high is None or value <= self.high


def layer_sizes(value: Any) -> bool:
    return isinstance(value, list) and all(isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in value)


UNIT = (0.0, 1.0)
SCHEMA: dict[str, Rule] = {
    # RL Zoo's keys and ours
    "n_timesteps": Rule("int", 1),
    "n_envs": Rule("int", 1),
    "normalize": Rule(
        "bool",
        mapping={
            "norm_obs": Rule("bool"),
            "norm_reward": Rule("bool"),
            "clip_obs": Rule("float", 0, above=True),
            "clip_reward": Rule("float", 0, above=True),
            "gamma": Rule("float", *UNIT),
            "epsilon": Rule("float", 0, above=True),
        },
    ),
    "noise_std": Rule("float", 0),
    "vec_env_kwargs": Rule("mapping", mapping={"threads": Rule("int", 1, numba.config.NUMBA_NUM_THREADS)}),  # type: ignore[attr-defined]
    "torch_threads": Rule("int", 1),
    "eval_freq": Rule("int", 0),
    "eval_targets": Rule("int", 1),
    "checkpoint_freq": Rule("int", 0),
    # the algorithms' constructor arguments
    "learning_rate": Rule("float", 0, above=True, schedule=True),
    "n_steps": Rule("int", 1),
    "batch_size": Rule("int", 2),
    "n_epochs": Rule("int", 1),
    "gamma": Rule("float", *UNIT),
    "gae_lambda": Rule("float", *UNIT),
    "clip_range": Rule("float", 0, above=True, schedule=True),
    "ent_coef": Rule("float", 0, choices=("auto",)),
    "vf_coef": Rule("float", 0),
    "max_grad_norm": Rule("float", 0, above=True),
    "buffer_size": Rule("int", 1),
    "learning_starts": Rule("int", 0),
    "tau": Rule("float", *UNIT),
    "gradient_steps": Rule("int", 1, choices=(-1,)),
    "policy_delay": Rule("int", 1),
    "target_policy_noise": Rule("float", 0),
    "target_noise_clip": Rule("float", 0),
    "policy_kwargs": Rule(
        "mapping", mapping={"net_arch": Rule("layers"), "log_std_init": Rule("float"), "ortho_init": Rule("bool")}
    ),
}
"""Every key with a range. ``check_config`` applies it; the bad-option tests are generated from it."""


def check_value(key: str, value: Any, rule: Rule) -> None:
    if rule.mapping and isinstance(value, dict):
        for name, item in value.items():
            if name in rule.mapping:
                check_value(f"{key}.{name}", item, rule.mapping[name])
        return
    if not rule.ok(value):
        allowed = rule.allowed
        if rule.kind == "bool" and rule.mapping:
            allowed = f"true, false or a mapping of {sorted(rule.mapping)}"
        raise ConfigError(f"{key} must be {allowed}, got {value!r}")


def check_schema(config: dict[str, Any], algo: str = "ppo") -> None:
    """A ConfigError naming the first key (dotted into mappings) whose value is out of its range. An on-policy
    rollout (``n_steps`` x ``n_envs``) must hold a ``batch_size``; an off-policy ``n_steps`` is the n-step return's
    length, which the batch does not depend on."""
    for key, rule in SCHEMA.items():
        if key in config and not (config[key] is None and key in ("policy_kwargs", "vec_env_kwargs")):
            check_value(key, config[key], rule)
    on_policy = not algorithms.is_off_policy(algo)
    if on_policy and "batch_size" in config and "n_steps" in config and config.get("n_envs"):
        if config["batch_size"] > config["n_steps"] * config["n_envs"]:
            raise ConfigError(
                f"batch_size must be <= n_steps x n_envs = {config['n_steps'] * config['n_envs']} "
                f"(the rollout), got {config['batch_size']}"
            )


# -- constructor arguments -------------------------------------------------------------------------
def algorithm_kwargs(config: dict[str, Any], algo: str, action_size: int = 3) -> dict[str, Any]:
    """The constructor arguments of ``algo`` from ``config``: activation names made torch classes,
    ``lin_<x>`` made schedules, a ``train_freq`` list a tuple, ``noise_type`` an action noise."""
    keys = algorithms.constructor_keys(algo)
    kwargs = {key: copy.deepcopy(value) for key, value in config.items() if key in keys}
    policy_kwargs = kwargs.setdefault("policy_kwargs", {})
    if "activation_fn" in policy_kwargs:
        policy_kwargs["activation_fn"] = getattr(torch.nn, policy_kwargs["activation_fn"][3:])
    for key in ("learning_rate", "clip_range"):
        if isinstance(kwargs.get(key), str):
            kwargs[key] = schedule(key, kwargs[key])
    if isinstance(kwargs.get("train_freq"), list):
        kwargs["train_freq"] = tuple(kwargs["train_freq"])
    if isinstance(kwargs.get("replay_buffer_class"), str):  # Zoo names the class: HerReplayBuffer
        import stable_baselines3

        kwargs["replay_buffer_class"] = getattr(stable_baselines3, kwargs["replay_buffer_class"])
    if config.get("noise_type") == "normal":
        sigma = float(config["noise_std"]) * np.ones(action_size)
        kwargs["action_noise"] = NormalActionNoise(np.zeros(action_size), sigma)
    return kwargs


def schedule(name: str, text: str):
    """``"lin_X"`` (Zoo's notation): a value decaying linearly from X at the start of training to 0
    at its end (SB3 calls schedules with the fraction of training remaining, 1 -> 0, and below 0 in
    the last rollout when the budget is not a multiple of the rollout size)."""
    prefix, _, value = text.partition("_")
    start = read_value(value)
    if prefix != "lin" or not isinstance(start, (int, float)):
        raise ConfigError(f"{name} must be a number or 'lin_<number>' (linear decay to 0), got {text!r}")
    return LinearSchedule(float(start))


class LinearSchedule:
    """X * (fraction of training remaining); a class rather than a lambda, so saved models load anywhere."""

    def __init__(self, start: float):
        self.start = start

    def __call__(self, progress_remaining: float) -> float:
        return self.start * max(progress_remaining, 0.0)  # SB3 may overshoot the budget by part of a rollout

    def __repr__(self) -> str:
        return f"lin_{self.start:g}"
