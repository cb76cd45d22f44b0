"""The BoxToss task's configuration, validated once (``TaskConfig``, ``make_task_config``: the env's arguments
and their allowed ranges, ``ENV_RANGES``), and the episodes it draws (``Episodes``)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from box_toss_env.envs.arguments import BASE_DEFAULTS, ENV_ARGUMENTS
from box_toss_env.envs.task_columns import (
    BASE_OBS_SIZE,
    BOX_SIZE_OBS,
    EP_BASE_HEIGHT,
    EP_BASE_LENGTH,
    EP_DYNAMICS,
    EP_FRICTION,
    EP_MASS,
    EP_RELEASE,
    EP_RELEASE_ANGLE,
    EP_RELEASE_X,
    EP_RELEASE_Y,
    EP_RESTITUTION,
    EP_TARGET_FACES,
    EP_TARGET_X,
    EPISODE_SIZE,
    EPISODE_SIZE_WITH_BASE,
    OBS_SIZE,
    OBS_SIZE_WITH_DYNAMICS,
    TARGET_FACE_KINDS,
)
from box_toss_env.physics.ranges import Range
from box_toss_env.physics.validation import check_bool, check_choice


@dataclass(frozen=True)
class TaskConfig:
    """Everything the task functions need, validated once (``make_task_config``). SI units.

    Ranges are ``(low, high)`` tuples with low <= high; low == high fixes the value.
    """

    half_length: float  # [m] along the body's local x
    half_width: float  # [m] along local y
    gravity: float  # [m/s^2] magnitude, pointing down
    mass_range: tuple[float, float]  # [kg]
    friction_range: tuple[float, float]  # [-]
    restitution_range: tuple[float, float]  # [-]
    penalty_stiffness: float  # [N/m]
    release_x_range: tuple[float, float]  # [m]
    release_height_range: tuple[float, float]  # [m] of the box's centre
    release_angle_range: tuple[float, float]  # [rad]
    target_x_range: tuple[float, float]  # [m]
    target_face: str
    max_speed: float  # [m/s]
    launch_angle_range: tuple[float, float]  # [rad] above the horizontal
    max_spin: float  # [rad/s]
    position_tolerance: float  # [m]
    distance_weight: float  # [1/m]
    orientation_weight: float  # [1/rad]
    success_bonus: float  # [-]
    observe_dynamics: bool
    max_sim_time: float  # [s]
    base_box: bool = False  # a base box to land on (BoxToss-OnBox-v0)
    base_length_range: tuple[float, float] = (0.0, 0.0)  # [m] of the base box, with base_box
    base_height_range: tuple[float, float] = (0.0, 0.0)  # [m] of the base box, with base_box
    base_mass: float = 0.0  # [kg] of the base box, with base_box
    box_length_range: tuple[float, float] = (0.0, 0.0)  # [m] of the thrown box (low == high: not drawn)
    box_width_range: tuple[float, float] = (0.0, 0.0)  # [m]

    def __post_init__(self):
        if self.box_length_range == (0.0, 0.0):  # not given: the fixed size of half_length, half_width
            object.__setattr__(self, "box_length_range", (2.0 * self.half_length,) * 2)
            object.__setattr__(self, "box_width_range", (2.0 * self.half_width,) * 2)

    @functools.cached_property
    def draws_box_size(self) -> bool:
        """Whether the thrown box's length or width is drawn per episode (and observed)."""
        return (
            self.box_length_range[0] != self.box_length_range[1] or self.box_width_range[0] != self.box_width_range[1]
        )

    @property
    def box_size_columns(self) -> tuple[int, int]:
        """The columns of ``Episodes.data`` holding the box's length and width (with ``draws_box_size``): after all
        the others."""
        first = EPISODE_SIZE_WITH_BASE if self.base_box else EPISODE_SIZE
        return first, first + 1

    @property
    def box_size_observed(self) -> tuple[int, int]:
        """The observation's columns of the box's length and width (with ``draws_box_size``): after the dynamics,
        before a base box's."""
        first = OBS_SIZE_WITH_DYNAMICS if self.observe_dynamics else OBS_SIZE
        return first, first + 1

    @functools.cached_property
    def randomises_dynamics(self) -> bool:
        """Whether mass, friction or restitution are drawn per episode."""
        return any(low != high for low, high in (self.mass_range, self.friction_range, self.restitution_range))

    @functools.cached_property
    def draws_body_params(self) -> bool:
        """Whether the engine's body parameters change from episode to episode: drawn dynamics, the thrown box's
        drawn size, or the base box's."""
        base_drawn = self.base_length_range[0] != self.base_length_range[1] or (
            self.base_height_range[0] != self.base_height_range[1]
        )
        return self.randomises_dynamics or self.draws_box_size or (self.base_box and base_drawn)

    @property
    def obs_size(self) -> int:
        size = OBS_SIZE_WITH_DYNAMICS if self.observe_dynamics else OBS_SIZE
        size += BOX_SIZE_OBS if self.draws_box_size else 0
        return size + BASE_OBS_SIZE if self.base_box else size

    @property
    def episode_size(self) -> int:
        """Columns of ``Episodes.data`` (and variates drawn per episode): a drawn box size's two come last, so a task
        that draws none draws what it always drew."""
        size = EPISODE_SIZE_WITH_BASE if self.base_box else EPISODE_SIZE
        return size + BOX_SIZE_OBS if self.draws_box_size else size

    @property
    def bodies_per_env(self) -> int:
        """Engine bodies per episode: the thrown box, and the base box with ``base_box``."""
        return 2 if self.base_box else 1

    @property
    def corner_radius(self) -> float:
        """Distance from the centre to a corner [m] (of the largest box thrown, with a drawn size)."""
        return math.hypot(0.5 * self.box_length_range[1], 0.5 * self.box_width_range[1])

    @property
    def max_corner_radius(self) -> float:
        """The largest distance from the centre to a corner of any box thrown [m]."""
        return self.corner_radius

    @property
    def gyration_radius_squared(self) -> float:
        """I / m = (L^2 + W^2) / 12 [m^2] for a uniform box, whatever its mass (the largest box's, with a drawn
        size)."""
        return (self.box_length_range[1] ** 2 + self.box_width_range[1] ** 2) / 12.0

    @property
    def min_gyration_radius_squared(self) -> float:
        """I / m of the smallest box thrown [m^2]."""
        return (self.box_length_range[0] ** 2 + self.box_width_range[0] ** 2) / 12.0

    # constant arrays, computed once (the functions below run per step and stay cheap on small batches)
    @functools.cached_property
    def episode_low_span(self) -> tuple[np.ndarray, np.ndarray]:
        """(episode_size,) low and high - low of each drawn column (0 for the face columns)."""
        low, span = np.zeros(self.episode_size), np.zeros(self.episode_size)
        columns = [
            (EP_RELEASE_X, self.release_x_range),
            (EP_RELEASE_Y, self.release_height_range),
            (EP_RELEASE_ANGLE, self.release_angle_range),
            (EP_TARGET_X, self.target_x_range),
            (EP_MASS, self.mass_range),
            (EP_FRICTION, self.friction_range),
            (EP_RESTITUTION, self.restitution_range),
        ]
        if self.base_box:
            columns += [(EP_BASE_LENGTH, self.base_length_range), (EP_BASE_HEIGHT, self.base_height_range)]
        if self.draws_box_size:
            columns += list(zip(self.box_size_columns, (self.box_length_range, self.box_width_range), strict=True))
        for column, (a, b) in columns:
            low[column], span[column] = a, b - a
        return low, span

    @functools.cached_property
    def action_scale_offset(self) -> tuple[np.ndarray, np.ndarray]:
        """(3,) scale and offset mapping actions in [-1, 1] to speed, launch angle and spin."""
        low, high = self.launch_angle_range
        scale = np.array([0.5 * self.max_speed, 0.5 * (high - low), self.max_spin])
        offset = np.array([0.5 * self.max_speed, 0.5 * (high + low), 0.0])
        return scale, offset


