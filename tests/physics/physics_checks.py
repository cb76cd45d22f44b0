"""Quantities the physics tests measure on trajectories."""

import numpy as np

from box_toss_env.physics import Scene, Simulator, Trajectory, layout, make_settings, warm_start_memory


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


def advance_in_runs(scene: Scene, runs: int, steps: int, warm_start: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """(state, stats) of the scene after ``runs`` calls of ``steps`` steps each, with one warm start carried through
    the calls or none. Sleeping off: every body stepped at every step (a pair asleep at the start hands a falling box
    to the alone stage, which ends it by rounding elsewhere than the substeps do)."""
    simulator = Simulator.for_scene(scene, parallel=False)
    state, params = scene.initial_state(), scene.body_params()
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    warm = warm_start_memory(scene.n_bodies) if warm_start else None
    for _ in range(runs):
        simulator.run(state, params, make_settings(scene, steps, until_rest=False, sleep=False), stats, warm_start=warm)
    return state, stats
