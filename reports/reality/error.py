"""Trajectory error against the measured drops: simulate from the measured state a few frames before the
first impact, compare the poses frame by frame (the metric of ContactNets, Pfrommer et al. 2020: centre
position error and angle error against time).

The initial state of a drop is the least-squares fit of its free flight up to the start frame
(``data.fit_flight``: a parabola in z, lines in x and theta), so it carries no single frame's noise.
Our engine runs all the drops of a split as one scene of independent boxes, each with its own restitution
and friction, with the step ``FRAME / substeps`` (the poses compared on the 250 Hz frames).

The material is fitted on the training half (odd drop numbers; the first ``FIT_DROPS`` of them, the same for
every engine) by a grid search over restitution and friction (0, 0.2, ..., 1) of the mean error over the first
``FIT_FRAMES`` frames, refined once on a grid of 0.04 around the best point; the
effective gravity, when fitted, is the median free-flight acceleration of the training drops. Everything
is reported on the held-out half (even drop numbers).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from box_toss_env import physics
from box_toss_env.physics import Box, NonFiniteStateError, Scene

from . import data

HORIZONS = (20, 50, 150)  # frames after the start
FIT_FRAMES = 50
FIT_DROPS = 60
MASS = 0.05  # [kg] the square's mass does not change rigid impacts; with STIFFNESS it sets the penalty's rate
STIFFNESS = 1e3  # [N/m] a resting square sinks m g / k = 0.5 mm under the penalty
COARSE = np.linspace(0.0, 1.0, 6)
EARTH = -9.81


@dataclass(frozen=True)
class Material:
    restitution: float
    friction: float
    gravity: float = EARTH


@dataclass(frozen=True)
class Model:
    """One way of simulating the drops: an engine ("ours" with a solver, or a name in ``other_engines()``) and
    its step, ``substeps`` steps a frame."""

    engine: str = "ours"
    solver: str = "robust"
    substeps: int = 1

    @property
    def name(self) -> str:
        engine = f"ours, {self.solver}" if self.engine == "ours" else self.engine
        return f"{engine}, dt = 4 ms / {self.substeps}" if self.substeps > 1 else f"{engine}, dt = 4 ms"

    @property
    def dt(self) -> float:
        return data.FRAME / self.substeps


def split(drops: list[data.Drop]) -> tuple[list[data.Drop], list[data.Drop]]:
    """Training half (odd drop numbers) and held-out half (even)."""
    return [d for d in drops if d.number % 2], [d for d in drops if not d.number % 2]


def initial_states(drops: list[data.Drop]) -> np.ndarray:
    """(n, 6): x, y, angle, vx, vy, spin of each drop at its start frame, fitted to its free flight."""
    return np.array([data.fit_flight(d.pose, d.start)[0] for d in drops])


def measured(drops: list[data.Drop], frames: int) -> np.ndarray:
    """(n, frames + 1, 3) the measured poses from each start frame on (nan past the end of a recording)."""
    out = np.full((len(drops), frames + 1, 3), np.nan)
    for k, d in enumerate(drops):
        piece = d.pose[d.start : d.start + frames + 1]
        out[k, : len(piece)] = piece
    return out


def simulate(
    states: np.ndarray, material: Material | list[Material], model: Model, frames: int = max(HORIZONS)
) -> tuple[np.ndarray, float]:
    """(n, frames + 1, 3) poses on the frames from ``states`` (n, 6) with ``model``, and the wall time of the
    stepping [s]; nan poses where a run diverged."""
    if model.engine == "ours":
        return simulate_ours(states, material, model, frames)
    return simulate_other(states, material, model, frames)


def other_engines() -> dict:
    """``benchmarks.other_engines.ENGINES`` and Box2D v3 (``box2d_v3``), by name."""
    from benchmarks.other_engines import ENGINES

    from .box2d_v3 import Box2DV3Engine

    return {**ENGINES, Box2DV3Engine.name: Box2DV3Engine()}


def simulate_other(states, material, model, frames):
    """As ``simulate``, with an engine of ``benchmarks.other_engines``: one toss per drop, stepped from Python
    (the wall time includes reading the state after every step, as ``record=True`` does there)."""
    from benchmarks.other_engines import Toss

    engine = other_engines()[model.engine]
    materials = material if isinstance(material, list) else [material] * len(states)
    out = np.full((len(states), frames + 1, 3), np.nan)
    seconds = 0.0
    for k, (s, m) in enumerate(zip(states, materials, strict=True)):
        toss = Toss(
            length=data.SIDE,
            width=data.SIDE,
            mass=MASS,
            x=s[0],
            y=s[1],
            angle=s[2],
            vx=s[3],
            vy=s[4],
            omega=s[5],
            gravity=m.gravity,
            restitution=m.restitution,
            friction=m.friction,
        )
        result = engine.simulate_toss(toss, model.dt, frames * model.substeps, record=True)
        seconds += result.wall_seconds
        poses = result.states[:: model.substeps, :3]
        if np.isfinite(poses).all():
            out[k] = poses
    return out, seconds


def simulate_ours(
    states: np.ndarray, material: Material | list[Material], model: Model, frames: int = max(HORIZONS)
) -> tuple[np.ndarray, float]:
    """(n, frames + 1, 3) poses on the frames from ``states`` with our engine, and the run's wall time [s]
    (nan poses where the run diverged: the seed scheme at too large a step)."""
    materials = material if isinstance(material, list) else [material] * len(states)
    gravity = materials[0].gravity
    boxes = tuple(
        Box(
            length=data.SIDE,
            width=data.SIDE,
            mass=MASS,
            position=(s[0], s[1]),
            angle=s[2],
            velocity=(s[3], s[4]),
            spin=s[5],
            restitution=m.restitution,
            friction=m.friction,
        )
        for s, m in zip(states, materials, strict=True)
    )
    scene = Scene(boxes=boxes, dt=model.dt, gravity=gravity, penalty_stiffness=STIFFNESS, solver=model.solver)
    begin = time.perf_counter()
    try:
        result = physics.simulate(scene, steps=frames * model.substeps, record=True)
    except NonFiniteStateError:
        return np.full((len(states), frames + 1, 3), np.nan), time.perf_counter() - begin
    seconds = time.perf_counter() - begin
    return np.transpose(result.trajectory.state[:: model.substeps, :, :3], (1, 0, 2)).copy(), seconds


def errors(predicted: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position error [m] (distance between centres) and angle error [rad] (folded to the nearest quarter
    turn, the square's symmetry), each (n, frames + 1)."""
    position = np.hypot(*(predicted[:, :, :2] - truth[:, :, :2]).transpose(2, 0, 1))
    angle = np.abs(data.face_angle(predicted[:, :, 2] - truth[:, :, 2]))
    return position, angle


