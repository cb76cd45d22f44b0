"""The hyperparameter search spaces of ``agents.tune``, declared in ``agents/search_space.yml``.

A space maps hyperparameter keys (dotted for dicts: ``policy_kwargs.log_std_init``) to a
``Dimension``: an Optuna distribution and how a sampled value is written as an override of
``agents.config`` (``"lin_{}"`` makes a linear-decay schedule of the number). A trial's
configuration is the algorithm's hyperparameter file with the sampled overrides applied, checked
like any configuration, so a sweep trains exactly what ``agents.train --set ...`` would.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import optuna.distributions as distributions

from agents import config as configuration

SEARCH_SPACE = Path(__file__).parent / "search_space.yml"


@dataclass(frozen=True)
class Dimension:
    """One searched hyperparameter: its distribution, and ``write``, the override text of a
    sampled value (``"{}"``: the value itself; ``"lin_{}"``: a linear decay starting there)."""

    distribution: distributions.BaseDistribution
    write: str = "{}"

    def override(self, key: str, value: Any) -> str:
        """``key=<written value>``; floats rounded to 3 significant digits (what the trial trains)."""
        if isinstance(value, float):
            value = f"{value:.3g}"
            value += "" if any(c in value for c in ".en") else ".0"  # stays a float: 0.0, not 0
        return f"{key}={self.write.format(value)}"

    def point(self, value: Any) -> Any:
        """The sampled value that writes as ``value`` (a configuration's), or None if none does."""
        if isinstance(self.distribution, distributions.CategoricalDistribution):
            for choice in self.distribution.choices:
                if configuration.read_value(self.write.format(choice)) == value:
                    return choice
            return None
        prefix, _, suffix = self.write.partition("{}")
        if self.write != "{}":
            if not (isinstance(value, str) and value.startswith(prefix) and value.endswith(suffix)):
                return None
            value = configuration.read_value(value[len(prefix) : len(value) - len(suffix)])
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return None
        if isinstance(self.distribution, distributions.IntDistribution) and not float(value).is_integer():
            return None
        value = int(value) if isinstance(self.distribution, distributions.IntDistribution) else float(value)
        numeric = cast(distributions.FloatDistribution | distributions.IntDistribution, self.distribution)
        return value if numeric.low <= value <= numeric.high else None


def load_space(algo: str, path: str | Path = SEARCH_SPACE) -> dict[str, Dimension]:
    """The declared search space of ``algo`` in ``path``; a ConfigError names a bad entry."""
    table = configuration.read_mapping(Path(path))
    if not isinstance(table.get(algo), dict) or not table[algo]:
        raise configuration.ConfigError(f"{path} declares no search space for {algo!r}; it has {sorted(table)}")
    return read_space(table[algo], algo, f"{path}: {algo}")


def read_space(entries: dict[str, Any], algo: str, where: str) -> dict[str, Dimension]:
    """A space from its declaration (one algorithm's mapping of ``search_space.yml``)."""
    space = {}
    for key, entry in entries.items():
        if key.split(".")[0] not in configuration.known_keys(algo):
            raise configuration.ConfigError(
                f"{where}.{key}: {key.split('.')[0]!r} is not a hyperparameter "
                f"of {algo}; known: {configuration.known_keys(algo)}"
            )
        space[key] = read_dimension(entry, f"{where}.{key}")
    return space


def read_dimension(entry: Any, where: str) -> Dimension:
    """``{low, high[, log, step]}`` or ``{choices}``, with an optional ``write`` template."""
    if not isinstance(entry, dict):
        raise configuration.ConfigError(
            f"{where} must be a mapping like {{low: 0.1, high: 0.4}} or {{choices: [a, b]}}, got {entry!r}"
        )
    entry = {
        key: configuration.coerce_numbers(value) if key in ("low", "high", "step") else value
        for key, value in entry.items()
    }  # YAML 1.1 reads 1e-4 as a string; choices stay as written
    write = entry.pop("write", "{}")
    if not isinstance(write, str) or write.count("{}") != 1:
        raise configuration.ConfigError(f"{where}: write must be a string holding one {{}}, got {write!r}")
    if "choices" in entry:
        choices = entry.pop("choices")
        if entry:
            raise configuration.ConfigError(f"{where}: choices takes no other key than write, got {sorted(entry)}")
        if (
            not isinstance(choices, list)
            or not choices
            or not all(isinstance(c, (bool, int, float, str)) for c in choices)
        ):
            raise configuration.ConfigError(
                f"{where}: choices must be a non-empty list of numbers, strings or booleans, got {choices!r}"
            )
        return Dimension(distributions.CategoricalDistribution(choices), write)
    unknown = set(entry) - {"low", "high", "log", "step"}
    if unknown or "low" not in entry or "high" not in entry:
        raise configuration.ConfigError(
            f"{where} must have low and high (and optionally log, step), or choices; got {sorted(entry)}"
        )
    low, high, log, step = entry["low"], entry["high"], entry.get("log", False), entry.get("step")
    for name, value in (("low", low), ("high", high)):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise configuration.ConfigError(f"{where}: {name} must be a number, got {value!r}")
    if not low < high:
        raise configuration.ConfigError(f"{where}: low must be < high, got low={low!r}, high={high!r}")
    if not isinstance(log, bool):
        raise configuration.ConfigError(f"{where}: log must be true or false, got {log!r}")
    if log and low <= 0:
        raise configuration.ConfigError(f"{where}: a log scale needs low > 0, got low={low!r}")
    if log and step is not None:
        raise configuration.ConfigError(f"{where}: step and log cannot be combined")
    if isinstance(low, int) and isinstance(high, int) and (step is None or isinstance(step, int)):
        return Dimension(distributions.IntDistribution(low, high, log=log, step=step or 1), write)
    return Dimension(distributions.FloatDistribution(float(low), float(high), log=log, step=step), write)


def optuna_space(space: dict[str, Dimension]) -> dict[str, distributions.BaseDistribution]:
    """The space as Optuna distributions (what ``ray.tune.search.optuna.OptunaSearch`` takes)."""
    return {key: dimension.distribution for key, dimension in space.items()}


def overrides(space: dict[str, Dimension], params: dict[str, Any]) -> list[str]:
    """The ``key=value`` overrides of a trial's sampled ``params``."""
    missing = set(space) - set(params)
    if missing:
        raise configuration.ConfigError(f"a trial must set every dimension of the space; missing {sorted(missing)}")
    return [space[key].override(key, params[key]) for key in space]


def trial_config(
    base: dict[str, Any], space: dict[str, Dimension], params: dict[str, Any], algo: str
) -> dict[str, Any]:
    """``base`` with a trial's sampled values applied, checked (a ConfigError names a bad value)."""
    config = configuration.apply_overrides(base, overrides(space, params), algo)
    configuration.check_config(config, algo)
    return config


def current_point(space: dict[str, Dimension], config: dict[str, Any]) -> dict[str, Any] | None:
    """The point of ``space`` that reproduces ``config`` (the hyperparameter file's values), or None
    if the space cannot express one of them (then a sweep does not start from the file)."""
    point = {}
    for key, dimension in space.items():
        node: Any = config
        for part in key.split("."):
            node = node.get(part) if isinstance(node, dict) else None
        value = dimension.point(node)
        if value is None:
            return None
        point[key] = value
    return point


def first_point(space: dict[str, Dimension]) -> dict[str, Any]:
    """Each dimension's low end or first choice: a point to check that the space's values make a
    valid configuration before a sweep starts."""
    return {
        key: (
            dimension.distribution.choices[0]
            if isinstance(dimension.distribution, distributions.CategoricalDistribution)
            else cast(distributions.FloatDistribution | distributions.IntDistribution, dimension.distribution).low
        )
        for key, dimension in space.items()
    }