@dataclass
class Episodes:
    """What is drawn at reset for a batch of n episodes: one row of ``data`` (n, EPISODE_SIZE) per
    episode, columns ``EP_*``. The properties are views of ``data``."""

    data: np.ndarray

    @classmethod
    def empty(cls, n: int, size: int = EPISODE_SIZE) -> Episodes:
        """``n`` episodes of ``size`` columns (``TaskConfig.episode_size``)."""
        return cls(np.zeros((n, size)))

    @property
    def release(self) -> np.ndarray:  # (n, 3): x [m], y [m], angle [rad] of the box in the hand
        return self.data[:, EP_RELEASE]

    @property
    def target_x(self) -> np.ndarray:  # (n,) [m], where the box's centre should come to rest
        return self.data[:, EP_TARGET_X]

    @property
    def target_faces(self) -> np.ndarray:  # (n, 4), 1.0 for each face that may end down
        return self.data[:, EP_TARGET_FACES]

    @property
    def dynamics(self) -> np.ndarray:  # (n, 3): mass [kg], friction [-], restitution [-]
        return self.data[:, EP_DYNAMICS]

    @property
    def base_size(self) -> np.ndarray:  # (n, 2): the base box's length and height [m] (with base_box)
        return self.data[:, EP_BASE_LENGTH : EP_BASE_HEIGHT + 1]


