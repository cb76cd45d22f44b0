"""The recipe options of our own that change how training starts and proceeds, read and checked without loading
torch or SB3 (``agents.config`` checks a recipe with them before anything is made): ``initial_mean``
(``agents.initial_mean`` applies it) and ``curriculum`` (``agents.curriculum``)."""

from __future__ import annotations

from typing import Any

import numpy as np


def read_initial_mean(value: Any) -> tuple[str, np.ndarray] | None:
    """``initial_mean`` as (kind, vector): ("constant", action) or ("ballistic", command); None for None. A
    ValueError names what is accepted."""
    if value is None:
        return None
    kind, vector = ("ballistic", [0.0, 0.0, 0.0]) if value == "ballistic" else ("constant", value)
    if isinstance(value, dict) and list(value) == ["ballistic"]:
        kind, vector = "ballistic", value["ballistic"]
    ok = (
        isinstance(vector, (list, tuple))
        and len(vector) == 3
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) and -1.0 <= v <= 1.0 for v in vector)
    )
    if not ok:
        raise ValueError(
            "initial_mean must be a list of 3 numbers in [-1, 1] (a constant env action), 'ballistic' or "
            f"{{ballistic: [c0, c1, c2]}} (a ballistic command, each in [-1, 1]), got {value!r}"
        )
    return kind, np.asarray(vector, dtype=np.float64)


def check_initial_mean(config: dict[str, Any]) -> None:
    """A ValueError for an ``initial_mean`` that is malformed, or ballistic in a recipe acting through a wrapper."""
    option = read_initial_mean(config.get("initial_mean"))
    if option is not None and option[0] == "ballistic" and config.get("env_wrapper") is not None:
        raise ValueError(
            "initial_mean: a ballistic start is a throw in the env's own actions; this recipe acts through "
            f"env_wrapper {config['env_wrapper']!r} (set env_wrapper=null, or give a constant action)"
        )


def read_stages(value: Any, n_timesteps: int | None = None) -> list[tuple[int, dict[str, Any]]]:
    """``curriculum`` as (until, env_kwargs) stages in order ([] for None); a ValueError names what is wrong."""
    if value is None:
        return []
    expected = "curriculum must be a list of {until: <throws>, env_kwargs: {...}} with until increasing"
    if not isinstance(value, list) or not value:
        raise ValueError(f"{expected}, got {value!r}")
    stages: list[tuple[int, dict[str, Any]]] = []
    for stage in value:
        if not isinstance(stage, dict) or set(stage) != {"until", "env_kwargs"}:
            raise ValueError(f"{expected}, got the stage {stage!r}")
        until, kwargs = stage["until"], stage["env_kwargs"]
        if not isinstance(until, int) or isinstance(until, bool) or until < 1 or not isinstance(kwargs, dict):
            raise ValueError(f"{expected}, got the stage {stage!r}")
        if stages and until <= stages[-1][0]:
            raise ValueError(f"{expected}: {until} after {stages[-1][0]}")
        stages.append((until, kwargs))
    if n_timesteps is not None and stages[-1][0] >= n_timesteps:
        raise ValueError(f"curriculum: the last stage must end before n_timesteps = {n_timesteps}, got {stages[-1][0]}")
    return stages
