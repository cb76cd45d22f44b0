"""What a run of a scene did, measured the same way in every engine from its states (x, y, angle, vx, vy, spin per
box, our frame): penetration, energy, bodies shot up, tunnelling, sleep, jitter and whether a structure stands.

``Track`` takes the states of one timed window sample by sample (every step of the engine) and sums it up in a
``Quality``. Penetration between two boxes is their separating-axis depth: the least, over the four face normals of
the pair, of the overlap of their projections (the distance that parts them; 0 if apart), so crossed thin boxes count
as well as a corner inside a face. Into the floor: the lowest corner below y = 0. Boxes are taken with sharp corners
(Box2D 2.3 rounds its corners by its 1 cm skin, which this counts as up to about 4 mm of overlap).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from box_toss_env.physics import Scene

DEEP = 0.5
"""A box is inside another (tunnelled) once their depth passes this share of the thinner box's thickness."""
JITTER_SPEED = 0.01
"""[m/s at the 40 x 20 cm box's scale, times the square root of the scale] a box still faster than this (its centre,
or a corner by its spin) at the end of a window in which the scene should lie still, and not asleep, is jittering
(our default ``sleep_speed``)."""
STAND_DRIFT = 0.01
"""[m at the box's scale] a built structure stands while every box stays this close to where it was built
(centre and corners)."""
ENERGY_SHARE = 1e-3
"""Energy is gained when the total rises above its start by more than this share of the energy above the lowest
pose (every box lying flat on the floor), plus 1e-9 J a body of float rounding."""


