"""The BoxToss task as pure, batch-first numpy functions.

Every function works on a leading batch dimension ``n`` (a single environment is a batch of one),
so the single env (``box_toss.BoxTossEnv``) and the batched vector env share this one copy of the
task logic. The physics itself is the engine's (``box_toss_env.physics``); this module only says
what is thrown, where it should land and how a landing is scored:

1. ``sample_episodes``: draw release poses, targets and (optionally randomised) dynamics from one
   ``np.random.Generator`` (one call per batch, so a seed fixes every episode);
2. ``check_actions`` and ``actions_to_throws``: validate actions in [-1, 1] and map them to the
   launch speed, direction and spin; ``write_initial_states`` puts the box in the hand, thrown;
3. ``observe``: body state and target as float32, inside ``observation_bounds``;
4. ``reward_terms``: the reward of a landing, its named terms and success.

With ``base_box`` (``BoxToss-OnBox-v0``) every episode also has a base box resting on the floor, which the
thrown box must come to rest on: the base stands centred at the target x, its length and height are drawn
per episode, and the engine steps the two boxes together with box-box contact. An env's bodies are then
consecutive rows of the engine's arrays, its thrown box first (``thrown_rows``, ``base_rows``); the
functions above take the thrown box's rows, and the base's where it matters (``write_base_states``,
``observe``, ``reward_terms``).

Faces are numbered by their outward normal in the body frame (as in ``physics.face_down`` and the
renderer): 0 = local -y, 1 = +x, 2 = +y, 3 = -x. The box's length runs along local x, so faces 0
and 2 are its long sides and faces 1 and 3 its short ends. Face f is down when the box's angle is
-f pi/2 (mod 2 pi).
"""

from __future__ import annotations

import math

import numpy as np

from box_toss_env.envs.task_columns import (
    _FACE_SET_TABLE,
    ACTION_SIZE,
    ENERGY_MARGIN,
    EP_BASE_HEIGHT,
    EP_BASE_LENGTH,
    EP_FRICTION,
    EP_MASS,
    EP_RELEASE,
    EP_RESTITUTION,
    EP_TARGET_FACES,
    EP_TARGET_X,
    FACE_SET_NAMES,
    FACE_SETS,
    MIXED_KINDS,
    OBS_SIZE,
    OBS_SIZE_WITH_DYNAMICS,
    OBS_TARGET_X,
    QUARTER_TURN,
    U_TARGET_FACE,
    U_TARGET_KIND,
)
from box_toss_env.envs.task_config import (
    Episodes,
    TaskConfig,
)
from box_toss_env.physics import layout


# -- 1. sampling ---------------------------------------------------------------------------------
def sample_episodes(rng: np.random.Generator, config: TaskConfig, out: Episodes) -> Episodes:
    """Draw ``len(out.data)`` episodes into ``out`` (of ``config.episode_size`` columns) with one call to
    ``rng`` and return it (``episodes_from_uniforms`` of ``rng.random(out.data.shape)``)."""
    return episodes_from_uniforms(rng.random(out.data.shape), config, out)


def episodes_from_uniforms(u: np.ndarray, config: TaskConfig, out: Episodes) -> Episodes:
    """The episodes (written into ``out`` and returned) that the uniform variates ``u`` (n,
    episode_size) in [0, 1) stand for: each value is uniform over its range (release x, height and
    angle, target x, mass, friction, restitution; with a base box its length and height); the
    target faces follow ``config.target_face`` (see ``TARGET_FACE_KINDS``). ``u`` may be ``out.data``
    itself (the episodes are then drawn in place)."""
    low, span = config.episode_low_span
    faces = target_face_sets(config.target_face, u[:, U_TARGET_KIND], u[:, U_TARGET_FACE])  # before u changes
    np.multiply(u, span, out=out.data)
    out.data += low
    out.data[:, EP_TARGET_FACES] = faces
    return out


