"""The measured square drops: reading a local folder of ``traj_N.csv`` files and cleaning them openly.

The data (DAIRLab/ImpactModeling, BSD-3, ``Wang/Wang-Mason Square/dice-data-processed``; measured on
Fazeli's MCube rig) are 500 drops of a 0.06 m square onto a flat surface in a vertical channel, tracked at
250 Hz, 200 frames each, one CSV per drop with the header ``x,z,th,vx,vz,vth`` (m, rad, m/s, rad/s).
The velocities in the files are raw backward differences (``v[n] = (p[n] - p[n-1]) * 250``); ``th`` is
not wrapped and jumps by multiples of pi/2 where the tracker swaps the square's (identical) faces.

Cleaning, in order (``clean``), each step counted in ``Cleaning``:

1. format: a file that is not 200 finite rows of the six columns is dropped;
2. angle: ``th`` is unwrapped with period pi/2 (the square looks the same after a quarter turn, so
   a jump of a quarter turn between frames is the tracker, not the square);
3. frame: the square at rest reads ``rest_height`` above the floor (31.5 mm, not the 30 mm of its half
   side) and ``rest_angle`` (-1.91 deg, not 0) on a face: both offsets, the medians over the drops at
   rest at their end, are subtracted from every frame (one correction for the whole set);
4. velocities: recomputed as backward differences of the cleaned poses, so the vtheta outliers of the
   files (up to 700 rad/s, from the unwrapping) are gone; the count of raw ``|vth| > 100 rad/s`` frames
   is reported;
5. first impact: the first frame where the lowest corner is within ``CONTACT_HEIGHT`` of the floor
   while falling, or within ``NEAR_HEIGHT`` while the vertical velocity jumps up by more than ``IMPACT_DV``
   in one frame (whichever comes first: the tracked corner height is only good to a millimetre or two),
   refined to the frame of least corner height among the next two;
6. a drop is dropped (and counted) if its first impact comes before ``MIN_FLIGHT_FRAMES`` of free
   flight (the initial state could not be fitted), if no impact is found, or if its free flight is
   not a parabola (residual RMS above ``MAX_FLIGHT_RESIDUAL``: a tracking glitch).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from box_toss_env.files import write_atomic

FPS = 250.0  # [Hz]
FRAME = 1.0 / FPS  # [s]
FRAMES = 200
SIDE = 0.06  # [m]
HALF = SIDE / 2
COLUMNS = ("x", "z", "th", "vx", "vz", "vth")
QUARTER = math.pi / 2
CONTACT_HEIGHT = 2e-3  # [m] a corner this close to the floor touches it (the rest pose spreads +-1 mm)
NEAR_HEIGHT = 6e-3  # [m] and one this close touches it if the fall stops
IMPACT_DV = 0.3  # [m/s] the fall stops: the vertical velocity rises by this much in one frame
MIN_FLIGHT_FRAMES = 8  # frames of free flight needed before the start frame
START_BEFORE_IMPACT = 3  # the simulations start this many frames before the first impact
MAX_FLIGHT_RESIDUAL = 1e-3  # [m] RMS of the free-flight parabola fit
REST_MOTION = 2e-4  # [m] largest frame-to-frame move of the last REST_FRAMES frames of a drop at rest
REST_FRAMES = 10
RAW_VTH_OUTLIER = 100.0  # [rad/s]


def file_name(number: int) -> str:
    return f"traj_{number}.csv"


@dataclass
class Drop:
    """One drop, cleaned: poses (x, z, theta) per frame and their backward-difference velocities."""

    number: int
    pose: np.ndarray  # (200, 3) x [m], z [m] (centre above the floor), theta [rad] unwrapped
    velocity: np.ndarray  # (200, 3) backward differences, the first row copied from the second
    impact: int = -1  # frame of the first impact
    flight_gravity: float = math.nan  # [m/s^2] parabola fitted to the free flight before the impact

    @property
    def start(self) -> int:
        return self.impact - START_BEFORE_IMPACT


@dataclass
class Cleaning:
    """What the cleaning did: the offsets it found and what it dropped, with the reasons."""

    files: int = 0
    rest_height: float = math.nan  # [m] median centre height at rest, as read
    rest_angle: float = math.nan  # [rad] median face angle at rest, as read
    rest_drops: int = 0  # drops at rest at their end, used for the two offsets
    angle_jumps: int = 0  # quarter turns removed by the unwrapping
    raw_vth_outliers: int = 0  # frames with |vth| > RAW_VTH_OUTLIER in the files
    dropped: dict[str, list[int]] = field(default_factory=dict)  # reason -> drop numbers

    def drop(self, reason: str, number: int) -> None:
        self.dropped.setdefault(reason, []).append(number)

    @property
    def n_dropped(self) -> int:
        return sum(len(v) for v in self.dropped.values())


def read_folder(folder: Path) -> tuple[dict[int, np.ndarray], Cleaning]:
    """The raw (200, 6) arrays of every ``traj_N.csv`` in ``folder`` by drop number, and a ``Cleaning``
    that counts the files dropped for their format. ValueError if the folder holds no such file."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"--data: {folder} is not a folder")
    paths = sorted(folder.glob("traj_*.csv"), key=lambda p: p.stem)
    cleaning = Cleaning()
    raw = {}
    for path in paths:
        suffix = path.stem.removeprefix("traj_")
        if not suffix.isdigit():  # trajSim_N.csv (simulated) and others do not match traj_<digits>
            continue
        number = int(suffix)
        cleaning.files += 1
        try:
            with path.open() as f:
                header = f.readline().strip().split(",")
                table = np.loadtxt(f, delimiter=",", ndmin=2)
        except (OSError, ValueError, UnicodeDecodeError):
            cleaning.drop("unreadable", number)
            continue
        if tuple(header) != COLUMNS or table.shape != (FRAMES, len(COLUMNS)) or not np.isfinite(table).all():
            cleaning.drop("not 200 finite rows of x,z,th,vx,vz,vth", number)
            continue
        raw[number] = table
    if not cleaning.files:
        raise ValueError(f"--data: no traj_N.csv files in {folder}")
    return dict(sorted(raw.items())), cleaning


