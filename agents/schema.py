"""Every training option's type and range, derived from the signatures of what takes it, checked before anything runs.

A configuration (``agents.config``) holds RL Zoo's keys, our own settings and the constructor arguments of an SB3
algorithm, some of them mappings handed on to other constructors. The schema of each comes from the signature of
the callable that receives it:

- the algorithm's constructor (``PPO``, ``SAC``, ``TD3``): every argument a run does not set itself;
- ``policy_kwargs``: the constructor of the policy class that ``policy`` names (``MlpPolicy`` of that algorithm),
  and inside it ``optimizer_kwargs`` (of ``optimizer_class``) and ``features_extractor_kwargs`` (of
  ``features_extractor_class``);
- ``replay_buffer_kwargs`` / ``rollout_buffer_kwargs``: the buffer class's constructor, less what SB3 passes;
- ``normalize``: ``VecNormalize``'s constructor (or true / false).

A parameter's annotation gives the forms it accepts: ``bool`` is true or false and nothing else (a string
``"Flase"`` is refused, never taken as true), ``int`` an integer (not a bool, not 2.5), ``float`` a finite number,
``Callable[[float], float]`` RL Zoo's schedule ``lin_<number>``, ``type[C]`` the name of a subclass of C
(``nn.ReLU``, ``HerReplayBuffer``), an ``Enum`` or ``Literal`` its values, ``X | None`` also null. What a type
cannot say (the bounds) is added by name in ``RANGES``; every number an algorithm's constructor takes has an entry
there (a test holds it to that), so a new SB3 argument gets its bounds decided, not forgotten.
"""

from __future__ import annotations

import collections.abc
import enum
import functools
import inspect
import math
import types
import typing
from dataclasses import dataclass, field
from typing import Any

from agents import algorithms

MAX_NUM_ENVS = 2**20  # box_toss_env.envs.box_toss_vector.MAX_NUM_ENVS (not imported: it loads the engine)


class SchemaError(ValueError):
    """A value outside its rule; the message names the key, what is allowed and the value."""


@dataclass(frozen=True)
class Bounds:
    """What a type does not say: a number's bounds (``above``: low itself excluded), extra accepted values
    (``choices``, e.g. -1 for "as many as"), strings with a number after a prefix (``"auto_0.1"``), and the keys
    a mapping of lists may have."""

    low: float | None = None
    high: float | None = None
    above: bool = False
    choices: tuple = ()
    prefixes: tuple[str, ...] = ()
    keys: tuple[str, ...] = ()


UNBOUNDED = Bounds()
UNIT = Bounds(0.0, 1.0)
POSITIVE = Bounds(0.0, above=True)
AT_LEAST_0, AT_LEAST_1 = Bounds(0), Bounds(1)

RANGES: dict[str, Bounds] = {
    # RL Zoo's keys and ours
    "n_timesteps": Bounds(1, 2**63 - 1),  # SB3 counts timesteps in numpy's int64
    "n_envs": Bounds(1, MAX_NUM_ENVS),
    "noise_std": AT_LEAST_0,
    "torch_threads": AT_LEAST_1,
    "eval_freq": AT_LEAST_0,
    "eval_targets": AT_LEAST_1,
    "checkpoint_freq": AT_LEAST_0,
    # the algorithms' constructors
    "learning_rate": POSITIVE,
    "n_steps": AT_LEAST_1,
    "batch_size": AT_LEAST_1,
    "n_epochs": AT_LEAST_1,
    "gamma": UNIT,
    "gae_lambda": UNIT,
    "clip_range": POSITIVE,
    "clip_range_vf": POSITIVE,
    "ent_coef": Bounds(0, choices=("auto",), prefixes=("auto_",)),
    "target_entropy": Bounds(choices=("auto",)),
    "vf_coef": AT_LEAST_0,
    "max_grad_norm": POSITIVE,
    "sde_sample_freq": Bounds(-1),
    "target_kl": POSITIVE,
    "stats_window_size": AT_LEAST_1,
    "buffer_size": AT_LEAST_1,
    "learning_starts": AT_LEAST_0,
    "tau": UNIT,
    "train_freq": Bounds(1, choices=("step", "episode")),
    "gradient_steps": Bounds(1, choices=(-1,)),
    "target_update_interval": AT_LEAST_1,
    "policy_delay": AT_LEAST_1,
    "target_policy_noise": AT_LEAST_0,
    "target_noise_clip": AT_LEAST_0,
    # the policies' constructors
    "net_arch": Bounds(1, keys=("pi", "vf", "qf")),
    "log_std_init": UNBOUNDED,
    "clip_mean": AT_LEAST_0,  # 0: the mean is not clipped (SB3 clips it only for clip_mean > 0)
    "n_critics": AT_LEAST_1,
    # the buffers', the optimiser's and VecNormalize's
    "n_sampled_goal": AT_LEAST_1,
    "lr": POSITIVE,
    "betas": Bounds(0.0, 1.0),
    "eps": POSITIVE,
    "epsilon": POSITIVE,
    "weight_decay": AT_LEAST_0,
    "clip_obs": POSITIVE,
    "clip_reward": POSITIVE,
    "features_dim": AT_LEAST_1,
}
"""Bounds by parameter name, wherever that name appears (``gamma`` of PPO and of VecNormalize alike)."""
ALGORITHM_RANGES = {("ppo", "batch_size"): Bounds(2)}  # PPO normalises advantages over a minibatch: 2 at least

