"""The robust default solver: the seed's ingredients (impulses with restitution, Coulomb
friction, a penalty for penetration, symplectic Euler), arranged so they stay right.

A box is in one of two modes.

Flight: no stepping at all. The motion is the closed-form parabola with constant spin
(``flight``), and conservative advancement finds the first time a corner reaches y = 0, so
flights and bounces are exact whatever the time step and however fast the box moves (no
tunnelling). At that instant an impact is resolved (``resolve_impact``): the touching corners
together, compression then restitution (Poisson: e times the compression impulse, which is
Newton's u_n+ = -e u_n- for one frictionless corner and never creates energy with friction) for
corners approaching faster than the restitution threshold, friction clamped to mu times the
normal impulse. A box that leaves the floor flies on;
one that stays goes to

Contact: time-stepping on the grid t_n = n dt (the stage script in ``make_robust_kernel``), the
stages of one step being
  1. integrate velocities: v += dt g;
  2. solve contact velocities: the two corners of the face that is down together (2 x 2 LCP),
     each may close its gap but not pass it (speculative: u_n >= -max(y_i, 0)/dt), with clamped
     friction that never reverses sliding;
  3. restitution: corners that hit faster than the threshold bounce back with e times the
     impulse that stopped them (Poisson; resting contact gets none, so it stays still);
  4. integrate positions: x += dt v, alpha += dt omega (symplectic Euler);
  5. penalty: penetration is removed by the critically damped penalty spring integrated with
     backward Euler, as a pseudo-velocity, stable for every stiffness and step
     (``penalty_correction_share``).
A step is split into substeps when the box would turn more than MAX_ROTATION_PER_STEP.
The box flies again when no corner is loaded or below the floor, and it is put to sleep
(velocities set to zero, stepping stops) once it has lain still on a face for ``sleep_time``.

What this fixes in the seed scheme (measured on it): corners resolved one after another make
a flat drop spin and bounce low; friction applied corner after corner makes a resting box creep
(13 cm in 10 s with mu = 0.5, none with mu = 0);
a friction impulse of mu |p| can reverse sliding; an explicit penalty spring blows up beyond
omega dt = 2; time-stepped flight and impacts move the landing pose with the step size.
"""

import math

import numpy as np

from . import layout
from .compilation import jit_kernel, jit_stage
from .contact_solver import (
    apply_normal_impulses,
    correct_penetration,
    delassus,
    friction_impulse,
    normal_impulses,
    solve_contact_velocities,
    solve_normal_velocities,
)
from .flight import flight_state, time_to_contact
from .geometry import lowest_face, lowest_pair, vertex_offset
from .kernel_support import lies_still, read_settings, record_event, store_state, write_stats

MAX_ROTATION_PER_STEP = 0.05  # [rad] a contact step turning the box further is split
MAX_SUBSTEPS = 64
CONTACT_TOLERANCE = 1e-12  # [m per m of corner radius + 1 m] a corner this close touches
SIMULTANEOUS_TOLERANCE = 1e-9  # [same units] corners this close hit at the same instant
FRICTION_ITERATIONS = 8  # at most this many Gauss-Seidel sweeps over friction and the normal block


@jit_stage
def resolve_impact(y, cos_a, sin_a, vx, vy, spin, half_length, half_width, inv_mass, inv_inertia, restitution,
                   friction, threshold, simultaneous):
    """Impulses of an impact at the instant a corner reaches the floor.

    The touching corners (the lowest one, and its neighbour if within ``simultaneous`` of the
    same height) are solved together, in Poisson's two phases:
      compression: the impulses lam_c that stop every approaching corner (u_n+ = 0), with friction
        clamped to mu lam_c;
      restitution: each corner that hit faster than the threshold gets e lam_c more along the
        normal, with friction clamped to mu e lam_c.
    For a frictionless single corner this is Newton's law u_n+ = -e u_n-; unlike Newton's law with
    friction, it never creates energy: compression removes 1/2 lam_c^T K lam_c and restitution
    returns e^2 of it, and clamped friction only removes energy.
    Returns (vx, vy, spin, corners hit, approach speed, leaves), ``leaves`` being True when every
    touching corner separates faster than the threshold.
    """
    first, second = lowest_face(cos_a, sin_a, half_length, half_width)
    rx1, ry1 = vertex_offset(first, cos_a, sin_a, half_length, half_width)
    rx2, ry2 = vertex_offset(second, cos_a, sin_a, half_length, half_width)
    pair = ry2 <= ry1 + simultaneous
    u1 = vy + spin * rx1
    u2 = vy + spin * rx2
    approach = max(-u1, -u2) if pair else -u1
    if approach <= 0.0:
        return vx, vy, spin, 0, 0.0, False
    # compression
    if friction > 0.0:
        vx, vy, spin, lam1, lam2 = solve_contact_velocities(vx, vy, spin, rx1, ry1, rx2, ry2, pair, 0.0, 0.0,
                                                            friction, inv_mass, inv_inertia, FRICTION_ITERATIONS)
    else:
        vy, spin, lam1, lam2 = solve_normal_velocities(vy, spin, rx1, rx2, pair, 0.0, 0.0, inv_mass, inv_inertia)
    # restitution
    vx, vy, spin = restitution_impulses(vx, vy, spin, rx1, ry1, rx2, ry2, pair, lam1 if u1 < -threshold else 0.0,
                                        lam2 if u2 < -threshold else 0.0, 0.0, 0.0, restitution, friction,
                                        inv_mass, inv_inertia)
    leaves = vy + spin * rx1 > threshold and (not pair or vy + spin * rx2 > threshold)
    return vx, vy, spin, 2 if pair else 1, approach, leaves


