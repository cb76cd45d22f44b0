"""Every keyword argument of ``BoxToss-v0``, declared once: name, type, default, allowed range and meaning.

``ENV_ARGUMENTS`` is the one declaration. What reads it:

- ``BoxTossEnv.__init__`` takes its defaults (``ENV_DEFAULTS``) and refuses a name it does not list;
- the validation (``task_config.make_task_config``, ``task_config.ENV_RANGES``) takes the ranges;
- the "Arguments" table of ``BoxTossEnv``'s docstring (the environment page and ``help()``) is
  ``arguments_table()``;
- ``BoxTossFunctional`` (``envs.functional``) takes the same arguments, less the rendering ones.

A range is the engine's ``Range`` (``physics.ranges``); for a ``(low, high)`` pair it bounds each end.
Rules that tie two arguments together (``release_height_range`` above the corner radius, the base box's
clearance) are the validation's, written in docs/ranges.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from box_toss_env.physics.ranges import ENGINE_RANGES, Range


@dataclass(frozen=True)
class Argument:
    """One keyword argument of the env.

    Attributes:
        name: the keyword.
        type: its Python type as the docs write it.
        default: the value when it is not given.
        doc: what it means, with its unit.
        allowed: the range a number (or each end of a pair) must lie in; None for choices and flags.
        shown: how the docs write the default (``repr(default)`` when empty).
        group: "task" (what is thrown and scored), "engine" (how it is simulated), "observation" (what the agent
            sees) or "render".
    """

    name: str
    type: str
    default: Any
    doc: str
    allowed: Range | None = None
    shown: str = ""
    group: str = "task"

    @property
    def shown_default(self) -> str:
        return self.shown or repr(self.default)


BASE_DEFAULTS = {"base_length_range": (0.6, 1.0), "base_height_range": (0.2, 0.5), "base_mass": 10.0}
"""The base box's size ranges [m] and mass [kg] when ``base_box=True`` leaves them None."""

PAIR, OPTIONAL_PAIR = "(float, float)", "(float, float) | None"
LENGTH, WIDTH, MASS = ENGINE_RANGES["length"], ENGINE_RANGES["width"], ENGINE_RANGES["mass"]