def loss(predicted: np.ndarray, truth: np.ndarray, frames: int = FIT_FRAMES) -> float:
    """Mean over drops and frames 1..frames of position error + HALF * angle error [m] (a corner's error,
    roughly); inf if any prediction diverged."""
    position, angle = errors(predicted[:, 1 : frames + 1], truth[:, 1 : frames + 1])
    value = float(np.nanmean(position + data.HALF * angle))
    return value if np.isfinite(predicted).all() else math.inf


def fit_material(
    drops: list[data.Drop], model: Model, gravity: float = EARTH, grid: np.ndarray = COARSE
) -> tuple[Material, float]:
    """The restitution and friction on ``grid`` (then a grid of a fifth of its spacing around the best) that
    minimise ``loss`` on ``drops``; returns it with its loss."""
    states, truth = initial_states(drops), measured(drops, FIT_FRAMES)

    def search(restitutions, frictions):
        points = [Material(float(e), float(mu), gravity) for e in restitutions for mu in frictions]
        # every grid point's drops in one scene: one compiled run per grid, not one per point
        n = len(states)
        predicted, _ = simulate(
            np.tile(states, (len(points), 1)), [p for p in points for _ in range(n)], model, FIT_FRAMES
        )
        losses = [loss(predicted[k * n : (k + 1) * n], truth) for k in range(len(points))]
        best = int(np.argmin(losses))
        return points[best], losses[best]

    best, _ = search(grid, grid)
    step = (grid[1] - grid[0]) / 5
    fine = np.arange(-2, 3) * step
    best, value = search(np.clip(best.restitution + fine, 0.0, 1.0), np.clip(best.friction + fine, 0.0, 10.0))
    return best, value