# -- configuration ------------------------------------------------------------------------------
DYNAMICS_RANGES = ("mass_range", "friction_range", "restitution_range")
ENV_RANGES = {
    argument.name: argument.allowed
    for argument in ENV_ARGUMENTS
    if argument.allowed is not None and argument.name not in DYNAMICS_RANGES
}
"""The env's arguments and their allowed ranges (docs/ranges.md), read from their declaration
(``arguments.ENV_ARGUMENTS``): every observation stays finite in float32 and every throw is simulated, at
every combination of them. ``mass_range``, ``friction_range`` and ``restitution_range`` take the ranges of
``mass``, ``friction`` and ``restitution`` at each end."""


def check_interval(name: str, value, allowed: Range) -> tuple[float, float]:
    """``value`` as a (low, high) tuple of floats inside ``allowed``, with low <= high; a TypeError
    if it is not a pair of real numbers, a ValueError naming the parameter and the range otherwise."""
    if not isinstance(value, (tuple, list, np.ndarray)):  # not a dict, set, range or str: no order or not numbers
        raise TypeError(
            f"{name} must be a (low, high) pair of real numbers (a tuple or list), got {type(value).__name__} {value!r}"
        )
    try:
        first, second = value
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a (low, high) pair of real numbers, got {value!r}") from None
    first = allowed.check(f"{name}[0]", first)
    second = allowed.check(f"{name}[1]", second)
    if first > second:
        raise ValueError(f"{name} must have low <= high, got {value!r}")
    return first, second


def check_scalar_or_interval(name: str, value, interval, allowed: Range) -> tuple[float, float]:
    """``(value, value)``, or the (low, high) ``interval`` (named ``name_range``) when it is given."""
    scalar = None if value is None and interval is not None else allowed.check(name, value)  # checked in any case
    if interval is None:
        return (cast(float, scalar),) * 2  # not None: checked above
    return check_interval(f"{name}_range", interval, allowed)


def checked_scalars(**values: Any) -> dict[str, Any]:
    """Each scalar argument checked against its range in ``ENV_RANGES``."""
    return {name: ENV_RANGES[name].check(name, value) for name, value in values.items()}


def checked_intervals(**values: Any) -> dict[str, Any]:
    """Each (low, high) argument checked against its range in ``ENV_RANGES``."""
    return {name: check_interval(name, value, ENV_RANGES[name]) for name, value in values.items()}


def clear_release_height(lengths: tuple[float, float], widths: tuple[float, float], heights, given: Any) -> float:
    """The largest box's corner radius, after checking that every release height lies above it (so the box starts
    clear of the floor at any angle)."""
    corner_radius = math.hypot(lengths[1], widths[1]) / 2
    if heights[0] <= corner_radius:
        raise ValueError(
            f"release_height_range must lie above the box's corner radius {corner_radius:g} m (so the box "
            f"starts clear of the floor at any angle), got {given!r}"
        )
    return corner_radius


def box_sizes(box_length, box_width, box_length_range, box_width_range) -> tuple[tuple[float, float], ...]:
    """The thrown box's (low, high) length and width [m], checked: a drawn range, or the fixed size twice."""
    lengths = check_scalar_or_interval("box_length", box_length, box_length_range, ENV_RANGES["box_length"])
    widths = check_scalar_or_interval("box_width", box_width, box_width_range, ENV_RANGES["box_width"])
    return lengths, widths


