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
the value is read as YAML (``read_value``: only true and false are booleans).
"""

from __future__ import annotations

import ast
import copy
import re
from pathlib import Path
from typing import Any

import yaml

from agents import algorithms, schema
from agents.command_line import InputError, OneLineParser  # noqa: F401  (OneLineParser: re-exported)
from agents.env_wrappers import read_env_wrapper
from agents.recipe_options import check_initial_mean, read_stages

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
    "initial_mean": "where the untrained policy throws: [a0, a1, a2], 'ballistic' or {ballistic: [c0, c1, c2]} "
    "(agents.initial_mean)",
    "curriculum": "stages of env kwargs while training: [{until: throws, env_kwargs: {...}}, ...] (agents.curriculum)",
}
EXPRESSION_KEYS = ("policy_kwargs", "normalize", "replay_buffer_kwargs")  # Zoo evaluates these strings


class ConfigError(InputError):
    """A configuration that cannot run; the message names the key and what is allowed."""


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
    for path in project_paths(directory):
        config.update(project_settings(algo, env_id, path))
    return config


def project_paths(directory: str | Path) -> list[Path]:
    """The ``project.yml`` files of ``directory``'s settings, applied in this order: its parent's where the parent
    has one (``raw/`` shares the recipes' settings), then its own where it has one."""
    own, parent = Path(directory) / PROJECT_FILE, Path(directory).parent / PROJECT_FILE
    paths = [path for path in (parent, own) if path.exists()]
    return paths or [own]


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
        if isinstance(node, ast.Attribute) and (name := dotted_name(node)) and name.split(".")[0] in CLASS_ROOTS:
            return name
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            return -value(node.operand)
        raise ConfigError(
            f"{key}: {text!r} may hold only dict(...), numbers, strings, lists and class names (nn.<Name>, th.<...>)"
        )

    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError:
        raise ConfigError(f"{key}: {text!r} is not a Python expression") from None
    return value(tree.body)


CLASS_ROOTS = ("nn", "th", "torch")  # Zoo's expressions name torch classes as nn.Tanh, th.optim.Adam


def dotted_name(node: ast.AST) -> str | None:
    """``a.b.C`` of an attribute chain on a name, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    return ".".join([node.id, *reversed(parts)]) if isinstance(node, ast.Name) else None


def coerce_numbers(value: Any) -> Any:
    """``value`` with every string that reads as a number (``1e-3``) made that number, recursively."""
    if isinstance(value, dict):
        return {key: coerce_numbers(item) for key, item in value.items()}
    if isinstance(value, list):
        return [coerce_numbers(item) for item in value]
    if isinstance(value, str):
        return as_number(value)
    return value


class StrictBooleans(yaml.SafeLoader):
    """YAML's safe loader with YAML 1.2's booleans: only true and false (any case) are booleans; YAML 1.1's
    ``yes``, ``no``, ``on``, ``off`` stay strings, which a boolean option refuses, rather than a typo's neighbour
    being taken for a boolean."""


StrictBooleans.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != "tag:yaml.org,2002:bool"]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
StrictBooleans.add_implicit_resolver(
    "tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)


def load_strict(text: str) -> Any:
    """``text`` read as YAML with ``StrictBooleans``."""
    return yaml.load(text, Loader=StrictBooleans)  # noqa: S506  (a SafeLoader)


def read_value(text: str) -> Any:
    """``text`` read as YAML (``load_strict``: only true and false are booleans), except that numbers YAML 1.1
    reads as strings (``1e-3``, ``3E5``) are numbers. An empty value is an error, not null."""
    if not text.strip():
        raise ConfigError("an empty value: write null for none, '' for an empty string")
    try:
        value = load_strict(text)
    except yaml.YAMLError as error:
        raise ConfigError(f"{text!r} is not a YAML value: {one_line(str(error))}") from None
    return as_number(value) if isinstance(value, str) else value


def as_number(text: str) -> Any:
    """``text`` as a number if it reads as one (``1e-3``, ``3E5``, which YAML 1.1 leaves strings), else ``text``."""
    try:
        number = float(text)
    except ValueError:
        return text
    return int(number) if number.is_integer() and "." not in text and "e-" not in text.lower() else number


def one_line(text: str) -> str:
    """``text`` with its lines joined (YAML's and pickle's messages span several)."""
    return " ".join(line.strip() for line in text.splitlines() if line.strip())


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
    if isinstance(value, str) and value.split(".")[0] in CLASS_ROOTS and "." in value:
        return value  # a class name: nn.Tanh, th.optim.Adam
    return repr(value)


def save_yaml(data: Any, path: str | Path) -> None:
    from box_toss_env.files import write_atomic

    write_atomic(path, yaml.safe_dump(data, sort_keys=False))


def load_yaml(path: str | Path) -> Any:
    with open(path) as file:
        return yaml.safe_load(file)


# -- overrides and checks ------------------------------------------------------------------------
def known_keys(algo: str) -> list[str]:
    return sorted(schema.algorithm_rules(algo))


def parse_override(text: str) -> tuple[list[str], Any]:
    """``"a.b=value"`` as (["a", "b"], the value read as YAML: ``read_value``)."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip() or any(not part.strip() for part in key.split(".")):
        raise ConfigError(f"an override must look like key=value (e.g. n_timesteps=100000), got {text!r}")
    try:
        return [part.strip() for part in key.split(".")], read_value(value)
    except ConfigError as error:
        raise ConfigError(f"{key.strip()}: {error}") from None


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
    """A ConfigError naming the first key that is unknown, missing or out of range (``agents.schema``: the
    types and ranges from the signatures of the algorithm, its policy, its buffers and VecNormalize), then
    the rules that tie keys together."""
    if not isinstance(config, dict):
        raise ConfigError(f"a configuration must be a mapping, got {config!r}")
    try:
        schema.check_schema(config, algo)
    except schema.SchemaError as error:
        raise ConfigError(str(error)) from None
    if not isinstance(config.get("policy"), str):
        raise ConfigError(f"policy must be given, e.g. policy: MlpPolicy (got {config.get('policy')!r})")
    for key in ("n_timesteps", "n_envs"):
        if key not in config:
            raise ConfigError(f"{key} must be given, an integer >= 1")
    try:
        read_env_wrapper(config.get("env_wrapper"))
    except ValueError as error:
        raise ConfigError(str(error)) from None
    try:
        check_initial_mean(config)
        read_stages(config.get("curriculum"), config.get("n_timesteps"))
    except ValueError as error:
        raise ConfigError(str(error)) from None
    if config.get("noise_std") is not None and config.get("noise_type") is None:
        raise ConfigError("noise_std needs noise_type: normal (the action noise it is the size of)")
    if config.get("noise_type") == "normal" and config.get("noise_std") is None:
        raise ConfigError("noise_type normal needs noise_std, a number >= 0 (in action units)")
    on_policy = not algorithms.is_off_policy(algo)
    if on_policy and "batch_size" in config and "n_steps" in config:
        rollout = config["n_steps"] * config["n_envs"]
        if config["batch_size"] > rollout:
            raise ConfigError(
                f"batch_size must be <= n_steps x n_envs = {rollout} (the rollout), got {config['batch_size']}"
            )
    check_policy_parts(config, algo)


OBSERVATION_PARTS = {
    # policy: (the observations it reads, the classes its buffers and features extractor must be)
    "MlpPolicy": ("flat (Box)", {"ReplayBuffer", "RolloutBuffer", "FlattenExtractor"}),
    "MultiInputPolicy": ("Dict", {"DictReplayBuffer", "DictRolloutBuffer", "HerReplayBuffer", "CombinedExtractor"}),
    "CnnPolicy": ("image", {"ReplayBuffer", "RolloutBuffer", "NatureCNN"}),
}
"""Which buffers and features extractors each policy's observations take (SB3 asserts or fails on the others,
after the run folder exists); ``CnnPolicy`` reads the pixel ids' images (``BoxToss-*-Pixels-v0``)."""


def check_policy_parts(config: dict[str, Any], algo: str) -> None:
    """A ConfigError if the policy, the buffer classes, the features extractor or ``net_arch``'s keys do not fit
    together: SB3 checks them only when it builds the model, with an assertion or an AttributeError."""
    policy = config["policy"]
    if policy not in OBSERVATION_PARTS:
        raise ConfigError(
            f"policy must be one of {sorted(OBSERVATION_PARTS)} (BoxToss observations are flat, a Dict or "
            f"images), got {policy!r}"
        )
    observations, fitting = OBSERVATION_PARTS[policy]
    policy_kwargs = config.get("policy_kwargs") or {}
    named = [(key, config.get(key)) for key in ("replay_buffer_class", "rollout_buffer_class")]
    named.append(("policy_kwargs.features_extractor_class", policy_kwargs.get("features_extractor_class")))
    for key, value in named:
        known = {name for parts in OBSERVATION_PARTS.values() for name in parts[1]} | {"NatureCNN"}
        if value in known and value not in fitting:
            raise ConfigError(f"{key} {value} does not take {policy}'s {observations} observations")
    if config.get("replay_buffer_class") == "HerReplayBuffer" and policy != "MultiInputPolicy":
        raise ConfigError(
            "replay_buffer_class HerReplayBuffer needs policy: MultiInputPolicy (a goal env's Dict observations)"
        )
    net_arch = policy_kwargs.get("net_arch")
    if isinstance(net_arch, dict):
        keys = ("pi", "qf") if algorithms.is_off_policy(algo) else ("pi", "vf")
        if set(net_arch) - set(keys) or (algorithms.is_off_policy(algo) and set(net_arch) != set(keys)):
            need = "both" if algorithms.is_off_policy(algo) else "only"
            raise ConfigError(
                f"policy_kwargs.net_arch of {algo} takes {need} the keys {list(keys)} (actor, critic), "
                f"got {sorted(net_arch)}"
            )


# -- constructor arguments -------------------------------------------------------------------------
def algorithm_kwargs(config: dict[str, Any], algo: str, action_size: int = 3) -> dict[str, Any]:
    """The constructor arguments of ``algo`` from ``config``: activation names made torch classes,
    ``lin_<x>`` made schedules, a ``train_freq`` list a tuple, ``noise_type`` an action noise."""
    import numpy as np
    from stable_baselines3.common.noise import NormalActionNoise

    rules = schema.algorithm_rules(algo)
    kwargs = {key: copy.deepcopy(value) for key, value in config.items() if key in algorithms.constructor_keys(algo)}
    kwargs["policy_kwargs"] = with_classes(kwargs.get("policy_kwargs") or {})
    for key, value in list(kwargs.items()):
        if isinstance(value, str) and "schedule" in rules[key].forms and value.startswith("lin_"):
            kwargs[key] = schedule(key, value)
        elif isinstance(value, str) and "class" in rules[key].forms and (base := rules[key].base) is not None:
            kwargs[key] = schema.resolve_class(value, base)  # Zoo names the class: HerReplayBuffer
    if isinstance(kwargs.get("train_freq"), list):
        kwargs["train_freq"] = tuple(kwargs["train_freq"])
    if config.get("noise_type") == "normal":
        sigma = float(config["noise_std"]) * np.ones(action_size)
        kwargs["action_noise"] = NormalActionNoise(np.zeros(action_size), sigma)
    return kwargs


def with_classes(policy_kwargs: dict[str, Any]) -> dict[str, Any]:
    """``policy_kwargs`` with the classes it names (``nn.Tanh``, ``th.optim.Adam``: ``*_fn`` and ``*_class``)
    made classes; a name that ``check_config`` has refused is left as it is."""
    resolved = dict(policy_kwargs)
    for key, value in policy_kwargs.items():
        if isinstance(value, str) and (key.endswith("_fn") or key.endswith("_class")):
            resolved[key] = schema.resolve_class(value, object) or value
    return resolved


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
