"""What the floor-only solver's stages pass one another: a box's motion, its constants, the step's settings and
the work arrays, each a named tuple (compiled as plain scalars and arrays: no cost over passing them one by one).
"""

from typing import NamedTuple

import numpy as np


class Motion(NamedTuple):
    """A box's pose and velocity at one instant, with its angle's cosine and sine."""

    x: float  # [m]
    y: float  # [m]
    angle: float  # [rad]
    vx: float  # [m/s]
    vy: float  # [m/s]
    spin: float  # [rad/s]
    cos_a: float
    sin_a: float


class BoxConstants(NamedTuple):
    """What stays of a box through a run: its half extents, inverse mass and inertia, its floor contact's material
    (``contact_law``), its corner radius and the contact tolerances at its size."""

    hx: float  # [m]
    hy: float  # [m]
    inv_mass: float  # [1/kg]
    inv_inertia: float  # [1/(kg m^2)]
    restitution: float  # [-]
    friction: float  # [-] Coulomb coefficient against the floor (0 without friction)
    stiffness: float  # [N/m] penalty
    radius: float  # [m] sqrt(hx^2 + hy^2)
    tolerance: float  # [m] a corner this close touches (``tunables.CONTACT_TOLERANCE``)
    simultaneous: float  # [m] corners this close in height hit at once (``tunables.SIMULTANEOUS_TOLERANCE``)


class FloorSettings(NamedTuple):
    """The scene's settings as the floor-only stages read them, and the kernel's compile-time switches."""

    dt: float  # [s]
    gravity: float  # [m/s^2]
    until_rest: bool
    threshold: float  # [m/s] restitution threshold
    sleep_speed: float  # [m/s]
    sleep_time: float  # [s]
    slop: float  # [m] penetration slop
    use_penalty: bool
    use_friction: bool
    record: bool


class CornerWork(NamedTuple):
    """The corner work arrays of ``contact_solver``: the corners' rows, their Delassus matrix, their indices."""

    corners: np.ndarray  # (CORNER_ROWS, MAX_CORNERS)
    k: np.ndarray  # (MAX_CORNERS, MAX_CORNERS)
    ids: np.ndarray  # (MAX_CORNERS,) int64


class Recording(NamedTuple):
    """Where a recorded run writes: the states on the grid and the impacts (empty arrays when not recording)."""

    trajectory: np.ndarray  # (max_steps + 1, n, STATE_SIZE)
    events: np.ndarray  # (n, MAX_EVENTS, EVENT_SIZE)