# what SB3 (or the run) passes itself to the constructors a mapping is handed to
SUPPLIED = {
    "policy_kwargs": {"observation_space", "action_space", "lr_schedule", "use_sde"},  # use_sde: the algorithm's
    "replay_buffer_kwargs": {"buffer_size", "observation_space", "action_space", "env", "device", "n_envs"}
    | {"optimize_memory_usage"},
    "rollout_buffer_kwargs": {"buffer_size", "observation_space", "action_space", "device", "gae_lambda", "gamma"}
    | {"n_envs"},
    "optimizer_kwargs": {"params", "lr"},
    "features_extractor_kwargs": {"observation_space"},
    "normalize": {"venv"},
}
# class names the configuration may give, looked up in these modules (and torch's as nn.<Name>, th.optim.<Name>)
CLASS_MODULES = ("stable_baselines3", "stable_baselines3.common.buffers", "stable_baselines3.common.torch_layers")


@dataclass
class Rule:
    """The values one key accepts: ``forms`` among none, bool, int, float, str, schedule, class, mapping and
    sequence; ``bounds`` for numbers and strings; ``base`` for a class; ``items`` for a sequence (one rule per
    position, or one for every item); ``keys`` for a mapping whose keys are checked (``open``: others pass)."""

    forms: set[str]
    bounds: Bounds = UNBOUNDED
    base: type | None = None
    items: list[Rule] = field(default_factory=list)
    length: int | None = None
    keys: dict[str, Rule] | None = None
    open: bool = False
    values: Rule | None = None  # a mapping's values, when its keys are free (dict[str, list[int]])

    @property
    def allowed(self) -> str:
        return " or ".join(part for part in _allowed_parts(self) if part)

    def __repr__(self) -> str:
        return f"Rule({self.allowed})"


def _allowed_parts(rule: Rule) -> list[str]:
    b = rule.bounds
    parts = []
    for form in ("int", "float"):
        if form in rule.forms:
            noun = "an integer" if form == "int" else "a number"
            limits = [f"{'>' if b.above else '>='} {number(b.low)}"] if b.low is not None else []
            limits += [f"<= {number(b.high)}"] if b.high is not None else []
            parts.append(f"{noun} {' and '.join(limits)}".strip())
            break
    if "bool" in rule.forms:
        parts.append("true or false")
    text = "str" in rule.forms
    parts += [repr(choice) for choice in b.choices if text or not isinstance(choice, str)]
    parts += [f"'{prefix}<number>'" for prefix in b.prefixes if text]
    if "schedule" in rule.forms:
        parts.append("'lin_<number>' (linear decay to 0)")
    if "str" in rule.forms and not b.choices and not b.prefixes:
        parts.append("a string")
    if "class" in rule.forms and rule.base is not None:
        parts.append(
            f"the name of a {rule.base.__module__}.{rule.base.__qualname__} class ({class_examples(rule.base)})"
        )
    if "sequence" in rule.forms:
        if rule.length:
            parts.append(f"a list of {rule.length}: " + ", ".join(f"[{item.allowed}]" for item in rule.items))
        else:
            parts.append(f"a list of items each {rule.items[0].allowed}" if rule.items else "a list")
    if "mapping" in rule.forms:
        parts.append(_mapping_text(rule))
    if "none" in rule.forms:
        parts.append("null")
    return parts


def number(value: float) -> str:
    """A bound as the messages write it: 1048576, 0.5, 1e-08."""
    return str(int(value)) if float(value).is_integer() else f"{value:g}"


