"""The stability report's rows of boxes that collide with one another: stacks, box-box impacts, mass ratios."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from box_toss_env.physics import NonFiniteStateError, Scene, layout, simulate

from . import cases
from .cases import STIFFNESS, corner_radius, dt_of
from .document import dt_label, sci
from .stability_checks import ENERGY_ROUNDING, SOLVERS, Check, Row


# -- boxes that collide with one another ------------------------------------------------------------------------
@dataclass
class BodiesRun:
    """A run of several boxes: the checks' figures over every grid state, or the reason there are none."""

    scene: Scene
    drift: float = math.nan  # largest |dx| + R |da| of any box from its start [m]
    overlap_boxes: float = math.nan  # deepest overlap of two boxes [m]
    overlap_floor: float = math.nan  # deepest penetration of a box into the floor [m]
    energy_rise: float = math.nan  # largest rise of the total energy above its start [J]
    kinetic_rise: float = math.nan  # largest step-to-step rise of the kinetic energy [J]
    kinetic_start: float = math.nan  # [J]
    momentum_change: np.ndarray | None = None  # (2,) end minus start, gravity's impulse removed [kg m/s]
    order_kept: bool = True  # ``order`` (below) held at every grid state
    end: np.ndarray | None = None  # (n, 6) final state
    error: str = ""

    @property
    def finite(self) -> bool:
        return not self.error

    def energy_allowance(self) -> float:
        """Rounding, plus M |g| times the deepest overlap: the potential energy a position correction may
        give back when it pushes the boxes apart."""
        mass = sum(box.mass for box in self.scene.boxes)
        start = float(cases.scene_energy(self.scene, self.scene.initial_state()[None])[0])
        return ENERGY_ROUNDING * abs(start) + mass * abs(self.scene.gravity) * self.overlap

    @property
    def overlap(self) -> float:
        """The deeper of the box-box and box-floor overlaps [m]."""
        return max(self.overlap_boxes, self.overlap_floor)

    def overlap_text(self) -> str:
        return f"overlap {sci(self.overlap_boxes)} m between boxes, {sci(self.overlap_floor)} m into the floor"


def run_bodies(
    scene: Scene, duration: float, order: Callable[[Scene, np.ndarray], np.ndarray] | None = None
) -> BodiesRun:
    """Run a scene of several boxes in one recorded call (restarting a run from its last state would wake
    sleeping boxes and drop the solver's warm start, which moves a stack) and check every grid state;
    ``order(scene, states) -> (T,) bool`` is a condition that must hold throughout (e.g. no box passed
    through another)."""
    run = BodiesRun(scene)
    try:
        result = simulate(scene, duration=duration, record=True)
    except NonFiniteStateError as error:
        run.error = f"non-finite at step {error.step}"
        return run
    states = result.trajectory.state
    if not np.isfinite(states).all():
        run.error = "non-finite"
        return run
    start = states[0]
    radius = np.array([corner_radius(box) for box in scene.boxes])
    moved = np.hypot(states[..., 0] - start[:, 0], states[..., 1] - start[:, 1])
    run.drift = float((moved + radius * np.abs(cases.wrap(states[..., 2] - start[:, 2]))).max())
    run.overlap_boxes, run.overlap_floor = cases.deepest_overlaps(scene, states)
    total = cases.scene_energy(scene, states)
    run.energy_rise = float(total.max() - total[0])
    kinetic = cases.scene_kinetic_energy(scene, states)
    run.kinetic_start = float(kinetic[0])
    run.kinetic_rise = float(np.diff(kinetic).max(initial=0.0))
    if order is not None:
        run.order_kept = bool(order(scene, states).all())
    run.end = states[-1].copy()
    mass = np.array([box.mass for box in scene.boxes])
    elapsed = float(result.end_time.max())
    run.momentum_change = (
        mass @ run.end[:, 3:5] - mass @ start[:, 3:5] - np.array([0.0, mass.sum() * scene.gravity * elapsed])
    )
    return run


def passed_through(scene: Scene, states: np.ndarray, along: int) -> np.ndarray:
    """(T,) True at the grid states where box 1 has just passed through box 0: the component of the line of
    centres along ``along`` (x or y) changed sign since the previous state while the two boxes' extents across
    it (their projections on the other axis, at their angles of that state) overlapped, so the boxes could not
    have gone round each other (two boxes thrown side by side, their centres passing at the same height, are
    not a pass-through)."""
    across = layout.Y if along == layout.X else layout.X
    d_along = states[:, 1, along] - states[:, 0, along]
    d_across = np.abs(states[:, 1, across] - states[:, 0, across])
    extent = np.zeros(states.shape[0])
    for b, box in enumerate(scene.boxes[:2]):
        cos, sin = np.abs(np.cos(states[:, b, 2])), np.abs(np.sin(states[:, b, 2]))
        if across == layout.X:
            extent += 0.5 * box.length * cos + 0.5 * box.width * sin
        else:
            extent += 0.5 * box.length * sin + 0.5 * box.width * cos
    near = d_across < extent
    flipped = np.zeros(states.shape[0], dtype=bool)
    flipped[1:] = (np.sign(d_along[1:]) != np.sign(d_along[:-1])) & near[1:] & near[:-1]
    return flipped