def box_arrays(scene: Scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(half extents (n, 2) [m], mass (n,) [kg], moment (n,) [kg m^2])."""
    half = np.array([(0.5 * b.length, 0.5 * b.width) for b in scene.boxes])
    return half, np.array([b.mass for b in scene.boxes]), np.array([b.inertia for b in scene.boxes])


@numba.njit(cache=True)
def corners(state: np.ndarray, half: np.ndarray) -> np.ndarray:
    """(n, 4, 2) world corners of every box."""
    n = state.shape[0]
    out = np.empty((n, 4, 2))
    for i in range(n):
        c, s = math.cos(state[i, 2]), math.sin(state[i, 2])
        for k, (sx, sy) in enumerate(((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0))):
            lx, ly = sx * half[i, 0], sy * half[i, 1]
            out[i, k, 0] = state[i, 0] + c * lx - s * ly
            out[i, k, 1] = state[i, 1] + s * lx + c * ly
    return out


@numba.njit(cache=True)
def pair_depth(points: np.ndarray, i: int, j: int, state: np.ndarray) -> float:
    """Separating-axis depth of boxes i and j (0 if apart) from their corners ``points``."""
    depth = np.inf
    for a in (i, j):
        c, s = math.cos(state[a, 2]), math.sin(state[a, 2])
        for nx, ny in ((c, s), (-s, c)):
            lo_i = lo_j = np.inf
            hi_i = hi_j = -np.inf
            for k in range(4):
                p = points[i, k, 0] * nx + points[i, k, 1] * ny
                q = points[j, k, 0] * nx + points[j, k, 1] * ny
                lo_i, hi_i = min(lo_i, p), max(hi_i, p)
                lo_j, hi_j = min(lo_j, q), max(hi_j, q)
            overlap = min(hi_i, hi_j) - max(lo_i, lo_j)
            if overlap <= 0.0:
                return 0.0
            depth = min(depth, overlap)
    return depth


@numba.njit(cache=True)
def overlaps(state: np.ndarray, half: np.ndarray, deep: np.ndarray) -> tuple[float, float]:
    """(deepest penetration between two boxes, deepest into the floor) [m]; sets ``deep[i]`` for every box inside
    another by more than DEEP of the thinner one's thickness or with its centre below the floor. Pairs from a sweep
    along x over the boxes' bounds."""
    n = state.shape[0]
    points = corners(state, half)
    low = np.empty((n, 2))
    high = np.empty((n, 2))
    floor = 0.0
    for i in range(n):
        for axis in range(2):
            low[i, axis], high[i, axis] = points[i, :, axis].min(), points[i, :, axis].max()
        floor = max(floor, -low[i, 1])
        if state[i, 1] < 0.0:
            deep[i] = True
    order = np.argsort(low[:, 0])
    between = 0.0
    for rank in range(n):
        i = order[rank]
        for other in range(rank + 1, n):
            j = order[other]
            if low[j, 0] > high[i, 0]:
                break
            if low[j, 1] > high[i, 1] or high[j, 1] < low[i, 1]:
                continue
            depth = pair_depth(points, i, j, state)
            between = max(between, depth)
            if depth > DEEP * 2.0 * min(half[i, 1], half[j, 1], half[i, 0], half[j, 0]):
                deep[i] = deep[j] = True
    return between, floor


def energy(state: np.ndarray, mass: np.ndarray, inertia: np.ndarray, gravity: float) -> float:
    """Kinetic and potential energy of every box, sum of 0.5 m |v|^2 + 0.5 I w^2 - m g y [J] (g < 0)."""
    speed2 = state[:, 3] ** 2 + state[:, 4] ** 2
    return float(0.5 * mass @ speed2 + 0.5 * inertia @ state[:, 5] ** 2 - gravity * mass @ state[:, 1])


@dataclass
class Quality:
    """A window's measures (nan where not measured). Lengths [m], energy [J], times [s] from the window's start."""

    penetration: float = 0.0  # deepest, box into box or into the floor, over every sample
    penetration_end: float = math.nan  # at the last sample
    energy_start: float = math.nan  # total energy at the start (potential from the floor)
    energy_gain: float = 0.0  # highest total energy above the start
    gains_energy: bool = False  # above ENERGY_SHARE of the energy above the lowest pose
    rise: float = 0.0  # the most any box rose above where it was at the start
    tunnelled: int = 0  # boxes found inside another or with their centre below the floor
    crossed: bool = False  # a thrown box passed the far side of the pile below its top
    asleep_at: float = math.nan  # first sample at which every box slept (nan: none did)
    asleep_end: int = 0  # boxes asleep at the end
    moving_end: int = 0  # boxes awake and faster than JITTER_SPEED at the end
    drift: float = math.nan  # the most any box moved (centre or corner) from its pose at the start
    top_drift: float = math.nan  # the same for the top box (highest at the start)
    samples: int = 0


@dataclass
class Track:
    """Accumulates a window's samples: ``add(state, asleep)`` after every step (``time`` from the window's start)."""

    scene: Scene
    start: np.ndarray  # (n, 6) at the window's start
    scale: float = 1.0
    thrown: int | None = None  # body thrown at the window's start: its crossing of the pile is checked
    quality: Quality = field(default_factory=Quality)

    def __post_init__(self) -> None:
        self.half, self.mass, self.inertia = box_arrays(self.scene)
        self.deep = np.zeros(self.scene.n_bodies, dtype=np.bool_)
        self.energy0 = energy(self.start, self.mass, self.inertia, self.scene.gravity)
        self.quality.energy_start = self.energy0
        lowest = float(-self.scene.gravity * self.mass @ self.half.min(axis=1))
        self.allowance = ENERGY_SHARE * max(self.energy0 - lowest, 0.0) + 1e-9 * self.scene.n_bodies
        self.pile = self.pile_bounds() if self.thrown is not None else None
        self.last_thrown = None if self.thrown is None else self.start[self.thrown, :2].copy()

    def pile_bounds(self) -> tuple[float, float]:
        """(x of the pile's far side, height of the pile's top over its last 0.6 m there) at the throw."""
        others = np.delete(np.arange(self.scene.n_bodies), self.thrown)
        points = corners(self.start[others], self.half[others])
        far = float(points[..., 0].max())
        near_far = points[..., 0].max(axis=1) > far - 0.6 * self.scale
        return far, float(points[near_far, :, 1].max())

    def add(self, state: np.ndarray, asleep: np.ndarray, time: float) -> None:
        q = self.quality
        between, floor = overlaps(state, self.half, self.deep)
        depth = max(between, floor)
        q.penetration = max(q.penetration, depth)
        q.penetration_end = depth
        gain = energy(state, self.mass, self.inertia, self.scene.gravity) - self.energy0
        q.energy_gain = max(q.energy_gain, gain)
        q.gains_energy = q.gains_energy or bool(gain > self.allowance)
        q.rise = max(q.rise, float((state[:, 1] - self.start[:, 1]).max()))
        q.tunnelled = int(self.deep.sum())
        if self.pile is not None and self.last_thrown is not None:
            x0, y0 = self.last_thrown
            x1, y1 = state[self.thrown, :2]
            q.crossed = q.crossed or bool(x0 <= self.pile[0] < x1 and min(y0, y1) < self.pile[1])
            self.last_thrown = state[self.thrown, :2].copy()
        if math.isnan(q.asleep_at) and asleep.all():
            q.asleep_at = time
        q.asleep_end = int(asleep.sum())
        speed = np.hypot(state[:, 3], state[:, 4]) + np.abs(state[:, 5]) * np.hypot(*self.half.T)
        q.moving_end = int(np.count_nonzero((speed > JITTER_SPEED * math.sqrt(self.scale)) & ~asleep))
        moved = self.displacement(state)
        q.drift = float(moved.max())
        q.top_drift = float(moved[int(np.argmax(self.start[:, 1]))])
        q.samples += 1

    def displacement(self, state: np.ndarray) -> np.ndarray:
        """(n,) how far each box moved from its start: its centre, plus its half diagonal times the turn."""
        turn = np.abs(np.remainder(state[:, 2] - self.start[:, 2] + math.pi, 2 * math.pi) - math.pi)
        return np.hypot(*(state[:, :2] - self.start[:, :2]).T) + turn * np.hypot(*self.half.T)

    @property
    def stands(self) -> bool:
        return bool(self.quality.drift <= STAND_DRIFT * self.scale)