def target_face_sets(kind: str, u_kind: np.ndarray, u_face: np.ndarray) -> np.ndarray:
    """(n, 4) masks of the faces that may end down, for the target kind ``kind``.

    ``u_kind`` and ``u_face`` (n,) are uniform in [0, 1): ``u_face`` picks the face of "exact"
    targets, ``u_kind`` the kind of "mixed" ones (``MIXED_KINDS``).
    """
    if kind in FACE_SETS:
        return _FACE_SET_TABLE[FACE_SET_NAMES.index(kind)]  # broadcasts over the batch
    one_face = np.minimum((u_face * 4).astype(np.int64), 3)
    masks = np.zeros((u_face.shape[0], 4))
    masks[np.arange(u_face.shape[0]), one_face] = 1.0
    if kind == "mixed":
        kinds = np.minimum((u_kind * len(MIXED_KINDS)).astype(np.int64), len(MIXED_KINDS) - 1)
        is_set = kinds < len(_FACE_SET_TABLE)
        masks[is_set] = _FACE_SET_TABLE[kinds[is_set]]
    return masks


def describe_target_faces(target_faces: np.ndarray) -> str:
    """A short label for one (4,) mask: "any face", "a long side", "a short end" or "face 2"."""
    mask = tuple(float(v) for v in target_faces)
    for kind, label in (("any", "any face"), ("long_side", "a long side"), ("short_end", "a short end")):
        if mask == FACE_SETS[kind]:
            return label
    return "face " + " or ".join(str(f) for f in range(4) if mask[f])


def thrown_rows(array: np.ndarray, config: TaskConfig) -> np.ndarray:
    """The thrown boxes' rows (n, ...) of an engine array (n * bodies_per_env, ...): a view (``array``
    itself without a base box)."""
    return array[:: config.bodies_per_env]


def base_rows(array: np.ndarray, config: TaskConfig) -> np.ndarray:
    """The base boxes' rows (n, ...) of an engine array (n * 2, ...) of a task with ``base_box``: a view."""
    return array[1 :: config.bodies_per_env]


def write_body_params(params: np.ndarray, episodes: Episodes, config: TaskConfig) -> np.ndarray:
    """Fill the engine's body parameters (n * bodies_per_env, layout.PARAM_SIZE) for the drawn
    dynamics (and base boxes: same friction, restitution and stiffness as the thrown box)."""
    mass = episodes.data[:, EP_MASS]
    thrown = thrown_rows(params, config)
    half = box_half_sizes(episodes, config)
    thrown[:, layout.HALF_LENGTH] = half[:, 0]
    thrown[:, layout.HALF_WIDTH] = half[:, 1]
    thrown[:, layout.MASS] = mass
    thrown[:, layout.INERTIA] = mass * (half[:, 0] ** 2 + half[:, 1] ** 2) / 3.0
    thrown[:, layout.RESTITUTION] = episodes.data[:, EP_RESTITUTION]
    thrown[:, layout.FRICTION] = episodes.data[:, EP_FRICTION]
    thrown[:, layout.STIFFNESS] = config.penalty_stiffness
    if config.base_box:
        base = base_rows(params, config)
        half = 0.5 * episodes.base_size
        base[:, layout.HALF_LENGTH] = half[:, 0]
        base[:, layout.HALF_WIDTH] = half[:, 1]
        base[:, layout.MASS] = config.base_mass
        base[:, layout.INERTIA] = config.base_mass * (half[:, 0] ** 2 + half[:, 1] ** 2) / 3.0
        base[:, layout.RESTITUTION : layout.STIFFNESS + 1] = thrown[:, layout.RESTITUTION : layout.STIFFNESS + 1]
    return params


def box_half_sizes(episodes: Episodes, config: TaskConfig) -> np.ndarray:
    """(n, 2) half the thrown box's length and width [m] in each episode: drawn (``config.draws_box_size``), or the
    task's one size."""
    if config.draws_box_size:
        return 0.5 * episodes.data[:, list(config.box_size_columns)]
    return np.broadcast_to(np.array([config.half_length, config.half_width]), (len(episodes.data), 2))