ENV_ARGUMENTS: tuple[Argument, ...] = (
    Argument("box_length", "float", 0.4, "box size along its local x [m] (faces 1 and 3 are its ends)", LENGTH),
    Argument("box_width", "float", 0.2, "box size along its local y [m]", WIDTH),
    Argument("mass", "float", 2.0, "box mass [kg]; inertia is that of a uniform box", MASS),
    Argument("friction", "float", 0.5, "Coulomb friction coefficient with the floor", ENGINE_RANGES["friction"]),
    Argument("restitution", "float", 0.3, "coefficient of restitution with the floor", ENGINE_RANGES["restitution"]),
    Argument(
        "penalty_stiffness",
        "float",
        1e5,
        "stiffness of the penetration correction [N/m]",
        ENGINE_RANGES["penalty_stiffness"],
        shown="1e5",
    ),
    Argument("gravity", "float", 9.81, "gravitational acceleration, pointing down [m/s^2]", Range(1e-3, 1e4, "m/s^2")),
    Argument("release_x_range", PAIR, (-0.1, 0.1), "release x of the box's centre [m]", Range(-1e3, 1e3, "m")),
    Argument(
        "release_height_range",
        PAIR,
        (1.2, 1.6),
        "release height of the centre [m], above the corner radius",
        Range(0.0, 1e4, "m", low_open=True),
    ),
    Argument("release_angle_range", PAIR, (-0.3, 0.3), "release angle [rad]", Range(-math.pi, math.pi, "rad")),
    Argument("target_x_range", PAIR, (1.0, 4.0), "target x [m]", Range(-1e3, 1e3, "m")),
    Argument("target_face", "str", "any", '"any", "long_side", "short_end", "exact" or "mixed"'),
    Argument("max_speed", "float", 8.0, "launch speed at action[0] = 1 [m/s]", Range(0.0, 1e3, "m/s", low_open=True)),
    Argument(
        "launch_angle_range",
        PAIR,
        (-0.25 * math.pi, 0.5 * math.pi),
        "launch direction at action[1] = -1 and +1 [rad]",
        Range(-math.pi, math.pi, "rad"),
        shown="(-pi/4, pi/2)",
    ),
    Argument("max_spin", "float", 20.0, "spin at action[2] = 1 [rad/s]", Range(0.0, 1e4, "rad/s")),
    Argument(
        "position_tolerance", "float", 0.1, "success radius around the target [m]", Range(0.0, 1e3, "m", low_open=True)
    ),
    Argument("distance_weight", "float", 1.0, "weight of the distance term [1/m]", Range(0.0, 1e6, "1/m")),
    Argument("orientation_weight", "float", 0.5, "weight of the orientation term [1/rad]", Range(0.0, 1e6, "1/rad")),
    Argument("success_bonus", "float", 1.0, "reward added on success", Range(0.0, 1e6)),
    Argument(
        "mass_range", OPTIONAL_PAIR, None, "(low, high) [kg]: draw the mass per episode (replaces ``mass``)", MASS
    ),
    Argument(
        "friction_range", OPTIONAL_PAIR, None, "(low, high): draw the friction per episode", ENGINE_RANGES["friction"]
    ),
    Argument(
        "restitution_range",
        OPTIONAL_PAIR,
        None,
        "(low, high): draw the restitution per episode",
        ENGINE_RANGES["restitution"],
    ),
    Argument(
        "box_length_range",
        OPTIONAL_PAIR,
        None,
        "(low, high) [m]: draw the box length per episode (replaces ``box_length``; observed)",
        LENGTH,
    ),
    Argument(
        "box_width_range",
        OPTIONAL_PAIR,
        None,
        "(low, high) [m]: draw the box width per episode (replaces ``box_width``; observed)",
        WIDTH,
    ),
    Argument("observe_dynamics", "bool", False, "append mass, friction, restitution to the observation"),
    Argument(
        "split",
        "str | None",
        None,
        '"train" or "test": the held-out split (``SPLITS``): box size, mass, friction, restitution and target x '
        "drawn per episode from the split's ranges, all observed",
    ),
    Argument("base_box", "bool", False, 'a base box to come to rest on (see "A base box to land on")'),
    Argument(
        "base_length_range",
        OPTIONAL_PAIR,
        None,
        "with ``base_box``: the base box's length, drawn per episode [m]",
        LENGTH,
        shown=f"None: {BASE_DEFAULTS['base_length_range']}",
    ),
    Argument(
        "base_height_range",
        OPTIONAL_PAIR,
        None,
        "with ``base_box``: its height, drawn per episode [m]",
        WIDTH,
        shown=f"None: {BASE_DEFAULTS['base_height_range']}",
    ),
    Argument(
        "base_mass",
        "float | None",
        None,
        "with ``base_box``: its mass [kg]",
        MASS,
        shown=f"None: {BASE_DEFAULTS['base_mass']}",
    ),
    Argument(
        "solver", "str", "robust", '"robust" (the engine\'s default) or "seed" (the explicit scheme)', group="engine"
    ),
    Argument(
        "dt",
        "float",
        1 / 128,
        "solver time step [s] (docs/precision.md: the cheapest accurate one)",
        ENGINE_RANGES["dt"],
        shown="1/128",
        group="engine",
    ),
    Argument(
        "max_sim_time",
        "float",
        10.0,
        "simulated time after which a throw ends anyway [s]",
        Range(0.0, 1e4, "s", low_open=True),
        group="engine",
    ),
    Argument(
        "observation_mode",
        "str",
        "state",
        '"state" (the vector below) or "pixels" (an image of the scene, ``envs.pixels``)',
        group="observation",
    ),
    Argument(
        "pixel_size",
        "(int, int)",
        (96, 40),
        'width and height of a "pixels" observation [px], each in [16, 1024]',
        group="observation",
    ),
    Argument(
        "render_fps",
        "float",
        30,
        'frame rate of "human" playback and "rgb_array_list" frames',
        Range(0.0, 1e3, "1/s", low_open=True),
        group="render",
    ),
    Argument("render_width", "int", 600, "frame width [px], in [16, 8192]", group="render"),
    Argument("render_height", "int", 400, "frame height [px], in [16, 8192]", group="render"),
)
"""The keyword arguments of ``BoxToss-v0`` (and of ``gymnasium.make_vec``'s batched env), in the order
the docs list them. ``render_mode`` is Gymnasium's and not among them."""