def make_task_config(
    *,
    box_length,
    box_width,
    gravity,
    mass,
    friction,
    restitution,
    penalty_stiffness,
    mass_range,
    friction_range,
    restitution_range,
    release_x_range,
    release_height_range,
    release_angle_range,
    target_x_range,
    target_face,
    max_speed,
    launch_angle_range,
    max_spin,
    position_tolerance,
    distance_weight,
    orientation_weight,
    success_bonus,
    observe_dynamics,
    max_sim_time,
    base_box=False,
    base_length_range=None,
    base_height_range=None,
    base_mass=None,
    box_length_range=None,
    box_width_range=None,
) -> TaskConfig:
    """Validate the task's keyword arguments into a TaskConfig: a TypeError names an argument of the
    wrong type, a ValueError one outside its range (``ENV_RANGES``). ``*_range=None`` fixes that
    quantity at its scalar argument. ``base_*=None`` takes ``BASE_DEFAULTS`` with ``base_box=True``
    (they must stay None without it)."""
    lengths, widths = box_sizes(box_length, box_width, box_length_range, box_width_range)
    scalar = checked_scalars(
        gravity=gravity,
        penalty_stiffness=penalty_stiffness,
        max_speed=max_speed,
        max_spin=max_spin,
        position_tolerance=position_tolerance,
        distance_weight=distance_weight,
        orientation_weight=orientation_weight,
        success_bonus=success_bonus,
        max_sim_time=max_sim_time,
    )
    pairs = checked_intervals(
        release_x_range=release_x_range,
        release_height_range=release_height_range,
        release_angle_range=release_angle_range,
        target_x_range=target_x_range,
        launch_angle_range=launch_angle_range,
    )
    corner_radius = clear_release_height(lengths, widths, pairs["release_height_range"], release_height_range)
    clear = (pairs["target_x_range"], pairs["release_x_range"], corner_radius)
    base = check_base_box(base_box, base_length_range, base_height_range, base_mass, *clear)
    return TaskConfig(
        half_length=0.5 * lengths[1],  # the largest box's, with a drawn size (the episode's: task.box_half_sizes)
        half_width=0.5 * widths[1],
        box_length_range=lengths,
        box_width_range=widths,
        mass_range=check_scalar_or_interval("mass", mass, mass_range, ENV_RANGES["mass"]),
        friction_range=check_scalar_or_interval("friction", friction, friction_range, ENV_RANGES["friction"]),
        restitution_range=check_scalar_or_interval(
            "restitution", restitution, restitution_range, ENV_RANGES["restitution"]
        ),
        target_face=check_choice("target_face", target_face, TARGET_FACE_KINDS),
        observe_dynamics=check_bool("observe_dynamics", observe_dynamics),
        **scalar,
        **pairs,
        **base,
    )


def check_base_box(
    base_box, base_length_range, base_height_range, base_mass, target_x_range, release_x_range, corner_radius
) -> dict:
    """The TaskConfig fields of the base box, validated (``make_task_config``)."""
    given = {"base_length_range": base_length_range, "base_height_range": base_height_range, "base_mass": base_mass}
    if not check_bool("base_box", base_box):
        for name, value in given.items():
            if value is not None:
                raise ValueError(
                    f"{name} applies only with base_box=True (a base box to land on), got {name}="
                    f"{value!r} with base_box=False"
                )
        return {}
    values = {name: BASE_DEFAULTS[name] if value is None else value for name, value in given.items()}
    lengths = check_interval("base_length_range", values["base_length_range"], ENV_RANGES["base_length_range"])
    heights = check_interval("base_height_range", values["base_height_range"], ENV_RANGES["base_height_range"])
    mass = ENV_RANGES["base_mass"].check("base_mass", values["base_mass"])
    if heights[1] > lengths[0]:
        raise ValueError(
            f"base_height_range must not exceed base_length_range[0] = {lengths[0]:g} m (the base box "
            f"lies on its long side, its lowest pose), got {values['base_height_range']!r}"
        )
    clearance = release_x_range[1] + corner_radius + 0.5 * lengths[1]
    if target_x_range[0] < clearance:
        raise ValueError(
            f"target_x_range must start at {clearance:g} m or beyond with base_box=True (the base box, "
            f"centred at the target x, must stand clear of the box in the hand: release x max + its "
            f"corner radius + half the longest base), got {target_x_range!r}"
        )
    return {"base_box": True, "base_length_range": lengths, "base_height_range": heights, "base_mass": mass}