def write_base_states(states: np.ndarray, episodes: Episodes) -> np.ndarray:
    """The engine states (n, 6) of base boxes at rest on the floor, centred at the target x, level
    (angle 0: the length along the floor)."""
    states[:, layout.X] = episodes.data[:, EP_TARGET_X]
    states[:, layout.Y] = 0.5 * episodes.data[:, EP_BASE_HEIGHT]
    states[:, layout.ANGLE :] = 0.0
    return states


# -- 2. actions ----------------------------------------------------------------------------------
def check_actions(actions, shape: tuple[int, ...]) -> np.ndarray:
    """Actions as a float64 (n, 3) array clipped to [-1, 1]; a TypeError for values that are not real
    numbers (strings, booleans, complex numbers), a ValueError for a shape other than ``shape`` ((3,)
    for a single env, (n, 3) for a batch) or a non-finite value (NaN, inf)."""
    try:
        array = np.asarray(actions)
    except (TypeError, ValueError):
        raise ValueError(
            f"action must be an array of {ACTION_SIZE} finite numbers in [-1, 1] "
            f"(speed, launch angle, spin), got {actions!r}"
        ) from None
    if array.dtype.kind not in "iuf":
        raise TypeError(f"action must hold real numbers (int or float), got an array of {array.dtype}: {actions!r}")
    array = array.astype(np.float64, copy=False)
    if array.shape != shape:
        raise ValueError(
            f"action must have shape {shape} (speed, launch angle, spin, each in [-1, 1]), got shape {array.shape}"
        )
    finite = np.isfinite(array)
    if not finite.all():
        if array.ndim == 1:
            raise ValueError(f"action must be finite (no NaN or inf), got {array.tolist()}")
        bad = np.flatnonzero(~finite.reshape(len(array), -1).all(axis=1))
        raise ValueError(
            f"action must be finite (no NaN or inf): row {bad[0]} is {array[bad[0]].tolist()}"
            + (f" ({len(bad)} such rows)" if len(bad) > 1 else "")
        )
    return np.minimum(np.maximum(array.reshape(-1, ACTION_SIZE), -1.0), 1.0)


def actions_to_throws(actions: np.ndarray, config: TaskConfig) -> np.ndarray:
    """(n, 3) launch speed [m/s], launch angle above the horizontal [rad] and spin [rad/s] of
    actions (n, 3) in [-1, 1], each mapped linearly:

        speed = max_speed (a0 + 1) / 2,   theta = theta_lo + (theta_hi - theta_lo) (a1 + 1) / 2,
        spin = max_spin a2.
    """
    scale, offset = config.action_scale_offset
    throws = actions * scale
    throws += offset
    return throws


def throws_to_actions(throws: np.ndarray, config: TaskConfig) -> np.ndarray:
    """The inverse of ``actions_to_throws``: actions (n, 3) a = (throw - offset) / scale for throws
    (n, 3) of speed, launch angle and spin (a range of zero width maps to 0). Not clipped."""
    scale, offset = config.action_scale_offset
    throws = np.asarray(throws, dtype=np.float64)
    return np.divide(throws - offset, scale, out=np.zeros(throws.shape), where=scale > 0.0)


def write_initial_states(states: np.ndarray, episodes: Episodes, throws: np.ndarray | None) -> np.ndarray:
    """The engine states (n, 6) of boxes in the hand at the release pose, thrown with ``throws``
    (n, 3: speed, launch angle, spin; ``actions_to_throws``), i.e. moving at
    speed (cos theta, sin theta) and spinning; at rest when ``throws`` is None (before the throw)."""
    states[:, layout.X : layout.ANGLE + 1] = episodes.data[:, EP_RELEASE]
    if throws is None:
        states[:, layout.VX :] = 0.0
        return states
    speed, theta = throws[:, 0], throws[:, 1]
    np.multiply(speed, np.cos(theta), out=states[:, layout.VX])
    np.multiply(speed, np.sin(theta), out=states[:, layout.VY])
    states[:, layout.SPIN] = throws[:, 2]
    return states