@jit_stage
def restitution_impulses(vx, vy, spin, rx1, ry1, rx2, ry2, use2, compression1, compression2, target1, target2,
                         restitution, friction, inv_mass, inv_inertia):
    """Poisson's restitution phase: corner i gets the normal impulse e * compression_i, with friction
    clamped to mu e compression_i (it can stop the slip there, never reverse it); then a corner pushed
    towards the floor by the other's bounce is held at its target velocity (u_n >= target_i).
    Returns (vx, vy, spin)."""
    bounce1 = restitution * compression1
    bounce2 = restitution * compression2
    vy, spin = apply_normal_impulses(vy, spin, bounce1, bounce2, rx1, rx2, inv_mass, inv_inertia)
    if friction > 0.0:
        vx, spin, _ = friction_impulse(vx, spin, ry1, bounce1, 0.0, friction, inv_mass, inv_inertia)
        if use2:
            vx, spin, _ = friction_impulse(vx, spin, ry2, bounce2, 0.0, friction, inv_mass, inv_inertia)
    k11, k12, k22 = delassus(rx1, rx2, inv_mass, inv_inertia)
    hold1, hold2 = normal_impulses(vy + spin * rx1, vy + spin * rx2, target1, target2, 0.0, 0.0, k11, k12, k22,
                                   True, use2)
    vy, spin = apply_normal_impulses(vy, spin, hold1, hold2, rx1, rx2, inv_mass, inv_inertia)
    return vx, vy, spin


@jit_stage
def predicted_height(k, y, cos_a, sin_a, half_length, half_width, fall, spin, h):
    """Height of corner k after a step h at the current velocities, to first order."""
    rx, ry = vertex_offset(k, cos_a, sin_a, half_length, half_width)
    return y + ry + fall + h * spin * rx


@jit_stage
def contact_corners(y, cos_a, sin_a, vy, spin, half_length, half_width, gravity, h):
    """Lever arms (rx1, ry1, rx2, ry2) of the two corners that bound the face that will be down at
    the end of a step h, judged by the heights they would reach at the current velocities, so a
    corner swinging down is constrained before it gets there."""
    fall = h * (vy + gravity * h)
    first, second = lowest_pair(predicted_height(0, y, cos_a, sin_a, half_length, half_width, fall, spin, h),
                                predicted_height(1, y, cos_a, sin_a, half_length, half_width, fall, spin, h),
                                predicted_height(2, y, cos_a, sin_a, half_length, half_width, fall, spin, h),
                                predicted_height(3, y, cos_a, sin_a, half_length, half_width, fall, spin, h))
    rx1, ry1 = vertex_offset(first, cos_a, sin_a, half_length, half_width)
    rx2, ry2 = vertex_offset(second, cos_a, sin_a, half_length, half_width)
    return rx1, ry1, rx2, ry2


@jit_stage
def apply_restitution(vx, vy, spin, rx1, ry1, rx2, ry2, u1_before, u2_before, target1, target2, lam1, lam2,
                      restitution, friction, threshold, inv_mass, inv_inertia):
    """Corners that hit faster than the threshold and were stopped by the contact solve bounce back
    with e times the impulse that stopped their approach (Poisson, ``restitution_impulses``);
    resting contact gets none, so it stays still. Returns (vx, vy, spin, approach speed of the fastest such corner,
    0 if none)."""
    bounce1 = lam1 > 0.0 and u1_before < -threshold
    bounce2 = lam2 > 0.0 and u2_before < -threshold
    if not (bounce1 or bounce2):
        return vx, vy, spin, 0.0
    approach = max(-u1_before if bounce1 else 0.0, -u2_before if bounce2 else 0.0)
    if restitution > 0.0:
        # the compression impulse is what stopped the approach, -u_n- K_ii^-1, not the part of lam that
        # carried the weight during the step (bouncing that back would pump energy into a resting box)
        k11, _, k22 = delassus(rx1, rx2, inv_mass, inv_inertia)
        compression1 = min(lam1, -u1_before / k11) if bounce1 else 0.0
        compression2 = min(lam2, -u2_before / k22) if bounce2 else 0.0
        vx, vy, spin = restitution_impulses(vx, vy, spin, rx1, ry1, rx2, ry2, True, compression1, compression2,
                                            target1, target2, restitution, friction, inv_mass, inv_inertia)
    return vx, vy, spin, approach