def _mapping_text(rule: Rule) -> str:
    if rule.values is not None:
        keys = f" of {'/'.join(rule.bounds.keys)}" if rule.bounds.keys else ""
        low = rule.values.items[0].bounds.low if rule.values.items else None
        return f"a mapping{keys} to lists of integers" + (f" >= {number(low)}" if low is not None else "")
    return "a mapping" + (f" of {sorted(rule.keys)}" if rule.keys and len(rule.keys) <= 12 else "")


# -- rules from annotations --------------------------------------------------------------------------
def rule_for(annotation: Any, default: Any, name: str) -> Rule | None:
    """The rule of a parameter ``name`` annotated ``annotation`` (its default's type if it has none), with
    ``RANGES[name]``; None if no form of it can be written in a configuration (a tensor, an env)."""
    if annotation is inspect.Parameter.empty:
        annotation = type(default) if default not in (None, inspect.Parameter.empty) else Any
    rule = Rule(set(), RANGES.get(name, UNBOUNDED))
    for part in _union_parts(annotation):
        _add_form(rule, part, name)
    if default is None:
        rule.forms.add("none")
    return rule if rule.forms - {"none"} else None


def _union_parts(annotation: Any) -> tuple:
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return typing.get_args(annotation)
    return (annotation,)


def _add_form(rule: Rule, part: Any, name: str) -> None:
    origin, args = typing.get_origin(part), typing.get_args(part)
    simple = {type(None): "none", bool: "bool", int: "int", float: "float", str: "str"}
    if part in simple:
        rule.forms.add(simple[part])
    elif part is Any:
        rule.forms |= {"bool", "float", "str", "sequence", "mapping"}
    elif origin is collections.abc.Callable:
        rule.forms.add("schedule")
    elif origin is typing.Literal or (isinstance(part, type) and issubclass(part, enum.Enum)):
        # a Literal's values; an Enum's values if strings, else its names as SB3 reads them ("future")
        values = args if origin is typing.Literal else tuple(enum_names(part))
        rule.forms.add("str")
        rule.bounds = Bounds(choices=tuple(dict.fromkeys((*rule.bounds.choices, *values))))
    elif origin is type and args and isinstance(args[0], type):
        rule.forms.add("class")
        rule.base = args[0]
    elif origin in (list, tuple, collections.abc.Sequence):
        _add_sequence(rule, origin, args, name)
    elif origin is dict:
        rule.forms.add("mapping")
        value_args = args[1] if len(args) == 2 else Any
        if value_args is not Any:  # dict[str, list[int]]: net_arch's dict(pi=[...], vf=[...])
            rule.values = rule_for(value_args, inspect.Parameter.empty, name)
        else:
            rule.open = True


def enum_names(cls: type[enum.Enum]) -> list[str]:
    """How a configuration names the members of ``cls``: their values if strings, else their names in lower case."""
    return [member.value if isinstance(member.value, str) else member.name.lower() for member in cls]


def _add_sequence(rule: Rule, origin: Any, args: tuple, name: str) -> None:
    if origin is tuple and args and args[-1] is not Ellipsis:
        items = [rule_for(arg, inspect.Parameter.empty, name) for arg in args]
        if any(item is None for item in items):
            return
        rule.items, rule.length = [item for item in items if item is not None], len(args)
    elif args:
        item = rule_for(args[0], inspect.Parameter.empty, name)
        if item is None:
            return
        rule.items = [item]
    rule.forms.add("sequence")


def signature_rules(target: Any, supplied: set[str]) -> tuple[dict[str, Rule], bool]:
    """The rules of the keyword arguments of ``target`` (a class or a function) that a configuration may set:
    every parameter but ``self``, those in ``supplied`` and those no configuration can write; and whether
    ``target`` takes ``**kwargs`` too (then other keys pass). Read once per target (the rules are not changed)."""
    return _signature_rules(target, frozenset(supplied))


@functools.cache
def _signature_rules(target: Any, supplied: frozenset[str]) -> tuple[dict[str, Rule], bool]:
    function = target.__init__ if isinstance(target, type) else target  # type: ignore[misc]  # the class's own
    rules, open_ = {}, False
    for name, parameter in inspect.signature(function).parameters.items():
        if parameter.kind is inspect.Parameter.VAR_KEYWORD:
            open_ = True
            continue
        if name == "self" or name in supplied or parameter.kind is inspect.Parameter.VAR_POSITIONAL:
            continue
        rule = rule_for(parameter.annotation, parameter.default, name)
        if rule is not None:
            rules[name] = rule
    return rules, open_