# -- 3. observations -----------------------------------------------------------------------------
def observe(
    states: np.ndarray, episodes: Episodes, config: TaskConfig, base_states: np.ndarray | None = None
) -> np.ndarray:
    """A new float32 (n, obs_size) array: x, y, cos(angle), sin(angle), vx, vy, spin, target x,
    the four target-face flags, with ``observe_dynamics`` the mass, friction and restitution, with a drawn box size
    the box's length and width, and with ``base_box`` the base box's x, y, cos(angle), sin(angle) (from
    ``base_states`` (n, 6)), length and height."""
    angles = states[:, layout.ANGLE : layout.ANGLE + 1]
    size = OBS_SIZE_WITH_DYNAMICS if config.observe_dynamics else OBS_SIZE
    parts = [
        states[:, layout.X : layout.Y + 1],
        np.cos(angles),
        np.sin(angles),
        states[:, layout.VX :],
        episodes.data[:, EP_TARGET_X : EP_TARGET_X + size - OBS_TARGET_X],
    ]
    if config.draws_box_size:
        parts.append(episodes.data[:, list(config.box_size_columns)])
    if config.base_box:
        assert base_states is not None  # given with a base box
        base_angles = base_states[:, layout.ANGLE : layout.ANGLE + 1]
        parts += [base_states[:, layout.X : layout.Y + 1], np.cos(base_angles), np.sin(base_angles), episodes.base_size]
    return np.concatenate(parts, axis=1, dtype=np.float32)