@jit_stage
def is_finite_state(x, y, angle, vx, vy, spin):
    return (math.isfinite(x) and math.isfinite(y) and math.isfinite(angle) and math.isfinite(vx)
            and math.isfinite(vy) and math.isfinite(spin))


def make_robust_kernel(use_penalty: bool, use_friction: bool, record: bool, source_digest: int):
    """Build the robust kernel for exactly the stages a scene uses (flags are compile-time).

    ``run(state, params, settings, stats, trajectory, events)`` advances every body in place up
    to ``settings[MAX_STEPS]`` grid steps, or until it sleeps when ``settings[UNTIL_REST]``.
    """
    PENALTY, FRICTION, RECORD, DIGEST = use_penalty, use_friction, record, source_digest

    @jit_kernel
    def run(state, params, settings, stats, trajectory, events):
        # numba keys its on-disk cache on this file and the closure values: the digest of every engine
        # source must be a closure value, or a kernel compiled with an older stage would be loaded
        _ = DIGEST
        dt, gravity, max_steps, until_rest, threshold, sleep_speed, sleep_time, slop = read_settings(settings)
        end_time = max_steps * dt
        for i in range(state.shape[0]):
            x, y, angle, vx, vy, spin = (state[i, 0], state[i, 1], state[i, 2],
                                         state[i, 3], state[i, 4], state[i, 5])
            hx = params[i, layout.HALF_LENGTH]
            hy = params[i, layout.HALF_WIDTH]
            inv_mass = 1.0 / params[i, layout.MASS]
            inv_inertia = 1.0 / params[i, layout.INERTIA]
            restitution = params[i, layout.RESTITUTION]
            friction = params[i, layout.FRICTION]
            stiffness = params[i, layout.STIFFNESS]
            radius = math.sqrt(hx * hx + hy * hy)
            tolerance = CONTACT_TOLERANCE * (1.0 + radius)
            simultaneous = SIMULTANEOUS_TOLERANCE * (1.0 + radius)
            first_contact = math.nan
            rest_time = math.nan
            max_penetration = 0.0
            n_impacts = 0
            n_steps = 0
            status = layout.STATUS_OK
            fail_step = -1
            still_for = 0.0
            if RECORD:
                store_state(trajectory, 0, i, x, y, angle, vx, vy, spin)
            n = 0  # last grid step reached (and recorded)
            t = 0.0
            in_flight = True
            cos_a = math.cos(angle)
            sin_a = math.sin(angle)
            while n < max_steps:
                if in_flight:
                    # ---- flight: closed form up to the first contact ----
                    tau, touched = time_to_contact(y, angle, vy, spin, hx, hy, gravity, end_time - t, tolerance)
                    # grid rows passed in this flight: up to the end, or to the last one before the contact
                    last = max_steps if not touched else min(np.int64(math.floor((t + tau) / dt)), max_steps)
                    if RECORD:
                        for row in range(n + 1, last + 1):
                            xr, yr, ar, vxr, vyr, wr = flight_state(x, y, angle, vx, vy, spin, gravity, row * dt - t)
                            store_state(trajectory, row, i, xr, yr, ar, vxr, vyr, wr)
                    x, y, angle, vx, vy, spin = flight_state(x, y, angle, vx, vy, spin, gravity, tau)
                    cos_a = math.cos(angle)
                    sin_a = math.sin(angle)
                    if not touched:
                        n = max_steps
                        t = end_time
                        if not is_finite_state(x, y, angle, vx, vy, spin):
                            status = layout.STATUS_NONFINITE
                            fail_step = n
                        break
                    t = t + tau
                    if math.isnan(first_contact):
                        first_contact = t
                    # ---- impact at the contact instant ----
                    vx, vy, spin, corners, approach, leaves = resolve_impact(
                        y, cos_a, sin_a, vx, vy, spin, hx, hy, inv_mass, inv_inertia, restitution, friction,
                        threshold, simultaneous)
                    if corners > 0 and approach > threshold:
                        if RECORD:
                            record_event(events, i, n_impacts, t, approach, corners)
                        n_impacts += 1
                    if not is_finite_state(x, y, angle, vx, vy, spin):
                        status = layout.STATUS_NONFINITE
                        fail_step = np.int64(math.floor(t / dt))
                        break
                    n = max(n, last)  # rows up to n hold the flight
                    if leaves:
                        continue
                    in_flight = False
                    if (n + 1) * dt <= t and n < max_steps:  # the contact fell on grid point n + 1
                        n += 1
                        if RECORD:
                            store_state(trajectory, n, i, x, y, angle, vx, vy, spin)
                    if n >= max_steps:
                        t = end_time
                        break
                    h = (n + 1) * dt - t  # a partial step brings the box back onto the grid
                else:
                    h = dt
                # ---- one contact step on the grid, split where the box turns fast ----
                n_sub = min(max(np.int64(math.ceil(abs(spin) * h / MAX_ROTATION_PER_STEP)), 1), MAX_SUBSTEPS)
                h_sub = h / n_sub
                held = False
                ry1 = ry2 = rx1 = rx2 = 0.0
                for _ in range(n_sub):
                    rx1, ry1, rx2, ry2 = contact_corners(y, cos_a, sin_a, vy, spin, hx, hy, gravity, h_sub)
                    u1_before = vy + spin * rx1
                    u2_before = vy + spin * rx2
                    # 1. integrate velocities
                    vy = vy + gravity * h_sub
                    # 2. contact velocities: each corner may close its gap but not pass it
                    target1 = -max(y + ry1, 0.0) / h_sub
                    target2 = -max(y + ry2, 0.0) / h_sub
                    if FRICTION:
                        vx, vy, spin, lam1, lam2 = solve_contact_velocities(
                            vx, vy, spin, rx1, ry1, rx2, ry2, True, target1, target2, friction, inv_mass,
                            inv_inertia, FRICTION_ITERATIONS)
                    else:
                        vy, spin, lam1, lam2 = solve_normal_velocities(vy, spin, rx1, rx2, True, target1, target2,
                                                                       inv_mass, inv_inertia)
                    # 3. restitution
                    vx, vy, spin, approach = apply_restitution(vx, vy, spin, rx1, ry1, rx2, ry2, u1_before, u2_before,
                                                               target1, target2, lam1, lam2, restitution, friction,
                                                               threshold, inv_mass, inv_inertia)
                    if approach > 0.0:
                        if RECORD:
                            record_event(events, i, n_impacts, t, approach, 1)
                        n_impacts += 1
                    # 4. integrate positions
                    x = x + h_sub * vx
                    y = y + h_sub * vy
                    angle = angle + h_sub * spin
                    cos_a = math.cos(angle)
                    sin_a = math.sin(angle)
                    first, second = lowest_face(cos_a, sin_a, hx, hy)
                    rx1, ry1 = vertex_offset(first, cos_a, sin_a, hx, hy)
                    rx2, ry2 = vertex_offset(second, cos_a, sin_a, hx, hy)
                    penetration = -(y + ry1)
                    max_penetration = max(max_penetration, penetration)
                    # 5. penalty: implicit correction of what penetrates beyond the slop
                    if PENALTY and penetration > slop + tolerance:
                        y, angle = correct_penetration(y, angle, penetration - slop, -(y + ry2) - slop, rx1, rx2,
                                                       stiffness, h_sub, inv_mass, inv_inertia)
                        cos_a = math.cos(angle)
                        sin_a = math.sin(angle)
                        rx1, ry1 = vertex_offset(first, cos_a, sin_a, hx, hy)
                        rx2, ry2 = vertex_offset(second, cos_a, sin_a, hx, hy)
                    held = held or lam1 > 0.0 or lam2 > 0.0 or penetration > 0.0
                n_steps += 1
                n += 1
                t = n * dt
                if RECORD:
                    store_state(trajectory, n, i, x, y, angle, vx, vy, spin)
                if not is_finite_state(x, y, angle, vx, vy, spin):
                    status = layout.STATUS_NONFINITE
                    fail_step = n
                    break
                if until_rest:
                    if lies_still(y, ry1, ry2, rx1, rx2, vx, vy, spin, hx, hy, sleep_speed):
                        still_for += h
                        if still_for >= sleep_time:
                            vx, vy, spin = 0.0, 0.0, 0.0
                            rest_time = t
                            if RECORD:
                                store_state(trajectory, n, i, x, y, angle, vx, vy, spin)
                            break
                    else:
                        still_for = 0.0
                if not held:
                    in_flight = True
            state[i, 0], state[i, 1], state[i, 2] = x, y, angle
            state[i, 3], state[i, 4], state[i, 5] = vx, vy, spin
            write_stats(stats, i, first_contact, n_impacts, n_steps, max_penetration, rest_time, t,
                        status, fail_step, n + 1)

    return run
