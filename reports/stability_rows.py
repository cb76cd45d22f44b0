"""The stability report's single-box rows: each a function of its parameter points returning a ``Row``."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from box_toss_env.physics import Scene, Simulator, layout, make_settings, scenes

from . import cases
from .cases import STIFFNESS, corner_radius, dt_of, energy, kinetic_energy
from .document import dt_label, sci
from .stability_checks import ENERGY_ROUNDING, SOLVERS, Check, Row, Run, k_text, not_finite, run_scene


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
                checks.append(
                    Check(
                        point,
                        solver,
                        passed,
                        f"rise {sci(max(rise, 0.0))} m, energy rise {sci(max(gain, 0.0))} J (allowed {sci(allowed)})",
                        values,
                    )
                )
    return Row(
        "stiffness_map",
        "Penalty stiffness against dt",
        "finite; the resting box never rises more than 1 cm; its energy never rises above its start "
        "(allowance: rounding and m g times the deepest penetration)",
        f"k {k_text(min(stiffnesses))} to {k_text(max(stiffnesses))} N/m, dt {dt_label(min(exponents))} to "
        f"{dt_label(max(exponents))} s",
        checks,
    )


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
    return Row(
        "elastic_bouncing",
        "e = 1 bouncing for 20 s",
        "total energy within 1% of its start at every step (flat drop from 1 m, e = 1, no friction)",
        f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s, k = {STIFFNESS:g} N/m",
        checks,
    )


def long_rest(exponents, minutes: float = 10.0) -> Row:
    """The resting box for ``minutes`` of simulated time without sleeping, in 1 s chunks, every grid state checked."""
    checks = []
    for exponent in exponents:
        for solver in SOLVERS:
            scene = scenes.resting(
                restitution=0.5, friction=0.02, penalty_stiffness=STIFFNESS, dt=dt_of(exponent), solver=solver
            )
            point = {"dt": dt_label(exponent)}
            drift, gain, finite = resting_drift(scene, minutes * 60.0)
            e0 = float(energy(scene.boxes[0], scene.gravity, scene.initial_state()[0]))
            passed = finite and drift < 1e-3 and gain <= ENERGY_ROUNDING * abs(e0)
            measured = f"drift {sci(drift)} m, energy gain {sci(gain)} J" if finite else "non-finite"
            checks.append(Check(point, solver, passed, measured))
    return Row(
        "long_rest",
        f"Resting for {minutes:g} minutes",
        "drift (|dx| + R |da|, every step) < 1 mm and no energy gain; sleeping off (the box is stepped throughout)",
        f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s, e 0.5, mu 0.02, k = {STIFFNESS:g} N/m",
        checks,
    )


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
                    scene = scenes.slide(
                        speed=speed, friction=friction, dt=dt_of(exponent), penalty_stiffness=STIFFNESS, solver=solver
                    )
                    point = {"v0": f"{speed:g} m/s", "mu": f"{friction:g}", "dt": dt_label(exponent)}
                    run = run_scene(scene, speed / (friction * -scene.gravity) + 1.0)
                    if not run.finite:
                        checks.append(not_finite(run, point, solver))
                        continue
                    lowest = float(run.states[:, layout.VX].min())
                    end = run.states[-1]
                    end_speed = math.hypot(end[3], end[4]) + corner_radius(run.box) * abs(end[5])
                    passed = lowest >= -1e-9 * speed and end_speed <= 1e-3
                    checks.append(
                        Check(point, solver, passed, f"lowest vx {sci(lowest)} m/s, end speed {sci(end_speed)} m/s")
                    )
    return Row(
        "sliding",
        "Sliding to rest",
        "vx never below -1e-9 v0 (it never reverses; the slack is rounding) and the box stops "
        "(every point slower than 1 mm/s at the end)",
        f"v0 {', '.join(f'{v:g}' for v in speeds)} m/s, mu {', '.join(f'{m:g}' for m in frictions)}, "
        f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s",
        checks,
    )


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
                checks.append(
                    Check(
                        point,
                        solver,
                        passed,
                        f"penetration {sci(penetration)} m, rebound vy {sci(rebound)} m/s, "
                        f"lowest centre {sci(lowest_centre)} m",
                    )
                )
    return Row(
        "fast_impacts",
        "Impacts at 5 to 200 m/s",
        "penetration <= 1% of the box width (2 mm); no rebound with e = 0 (after the first contact the "
        "centre never rises faster than 1% of the impact speed); no tunnelling (the centre stays above "
        "the floor)",
        f"speeds {', '.join(f'{v:g}' for v in speeds)} m/s, corner first, e 0, mu 0.5, "
        f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s",
        checks,
    )


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
    return Row(
        "fast_spin",
        "Landing spinning at 50 to 600 rad/s",
        "finite; energy never rises (allowance: rounding and m g times the deepest penetration); "
        "penetration <= 1% of the box width",
        f"spin {', '.join(f'{s:g}' for s in spins)} rad/s, the toss box "
        f"released 0.5 m up, dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s",
        checks,
    )


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
                    return (
                        depth <= 0.05 * run.box.width and rests,
                        f"penetration {sci(depth)} m, {'rests' if rests else 'not at rest'} after 10 s",
                    )

                checks.append(energy_check(run_scene(scene, 10.0, until_rest=True), point, solver, lands))
    return Row(
        "thin_boxes",
        "Thin boxes 1:10 to 1:200",
        "finite; energy never rises (allowance as above); penetration <= 5% of the width; comes to rest "
        "lying on a face within 10 s",
        f"1 m long boxes, widths 1/{', 1/'.join(f'{r:g}' for r in ratios)} m, "
        f"the typical toss, dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s",
        checks,
    )


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
    return Row(
        "masses",
        "Masses 1e-3 to 1e3 kg, material unchanged",
        "finite; energy never rises (allowance as above); lands within 1 cm (|dx| + R |da|) of the same "
        "throw of the 2 kg box (rigid-body motion does not depend on the mass)",
        f"masses {', '.join(f'{m:g}' for m in values)} kg, e 0.3, mu 0.5, k {STIFFNESS:g} N/m, the typical "
        f"toss, dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s",
        checks,
    )


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
                checks.append(
                    Check(
                        point,
                        solver,
                        passed,
                        f"centre at {end:.4f} m after 3 s (rest {rest:g} m), highest {highest:.4f} m",
                    )
                )
    return Row(
        "embedded",
        "Started 25% inside the floor",
        "pushed out: the centre within 1 mm of its resting height after 3 s; not launched: never more "
        "than 1 mm above it (energy is not checked: pushing out raises the potential energy)",
        f"the 2 x 1 m box 25 cm deep, k {', '.join(k_text(k) for k in stiffnesses)} N/m, "
        f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s",
        checks,
    )


def far_from_origin(exponents, distance: float = 1e5) -> Row:
    checks = []
    for exponent in exponents:
        for solver in SOLVERS:
            runs = [
                run_scene(cases.far_toss(x, dt=dt_of(exponent), solver=solver), 10.0, until_rest=True)
                for x in (0.0, distance)
            ]
            point = {"dt": dt_label(exponent)}
            if not all(run.finite for run in runs):
                checks.append(Check(point, solver, False, "non-finite"))
                continue
            shifted = runs[1].states[-1] - np.array([distance, 0, 0, 0, 0, 0])
            off = cases.pose_error(shifted, runs[0].states[-1], corner_radius(runs[0].box))
            checks.append(Check(point, solver, off <= 1e-3, f"landings differ by {sci(off)} m"))
    return Row(
        "far_from_origin",
        f"Far from the origin (x = {distance:g} m)",
        "the typical toss released at x = 1e5 m lands within 1 mm (|dx| + R |da|) of the same toss at x = 0, "
        "shifted (float64)",
        f"dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s",
        checks,
    )


CORNER_HITS = ((0.4, (2.0, -3.0), 1.0), (1.2, (-3.0, -1.0), -2.0))  # angle, velocity, spin


def corner_friction(frictions, restitutions, exponents, hits=CORNER_HITS) -> Row:
    checks = []
    for friction in frictions:
        for restitution in restitutions:
            for hit, (angle, velocity, spin) in enumerate(hits):
                for exponent in exponents:
                    for solver in SOLVERS:
                        scene = cases.friction_corner_hit(
                            friction, restitution, angle, velocity, spin, dt=dt_of(exponent), solver=solver
                        )
                        point = {
                            "mu": f"{friction:g}",
                            "e": f"{restitution:g}",
                            "hit": hit + 1,
                            "dt": dt_label(exponent),
                        }
                        run = run_scene(scene, 1.0)
                        if not run.finite:
                            checks.append(not_finite(run, point, solver))
                            continue
                        ke = kinetic_energy(run.box, run.states)
                        rise = float(np.diff(ke).max(initial=0.0))
                        passed = rise <= ENERGY_ROUNDING * ke[0]
                        checks.append(
                            Check(
                                point, solver, passed, f"largest step-to-step KE rise {sci(rise)} J (KE0 {ke[0]:.3g} J)"
                            )
                        )
    hits_text = "; ".join(
        f"hit {i + 1}: angle {a:g}, v ({v[0]:g}, {v[1]:g}) m/s, spin {w:g} rad/s" for i, (a, v, w) in enumerate(hits)
    )
    return Row(
        "corner_friction",
        "Angled corner hit with friction",
        "kinetic energy never rises from one step to the next (zero gravity, so nothing feeds it)",
        f"mu {', '.join(f'{m:g}' for m in frictions)}, e {', '.join(f'{e:g}' for e in restitutions)}, "
        f"2 x 1 m box ({hits_text}), dt {dt_label(min(exponents))} to {dt_label(max(exponents))} s",
        checks,
    )
