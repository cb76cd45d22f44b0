"""Quantities the physics tests measure on trajectories."""

import numpy as np

from box_toss_env.physics import Scene, Trajectory


def energy(scene: Scene, trajectory: Trajectory, body: int = 0) -> np.ndarray:
    """Kinetic plus potential energy of one body at every recorded step [J]."""
    box = scene.boxes[body]
    v = trajectory.velocity[:, body]
    return (
        0.5 * box.mass * (v**2).sum(axis=1)
        + 0.5 * box.inertia * trajectory.spin[:, body] ** 2
        - box.mass * scene.gravity * trajectory.position[:, body, 1]
    )


def lowest_corner_height(scene: Scene, trajectory: Trajectory, body: int = 0) -> np.ndarray:
    box = scene.boxes[body]
    angle = trajectory.angle[:, body]
    reach = 0.5 * box.length * np.abs(np.sin(angle)) + 0.5 * box.width * np.abs(np.cos(angle))
    return trajectory.position[:, body, 1] - reach