def observation_bounds(config: TaskConfig, horizon: float) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) float32 bounds that no observation leaves, for throws simulated for at most ``horizon``
    seconds (the whole steps that cover ``max_sim_time``: a step longer than it simulates one step).

    The energy per unit mass of a throw is at most
        e = max_speed^2 / 2 + (I/m) max_spin^2 / 2 + g y_release_max,
    and contacts never add energy, so every speed is below sqrt(2 e), the spin below
    sqrt(2 e) / sqrt(I/m), the height below e / g, and the box cannot travel further than
    sqrt(2 e) horizon from where it was released. Each bound is ``ENERGY_MARGIN`` times that. With a drawn box
    size, I/m is the largest box's in e and the smallest box's under the spin's root, and the corner radius the
    largest box's. The centre cannot be lower than one corner radius below the floor (the whole box under it).
    A column whose value is fixed (low == high) gets bounds one float32 step either side of it.
    """
    energy = (
        0.5 * config.max_speed**2
        + 0.5 * config.gyration_radius_squared * config.max_spin**2
        + config.gravity * config.release_height_range[1]
    )
    speed = ENERGY_MARGIN * math.sqrt(2.0 * energy)
    spin = speed / math.sqrt(config.min_gyration_radius_squared)  # the smallest box spins fastest
    reach = speed * horizon
    low = [
        config.release_x_range[0] - reach,
        -config.corner_radius,
        -1.0,
        -1.0,
        -speed,
        -speed,
        -spin,
        config.target_x_range[0],
        0.0,
        0.0,
        0.0,
        0.0,
    ]
    high = [
        config.release_x_range[1] + reach,
        ENERGY_MARGIN * energy / config.gravity + config.corner_radius,
        1.0,
        1.0,
        speed,
        speed,
        spin,
        config.target_x_range[1],
        1.0,
        1.0,
        1.0,
        1.0,
    ]
    if config.observe_dynamics:
        low += [config.mass_range[0], config.friction_range[0], config.restitution_range[0]]
        high += [config.mass_range[1], config.friction_range[1], config.restitution_range[1]]
    if config.draws_box_size:
        low += [config.box_length_range[0], config.box_width_range[0]]
        high += [config.box_length_range[1], config.box_width_range[1]]
    if config.base_box:
        base_low, base_high = base_bounds(config, energy, horizon)
        low, high = low + base_low, high + base_high
    lows, highs = np.array(low, dtype=np.float32), np.array(high, dtype=np.float32)
    # a fixed quantity (target x, mass, friction or restitution not drawn) would have equal bounds, which
    # Gymnasium's checker flags as a degenerate space: its bounds are one float32 step either side instead
    fixed = lows == highs
    lows[fixed] = np.nextafter(lows[fixed], np.float32(-np.inf))
    highs[fixed] = np.nextafter(highs[fixed], np.float32(np.inf))
    return lows, highs


def base_bounds(config: TaskConfig, energy: float, horizon: float) -> tuple[list[float], list[float]]:
    """The base box's observation bounds (``observation_bounds``): it starts at rest in its lowest pose, so it can
    take at most the thrown box's energy m e: its speed stays below sqrt(2 e m / m_base), its height gain below
    e m / (m_base g)."""
    share = config.mass_range[1] / config.base_mass
    base_speed = ENERGY_MARGIN * math.sqrt(2.0 * energy * share)
    base_radius = 0.5 * math.hypot(config.base_length_range[1], config.base_height_range[1])
    low = [
        config.target_x_range[0] - base_speed * horizon,
        -base_radius,
        -1.0,
        -1.0,
        config.base_length_range[0],
        config.base_height_range[0],
    ]
    high = [
        config.target_x_range[1] + base_speed * horizon,
        base_radius + ENERGY_MARGIN * energy * share / config.gravity,
        1.0,
        1.0,
        config.base_length_range[1],
        config.base_height_range[1],
    ]
    return low, high


OBSERVATION_NAMES = (
    "x",
    "y",
    "cos(angle)",
    "sin(angle)",
    "vx",
    "vy",
    "spin",
    "target x",
    "target face 0",
    "target face 1",
    "target face 2",
    "target face 3",
    "mass",
    "friction",
    "restitution",
)
BASE_OBSERVATION_NAMES = ("base x", "base y", "base cos(angle)", "base sin(angle)", "base length", "base height")
BOX_SIZE_NAMES = ("box length", "box width")


def observation_names(config: TaskConfig) -> tuple[str, ...]:
    """The name of each observation column."""
    size = OBS_SIZE_WITH_DYNAMICS if config.observe_dynamics else OBS_SIZE
    box = BOX_SIZE_NAMES if config.draws_box_size else ()
    return OBSERVATION_NAMES[:size] + box + (BASE_OBSERVATION_NAMES if config.base_box else ())


def outside_bounds(obs: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(n,) bool: which observations (n, size) leave [low, high] somewhere."""
    return ((obs < low) | (obs > high)).any(axis=1)  # type: ignore[return-value]  # numpy's stubs: a bool


# -- 4. reward -----------------------------------------------------------------------------------
def faces_down(angles: np.ndarray) -> np.ndarray:
    """(n,) int index of the face that points down at each angle (as ``physics.face_down``)."""
    return np.rint(-angles / QUARTER_TURN).astype(np.int64) % 4


def wrap_angles(angles: np.ndarray) -> np.ndarray:
    """Angles wrapped to [-pi, pi)."""
    return (angles + math.pi) % (2.0 * math.pi) - math.pi


_FACE_TURNS_PLUS_PI = QUARTER_TURN * np.arange(4.0) + math.pi


def orientation_errors(angles: np.ndarray, target_faces: np.ndarray) -> np.ndarray:
    """(n,) [rad] in [0, pi]: how far the box must turn until one of its target faces is flat down,
    min over target faces f of |wrap(angle + f pi/2)|."""
    errors = np.abs((angles[:, None] + _FACE_TURNS_PLUS_PI) % (2.0 * math.pi) - math.pi)
    return np.where(target_faces > 0.0, errors, math.pi).min(axis=1)