# -- classes named in a configuration ----------------------------------------------------------------
def resolve_class(text: Any, base: type) -> type | None:
    """The subclass of ``base`` that ``text`` names (``nn.ReLU``, ``th.optim.Adam``, ``HerReplayBuffer``), or None."""
    if not isinstance(text, str) or not text:
        return None
    import importlib

    import torch

    head, _, rest = text.partition(".")
    found: Any = None
    if head in ("nn", "th", "torch") and rest:
        found = torch.nn if head == "nn" else torch
        for part in rest.split("."):
            found = getattr(found, part, None)
    elif "." not in text:
        for module in CLASS_MODULES:
            found = found or getattr(importlib.import_module(module), text, None)
    return found if isinstance(found, type) and issubclass(found, base) else None


def class_examples(base: type) -> str:
    """A few names ``resolve_class`` accepts for ``base``, for error messages."""
    import torch

    examples = {torch.nn.Module: "e.g. nn.Tanh, nn.ReLU", torch.optim.Optimizer: "e.g. th.optim.Adam"}
    for known, text in examples.items():
        if base is known:
            return text
    import importlib

    names = sorted(
        name
        for module in CLASS_MODULES
        for name, value in vars(importlib.import_module(module)).items()
        if isinstance(value, type) and issubclass(value, base)
    )
    return "one of " + ", ".join(dict.fromkeys(names))


# -- the rules of a configuration ---------------------------------------------------------------------
def zoo_rules() -> dict[str, Rule]:
    """RL Zoo's keys and our own settings (agents.config.ZOO_KEYS, PROJECT_KEYS)."""
    import numba
    from stable_baselines3.common.vec_env import VecNormalize

    threads = Bounds(1, numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]  # numba sets it at import  # the engine's threads: at most the cores available
    normalize = Rule({"bool", "mapping"})
    normalize.keys, normalize.open = signature_rules(VecNormalize, SUPPLIED["normalize"])
    integer = {"int"}
    return {
        "n_timesteps": Rule(integer, RANGES["n_timesteps"]),
        "n_envs": Rule(integer, RANGES["n_envs"]),
        "normalize": normalize,
        "env_kwargs": Rule({"mapping", "none"}, open=True),  # the env's own checks (agents.train.resolve)
        "noise_type": Rule({"str", "none"}, Bounds(choices=("normal",))),
        "noise_std": Rule({"float"}, RANGES["noise_std"]),
        "env_wrapper": Rule({"str", "mapping", "none"}, open=True),  # agents.envs.read_env_wrapper
        "vec_env_kwargs": Rule({"mapping", "none"}, keys={"threads": Rule(integer, threads)}),
        "torch_threads": Rule(integer, RANGES["torch_threads"]),
        "eval_freq": Rule(integer, RANGES["eval_freq"]),
        "eval_targets": Rule(integer, RANGES["eval_targets"]),
        "checkpoint_freq": Rule(integer, RANGES["checkpoint_freq"]),
        "initial_mean": Rule(
            {"sequence", "str", "mapping", "none"}, open=True
        ),  # agents.recipe_options.check_initial_mean
        "curriculum": Rule({"sequence", "none"}),  # agents.recipe_options.read_stages
    }


@functools.cache
def algorithm_rules(algo: str) -> dict[str, Rule]:
    """Every key a configuration of ``algo`` may hold: ``zoo_rules`` and the constructor's arguments (read once:
    the rules are not changed)."""
    rules = zoo_rules()
    for name, parameter in algorithms.constructor_parameters(algo).items():
        rule = rule_for(parameter.annotation, parameter.default, name)
        if rule is None:
            continue
        rule.bounds = ALGORITHM_RANGES.get((algo, name), rule.bounds)
        if name == "policy":  # a name of the algorithm's policy aliases
            rule.forms, rule.base = {"str"}, None
            rule.bounds = Bounds(choices=tuple(algorithms.algorithm_class(algo).policy_aliases))
        rules[name] = rule
    return rules


@dataclass(frozen=True)
class Context:
    """What the rules of a mapping depend on: the algorithm, and the policy alias the configuration names."""

    algo: str
    policy: str = "MlpPolicy"


def kwargs_target(name: str, context: Context, parent: dict[str, Any]) -> Any:
    """The callable the mapping ``name`` is handed to (None if unknown), given the mapping ``parent`` holding it:
    the configuration (``policy_kwargs``, the buffers' kwargs) or ``policy_kwargs`` (the optimiser's and the
    features extractor's kwargs, beside their ``*_class``)."""
    policy = algorithms.algorithm_class(context.algo).policy_aliases.get(context.policy)
    if name == "policy_kwargs":
        return policy
    class_key = name.replace("_kwargs", "_class")
    named = parent.get(class_key)
    if name in ("replay_buffer_kwargs", "rollout_buffer_kwargs"):
        from stable_baselines3.common import buffers

        kind = "Replay" if name == "replay_buffer_kwargs" else "Rollout"
        base = getattr(buffers, f"{kind}Buffer")
        if named:
            return resolve_class(named, base)
        return getattr(buffers, f"Dict{kind}Buffer") if context.policy == "MultiInputPolicy" else base
    if name in ("optimizer_kwargs", "features_extractor_kwargs") and policy is not None:
        if named:
            return resolve_class(named, object)
        return inspect.signature(policy.__init__).parameters[class_key].default
    return None


