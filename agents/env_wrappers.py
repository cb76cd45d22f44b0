"""The values of RL Zoo's ``env_wrapper`` key that training accepts (light: the configuration checks read it).

Each has a vector form and a ``command_map`` in ``agents.envs``.
"""

from __future__ import annotations

from typing import Any, cast

BALLISTIC = "box_toss_env.envs.ballistic.BallisticThrows"
STACK_COMMANDS = "box_toss_env.envs.stack_commands.StackCommands"
ENV_WRAPPERS = {
    BALLISTIC: "ballistic throw commands (flight time, landing offset, lean from the prior)",
    STACK_COMMANDS: "BoxToss-Stack-v0's throw commands (flight time, touchdown offset, lean, aimed at the stack's top)",
}
"""The values of ``env_wrapper`` that training accepts (each has a vector form and a ``command_map``)."""


def read_env_wrapper(spec: Any) -> tuple[str, dict[str, Any]] | None:
    """Zoo's ``env_wrapper`` value (None, a class path, or ``{class path: kwargs}``) as (path, kwargs);
    a ValueError naming what is accepted otherwise."""
    if spec is None:
        return None
    name, kwargs = spec, cast(dict[str, Any], {})
    if isinstance(spec, dict) and len(spec) == 1:
        name, kwargs = next(iter(spec.items()))
        kwargs = {} if kwargs is None else kwargs
    if not isinstance(name, str) or name not in ENV_WRAPPERS or not isinstance(kwargs, dict):
        raise ValueError(
            f"env_wrapper must be one of {sorted(ENV_WRAPPERS)}, optionally as {{name: {{kwargs}}}}, got {spec!r}"
        )
    return name, kwargs
