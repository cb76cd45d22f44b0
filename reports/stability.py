"""Stability on stiff and extreme cases: a matrix of scenes, each with a measurable pass criterion,
run for the seed scheme and the robust default.

    python -m reports.stability            # the full report: docs/stability.md, docs/figures/stability_map.png
    python -m reports.stability --quick    # a few points of each row, into build/reports/ (the tests run this)

Each row is a function returning a ``Row``: its criterion, the robust solver's declared range for it,
and one ``Check`` per parameter point and solver. Every point of every row lies inside the robust
solver's declared range (``DECLARED_RANGE``), so the robust default must pass them all; where it does
not, the row says FAIL and names the points. The seed scheme is run on the same points and shown as it is.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from box_toss_env.files import write_atomic
from box_toss_env.physics import Box, NonFiniteStateError, Scene, Simulator, layout, make_settings, scenes, simulate

from . import cases, document, fuzz
from .cases import STIFFNESS, corner_radius, dt_of, energy, kinetic_energy, lowest_corner
from .document import dt_label, sci, table
from .timing import Stopwatch

SOLVERS = ("robust", "seed")
DECLARED_RANGE = {
    "time step dt": "2^-14 to 2^-5 s",
    "penalty stiffness k": "1e2 to 1e9 N/m",
    "impact speed": "up to 200 m/s",
    "spin": "up to 600 rad/s",
    "aspect ratio": "up to 1:200",
    "mass": "1e-3 to 1e3 kg (material unchanged)",
    "restitution, friction": "e in [0, 1], mu in [0, 1.5]",
    "distance from the origin": "up to 1e5 m",
    "boxes that collide": "stacks of up to 10 boxes, mass ratio up to 1:1000, box-box impacts up to 200 m/s",
}
"""Where the robust default is meant to hold. Every point of every row is inside it."""

FULL_DTS = (5, 8, 11, 14)  # dt = 2^-k of the rows other than the map
QUICK_DTS = (5, 11)
MAP_STIFFNESS = tuple(10.0**e for e in range(2, 10))
MAP_DTS = tuple(range(5, 15))
QUICK_MAP_STIFFNESS = (1e2, 1e5, 1e8)
QUICK_MAP_DTS = (5, 9, 13)
ENERGY_ROUNDING = 1e-9  # relative energy change allowed for rounding
MAX_LISTED = 200  # a row with more points lists only some of them under "Every point"


@dataclass
class Check:
    """One solver on one parameter point of a row."""

    point: dict  # parameter name -> value, as shown
    solver: str
    passed: bool
    measured: str  # what was measured, as shown
    values: dict = field(default_factory=dict)


@dataclass
class Row:
    name: str
    title: str
    criterion: str
    declared: str  # the robust solver's declared range for this row
    checks: list[Check]
    smallest_failure: tuple | None = None  # random scenes: hypothesis's smallest robust failure

    def of(self, solver: str) -> list[Check]:
        return [c for c in self.checks if c.solver == solver]

    def passed(self, solver: str) -> bool:
        return all(c.passed for c in self.of(solver))

    def verdict(self, solver: str, limit: int = 4) -> str:
        checks = self.of(solver)
        failed = [c for c in checks if not c.passed]
        if not failed:
            return f"PASS {len(checks)}/{len(checks)}"
        where = "; ".join(point_text(c.point) for c in failed[:limit]) + ("; ..." if len(failed) > limit else "")
        return f"**FAIL** {len(checks) - len(failed)}/{len(checks)} (fails at {where})"


def point_text(point: dict) -> str:
    return ", ".join(f"{name} {value}" for name, value in point.items())


def k_text(k: float) -> str:
    return f"1e{round(math.log10(k))}"


# -- running a scene ------------------------------------------------------------------------------------
@dataclass
class Run:
    """A recorded run: states on the grid, or the reason there are none."""

    scene: Scene
    states: np.ndarray | None  # (T, 6)
    result: object | None
    error: str = ""

    @property
    def finite(self) -> bool:
        return self.states is not None and bool(np.isfinite(self.states).all())

    @property
    def box(self):
        return self.scene.boxes[0]

    def energy(self) -> np.ndarray:
        return energy(self.box, self.scene.gravity, self.states)

    def max_penetration(self) -> float:
        """Deepest any corner went below the floor, on the grid or inside the solver's substeps [m]."""
        return max(float(-lowest_corner(self.box, self.states).min()), float(self.result.max_penetration[0]), 0.0)

    def energy_gain(self) -> tuple[float, float]:
        """(largest rise of the total energy above its start [J], what is allowed for it [J]): rounding, plus
        m |g| times the deepest penetration, the potential energy a position correction may return when it
        pushes the box out (the robust solver moves positions, not velocities, to undo a penetration)."""
        e = self.energy()
        allowed = ENERGY_ROUNDING * abs(e[0]) + self.box.mass * abs(self.scene.gravity) * self.max_penetration()
        return float(e.max() - e[0]), allowed


def run_scene(scene: Scene, duration: float, until_rest: bool = False) -> Run:
    try:
        result = simulate(scene, duration=duration, until_rest=until_rest, record=True)
    except NonFiniteStateError as error:
        return Run(scene, None, None, f"non-finite at step {error.step}")
    return Run(scene, result.trajectory.state[:, 0], result)


def not_finite(run: Run, point: dict, solver: str) -> Check:
    return Check(point, solver, False, run.error or "non-finite")