def check_value(key: str, value: Any, rule: Rule, context: Context, parent: dict[str, Any]) -> None:
    """A SchemaError naming ``key`` (dotted into mappings, ``[i]`` into lists) if ``value`` breaks ``rule``;
    ``parent`` is the mapping that holds the value."""
    if isinstance(value, dict) and "mapping" in rule.forms:
        check_mapping(key, value, rule, context, parent)
        return
    if isinstance(value, (list, tuple)) and "sequence" in rule.forms:
        if rule.length is not None and len(value) != rule.length:
            raise SchemaError(f"{key} must be {rule.allowed}, got {value!r}")
        for i, item in enumerate(value):
            item_rule = rule.items[i] if rule.length is not None else (rule.items[0] if rule.items else None)
            if item_rule is not None:
                check_value(f"{key}[{i}]", item, item_rule, context, parent)
        return
    if not accepts(rule, value):
        raise SchemaError(f"{key} must be {rule.allowed}, got {value!r}")


def check_mapping(key: str, value: dict[str, Any], rule: Rule, context: Context, parent: dict[str, Any]) -> None:
    """Each key of a mapping (the keys of the signature it is handed to, from ``kwargs_target``) and its value."""
    if rule.values is not None:  # net_arch's dict(pi=[...], vf=[...])
        for sub, item in value.items():
            if rule.bounds.keys and sub not in rule.bounds.keys:
                raise SchemaError(f"{key} may have the keys {list(rule.bounds.keys)}, got {sub!r}")
            check_value(f"{key}.{sub}", item, rule.values, context, value)
        return
    keys, open_ = rule.keys, rule.open
    name = key.rsplit(".", 1)[-1]
    if name in SUPPLIED and name != "normalize":
        target = kwargs_target(name, context, parent)
        if target is None:
            return
        keys, open_ = signature_rules(target, SUPPLIED[name])
    if keys is None:
        return
    for sub, item in value.items():
        if sub in keys:
            check_value(f"{key}.{sub}", item, keys[sub], context, value)
        elif not open_:
            raise SchemaError(f"{key} has no key {sub!r}; it takes {sorted(keys)}")


def check_schema(config: dict[str, Any], algo: str) -> None:
    """A SchemaError naming the first key of ``config`` that ``algorithm_rules(algo)`` refuses (unknown keys
    included), dotted into mappings."""
    rules = algorithm_rules(algo)
    policy = config.get("policy")
    context = Context(algo, policy if isinstance(policy, str) else "MlpPolicy")
    for key, value in config.items():
        if key not in rules:
            raise SchemaError(f"unknown hyperparameter {key!r} for {algo}; known: {sorted(rules)}")
        check_value(key, value, rules[key], context, config)


def accepts(rule: Rule, value: Any) -> bool:
    """Whether a value that is not a mapping or a list fits ``rule``."""
    b, forms = rule.bounds, rule.forms
    if value is None:
        return "none" in forms
    if isinstance(value, bool):
        return "bool" in forms
    if isinstance(value, (int, float)):
        if value in b.choices:
            return True
        if "int" not in forms and "float" not in forms:
            return False
        if "float" not in forms and not isinstance(value, int):
            return False
        return in_bounds(value, b)
    if isinstance(value, str):
        if "str" in forms and value in b.choices:
            return True
        if "schedule" in forms and value.startswith("lin_"):
            return positive_number(value[4:])
        if "str" in forms and any(value.startswith(p) and positive_number(value[len(p) :]) for p in b.prefixes):
            return True
        if "class" in forms and rule.base is not None:
            return resolve_class(value, rule.base) is not None
        return "str" in forms and not b.choices and not b.prefixes
    return False


def in_bounds(value: float, b: Bounds) -> bool:
    if not math.isfinite(value):
        return False
    if b.low is not None and (value <= b.low if b.above else value < b.low):
        return False
    return b.high is None or value <= b.high


def positive_number(text: str) -> bool:
    try:
        number = float(text)
    except ValueError:
        return False
    return math.isfinite(number) and number > 0