SPLITS: dict[str, dict[str, Any]] = {
    "train": {
        "box_length_range": (0.3, 0.5),
        "box_width_range": (0.15, 0.25),
        "mass_range": (1.0, 3.0),
        "friction_range": (0.4, 0.6),
        "restitution_range": (0.2, 0.4),
        "target_x_range": (1.0, 3.5),
        "observe_dynamics": True,
    },
    "test": {
        "box_length_range": (0.28, 0.6),
        "box_width_range": (0.12, 0.28),
        "mass_range": (0.5, 4.0),
        "friction_range": (0.3, 0.8),
        "restitution_range": (0.1, 0.5),
        "target_x_range": (1.5, 4.0),
        "observe_dynamics": True,
    },
}
"""The held-out split of every one-throw variant (``split="train"`` or ``"test"``): what each episode draws. The test
ranges hold the training ones and reach past them (shorter and longer, thinner and thicker boxes; lighter and heavier;
slipperier and grippier; deader and bouncier), and its targets lie partly beyond the farthest training target
(3.5-4.0 m) while the nearest training ones (1.0-1.5 m) are left out. The task's default box and dynamics (0.4 x
0.2 m, 2 kg, friction 0.5, restitution 0.3) lie inside both."""


def apply_split(args: dict[str, Any]) -> dict[str, Any]:
    """``args`` (every argument, defaults filled in) with its ``split``'s settings; a ValueError names a setting the
    split makes that was also given (at another value than its default), or a split that does not exist."""
    split = args.get("split")
    if split is None:
        return args
    if split not in SPLITS:
        raise ValueError(f"split must be None, 'train' or 'test', got {split!r}")
    for name in SPLITS[split]:
        if args[name] != ARGUMENTS[name].default:
            raise ValueError(
                f"split={split!r} sets {name} ({SPLITS[split][name]!r}); got {name}={args[name]!r} as well: give one "
                "or the other"
            )
    return {**args, **SPLITS[split]}


ARGUMENTS = {argument.name: argument for argument in ENV_ARGUMENTS}
ENV_DEFAULTS = {argument.name: argument.default for argument in ENV_ARGUMENTS}
"""Every argument's default, by name."""
CORE_ARGUMENTS = tuple(argument.name for argument in ENV_ARGUMENTS if argument.group not in ("render", "observation"))
"""The arguments of the throw itself (``BoxTossFunctional``): all but the observation's and the rendering ones."""


def with_defaults(kwargs: dict[str, Any], names=tuple(ARGUMENTS), owner: str = "BoxTossEnv") -> dict[str, Any]:
    """``kwargs`` completed with the defaults of ``names``, in declaration order; a TypeError (as Python
    raises it for a function) names an argument that is not one of them."""
    unknown = [name for name in kwargs if name not in names]
    if unknown:
        raise TypeError(f"{owner}() got an unexpected keyword argument {unknown[0]!r}")
    return {name: kwargs.get(name, ARGUMENTS[name].default) for name in names}


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def arguments_table(arguments: tuple[Argument, ...] = ENV_ARGUMENTS) -> str:
    """The Markdown table of ``arguments`` (``ENV_ARGUMENTS``): argument, type, default, allowed range, meaning."""
    lines = ["| Argument | Type | Default | Range | Meaning |", "|---|---|---|---|---|"]
    for a in arguments:
        allowed = "" if a.allowed is None else f"{a.allowed}" + (" each end" if "float, float" in a.type else "")
        lines.append(f"| ``{a.name}`` | {_cell(a.type)} | {_cell(a.shown_default)} | {allowed} | {_cell(a.doc)} |")
    return "\n".join(lines)