def stacks(sizes, exponents, duration: float) -> Row:
    criterion = (
        "finite; every box within 1 mm of where it started (|dx| + R |da|, every step; no settling allowed); "
        "the total energy never rises above its start (allowance: rounding and M g times the deepest overlap)"
    )
    declared = (
        f"stacks of {', '.join(str(n) for n in sizes)} boxes (`scenes.stack`), {duration:g} s, "
        f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s, k = {STIFFNESS:g} N/m"
    )

    def build():
        checks = []
        for n in sizes:
            for exponent in exponents:
                for solver in SOLVERS:
                    point = {"boxes": n, "dt": dt_label(exponent)}
                    run = run_bodies(cases.stack(n, dt=dt_of(exponent), solver=solver), duration)
                    if not run.finite:
                        checks.append(Check(point, solver, False, run.error))
                        continue
                    allowed = run.energy_allowance()
                    passed = run.drift < 1e-3 and run.energy_rise <= allowed
                    checks.append(
                        Check(
                            point,
                            solver,
                            passed,
                            f"drift {sci(run.drift)} m, energy rise "
                            f"{sci(max(run.energy_rise, 0.0))} J (allowed "
                            f"{sci(allowed)})",
                        )
                    )
        return Row("stacks", f"Stacks resting {duration:g} s", criterion, declared, checks)

    return build()


def body_impacts(speeds, exponents) -> Row:
    title = f"Box-box impacts at {' and '.join(f'{v:g}' for v in speeds)} m/s"
    criterion = (
        "finite; no tunnelling (from one step to the next the line of centres never flips along the impact "
        "direction while the boxes are within reach of each other across it, and both centres stay above "
        "the floor); overlap <= 1% of the box width (2 mm), between the boxes and into the floor; in "
        "flight (zero gravity) momentum kept to 1e-9 of m v and kinetic energy never rises from one step to "
        "the next; onto a box, the total energy never rises above its start (allowance as "
        "above)"
    )
    declared = (
        f"the toss box corner first (angle 0.3) at {', '.join(f'{v:g}' for v in speeds)} m/s into a level toss "
        f"box, in flight or falling onto it lying on the floor, e 0, mu 0.5, dt {dt_label(min(exponents))} to "
        f"{dt_label(max(exponents))} s"
    )

    def apart_in_flight(scene, states):
        return ~passed_through(scene, states, along=layout.X)

    def apart_on_floor(scene, states):
        return ~passed_through(scene, states, along=layout.Y) & (states[:, :, layout.Y] > 0.0).all(axis=1)

    def build():
        checks = []
        for speed in speeds:
            for onto_floor in (False, True):
                for exponent in exponents:
                    for solver in SOLVERS:
                        scene = cases.body_impact(speed, onto_floor, dt=dt_of(exponent), solver=solver)
                        point = {
                            "speed": f"{speed:g} m/s",
                            "where": "onto a box" if onto_floor else "in flight",
                            "dt": dt_label(exponent),
                        }
                        apart = apart_on_floor if onto_floor else apart_in_flight
                        run = run_bodies(scene, 2.0 if onto_floor else 0.5, apart)
                        if not run.finite:
                            checks.append(Check(point, solver, False, run.error))
                            continue
                        width = scene.boxes[0].width
                        measured = f"{'no tunnelling' if run.order_kept else 'TUNNELLED'}, {run.overlap_text()}"
                        passed = run.order_kept and run.overlap <= 0.01 * width
                        if onto_floor:
                            allowed = run.energy_allowance()
                            passed &= run.energy_rise <= allowed
                            measured += f", energy rise {sci(max(run.energy_rise, 0.0))} J (allowed {sci(allowed)})"
                        else:
                            scale = scene.boxes[1].mass * speed
                            momentum = float(np.abs(run.momentum_change).max()) / scale
                            rise = run.kinetic_rise / run.kinetic_start
                            passed &= momentum <= 1e-9 and rise <= ENERGY_ROUNDING
                            measured += f", momentum error {sci(momentum)} of m v, KE rise {sci(rise)} of KE0"
                        checks.append(Check(point, solver, passed, measured))
        return Row("body_impacts", title, criterion, declared, checks)

    return build()


def mass_ratio_stacks(ratio: float, orders, exponents, duration: float) -> Row:
    title = f"Mass ratio 1:{ratio:g} in a stack"
    criterion = (
        "finite; every box within 1 mm of where it started (every step); overlap <= 1% of the box width "
        "(2 mm), between the boxes and into the floor; the total energy never rises above its start "
        "(allowance as above)"
    )
    declared = (
        f"stacks of `scenes.stack` whose boxes weigh 2 kg or {ratio:g} times that ({', '.join(orders)}), "
        f"material unchanged, {duration:g} s, dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s"
    )

    def build():
        checks = []
        for order in orders:
            for exponent in exponents:
                for solver in SOLVERS:
                    scene = cases.mass_ratio_stack(ratio, order, dt=dt_of(exponent), solver=solver)
                    point = {"order": order, "dt": dt_label(exponent)}
                    run = run_bodies(scene, duration)
                    if not run.finite:
                        checks.append(Check(point, solver, False, run.error))
                        continue
                    allowed = run.energy_allowance()
                    passed = (
                        run.drift < 1e-3 and run.overlap <= 0.01 * scene.boxes[0].width and run.energy_rise <= allowed
                    )
                    checks.append(
                        Check(
                            point,
                            solver,
                            passed,
                            f"drift {sci(run.drift)} m, {run.overlap_text()}, "
                            f"energy rise {sci(max(run.energy_rise, 0.0))} J "
                            f"(allowed {sci(allowed)})",
                        )
                    )
        return Row("mass_ratio_stacks", title, criterion, declared, checks)

    return build()