def face_angle(theta):
    """theta folded into [-pi/4, pi/4): the tilt of the face nearest the floor."""
    return np.mod(np.asarray(theta) + QUARTER / 2, QUARTER) - QUARTER / 2


def lowest_corner(z, theta):
    """Height of the square's lowest corner [m] above the floor, for centre height z and angle theta."""
    tilt = face_angle(theta)
    return z - HALF * (np.abs(np.cos(tilt)) + np.abs(np.sin(tilt)))


def backward_differences(pose: np.ndarray) -> np.ndarray:
    velocity = np.empty_like(pose)
    velocity[1:] = np.diff(pose, axis=0) * FPS
    velocity[0] = velocity[1]
    return velocity


def rest_pose(raw: dict[int, np.ndarray]) -> tuple[float, float, int]:
    """Median centre height and face angle of the drops at rest at their end (the last REST_FRAMES frames
    move less than REST_MOTION between frames), and how many drops that is."""
    heights, angles = [], []
    for table in raw.values():
        last = table[-REST_FRAMES:, :3].copy()
        last[:, 2] = np.unwrap(last[:, 2], period=QUARTER)
        if (
            np.abs(np.diff(last[:, :2], axis=0)).max() < REST_MOTION
            and np.abs(np.diff(last[:, 2])).max() * HALF < REST_MOTION
        ):
            heights.append(np.median(last[:, 1]))
            angles.append(np.median(face_angle(last[:, 2])))
    if not heights:
        return HALF, 0.0, 0
    return float(np.median(heights)), float(np.median(angles)), len(heights)