# -- the rows -------------------------------------------------------------------------------------------------
def contact_omega(scene: Scene) -> float:
    """omega = sqrt(k / m_eff) of the resting box's stiffest contact mode: m_eff = 1 / the largest eigenvalue
    of the Delassus matrix K_ij = 1/m + rx_i rx_j / I of its two bottom corners (for the 2 x 1 m, 1 kg box,
    the rocking mode, K = 4.8 / kg; the vertical mode has 2 / kg)."""
    box = scene.boxes[0]
    rx = np.array([-0.5 * box.length, 0.5 * box.length])
    delassus = 1.0 / box.mass + np.outer(rx, rx) / box.inertia
    return math.sqrt(scene.penalty_stiffness * float(np.linalg.eigvalsh(delassus).max()))


def stiffness_map(stiffnesses, exponents) -> Row:
    """The resting 2 x 1 m box (``scenes.resting``: e 0.5, mu 0.02) for 2 s at each (k, dt)."""
    checks = []
    for k in stiffnesses:
        for exponent in exponents:
            for solver in SOLVERS:
                scene = scenes.resting(penalty_stiffness=k, dt=dt_of(exponent), solver=solver)
                point = {"k": k_text(k), "dt": dt_label(exponent)}
                values = {"k": k, "exponent": exponent, "omega_dt": contact_omega(scene) * dt_of(exponent)}
                run = run_scene(scene, 2.0)
                if not run.finite:
                    checks.append(Check(point, solver, False, run.error or "non-finite", values))
                    continue
                rise = float(run.states[:, layout.Y].max() - run.states[0, layout.Y])
                gain, allowed = run.energy_gain()
                passed = rise <= 0.01 and gain <= allowed
                checks.append(Check(point, solver, passed, f"rise {sci(max(rise, 0.0))} m, energy rise "
                                                           f"{sci(max(gain, 0.0))} J (allowed {sci(allowed)})", values))
    return Row("stiffness_map", "Penalty stiffness against dt",
               "finite; the resting box never rises more than 1 cm; its energy never rises above its start "
               "(allowance: rounding and m g times the deepest penetration)",
               f"k {k_text(min(stiffnesses))} to {k_text(max(stiffnesses))} N/m, dt {dt_label(min(exponents))} to "
               f"{dt_label(max(exponents))} s", checks)