def fitted_gravity(drops: list[data.Drop]) -> float:
    """Median free-flight vertical acceleration of ``drops`` [m/s^2]."""
    return float(np.median([d.flight_gravity for d in drops]))


@dataclass
class Evaluation:
    """One model with one material on the held-out drops."""

    model: Model
    material: Material
    position: np.ndarray  # (n, frames + 1) [m]
    angle: np.ndarray  # (n, frames + 1) [rad]
    seconds: float  # wall time of the run [s]
    steps: int  # time steps per drop
    predicted: np.ndarray | None = None  # (n, frames + 1, 3) the simulated poses

    def at(self, frame: int, statistic=np.nanmedian) -> tuple[float, float]:
        return float(statistic(self.position[:, frame])), float(statistic(self.angle[:, frame]))

    def mean_over(self, frames: int) -> tuple[float, float]:
        """Mean over drops and frames 1..frames."""
        return float(np.nanmean(self.position[:, 1 : frames + 1])), float(np.nanmean(self.angle[:, 1 : frames + 1]))


def evaluate(
    drops: list[data.Drop], model: Model, material: Material, frames: int = max(HORIZONS), floorless: bool = False
) -> Evaluation:
    """``model`` with ``material`` on ``drops``; ``floorless``: the free-flight parabola instead (no floor, the
    baseline that shows when the impacts start to matter)."""
    states, truth = initial_states(drops), measured(drops, frames)
    if floorless:
        t = np.arange(frames + 1) * data.FRAME
        predicted = np.stack(
            [
                states[:, [0]] + states[:, [3]] * t,
                states[:, [1]] + states[:, [4]] * t + 0.5 * material.gravity * t**2,
                states[:, [2]] + states[:, [5]] * t,
            ],
            axis=2,
        )
        seconds = 0.0
    else:
        predicted, seconds = simulate(states, material, model, frames)
    position, angle = errors(predicted, truth)
    return Evaluation(model, material, position, angle, seconds, frames * model.substeps, predicted)


def noise_floor(drops: list[data.Drop]) -> dict[str, float]:
    """Frame-to-frame noise of the data against itself: at rest, the white-noise sigma from second differences
    (var(p[n+1] - 2 p[n] + p[n-1]) = 6 sigma^2), over the last REST_FRAMES frames of the drops at rest; in
    flight, the RMS residual of the free-flight fits (position: x and z together)."""
    rest, flight_position, flight_angle = [], [], []
    for d in drops:
        last = d.pose[-data.REST_FRAMES :]
        if np.abs(np.diff(last[:, :2], axis=0)).max() < data.REST_MOTION:
            rest.append(np.sqrt(np.mean(np.diff(last, 2, axis=0) ** 2, axis=0) / 6))
        state, _, _ = data.fit_flight(d.pose, d.start)
        t = (np.arange(d.start + 1) - d.start) * data.FRAME
        x = state[0] + state[3] * t
        z = state[1] + state[4] * t + 0.5 * d.flight_gravity * t**2
        th = state[2] + state[5] * t
        flight = d.pose[: d.start + 1]
        flight_position.append(np.sqrt(np.mean((flight[:, 0] - x) ** 2 + (flight[:, 1] - z) ** 2)))
        flight_angle.append(np.sqrt(np.mean((flight[:, 2] - th) ** 2)))
    rest = np.array(rest) if rest else np.full((1, 3), np.nan)
    return {
        "rest position": float(np.median(np.hypot(rest[:, 0], rest[:, 1]))),
        "rest angle": float(np.median(rest[:, 2])),
        "flight position": float(np.median(flight_position)),
        "flight angle": float(np.median(flight_angle)),
    }


def first_bounce(poses: np.ndarray, impact: int) -> tuple[float, float, float]:
    """Centre vertical velocity before and after the impact at frame ``impact`` of ``poses`` (T, 3), each the mean
    over two frames that exclude the impact frame's neighbours (frames impact-3..impact-1, impact+1..impact+3),
    and the spin after it [m/s, m/s, rad/s]."""
    before = (poses[impact - 1, 1] - poses[impact - 3, 1]) / (2 * data.FRAME)
    after = (poses[impact + 3, 1] - poses[impact + 1, 1]) / (2 * data.FRAME)
    spin = (poses[impact + 3, 2] - poses[impact + 1, 2]) / (2 * data.FRAME)
    return float(before), float(after), float(spin)