def first_impact(pose: np.ndarray) -> int:
    """The frame of the first impact (see the module's step 5), or -1 if there is none."""
    corner = lowest_corner(pose[:, 1], pose[:, 2])
    vz = np.diff(pose[:, 1]) * FPS  # vz[n] is the velocity between frames n and n + 1
    for n in range(1, len(corner) - 1):
        near = corner[n] < NEAR_HEIGHT
        touching = corner[n] < CONTACT_HEIGHT and vz[n - 1] < 0
        stopped = vz[n] - vz[n - 1] > IMPACT_DV  # gravity changes vz by -0.04 m/s a frame
        if near and (touching or stopped):
            window = corner[n : n + 3]
            return n + int(np.argmin(window))
    return -1


def fit_flight(pose: np.ndarray, end: int) -> tuple[np.ndarray, float, float]:
    """Least squares over frames 0..end (included) of a parabola in z, lines in x and theta.

    Returns the fitted (pose, velocity) at frame ``end`` as one row (x, z, theta, vx, vz, vtheta), the
    fitted vertical acceleration [m/s^2] and the RMS residual of z [m]."""
    t = (np.arange(end + 1) - end) * FRAME  # time relative to frame `end`
    cz = np.polyfit(t, pose[: end + 1, 1], 2)
    cx = np.polyfit(t, pose[: end + 1, 0], 1)
    cth = np.polyfit(t, pose[: end + 1, 2], 1)
    residual = pose[: end + 1, 1] - np.polyval(cz, t)
    state = np.array([cx[1], cz[2], cth[1], cx[0], cz[1], cth[0]])
    return state, float(2 * cz[0]), float(np.sqrt(np.mean(residual**2)))


def clean(raw: dict[int, np.ndarray], cleaning: Cleaning) -> list[Drop]:
    """The cleaned drops (module docstring, steps 2 to 6); ``cleaning`` records what was done and dropped."""
    rest_height, rest_angle, cleaning.rest_drops = rest_pose(raw)
    cleaning.rest_height, cleaning.rest_angle = rest_height, rest_angle
    drops = []
    for number, table in raw.items():
        pose = table[:, :3].copy()
        cleaning.raw_vth_outliers += int(np.sum(np.abs(table[:, 5]) > RAW_VTH_OUTLIER))
        unwrapped = np.unwrap(pose[:, 2], period=QUARTER)
        cleaning.angle_jumps += int(np.sum(np.abs(np.round(np.diff(unwrapped - pose[:, 2]) / QUARTER))))
        pose[:, 2] = unwrapped - rest_angle
        pose[:, 1] -= rest_height - HALF
        drop = Drop(number, pose, backward_differences(pose))
        drop.impact = first_impact(pose)
        if drop.impact < 0:
            cleaning.drop("no impact found", number)
            continue
        if drop.start < MIN_FLIGHT_FRAMES - 1:
            cleaning.drop(
                f"first impact before {MIN_FLIGHT_FRAMES + START_BEFORE_IMPACT} frames of free flight", number
            )
            continue
        _, drop.flight_gravity, residual = fit_flight(pose, drop.start)
        if residual > MAX_FLIGHT_RESIDUAL:
            cleaning.drop(f"free flight not a parabola (RMS residual > {MAX_FLIGHT_RESIDUAL * 1e3:g} mm)", number)
            continue
        drops.append(drop)
    return drops


def load(folder: Path) -> tuple[list[Drop], Cleaning]:
    """Read and clean the drops of ``folder``."""
    raw, cleaning = read_folder(folder)
    return clean(raw, cleaning), cleaning


def write_csv(path: Path, table: np.ndarray) -> None:
    """One drop in the files' format (header ``x,z,th,vx,vz,vth``, 17 significant digits)."""
    lines = [",".join(COLUMNS)] + [",".join(repr(float(v)) for v in row) for row in table]
    write_atomic(path, "\n".join(lines) + "\n")