def elastic_bouncing(exponents) -> Row:
    checks = []
    for exponent in exponents:
        for solver in SOLVERS:
            scene = scenes.bouncing(restitution=1.0, dt=dt_of(exponent), penalty_stiffness=STIFFNESS, solver=solver)
            point = {"dt": dt_label(exponent)}
            run = run_scene(scene, 20.0)
            if not run.finite:
                checks.append(not_finite(run, point, solver))
                continue
            e = run.energy()
            drift = float(np.abs(e / e[0] - 1.0).max())
            checks.append(Check(point, solver, drift <= 0.01, f"energy within {sci(drift)} of its start"))
    return Row("elastic_bouncing", "e = 1 bouncing for 20 s",
               "total energy within 1% of its start at every step (flat drop from 1 m, e = 1, no friction)",
               f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s, k = {STIFFNESS:g} N/m", checks)


def long_rest(exponents, minutes: float = 10.0) -> Row:
    """The resting box for ``minutes`` of simulated time without sleeping, in 1 s chunks, every grid state checked."""
    checks = []
    for exponent in exponents:
        for solver in SOLVERS:
            scene = scenes.resting(restitution=0.5, friction=0.02, penalty_stiffness=STIFFNESS, dt=dt_of(exponent),
                                   solver=solver)
            point = {"dt": dt_label(exponent)}
            drift, gain, finite = resting_drift(scene, minutes * 60.0)
            e0 = float(energy(scene.boxes[0], scene.gravity, scene.initial_state()[0]))
            passed = finite and drift < 1e-3 and gain <= ENERGY_ROUNDING * abs(e0)
            measured = f"drift {sci(drift)} m, energy gain {sci(gain)} J" if finite else "non-finite"
            checks.append(Check(point, solver, passed, measured))
    return Row("long_rest", f"Resting for {minutes:g} minutes",
               "drift (|dx| + R |da|, every step) < 1 mm and no energy gain; sleeping off (the box is stepped "
               "throughout)", f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s, e 0.5, mu 0.02, "
               f"k = {STIFFNESS:g} N/m", checks)


def resting_drift(scene: Scene, duration: float) -> tuple[float, float, bool]:
    """(largest drift [m], largest energy gain [J], finite) of a run in 1 s chunks (until_rest off)."""
    simulator = Simulator.for_scene(scene, record=True)
    chunk = int(round(1.0 / scene.dt))
    state, params = scene.initial_state(), scene.body_params()
    settings = make_settings(scene, chunk, until_rest=False)
    stats = np.zeros((1, layout.STATS_SIZE))
    trajectory = np.empty((chunk + 1, 1, layout.STATE_SIZE))
    events = np.zeros((1, layout.MAX_EVENTS, layout.EVENT_SIZE))
    box, start = scene.boxes[0], state[0].copy()
    e0 = float(energy(box, scene.gravity, start))
    drift = gain = 0.0
    for _ in range(int(round(duration))):
        simulator.run(state, params, settings, stats, trajectory, events)
        states = trajectory[:, 0]
        if stats[0, layout.STATUS] != layout.STATUS_OK or not np.isfinite(states).all():
            return math.inf, math.inf, False
        moved = np.hypot(states[:, 0] - start[0], states[:, 1] - start[1])
        turned = corner_radius(box) * np.abs(cases.wrap(states[:, 2] - start[2]))
        drift = max(drift, float((moved + turned).max()))
        gain = max(gain, float(energy(box, scene.gravity, states).max() - e0))
    return drift, gain, True


def sliding(speeds, frictions, exponents) -> Row:
    checks = []
    for speed in speeds:
        for friction in frictions:
            for exponent in exponents:
                for solver in SOLVERS:
                    scene = scenes.slide(speed=speed, friction=friction, dt=dt_of(exponent),
                                         penalty_stiffness=STIFFNESS, solver=solver)
                    point = {"v0": f"{speed:g} m/s", "mu": f"{friction:g}", "dt": dt_label(exponent)}
                    run = run_scene(scene, speed / (friction * -scene.gravity) + 1.0)
                    if not run.finite:
                        checks.append(not_finite(run, point, solver))
                        continue
                    lowest = float(run.states[:, layout.VX].min())
                    end = run.states[-1]
                    end_speed = math.hypot(end[3], end[4]) + corner_radius(run.box) * abs(end[5])
                    passed = lowest >= -1e-9 * speed and end_speed <= 1e-3
                    checks.append(Check(point, solver, passed,
                                        f"lowest vx {sci(lowest)} m/s, end speed {sci(end_speed)} m/s"))
    return Row("sliding", "Sliding to rest",
               "vx never below -1e-9 v0 (it never reverses; the slack is rounding) and the box stops "
               "(every point slower than 1 mm/s at the end)",
               f"v0 {', '.join(f'{v:g}' for v in speeds)} m/s, mu {', '.join(f'{m:g}' for m in frictions)}, "
               f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s", checks)


def fast_impacts(speeds, exponents) -> Row:
    checks = []
    for speed in speeds:
        for exponent in exponents:
            for solver in SOLVERS:
                scene = cases.fast_impact(speed, dt=dt_of(exponent), solver=solver)
                point = {"speed": f"{speed:g} m/s", "dt": dt_label(exponent)}
                run = run_scene(scene, 2.0)
                if not run.finite:
                    checks.append(not_finite(run, point, solver))
                    continue
                bound = 0.01 * run.box.width
                penetration = run.max_penetration()
                contact = run.result.first_contact_time[0]
                after = np.arange(run.states.shape[0]) * scene.dt > contact if not math.isnan(contact) else None
                rebound = float(run.states[after, layout.VY].max()) if after is not None and after.any() else 0.0
                lowest_centre = float(run.states[:, layout.Y].min())
                passed = penetration <= bound and rebound <= 0.01 * speed and lowest_centre > 0.0
                checks.append(Check(point, solver, passed,
                                    f"penetration {sci(penetration)} m, rebound vy {sci(rebound)} m/s, "
                                    f"lowest centre {sci(lowest_centre)} m"))
    return Row("fast_impacts", "Impacts at 5 to 200 m/s",
               "penetration <= 1% of the box width (2 mm); no rebound with e = 0 (after the first contact the "
               "centre never rises faster than 1% of the impact speed); no tunnelling (the centre stays above "
               "the floor)", f"speeds {', '.join(f'{v:g}' for v in speeds)} m/s, corner first, e 0, mu 0.5, "
               f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s", checks)


def energy_check(run: Run, point: dict, solver: str, extra: Callable[[Run], tuple[bool, str]] | None = None) -> Check:
    """Finite, and the energy never rises above its start (beyond ``Run.energy_gain``'s allowance)."""
    if not run.finite:
        return not_finite(run, point, solver)
    gain, allowed = run.energy_gain()
    start = abs(float(run.energy()[0]))
    share = f", {100 * gain / start:.2g}% of its start" if gain > allowed and start > 0 else ""
    passed, measured = gain <= allowed, f"energy rise {sci(max(gain, 0.0))} J (allowed {sci(allowed)}{share})"
    if extra is not None:
        more_passed, more = extra(run)
        passed, measured = passed and more_passed, f"{measured}, {more}"
    return Check(point, solver, passed, measured)


def fast_spin(spins, exponents) -> Row:
    checks = []
    for spin in spins:
        for exponent in exponents:
            for solver in SOLVERS:
                scene = cases.spinning_landing(spin, dt=dt_of(exponent), solver=solver)
                point = {"spin": f"{spin:g} rad/s", "dt": dt_label(exponent)}

                def penetration(run):
                    depth = run.max_penetration()
                    return depth <= 0.01 * run.box.width, f"penetration {sci(depth)} m"

                checks.append(energy_check(run_scene(scene, 3.0), point, solver, penetration))
    return Row("fast_spin", "Landing spinning at 50 to 600 rad/s",
               "finite; energy never rises (allowance: rounding and m g times the deepest penetration); "
               "penetration <= 1% of the box width", f"spin {', '.join(f'{s:g}' for s in spins)} rad/s, the toss box "
               f"released 0.5 m up, dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s", checks)


def thin_boxes(ratios, exponents) -> Row:
    checks = []
    for ratio in ratios:
        for exponent in exponents:
            for solver in SOLVERS:
                scene = cases.thin_toss(ratio, dt=dt_of(exponent), solver=solver)
                point = {"aspect": f"1:{ratio:g}", "dt": dt_label(exponent)}

                def lands(run):
                    depth = run.max_penetration()
                    rests = bool(run.result.at_rest[0])
                    return (depth <= 0.05 * run.box.width and rests,
                            f"penetration {sci(depth)} m, {'rests' if rests else 'not at rest'} after 10 s")

                checks.append(energy_check(run_scene(scene, 10.0, until_rest=True), point, solver, lands))
    return Row("thin_boxes", "Thin boxes 1:10 to 1:200",
               "finite; energy never rises (allowance as above); penetration <= 5% of the width; comes to rest "
               "lying on a face within 10 s", f"1 m long boxes, widths 1/{', 1/'.join(f'{r:g}' for r in ratios)} m, "
               f"the typical toss, dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s", checks)


def masses(values, exponents) -> Row:
    checks = []
    for exponent in exponents:
        for solver in SOLVERS:
            reference = run_scene(cases.mass_toss(2.0, dt=dt_of(exponent), solver=solver), 10.0, until_rest=True)
            for mass in values:
                scene = cases.mass_toss(mass, dt=dt_of(exponent), solver=solver)
                point = {"mass": f"{mass:g} kg", "dt": dt_label(exponent)}

                def same_landing(run, reference=reference):
                    if not reference.finite:
                        return False, "the 2 kg throw went non-finite"
                    off = cases.pose_error(run.states[-1], reference.states[-1], corner_radius(run.box))
                    return off <= 0.01, f"landing {sci(off)} m from the 2 kg box's"

                checks.append(energy_check(run_scene(scene, 10.0, until_rest=True), point, solver, same_landing))
    return Row("masses", "Masses 1e-3 to 1e3 kg, material unchanged",
               "finite; energy never rises (allowance as above); lands within 1 cm (|dx| + R |da|) of the same "
               "throw of the 2 kg box (rigid-body motion does not depend on the mass)",
               f"masses {', '.join(f'{m:g}' for m in values)} kg, e 0.3, mu 0.5, k {STIFFNESS:g} N/m, the typical "
               f"toss, dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s", checks)


def embedded_box(stiffnesses, exponents) -> Row:
    checks = []
    for k in stiffnesses:
        for exponent in exponents:
            for solver in SOLVERS:
                scene = cases.embedded(0.25, penalty_stiffness=k, dt=dt_of(exponent), solver=solver)
                point = {"k": k_text(k), "dt": dt_label(exponent)}
                run = run_scene(scene, 3.0)
                if not run.finite:
                    checks.append(not_finite(run, point, solver))
                    continue
                rest = 0.5 * run.box.width
                highest = float(run.states[:, layout.Y].max())
                end = float(run.states[-1, layout.Y])
                passed = abs(end - rest) <= 1e-3 and highest <= rest + 1e-3
                checks.append(Check(point, solver, passed, f"centre at {end:.4f} m after 3 s (rest {rest:g} m), "
                                                           f"highest {highest:.4f} m"))
    return Row("embedded", "Started 25% inside the floor",
               "pushed out: the centre within 1 mm of its resting height after 3 s; not launched: never more "
               "than 1 mm above it (energy is not checked: pushing out raises the potential energy)",
               f"the 2 x 1 m box 25 cm deep, k {', '.join(k_text(k) for k in stiffnesses)} N/m, "
               f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s", checks)


def far_from_origin(exponents, distance: float = 1e5) -> Row:
    checks = []
    for exponent in exponents:
        for solver in SOLVERS:
            runs = [run_scene(cases.far_toss(x, dt=dt_of(exponent), solver=solver), 10.0, until_rest=True)
                    for x in (0.0, distance)]
            point = {"dt": dt_label(exponent)}
            if not all(run.finite for run in runs):
                checks.append(Check(point, solver, False, "non-finite"))
                continue
            shifted = runs[1].states[-1] - np.array([distance, 0, 0, 0, 0, 0])
            off = cases.pose_error(shifted, runs[0].states[-1], corner_radius(runs[0].box))
            checks.append(Check(point, solver, off <= 1e-3, f"landings differ by {sci(off)} m"))
    return Row("far_from_origin", f"Far from the origin (x = {distance:g} m)",
               "the typical toss released at x = 1e5 m lands within 1 mm (|dx| + R |da|) of the same toss at x = 0, "
               "shifted (float64)", f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s", checks)


CORNER_HITS = ((0.4, (2.0, -3.0), 1.0), (1.2, (-3.0, -1.0), -2.0))  # angle, velocity, spin


def corner_friction(frictions, restitutions, exponents, hits=CORNER_HITS) -> Row:
    checks = []
    for friction in frictions:
        for restitution in restitutions:
            for hit, (angle, velocity, spin) in enumerate(hits):
                for exponent in exponents:
                    for solver in SOLVERS:
                        scene = cases.friction_corner_hit(friction, restitution, angle, velocity, spin,
                                                          dt=dt_of(exponent), solver=solver)
                        point = {"mu": f"{friction:g}", "e": f"{restitution:g}", "hit": hit + 1,
                                 "dt": dt_label(exponent)}
                        run = run_scene(scene, 1.0)
                        if not run.finite:
                            checks.append(not_finite(run, point, solver))
                            continue
                        ke = kinetic_energy(run.box, run.states)
                        rise = float(np.diff(ke).max(initial=0.0))
                        passed = rise <= ENERGY_ROUNDING * ke[0]
                        checks.append(Check(point, solver, passed, f"largest step-to-step KE rise {sci(rise)} J "
                                                                   f"(KE0 {ke[0]:.3g} J)"))
    hits_text = "; ".join(f"hit {i + 1}: angle {a:g}, v ({v[0]:g}, {v[1]:g}) m/s, spin {w:g} rad/s"
                          for i, (a, v, w) in enumerate(hits))
    return Row("corner_friction", "Angled corner hit with friction",
               "kinetic energy never rises from one step to the next (zero gravity, so nothing feeds it)",
               f"mu {', '.join(f'{m:g}' for m in frictions)}, e {', '.join(f'{e:g}' for e in restitutions)}, "
               f"2 x 1 m box ({hits_text}), dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s", checks)


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


def run_bodies(scene: Scene, duration: float, order: Callable[[Scene, np.ndarray], np.ndarray] | None = None
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
    run.momentum_change = mass @ run.end[:, 3:5] - mass @ start[:, 3:5] - np.array([0.0, mass.sum() * scene.gravity
                                                                                       * elapsed])
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
    criterion = ("finite; every box within 1 mm of where it started (|dx| + R |da|, every step; no settling allowed); "
                 "the total energy never rises above its start (allowance: rounding and M g times the deepest overlap)")
    declared = (f"stacks of {', '.join(str(n) for n in sizes)} boxes (`scenes.stack`), {duration:g} s, "
                f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s, k = {STIFFNESS:g} N/m")

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
                    checks.append(Check(point, solver, passed, f"drift {sci(run.drift)} m, energy rise "
                                                               f"{sci(max(run.energy_rise, 0.0))} J (allowed "
                                                               f"{sci(allowed)})"))
        return Row("stacks", f"Stacks resting {duration:g} s", criterion, declared, checks)

    return build()


def body_impacts(speeds, exponents) -> Row:
    title = f"Box-box impacts at {' and '.join(f'{v:g}' for v in speeds)} m/s"
    criterion = ("finite; no tunnelling (from one step to the next the line of centres never flips along the impact "
                 "direction while the boxes are within reach of each other across it, and both centres stay above "
                 "the floor); overlap <= 1% of the box width (2 mm), between the boxes and into the floor; in "
                 "flight (zero gravity) momentum kept to 1e-9 of m v and kinetic energy never rises from one step to "
                 "the next; onto a box, the total energy never rises above its start (allowance as "
                 "above)")
    declared = (f"the toss box corner first (angle 0.3) at {', '.join(f'{v:g}' for v in speeds)} m/s into a level toss "
                f"box, in flight or falling onto it lying on the floor, e 0, mu 0.5, dt {dt_label(min(exponents))} to "
                f"{dt_label(max(exponents))} s")

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
                        point = {"speed": f"{speed:g} m/s", "where": "onto a box" if onto_floor else "in flight",
                                 "dt": dt_label(exponent)}
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
    criterion = ("finite; every box within 1 mm of where it started (every step); overlap <= 1% of the box width "
                 "(2 mm), between the boxes and into the floor; the total energy never rises above its start "
                 "(allowance as above)")
    declared = (f"stacks of `scenes.stack` whose boxes weigh 2 kg or {ratio:g} times that ({', '.join(orders)}), "
                f"material unchanged, {duration:g} s, dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s")

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
                    passed = (run.drift < 1e-3 and run.overlap <= 0.01 * scene.boxes[0].width
                              and run.energy_rise <= allowed)
                    checks.append(Check(point, solver, passed, f"drift {sci(run.drift)} m, {run.overlap_text()}, "
                                                               f"energy rise {sci(max(run.energy_rise, 0.0))} J "
                                                               f"(allowed {sci(allowed)})"))
        return Row("mass_ratio_stacks", title, criterion, declared, checks)

    return build()


# -- random scenes (hypothesis) ---------------------------------------------------------------------------------
RANDOM_FIELDS = ("length", "aspect", "log_mass", "height", "angle", "vx", "vy", "spin", "restitution", "friction",
                 "log_stiffness", "dt_exponent")
KNOWN_EXAMPLES = ((1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 5),)
"""Examples always run (hypothesis ``@example``): the smallest robust failure found so far, kept as a regression."""


def random_strategy():
    from hypothesis import strategies as st

    return st.tuples(st.floats(0.05, 2.0), st.floats(1.0, 200.0), st.floats(-3.0, 3.0), st.floats(0.0, 3.0),
                     st.floats(-math.pi, math.pi), st.floats(-50.0, 50.0), st.floats(-50.0, 50.0),
                     st.floats(-200.0, 200.0), st.floats(0.0, 1.0), st.floats(0.0, 1.5), st.floats(2.0, 9.0),
                     st.integers(5, 14))


def random_scene(example, solver: str) -> Scene:
    """A box of length L and width L / aspect, mass 10^log_mass, its centre ``height`` above the corner radius
    (so it starts clear of the floor at any angle), thrown anywhere, on any material."""
    length, aspect, log_mass, height, angle, vx, vy, spin, restitution, friction, log_k, exponent = example
    width = length / aspect
    box = Box(length=length, width=width, mass=10.0**log_mass, position=(0.0, 0.5 * math.hypot(length, width)
                                                                                + height),
                    angle=angle, velocity=(vx, vy), spin=spin)
    return Scene(boxes=(box,), restitution=restitution, friction=friction, penalty_stiffness=10.0**log_k,
                 dt=dt_of(int(exponent)), solver=solver)


def random_check(example, solver: str) -> Check:
    point = {"example": "(" + ", ".join(f"{v:.4g}" for v in example) + ")"}
    return energy_check(run_scene(random_scene(example, solver), 2.0), point, solver)


def random_examples(count: int) -> list[tuple]:
    """``count`` examples drawn by hypothesis (derandomized, so the report is reproducible), after the known ones."""
    from hypothesis import HealthCheck, Phase, example, given, settings

    drawn = []

    def keep(example):
        drawn.append(example)

    body = given(random_strategy())(keep)
    for known in KNOWN_EXAMPLES:
        body = example(known)(body)
    settings(max_examples=count, derandomize=True, database=None, deadline=None,
             phases=[Phase.explicit, Phase.generate], suppress_health_check=list(HealthCheck))(body)()
    return drawn


def shrink_failure(solver: str, max_examples: int) -> tuple | None:
    """The smallest example hypothesis finds on which ``solver`` fails, or None."""
    from hypothesis import HealthCheck, find, settings
    from hypothesis.errors import NoSuchExample

    try:
        return find(random_strategy(), lambda example: not random_check(example, solver).passed,
                    settings=settings(max_examples=max_examples, derandomize=True, database=None, deadline=None,
                                      suppress_health_check=list(HealthCheck)))
    except NoSuchExample:
        return None


def random_scenes(count: int, shrink: bool) -> Row:
    checks = [random_check(example, solver) for example in random_examples(count) for solver in SOLVERS]
    row = Row("random_scenes", "Random scenes (hypothesis)",
              "finite; energy never rises above its start without input (allowance: rounding and m g times the "
              "deepest penetration); 2 s each",
              f"{count} drawn examples plus {len(KNOWN_EXAMPLES)} kept one(s): length 0.05 to 2 m, aspect 1 to 200, "
              "mass 1e-3 to 1e3 kg, any angle, |v| components up to 50 m/s, spin up to 200 rad/s, e 0 to 1, "
              "mu 0 to 1.5, k 1e2 to 1e9 N/m, dt 2^-14 to 2^-5 s", checks)
    row.smallest_failure = shrink_failure("robust", 500) if shrink and not row.passed("robust") else None
    return row


# -- the report ---------------------------------------------------------------------------------------------------
@dataclass
class StabilityReport:
    quick: bool
    rows: list[Row]
    run_seconds: float = math.nan
    fuzz: list[fuzz.FuzzResult] = field(default_factory=list)  # the property-based fuzz (reports.fuzz)
    load: str = ""  # the machine's load when the report ran (``document.load``)

    def row(self, name: str) -> Row:
        return next(r for r in self.rows if r.name == name)

    def seed_beyond_line(self) -> tuple[int, int]:
        """(seed failures, seed points) beyond omega dt = 2 in the map."""
        beyond = [c for c in self.row("stiffness_map").of("seed") if c.values["omega_dt"] > 2.0]
        return sum(not c.passed for c in beyond), len(beyond)


def run(quick: bool = False, log=print) -> StabilityReport:
    dts = QUICK_DTS if quick else FULL_DTS
    builders = [
        lambda: stiffness_map(QUICK_MAP_STIFFNESS if quick else MAP_STIFFNESS, QUICK_MAP_DTS if quick else MAP_DTS),
        lambda: elastic_bouncing(dts),
        lambda: long_rest(dts),
        lambda: sliding((5.0,) if quick else (1.0, 5.0, 20.0), (0.3,) if quick else (0.3, 1.0), dts),
        lambda: fast_impacts((5.0, 200.0) if quick else (5.0, 20.0, 50.0, 200.0), dts),
        lambda: fast_spin((600.0,) if quick else (50.0, 200.0, 600.0), dts),
        lambda: thin_boxes((200.0,) if quick else (10.0, 100.0, 200.0), dts),
        lambda: masses((1e-3, 1e3) if quick else (1e-3, 1e-1, 1e1, 1e3), dts),
        lambda: embedded_box((1e2, 1e5) if quick else (1e2, 1e5, 1e9), dts),
        lambda: far_from_origin((8,) if quick else dts),
        lambda: corner_friction((1.0,) if quick else (0.2, 1.0), (0.5,) if quick else (0.0, 0.5), dts,
                                CORNER_HITS[:1] if quick else CORNER_HITS),
        lambda: stacks((10,) if quick else (2, 10), dts, 2.0 if quick else 60.0),
        lambda: body_impacts((200.0,) if quick else (50.0, 200.0), dts),
        lambda: mass_ratio_stacks(1000.0, ("heavy on top",) if quick else tuple(cases.MASS_ORDERS), dts,
                                  2.0 if quick else 10.0),
        lambda: random_scenes(10 if quick else 1000, shrink=not quick),
    ]
    rows = []
    with Stopwatch() as watch:
        for build in builders:
            rows.append(build())
            row = rows[-1]
            log(f"  {row.name:18} robust {row.verdict('robust', 2)[:60]:60} seed {row.verdict('seed', 1)[:40]}")
        profile = fuzz.REDUCED if quick else fuzz.FULL
        fuzzed = []
        for name in fuzz.FUZZES:
            fuzzed.append(fuzz.run_fuzz(name, profile))
            log(f"  fuzz {name:13} {len(fuzzed[-1].failures)} of {fuzzed[-1].examples} examples fail")
    return StabilityReport(quick, rows, watch.seconds, fuzzed, document.load())


def plot_map(report: StabilityReport, path: Path) -> None:
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    row = report.row("stiffness_map")
    ks = sorted({c.values["k"] for c in row.checks})
    exponents = sorted({c.values["exponent"] for c in row.checks}, reverse=True)  # dt increasing
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True, layout="constrained")
    scene = scenes.resting()
    for ax, solver in zip(axes, SOLVERS, strict=True):
        grid = np.zeros((len(ks), len(exponents)))
        for c in row.of(solver):
            grid[ks.index(c.values["k"]), exponents.index(c.values["exponent"])] = 1.0 if c.passed else 0.0
        log_dt = [math.log10(dt_of(e)) for e in exponents]
        log_k = [math.log10(k) for k in ks]
        ax.pcolormesh(_edges(log_dt), _edges(log_k), grid, cmap=ListedColormap(["#e45756", "#54a24b"]), vmin=0,
                      vmax=1, edgecolors="white", linewidth=0.5)
        line_k = np.logspace(log_k[0] - 0.5, log_k[-1] + 0.5, 50)
        omega = np.array([contact_omega(scene.replace(penalty_stiffness=k)) for k in line_k])
        ax.plot(np.log10(2.0 / omega), np.log10(line_k), "k--", lw=1.5, label="omega dt = 2")
        ax.set(xlim=(_edges(log_dt)[0], _edges(log_dt)[-1]), ylim=(_edges(log_k)[0], _edges(log_k)[-1]),
               xlabel="log10 dt [s]", title=f"{solver}: green pass, red fail")
        ax.legend(loc="upper right", fontsize=8)
    axes[0].set_ylabel("log10 penalty stiffness k [N/m]")
    figure.suptitle("Resting 2 x 1 m box, 2 s: omega = sqrt(k / m_eff), m_eff of the stiffest contact mode")
    document.save_figure(figure, path)


def _edges(centres):
    centres = np.asarray(centres, dtype=float)
    step = np.diff(centres).mean() if centres.size > 1 else 1.0
    return np.concatenate([centres - step / 2, [centres[-1] + step / 2]])


def map_findings(report: StabilityReport) -> str:
    row = report.row("stiffness_map")
    failed, total = report.seed_beyond_line()
    seed = row.of("seed")
    inside_failed = [c.values["omega_dt"] for c in seed if not c.passed and c.values["omega_dt"] <= 2.0]
    passed = [c.values["omega_dt"] for c in seed if c.passed]
    text = (f"The seed scheme fails at {failed} of the {total} map points beyond omega dt = 2, as the explicit "
            "spring's stability limit says")
    if inside_failed:
        text += (f", and also at {len(inside_failed)} points below it, from omega dt = {min(inside_failed):.2f} up: "
                 "there the explicit spring is stable, but the seed's impulses, applied with restitution to corners "
                 "that are still inside the floor, feed the contact's oscillation until the box is thrown off")
    if passed:
        text += f". The largest omega dt at which it passed is {max(passed):.2f}"
    robust = row.of("robust")
    return text + f". The robust default passes {sum(c.passed for c in robust)} of {len(robust)} map points."


def findings(report: StabilityReport) -> str:
    """The closing notes, every number read from the checks."""
    lines = []
    for solver in SOLVERS:
        checks = [c for row in report.rows for c in row.of(solver)]
        passed_rows = [row for row in report.rows if row.passed(solver)]
        lines.append(f"- **{solver}**: passes {len(passed_rows)} of {len(report.rows)} rows "
                     f"({sum(c.passed for c in checks)} of {len(checks)} points).")
    for row in report.rows:
        failed = [c for c in row.of("robust") if not c.passed]
        for c in failed[:4]:
            lines.append(f"- The robust default fails *{row.title}* at {point_text(c.point)}: {c.measured}.")
        if len(failed) > 4:
            lines.append(f"- ... and at {len(failed) - 4} more points of that row.")
    failed, total = report.seed_beyond_line()
    lines.append(f"- The seed scheme fails at {failed} of the {total} map points beyond omega dt = 2.")
    return "\n".join(lines)


def markdown(report: StabilityReport, figure: str) -> str:
    rows = report.rows
    parts = [
        "# Stability on stiff and extreme cases",
        "",
        f"Generated by `python -m reports.stability{' --quick' if report.quick else ''}` in "
        f"{report.run_seconds / 60:.1f} min on {document.machine()} ({report.load}). Every number below comes "
        "from that command.",
        "",
        "Each row is a family of scenes with a measurable pass criterion, run for the robust default and the "
        "seed scheme at the same points. Energy is 0.5 m |v|^2 + 0.5 I w^2 - m g y (floor at y = 0). "
        f"Material, unless the row varies it: the env's penalty stiffness k = {STIFFNESS:g} N/m.",
        "",
        "## The robust default's declared range",
        "",
        table(["quantity", "range"], [[name, value] for name, value in DECLARED_RANGE.items()]),
        "",
        "Every point of every row lies inside this range, so the robust default must pass every row; "
        "a row it fails is marked **FAIL** with the points where it fails.",
        "",
        "## Summary",
        "",
        table(["row", "pass criterion", "points (inside the declared range)", "robust", "seed"],
              [[r.title, r.criterion, r.declared, r.verdict("robust"), r.verdict("seed")] for r in rows]),
        "",
        "## Findings",
        "",
        findings(report),
        "",
        "## Penalty stiffness against dt",
        "",
        map_findings(report),
        "",
        f"![pass/fail map over (k, dt)](figures/{figure})",
        "",
    ]
    random_row = report.row("random_scenes")
    smallest = random_row.smallest_failure
    if smallest is not None:
        parts += ["## Smallest random failure of the robust default", "",
                  "hypothesis's smallest example on which the robust default fails the random-scene criterion, "
                  f"as ({', '.join(RANDOM_FIELDS)}):", "", f"    {tuple(smallest)!r}", "",
                  f"measured: {random_check(smallest, 'robust').measured}.", ""]
    parts += fuzz_section(report)
    parts += ["## Every point", ""]
    for row in rows:
        pairs = list(zip(row.of("robust"), row.of("seed"), strict=True))
        note = ""
        if len(pairs) > MAX_LISTED:  # the random scenes: the robust default's failures and the first few
            shown = [pair for i, pair in enumerate(pairs) if i < 10 or not pair[0].passed]
            seed_failed = sum(not b.passed for _, b in pairs)
            note = (f" Listed: the first 10 points and every robust failure; of all {len(pairs)}, the robust default "
                    f"fails {sum(not a.passed for a, _ in pairs)} and the seed scheme {seed_failed}.")
            pairs = shown
        lines = [[point_text(a.point), ("pass" if a.passed else "**FAIL**") + ": " + a.measured,
                  ("pass" if b.passed else "**FAIL**") + ": " + b.measured] for a, b in pairs]
        parts += [f"### {row.title}", "", f"Criterion: {row.criterion}. Points: {row.declared}.{note}", "",
                  table(["point", "robust", "seed"], lines), ""]
    return "\n".join(parts)


FUZZ_TEXT = {
    "engine": ("robust-solver scenes over the declared range (length 0.02 to 5 m and the quantities above)",
               "finite; penetration < 5% of the smaller side; no recorded step gains energy (allowance: rounding "
               "and m g times the deepest penetration); at rest lying on a face, or ran the whole duration"),
    "env_declared": ("BoxToss-v0, robust, arguments inside the declared range, one throw each",
                     "no exception (EnergyGainError included); observations finite and inside the space; "
                     "penetration < 5% of the smaller side"),
    "env_accepted": ("BoxToss-v0, both solvers, arguments anywhere in the accepted ranges (docs/ranges.md)",
                     "no exception but the documented EnergyGainError and NonFiniteStateError; what is returned "
                     "is finite and inside the observation space"),
}


def fuzz_verdict(result: fuzz.FuzzResult) -> str:
    failed = len(result.failures)
    return f"PASS {result.examples}/{result.examples}" if not failed else \
        f"**FAIL** {result.examples - failed}/{result.examples}"


def fuzz_section(report: StabilityReport) -> list[str]:
    """The property-based fuzz: what each draws and checks, and what it found."""
    if not report.fuzz:
        return []
    profile = fuzz.REDUCED if report.quick else fuzz.FULL
    rows = []
    for result in report.fuzz:
        draws, checks = FUZZ_TEXT[result.name]
        documented = ", ".join(f"{solver}: {error} x{count}" for (solver, error), count in
                               sorted(result.documented_errors.items())) or "-"
        rows.append([result.name, draws, checks, fuzz_verdict(result), documented])
    parts = ["## Property-based fuzz (hypothesis)", "",
             f"`reports/fuzz.py`, the {profile.name} profile: {profile.examples} derandomized examples per fuzz, "
             f"engine scenes {profile.engine_duration:g} s each, env throws at most {profile.env_max_sim_time:g} s "
             f"and {profile.env_max_steps:,} steps (the tests run the reduced profile: {fuzz.REDUCED.examples} "
             "examples each).", "",
             table(["fuzz", "draws", "properties", "result", "documented errors raised"], rows), ""]
    for result in report.fuzz:
        for example, problems in result.failures[:4]:
            parts += [f"- {result.name} fails on `{example!r}`: {'; '.join(problems)}."]
    return parts + [""]


def readme_block(report: StabilityReport) -> str:
    return "\n".join([
        f"**Stability on stiff and extreme cases** (`docs/stability.md`): `python -m reports.stability` "
        f"({report.run_seconds / 60:.1f} min on {document.machine().split(',')[1].strip()}, {report.load}; `--quick` "
        "for the "
        "reduced version the tests run; both need the `reports` extra). Rows inside the robust default's "
        f"declared range ({', '.join(f'{k} {v}' for k, v in list(DECLARED_RANGE.items())[:6])}):",
        "",
        table(["row", "robust", "seed"], [[r.title, r.verdict("robust", limit=1), r.verdict("seed", limit=1)]
                                          for r in report.rows]),
        "",
        "Property-based fuzz (`reports/fuzz.py`, hypothesis): " + "; ".join(
            f"{result.name} {fuzz_verdict(result)}" for result in report.fuzz) + " examples.",
    ])


def write_report(report: StabilityReport, out: Path, readme: Path | None = None) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    figure = "stability_map.png"
    plot_map(report, out / "figures" / figure)
    path = out / "stability.md"
    write_atomic(path, markdown(report, figure))
    if readme is not None:
        document.update_readme("stability", readme_block(report), readme)
    return path


def main(argv=None) -> int:
    return document.report_command("stability", __doc__, run, write_report, argv)


if __name__ == "__main__":
    raise SystemExit(main())
