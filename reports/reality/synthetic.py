"""Synthetic square drops in the format of the measured ones, made by our own engine: the tests' fixture.

``write_drops(folder, n)`` simulates ``n`` drops of the 0.06 m square with the robust solver (restitution
``e``, friction ``mu``, gravity ``g``), samples them at 250 Hz for 200 frames and writes them as the
measured files are: the frame offsets of the rig added (centre ``HEIGHT_OFFSET`` too high, angle
``ANGLE_OFFSET``), Gaussian noise of ``noise`` m on positions and ``noise / HALF`` rad on the angle, the
angle wrapped into [-pi/4, pi/4) as the tracker reports a square, and velocities as raw backward
differences. Known values in, so the tests can check the cleaning and the fit get them back.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from box_toss_env.physics import Box, Scene, simulate

from . import data

HEIGHT_OFFSET = 1.5e-3  # [m] the rig reads the resting square 31.5 mm high
ANGLE_OFFSET = math.radians(-1.91)  # [rad] and tilted by this much
MASS = 0.05  # [kg]
STIFFNESS = 1e3  # [N/m]


def simulated_drops(
    n: int, seed: int = 0, e: float = 0.4, mu: float = 0.3, g: float = -9.81, substeps: int = 4
) -> np.ndarray:
    """(n, 200, 3) poses x, z, theta at 250 Hz of drops like the rig's: released 0.10-0.16 m high, falling,
    moving sideways and spinning a little, at any angle; no offsets, no noise."""
    rng = np.random.default_rng(seed)
    boxes = tuple(
        Box(
            length=data.SIDE,
            width=data.SIDE,
            mass=MASS,
            position=(float(rng.uniform(-0.4, -0.2)), float(rng.uniform(0.10, 0.16))),
            angle=float(rng.uniform(-math.pi, math.pi)),
            velocity=(float(rng.uniform(-0.6, 0.6)), float(rng.uniform(-2.3, -1.5))),
            spin=float(rng.uniform(-5.0, 5.0)),
            restitution=e,
            friction=mu,
        )
        for _ in range(n)
    )
    scene = Scene(boxes=boxes, dt=data.FRAME / substeps, gravity=g, penalty_stiffness=STIFFNESS)
    result = simulate(scene, steps=(data.FRAMES - 1) * substeps, record=True)
    return np.transpose(result.trajectory.state[::substeps, :, :3], (1, 0, 2)).copy()


def measured_like(pose: np.ndarray, rng: np.random.Generator, noise: float) -> np.ndarray:
    """One drop's (200, 6) table as the rig writes it, from its true (200, 3) poses."""
    read = pose.copy()
    read[:, 1] += HEIGHT_OFFSET
    read[:, 2] += ANGLE_OFFSET
    read[:, :2] += rng.normal(0.0, noise, size=(len(pose), 2))
    read[:, 2] += rng.normal(0.0, noise / data.HALF, size=len(pose))
    read[:, 2] = data.face_angle(read[:, 2])
    velocity = np.zeros_like(read)
    velocity[1:] = np.diff(read, axis=0) * data.FPS
    return np.hstack([read, velocity])


def write_drops(folder: Path, n: int = 24, seed: int = 0, noise: float = 3e-5, **material) -> np.ndarray:
    """Write ``traj_1.csv`` .. ``traj_n.csv`` into ``folder``; returns the true poses (n, 200, 3)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    poses = simulated_drops(n, seed, **material)
    rng = np.random.default_rng(seed + 1)
    for k, pose in enumerate(poses, start=1):
        data.write_csv(folder / data.file_name(k), measured_like(pose, rng, noise))
    return poses
