"""The stacking task (``BoxToss-Stack-v0``) as batch-first numpy functions.

An episode is a hand of ``n_boxes`` boxes (sizes and masses drawn per episode), thrown one per step onto
what is already there; everything thrown stays in the scene. This module says what is drawn, what the
agent sees and how a throw is scored; the physics is the engine's (``box_toss_env.physics``, its colliding
kernel over the boxes thrown so far) and the stateful env is ``stack.BoxTossStackEnv``.

Shapes: a scene of k boxes is ``states (..., k, 6)`` (the engine's state rows, box j thrown j-th) with
half extents ``half (k, 2)``; the leading dimensions are copies of one scene (the planner's candidate
throws) or a single scene. Nothing here loops over bodies in Python.

The stack. A thrown box is *on the target* when its centre lies within ``target_radius`` of the target x;
the stack's height is the highest top (highest corner) of the boxes on the target (0 when there are none).
The stack *fell* in a throw when a box that was on the target before it is no longer on the target, or its
top came down by more than ``fall_tolerance``: the throw knocked it off or over.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from box_toss_env.envs import task_columns, task_config
from box_toss_env.envs.arguments import ARGUMENTS, PAIR, Argument
from box_toss_env.envs.engine import EngineConfig
from box_toss_env.physics import layout
from box_toss_env.physics.ranges import ENGINE_RANGES, Range
from box_toss_env.physics.validation import check_integer

MAX_BOXES = 16
"""The largest hand (the engine's exact contact solve stays dense up to 64 contacts: 16 boxes)."""

STACK_RANGES = {
    "box_length_range": ENGINE_RANGES["length"],
    "box_width_range": ENGINE_RANGES["width"],  # and box_width_range[1] <= box_length_range[0]
    "mass_range": ENGINE_RANGES["mass"],
    "target_radius": Range(0.0, 1e3, "m", low_open=True),
    "height_weight": Range(0.0, 1e6, "1/m"),
    "fall_penalty": Range(0.0, 1e6),
    "fall_tolerance": Range(0.0, 1e3, "m", low_open=True),
    "success_fraction": Range(0.0, 1.0, low_open=True),
}
"""The stacking env's own arguments and their allowed ranges (the others are ``task_config.ENV_RANGES``')."""


def _one_throw(name: str, default: Any, doc: str = "") -> Argument:
    """``BoxToss-v0``'s argument ``name`` with the stack's default (and meaning, where it differs)."""
    argument = ARGUMENTS[name]
    return Argument(name, argument.type, default, doc or argument.doc, argument.allowed, argument.shown, argument.group)


STACK_ARGUMENTS: tuple[Argument, ...] = (
    Argument("n_boxes", "int", 4, f"boxes in the hand, thrown one per step, in [1, {MAX_BOXES}]"),
    Argument(
        "box_length_range",
        PAIR,
        (0.3, 0.5),
        "each box's length, drawn per episode [m]",
        STACK_RANGES["box_length_range"],
    ),
    Argument(
        "box_width_range",
        PAIR,
        (0.15, 0.25),
        "each box's width, drawn per episode [m], at most the shortest length",
        STACK_RANGES["box_width_range"],
    ),
    Argument("mass_range", PAIR, (1.0, 3.0), "each box's mass, drawn per episode [kg]", STACK_RANGES["mass_range"]),
    _one_throw("friction", 0.5, "Coulomb friction of every box (box-box: the same)"),
    _one_throw("restitution", 0.3, "restitution of every box"),
    _one_throw("penalty_stiffness", 1e5),
    _one_throw("gravity", 9.81),
    _one_throw("release_x_range", (-0.1, 0.1), "release x of each box's centre [m]"),
    _one_throw("release_height_range", (1.2, 1.6), "release height [m], above the largest corner radius"),
    _one_throw("release_angle_range", (-0.3, 0.3)),
    _one_throw("target_x_range", (1.5, 3.0), "target x [m], the target clear of the hand"),
    Argument(
        "target_radius",
        "float",
        0.25,
        "a box is on the target when its centre is this close to it [m]",
        STACK_RANGES["target_radius"],
    ),
    _one_throw("max_speed", 8.0),
    _one_throw("launch_angle_range", (-0.25 * math.pi, 0.5 * math.pi)),
    _one_throw("max_spin", 20.0),
    Argument("height_weight", "float", 5.0, "weight of the height term [1/m]", STACK_RANGES["height_weight"]),
    _one_throw("distance_weight", 0.5),
    Argument("fall_penalty", "float", 1.0, "reward taken when the stack falls", STACK_RANGES["fall_penalty"]),
    _one_throw("success_bonus", 1.0),
    Argument(
        "fall_tolerance",
        "float",
        0.05,
        "a box on the target whose top comes down further has fallen [m]",
        STACK_RANGES["fall_tolerance"],
    ),
    Argument(
        "success_fraction",
        "float",
        0.9,
        "share of the sum of the widths the final stack must reach",
        STACK_RANGES["success_fraction"],
    ),
    _one_throw("dt", 1 / 128),
    _one_throw("max_sim_time", 10.0),
    _one_throw("render_width", 600),
    _one_throw("render_height", 400),
)
"""The keyword arguments of ``BoxToss-Stack-v0``, declared once: the env's signature and its docstring's table
are made from them; ``render_mode`` is Gymnasium's and not among them."""

# -- observation layout ---------------------------------------------------------------------------------
BODY_COLUMNS = ("x", "y", "cos(angle)", "sin(angle)", "vx", "vy", "spin", "length", "width", "mass", "thrown")
"""Per box of the hand, in throwing order: its state once thrown (zeros before), its size and mass (always),
and 1.0 once thrown (the mask)."""
BODY_SIZE = len(BODY_COLUMNS)
B_X, B_Y, B_COS, B_SIN, B_VX, B_VY, B_SPIN, B_LENGTH, B_WIDTH, B_MASS, B_THROWN = range(BODY_SIZE)
TAIL_COLUMNS = (
    "hand x",
    "hand y",
    "hand cos(angle)",
    "hand sin(angle)",
    "hand length",
    "hand width",
    "hand mass",
    "in hand",
    "target x",
    "target radius",
    "stack height",
    "boxes left",
)
"""After the boxes' columns: the box in the hand (its release pose, size and mass, and 1.0 while there is one;
zeros after the last throw), the goal and the progress."""
TAIL_SIZE = len(TAIL_COLUMNS)
(H_X, H_Y, H_COS, H_SIN, H_LENGTH, H_WIDTH, H_MASS, H_IN_HAND, G_TARGET_X, G_TARGET_RADIUS, G_HEIGHT, G_LEFT) = range(
    TAIL_SIZE
)

REWARD_TERMS = ("reward_height", "reward_distance", "reward_fall", "reward_success")

# -- the episode's draws: one row per box ---------------------------------------------------------------
E_LENGTH, E_WIDTH, E_MASS, E_RELEASE_X, E_RELEASE_Y, E_RELEASE_ANGLE = range(6)
EPISODE_COLUMNS = 6


@dataclass(frozen=True)
class StackConfig:
    """The stacking task's validated arguments (``make_stack_config``), SI units."""

    n_boxes: int
    box_length_range: tuple[float, float]  # [m]
    box_width_range: tuple[float, float]  # [m]
    mass_range: tuple[float, float]  # [kg]
    friction: float
    restitution: float
    penalty_stiffness: float  # [N/m]
    gravity: float  # [m/s^2], pointing down
    release_x_range: tuple[float, float]  # [m]
    release_height_range: tuple[float, float]  # [m]
    release_angle_range: tuple[float, float]  # [rad]
    target_x_range: tuple[float, float]  # [m]
    target_radius: float  # [m]
    max_speed: float  # [m/s]
    launch_angle_range: tuple[float, float]  # [rad]
    max_spin: float  # [rad/s]
    height_weight: float  # [1/m]
    distance_weight: float  # [1/m]
    fall_penalty: float
    success_bonus: float
    fall_tolerance: float  # [m]
    success_fraction: float
    max_sim_time: float  # [s]
    dt: float  # [s]

    @property
    def obs_size(self) -> int:
        return BODY_SIZE * self.n_boxes + TAIL_SIZE

    @property
    def largest_corner_radius(self) -> float:
        return 0.5 * math.hypot(self.box_length_range[1], self.box_width_range[1])


def make_stack_config(**kwargs) -> StackConfig:
    """``StackConfig`` of the env's arguments (``STACK_ARGUMENTS`` but the rendering ones; the defaults where
    not given), each checked: a TypeError names an unknown or mistyped one, a ValueError one out of its range."""
    names = [argument.name for argument in STACK_ARGUMENTS if argument.group != "render"]
    unknown = [name for name in kwargs if name not in names]
    if unknown:
        raise TypeError(f"BoxTossStackEnv() got an unexpected keyword argument {unknown[0]!r}")
    kwargs = {a.name: kwargs.get(a.name, a.default) for a in STACK_ARGUMENTS if a.group != "render"}
    ranges = {**task_config.ENV_RANGES, **STACK_RANGES}
    values = dict(kwargs)
    values["n_boxes"] = check_integer("n_boxes", kwargs["n_boxes"], 1, MAX_BOXES)
    for name in (
        "box_length_range",
        "box_width_range",
        "mass_range",
        "release_x_range",
        "release_height_range",
        "release_angle_range",
        "target_x_range",
        "launch_angle_range",
    ):
        values[name] = task_config.check_interval(name, kwargs[name], ranges[name])
    for name in (
        "friction",
        "restitution",
        "penalty_stiffness",
        "gravity",
        "target_radius",
        "max_speed",
        "max_spin",
        "height_weight",
        "distance_weight",
        "fall_penalty",
        "success_bonus",
        "fall_tolerance",
        "success_fraction",
        "max_sim_time",
        "dt",
    ):
        values[name] = ranges[name].check(name, kwargs[name])
    if values["box_width_range"][1] > values["box_length_range"][0]:
        raise ValueError(
            f"box_width_range[1] must be at most box_length_range[0] (a box's length is its longer "
            f"side), got {values['box_width_range']!r} and {values['box_length_range']!r}"
        )
    low, high = values["launch_angle_range"]
    if low >= high:
        raise ValueError(f"launch_angle_range must have low < high, got {kwargs['launch_angle_range']!r}")
    config = StackConfig(**values)
    lowest_release = config.release_height_range[0]
    if lowest_release <= config.largest_corner_radius:
        raise ValueError(
            f"release_height_range[0] must be above the largest box's corner radius "
            f"({config.largest_corner_radius:g} m), got {lowest_release:g} m"
        )
    reach = config.release_x_range[1] + 2.0 * config.largest_corner_radius
    if config.target_x_range[0] - config.target_radius < reach:
        raise ValueError(
            f"target_x_range[0] - target_radius must be at least {reach:g} m (release_x_range[1] plus "
            f"two corner radii), so that the stack stands clear of the hand, got "
            f"{config.target_x_range[0] - config.target_radius:g} m"
        )
    return config


# -- drawing an episode ----------------------------------------------------------------------------------
def episode_from_uniforms(u: np.ndarray, config: StackConfig) -> tuple[np.ndarray, np.ndarray]:
    """The hands ((m,) n_boxes, EPISODE_COLUMNS): length, width [m], mass [kg], release x, y [m], angle [rad] of
    each box, and the target x [m] ((m,) or a 0-d array), from uniform variates u ((m,) n_boxes * EPISODE_COLUMNS
    + 1) in [0, 1)."""
    n = config.n_boxes
    boxes = u[..., : n * EPISODE_COLUMNS].reshape(u.shape[:-1] + (n, EPISODE_COLUMNS))
    ranges = np.array(
        [
            config.box_length_range,
            config.box_width_range,
            config.mass_range,
            config.release_x_range,
            config.release_height_range,
            config.release_angle_range,
        ]
    )
    hand = ranges[:, 0] + (ranges[:, 1] - ranges[:, 0]) * boxes
    low, high = config.target_x_range
    return hand, low + (high - low) * u[..., -1]


def uniforms_per_episode(config: StackConfig) -> int:
    """How many uniform variates one episode draws (one call of ``Generator.random`` per reset)."""
    return config.n_boxes * EPISODE_COLUMNS + 1


def draw_episode(rng: np.random.Generator, config: StackConfig) -> tuple[np.ndarray, float]:
    """``episode_from_uniforms`` of one draw from ``rng`` (one call per reset, so a seed fixes the episode)."""
    hand, target_x = episode_from_uniforms(rng.random(uniforms_per_episode(config)), config)
    return hand, float(target_x)


def body_params(hand: np.ndarray, config: StackConfig) -> np.ndarray:
    """The engine's body parameters ((m,) n_boxes, 7) of hands: uniform boxes, the scene's material."""
    params = np.empty(hand.shape[:-1] + (layout.PARAM_SIZE,))
    length, width, mass = hand[..., E_LENGTH], hand[..., E_WIDTH], hand[..., E_MASS]
    params[..., layout.HALF_LENGTH] = 0.5 * length
    params[..., layout.HALF_WIDTH] = 0.5 * width
    params[..., layout.MASS] = mass
    params[..., layout.INERTIA] = mass * (length**2 + width**2) / 12.0
    params[..., layout.RESTITUTION] = config.restitution
    params[..., layout.FRICTION] = config.friction
    params[..., layout.STIFFNESS] = config.penalty_stiffness
    return params


def thrown_states(release: np.ndarray, actions: np.ndarray, config: StackConfig) -> np.ndarray:
    """(m, 6) engine states of boxes released at ``release`` ((m,) 3: x, y, angle) and thrown with ``actions``
    (m, 3) in [-1, 1]: speed = max_speed (a0 + 1) / 2, direction = lo + (hi - lo) (a1 + 1) / 2 above the
    horizontal, spin = max_spin a2 (as ``BoxToss-v0``)."""
    speed = 0.5 * config.max_speed * (actions[:, 0] + 1.0)
    low, high = config.launch_angle_range
    direction = low + 0.5 * (high - low) * (actions[:, 1] + 1.0)
    states = np.empty((len(actions), layout.STATE_SIZE))
    states[:, layout.X : layout.ANGLE + 1] = release
    states[:, layout.VX] = speed * np.cos(direction)
    states[:, layout.VY] = speed * np.sin(direction)
    states[:, layout.SPIN] = config.max_spin * actions[:, 2]
    return states


def actions_of_throws(speed: np.ndarray, direction: np.ndarray, spin: np.ndarray, config: StackConfig) -> np.ndarray:
    """The actions (m, 3) that ``thrown_states`` maps to these throws, clipped to [-1, 1]."""
    low, high = config.launch_angle_range
    actions = np.stack(
        (
            2.0 * speed / config.max_speed - 1.0,
            2.0 * (direction - low) / (high - low) - 1.0,
            spin / config.max_spin if config.max_spin > 0 else np.zeros_like(spin),
        ),
        axis=-1,
    )
    return np.clip(actions, -1.0, 1.0)


# -- the stack -------------------------------------------------------------------------------------------
def tops(states: np.ndarray, half: np.ndarray) -> np.ndarray:
    """(..., k) height of each box's highest corner [m]: y + hx |sin a| + hy |cos a| (``half`` (..., k, 2))."""
    angle = states[..., layout.ANGLE]
    return states[..., layout.Y] + half[..., 0] * np.abs(np.sin(angle)) + half[..., 1] * np.abs(np.cos(angle))


def on_target(states: np.ndarray, target_x, config: StackConfig) -> np.ndarray:
    """(..., k) whether each box's centre lies within ``target_radius`` of the target x (a scalar or (...,))."""
    return np.abs(states[..., layout.X] - np.asarray(target_x)[..., None]) <= config.target_radius


def stack_heights(states: np.ndarray, half: np.ndarray, target_x, config: StackConfig) -> np.ndarray:
    """(...) the stack's height: the highest top of the boxes on the target, 0 without any [m]."""
    if states.shape[-2] == 0:
        return np.zeros(states.shape[:-2])
    return np.where(on_target(states, target_x, config), tops(states, half), 0.0).max(axis=-1, initial=0.0)


@dataclass
class ThrowOutcomes:
    """What m throws did, (m,) arrays (``score_throws``)."""

    reward: np.ndarray
    terms: dict[str, np.ndarray]
    height: np.ndarray  # [m] the stack's height after the throw
    on_target: np.ndarray  # (m, k + 1) which boxes are on the target after it
    fell: np.ndarray
    at_rest: np.ndarray
    success: np.ndarray
    distance: np.ndarray  # [m] of the thrown box's centre from the target x


def score_throws(
    before: np.ndarray, after: np.ndarray, half: np.ndarray, at_rest: np.ndarray, target_x, config: StackConfig
) -> ThrowOutcomes:
    """Score m throws of box k onto scenes of k boxes: ``before`` ((m,) k, 6) the scene before it, ``after``
    (m, k + 1, 6) the scene once the throw came to rest (the thrown box last), ``half`` ((m,) k + 1, 2),
    ``at_rest`` (m,) whether every body rests, ``target_x`` a scalar or (m,). Rewards (the env's docstring):

        reward_height   = height_weight * (H_after - H_before)
        reward_distance = -distance_weight * max(|x_thrown - target_x| - target_radius, 0)
        reward_fall     = -fall_penalty * fell
        reward_success  = success_bonus * success   (only the last box of the hand can succeed)
    """
    k = before.shape[-2]
    half_before = half[..., :k, :]
    height_before = stack_heights(before, half_before, target_x, config)
    height = stack_heights(after, half, target_x, config)
    members = on_target(after, target_x, config)
    was_member = on_target(before, target_x, config)
    dropped = tops(before, half_before) - tops(after[:, :k], half_before) > config.fall_tolerance
    fell = np.any(was_member & (~members[:, :k] | dropped), axis=1)
    distance = np.abs(after[:, k, layout.X] - target_x)
    last = k + 1 == config.n_boxes
    needed = config.success_fraction * np.sum(2.0 * half[..., 1], axis=-1)
    success = last & at_rest & ~fell & members.all(axis=1) & (height >= needed)
    terms = {
        "reward_height": config.height_weight * (height - height_before),
        "reward_distance": -config.distance_weight * np.maximum(distance - config.target_radius, 0.0),
        "reward_fall": -config.fall_penalty * fell,
        "reward_success": config.success_bonus * success,
    }
    reward = terms["reward_height"] + terms["reward_distance"] + terms["reward_fall"] + terms["reward_success"]
    return ThrowOutcomes(
        reward=reward,
        terms=terms,
        height=height,
        on_target=members,
        fell=fell,
        at_rest=at_rest,
        success=success,
        distance=distance,
    )


# -- observation -----------------------------------------------------------------------------------------
def observe(states: np.ndarray, hand: np.ndarray, thrown, target_x, height, config: StackConfig) -> np.ndarray:
    """The float32 observations ((m,) obs_size) of scenes whose first ``thrown`` ((m,)) boxes are thrown: ``states``
    ((m,) n_boxes, 6), their rows the engine's, the hands ((m,) n_boxes, EPISODE_COLUMNS), the target x and the
    stack's ``height`` (scalars or (m,)); the layout is ``BODY_COLUMNS`` per box, then ``TAIL_COLUMNS``."""
    single = states.ndim == 2
    states, hand = (states[None], hand[None]) if single else (states, hand)
    m, n = states.shape[0], config.n_boxes
    thrown = np.broadcast_to(np.asarray(thrown), (m,))
    is_thrown = np.arange(n) < thrown[:, None]  # (m, n)
    angle = states[..., layout.ANGLE]
    bodies = np.zeros((m, n, BODY_SIZE))
    bodies[..., B_X : B_Y + 1] = states[..., layout.X : layout.Y + 1]
    bodies[..., B_COS], bodies[..., B_SIN] = np.cos(angle), np.sin(angle)
    bodies[..., B_VX : B_SPIN + 1] = states[..., layout.VX :]
    bodies[..., :B_LENGTH] *= is_thrown[..., None]
    bodies[..., B_LENGTH : B_MASS + 1] = hand[..., E_LENGTH : E_MASS + 1]
    bodies[..., B_THROWN] = is_thrown
    in_hand = thrown < n
    box = hand[np.arange(m), np.minimum(thrown, n - 1)] * in_hand[:, None]  # (m, EPISODE_COLUMNS), 0 when empty
    tail = np.zeros((m, TAIL_SIZE))
    tail[:, H_X], tail[:, H_Y] = box[:, E_RELEASE_X], box[:, E_RELEASE_Y]
    tail[:, H_COS] = np.cos(box[:, E_RELEASE_ANGLE]) * in_hand
    tail[:, H_SIN] = np.sin(box[:, E_RELEASE_ANGLE])
    tail[:, H_LENGTH : H_MASS + 1] = box[:, E_LENGTH : E_MASS + 1]
    tail[:, H_IN_HAND] = in_hand
    tail[:, G_TARGET_X], tail[:, G_TARGET_RADIUS], tail[:, G_HEIGHT] = target_x, config.target_radius, height
    tail[:, G_LEFT] = n - thrown
    observations = np.concatenate((bodies.reshape(m, -1), tail), axis=1).astype(np.float32)
    return observations[0] if single else observations


def observation_bounds(config: StackConfig, horizon: float) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) float32 bounds no observation leaves, for throws simulated ``horizon`` seconds at most.

    One throw gives a box of mass m at most m e of energy, e = max_speed^2 / 2 + (I/m)_max max_spin^2 / 2
    + g y_release_max, and contacts never add any, so the scene never holds more than E = n m_max e. Every
    body's speed is then below sqrt(2 E / m_min), its spin below sqrt(2 E / I_min), its centre below
    E / (m_min g) above the floor plus its corner radius, and it travels less than that speed times the
    whole episode's simulated time n * horizon from the hand. Each bound is ``task_columns.ENERGY_MARGIN`` times that;
    a column whose value is fixed gets bounds one float32 step either side of it; columns that are zero
    before a box is thrown (or after the last) include 0.
    """
    n = config.n_boxes
    (l_lo, l_hi), (w_lo, w_hi), (m_lo, m_hi) = config.box_length_range, config.box_width_range, config.mass_range
    gyration_max = (l_hi**2 + w_hi**2) / 12.0
    inertia_min = m_lo * (l_lo**2 + w_lo**2) / 12.0
    energy = (
        n
        * m_hi
        * (
            0.5 * config.max_speed**2
            + 0.5 * gyration_max * config.max_spin**2
            + config.gravity * config.release_height_range[1]
        )
    )
    margin = task_columns.ENERGY_MARGIN
    speed = margin * math.sqrt(2.0 * energy / m_lo)
    spin = margin * math.sqrt(2.0 * energy / inertia_min)
    reach = speed * n * horizon
    radius = config.largest_corner_radius
    y_high = margin * energy / (m_lo * config.gravity) + radius
    body_low = [config.release_x_range[0] - reach, -radius, -1, -1, -speed, -speed, -spin, l_lo, w_lo, m_lo, 0]
    body_high = [config.release_x_range[1] + reach, y_high, 1, 1, speed, speed, spin, l_hi, w_hi, m_hi, 1]
    hand_ranges = [
        config.release_x_range,
        config.release_height_range,
        (-1, 1),
        (-1, 1),
        config.box_length_range,
        config.box_width_range,
        config.mass_range,
        (0, 1),
    ]
    tail_low = [min(low, 0.0) for low, _ in hand_ranges] + [config.target_x_range[0], config.target_radius, 0.0, 0.0]
    tail_high = [max(high, 0.0) for _, high in hand_ranges] + [
        config.target_x_range[1],
        config.target_radius,
        y_high + radius,
        n,
    ]
    low = np.array(body_low * n + tail_low, dtype=np.float32)
    high = np.array(body_high * n + tail_high, dtype=np.float32)
    fixed = low == high
    low[fixed] = np.nextafter(low[fixed], np.float32(-np.inf))
    high[fixed] = np.nextafter(high[fixed], np.float32(np.inf))
    return low, high


def observation_names(config: StackConfig) -> tuple[str, ...]:
    return tuple(f"box {j} {name}" for j in range(config.n_boxes) for name in BODY_COLUMNS) + TAIL_COLUMNS


# -- the task, for the multi-throw core ------------------------------------------------------------------
STEP_INFO_KEYS = (
    *REWARD_TERMS,
    "stack_height",
    "stack_size",
    "fell",
    "at_rest",
    "success",
    "distance",
    "final_x",
    "final_y",
    "final_angle",
    "thrown",
    "sim_time",
    "n_steps",
)
"""The step's info keys (``BoxTossStackEnv``'s docstring says what each is)."""


class StackTask:
    """``BoxToss-Stack-v0`` for the multi-throw core (``multi_throw.MultiThrowFunctional``): an episode is a hand
    of boxes and a target (``episodes`` rows: the hand's ``EPISODE_COLUMNS`` per box, then the target x), each
    throw adds the next box of the hand to the scene, and the stack's height is carried from throw to throw
    (``memory`` column 0). Keyword arguments: ``STACK_ARGUMENTS``' but the rendering ones."""

    carries_bodies = True
    memory_size = 1

    def __init__(self, **kwargs: Any):
        self.config = config = make_stack_config(**kwargs)
        self.max_bodies = config.n_boxes
        self.episode_size = uniforms_per_episode(config)
        self.engine_config = EngineConfig(
            box_size=(config.box_length_range[1], config.box_width_range[1]),
            mass=config.mass_range[1],
            release=(0.0, config.release_height_range[1]),
            gravity=config.gravity,
            restitution=config.restitution,
            friction=config.friction,
            penalty_stiffness=config.penalty_stiffness,
            solver="robust",
            dt=config.dt,
            max_sim_time=config.max_sim_time,
            boxes_collide=True,
        )

    def hands(self, episodes: np.ndarray) -> np.ndarray:
        """(m, n_boxes, EPISODE_COLUMNS) the hands of ``episodes`` (a view)."""
        return episodes[:, :-1].reshape(len(episodes), self.config.n_boxes, EPISODE_COLUMNS)

    def targets(self, episodes: np.ndarray) -> np.ndarray:
        """(m,) the target x of ``episodes`` [m] (a view)."""
        return episodes[:, -1]

    def draw(self, uniforms: np.ndarray) -> np.ndarray:
        hand, target_x = episode_from_uniforms(uniforms, self.config)
        return np.concatenate((hand.reshape(len(uniforms), -1), target_x[:, None]), axis=1)

    def body_params(self, episodes: np.ndarray) -> np.ndarray:
        return body_params(self.hands(episodes), self.config)

    def release(self, episodes: np.ndarray, thrown: np.ndarray) -> np.ndarray:
        return self.hands(episodes)[np.arange(len(episodes)), thrown, E_RELEASE_X:]

    def throw_states(self, release: np.ndarray, actions: np.ndarray) -> np.ndarray:
        return thrown_states(release, actions, self.config)

    def observe(self, batch) -> np.ndarray:
        episodes = batch.episodes
        return observe(
            batch.state, self.hands(episodes), batch.thrown, self.targets(episodes), batch.memory[:, 0], self.config
        )

    def score(self, batch, at_rest: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Each env's throw of box k onto its scene of k boxes (``score_throws``, the envs grouped by k); the
        stack's height is kept for the next throw. Terminated: the stack fell, or the hand is empty."""
        n, targets = batch.n, self.targets(batch.episodes)
        reward, info = np.zeros(n), {key: np.zeros(n) for key in STEP_INFO_KEYS}
        for size in np.unique(batch.thrown).tolist():
            envs = np.flatnonzero(batch.thrown == size)
            after = batch.state[envs, :size]
            half = batch.params[envs, :size, layout.HALF_LENGTH : layout.HALF_WIDTH + 1]
            before = batch.before[envs, : size - 1]
            outcome = score_throws(before, after, half, at_rest[envs], targets[envs], self.config)
            stats = batch.stats[envs, :size]
            reward[envs] = outcome.reward
            for name, value in outcome.terms.items():
                info[name][envs] = value
            info["stack_height"][envs], info["stack_size"][envs] = outcome.height, outcome.on_target.sum(axis=1)
            info["fell"][envs], info["success"][envs], info["distance"][envs] = (
                outcome.fell,
                outcome.success,
                outcome.distance,
            )
            thrown = after[:, size - 1]
            info["final_x"][envs], info["final_y"][envs] = thrown[:, layout.X], thrown[:, layout.Y]
            info["final_angle"][envs] = (thrown[:, layout.ANGLE] + math.pi) % (2.0 * math.pi) - math.pi
            info["sim_time"][envs] = stats[:, 0, layout.END_TIME]
            info["n_steps"][envs] = stats[..., layout.N_STEPS].max(axis=1)
        info["at_rest"], info["thrown"] = at_rest, batch.thrown
        for key, dtype in (("stack_size", np.int64), ("thrown", np.int64), ("n_steps", np.int64)):
            info[key] = info[key].astype(dtype)
        for key in ("fell", "at_rest", "success"):
            info[key] = info[key].astype(bool)
        batch.memory[:, 0] = info["stack_height"]
        return reward, info, info["fell"] | (batch.thrown == self.config.n_boxes)

    def reset_info(self, batch) -> dict[str, np.ndarray]:
        hands = self.hands(batch.episodes)
        return {
            "target_x": self.targets(batch.episodes).copy(),
            "box_lengths": hands[..., E_LENGTH].copy(),
            "box_widths": hands[..., E_WIDTH].copy(),
            "box_masses": hands[..., E_MASS].copy(),
        }

    def observation_bounds(self, horizon: float) -> tuple[np.ndarray, np.ndarray]:
        return observation_bounds(self.config, horizon)

    def observation_names(self) -> tuple[str, ...]:
        return observation_names(self.config)