REWARD_TERMS = ("reward_distance", "reward_orientation", "reward_success")


SUPPORT_TOLERANCE = 0.01
"""[m] With a base box, the thrown box rests on it when its lowest point is this close to the base's top."""


def half_extents_along_axes(angles: np.ndarray, half_length, half_width) -> tuple[np.ndarray, np.ndarray]:
    """(n,) half the horizontal and half the vertical extent [m] of boxes at ``angles``:
    hx |cos a| + hy |sin a| and hx |sin a| + hy |cos a|."""
    cos, sin = np.abs(np.cos(angles)), np.abs(np.sin(angles))
    return half_length * cos + half_width * sin, half_length * sin + half_width * cos


def base_top(base_states: np.ndarray, episodes: Episodes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, half length) [m] of the top of each base box (n,): its centre x, its highest point and half
    its horizontal extent (for a base lying on a face, the centre and half length of its top face)."""
    half_x, half_y = half_extents_along_axes(
        base_states[:, layout.ANGLE], 0.5 * episodes.data[:, EP_BASE_LENGTH], 0.5 * episodes.data[:, EP_BASE_HEIGHT]
    )
    return base_states[:, layout.X], base_states[:, layout.Y] + half_y, half_x


def landing_offsets(
    states: np.ndarray, episodes: Episodes, config: TaskConfig, base_states: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(dx, dy) [m]: the thrown box's centre x minus the target x, and (with a base box) its lowest point
    minus the top of the base box (where ``base_states`` ended), the base's centre x being the target
    x; dy = 0 without a base box."""
    if not config.base_box:
        return states[:, layout.X] - episodes.data[:, EP_TARGET_X], np.zeros(len(states))
    assert base_states is not None  # given with a base box
    top_x, top_y, _ = base_top(base_states, episodes)
    half = box_half_sizes(episodes, config)
    _, half_y = half_extents_along_axes(states[:, layout.ANGLE], half[:, 0], half[:, 1])
    return states[:, layout.X] - top_x, states[:, layout.Y] - half_y - top_y


def reward_terms(
    states: np.ndarray,
    at_rest: np.ndarray,
    episodes: Episodes,
    config: TaskConfig,
    base_states: np.ndarray | None = None,
):
    """Score landings. Returns (reward (n,), terms {name: (n,)}, success (n,) bool, distance (n,) [m],
    orientation error (n,) [rad]), with

        reward_distance    = -distance_weight    * distance
        reward_orientation = -orientation_weight * orientation error
        reward_success     =  success_bonus      * success
        reward             =  reward_distance + reward_orientation + reward_success,

    distance = |x - target_x|, and success meaning at rest, distance <= position_tolerance and a target
    face down. With a base box (``base_states`` (n, 6): where the base boxes ended), the target is the
    centre of the base's top: distance = sqrt(dx^2 + dy^2) with dx the centre's horizontal offset from the
    base's centre and dy the height of the box's lowest point above the base's top (``landing_offsets``),
    and success also needs the box to rest on the base, |dy| <= SUPPORT_TOLERANCE (|dx| <= position_tolerance
    keeps its centre over the top).
    """
    dx, dy = landing_offsets(states, episodes, config, base_states)
    distance = np.hypot(dx, dy) if config.base_box else np.abs(dx)
    orientation_error = orientation_errors(states[:, layout.ANGLE], episodes.data[:, EP_TARGET_FACES])
    success = at_rest & (distance <= config.position_tolerance) & (orientation_error < 0.5 * QUARTER_TURN)
    if config.base_box:
        success &= np.abs(dy) <= SUPPORT_TOLERANCE
    terms = {
        "reward_distance": 0.0 - config.distance_weight * distance,
        "reward_orientation": 0.0 - config.orientation_weight * orientation_error,
        "reward_success": config.success_bonus * success,
    }
    reward = terms["reward_distance"] + terms["reward_orientation"] + terms["reward_success"]
    return reward, terms, success, distance, orientation_error
