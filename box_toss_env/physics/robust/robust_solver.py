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
stages of one step (or of a piece of it) being
  0. impacts: where a corner touching the floor approaches faster than the restitution threshold,
     the touching corners take an impact at this instant (``contact_impact``, Poisson as above);
  1. integrate velocities: v += dt g;
  2. solve contact velocities: the corners that can reach the floor in the step (the lowest, and
     both its neighbours: a thin box's far end too, ``contact_corners``) together (an LCP of up to
     three corners; one corner with friction exactly), each may close its gap but not pass it
     (speculative: u_n >= -max(y_i, 0)/dt), with clamped friction that never reverses sliding;
  3. locate impacts: a corner off the floor that this solve had to stop while it approached faster
     than the threshold would hit inside the step, after gap / approach: the piece is redone up to
     that instant and the impact resolved there (0.), so impacts in contact are not tied to the grid;
  4. no energy gained: where the step would end with more kinetic + potential energy than it began
     with (the contacts pushing the centre up within a step), the velocities are scaled down to
     exactly what gains nothing (``energy_limit_scale``);
  5. integrate positions: x += dt v, alpha += dt omega (symplectic Euler);
  6. penalty: penetration is removed by the critically damped penalty spring integrated with
     backward Euler, as a pseudo-velocity, stable for every stiffness and step
     (``penalty_correction_share``); the potential energy this returns is taken from the kinetic.
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

from .. import layout
from ..compile.compilation import jit_kernel, jit_stage
from ..geometry import lowest_face, lowest_pair, vertex_offset
from ..kernel_support import lies_still, read_settings, record_event, store_state, write_stats
from .contact_solver import (
    APPROACH,
    COMPRESSION,
    CORNER_ROWS,
    DEPTH,
    IMPULSE,
    MAX_CORNERS,
    RX,
    RY,
    SCRATCH,
    TARGET,
    apply_normal_impulses,
    correct_penetration,
    delassus,
    friction_impulse,
    normal_velocities,
    solve_contact_velocities,
    solve_normal_block,
)
from .flight import flight_state, time_to_contact

MAX_ROTATION_PER_STEP = 0.05  # [rad] a contact step turning the box further is split
MAX_SUBSTEPS = 64
PENALTY_TRIGGER = 2.0  # [slops] the penalty starts once a corner is this deep, then removes what lies beyond one slop
# (a band, as Box2D 2.x's position solver stops within 3 slops: a pile whose looser solve lets corners creep to
# the slop would otherwise run the penalty at every step)
CONTACT_TOLERANCE = 1e-12  # [m per m of corner radius + 1 m] a corner this close touches
SIMULTANEOUS_TOLERANCE = 1e-9  # [same units] corners this close hit at the same instant
FRICTION_ITERATIONS = 8  # at most this many Gauss-Seidel sweeps over friction and the normal block
MAX_LOCATED_IMPACTS = 16  # impacts located inside one contact step at most; later ones are stopped on the grid


@jit_stage
def place_corner(corners, i, k, cos_a, sin_a, half_length, half_width):
    """Corner k of the box as column i of the corner work array (its lever arm)."""
    corners[RX, i], corners[RY, i] = vertex_offset(k, cos_a, sin_a, half_length, half_width)


@jit_stage
def impact_impulses(vx, vy, spin, corners, n, restitution, friction, threshold, inv_mass, inv_inertia, k):
    """Impulses of an impact at this instant on the first n corners (those touching the floor), in
    Poisson's two phases:
      compression: the impulses lam_c that stop every approaching corner (u_n+ >= 0), with friction
        clamped to mu lam_c;
      restitution: each corner that hit faster than the threshold gets e lam_c more along the
        normal, with friction clamped to mu e lam_c.
    For a frictionless single corner this is Newton's law u_n+ = -e u_n-; unlike Newton's law with
    friction, it never creates energy: compression removes 1/2 lam_c^T K lam_c and restitution
    returns e^2 of it, and clamped friction only removes energy. A touching corner that is not
    approaching (one the box rests or pivots on) takes part in the compression: it holds.
    Returns (vx, vy, spin, approach speed of the fastest corner, 0 if none approaches).
    """
    normal_velocities(vy, spin, corners, n, APPROACH)
    approach = 0.0
    for i in range(n):
        approach = max(approach, -corners[APPROACH, i])
        corners[TARGET, i] = 0.0
    if approach <= 0.0:
        return vx, vy, spin, 0.0
    # compression
    vx, vy, spin = solve_contact_velocities(vx, vy, spin, corners, n, friction, inv_mass, inv_inertia,
                                            FRICTION_ITERATIONS, k)
    # restitution
    for i in range(n):
        corners[COMPRESSION, i] = corners[IMPULSE, i] if corners[APPROACH, i] < -threshold else 0.0
    vx, vy, spin = restitution_impulses(vx, vy, spin, corners, n, restitution, friction, inv_mass, inv_inertia, k)
    return vx, vy, spin, approach


@jit_stage
def resolve_impact(y, cos_a, sin_a, vx, vy, spin, half_length, half_width, inv_mass, inv_inertia, restitution,
                   friction, threshold, simultaneous, corners, k):
    """The impact of a flying box at the instant a corner reaches the floor (``impact_impulses``) on the
    touching corners: the lowest one, and its neighbour if within ``simultaneous`` of the same height.
    Returns (vx, vy, spin, corners hit, approach speed, leaves), ``leaves`` being True when every
    touching corner separates faster than the threshold.
    """
    first, second = lowest_face(cos_a, sin_a, half_length, half_width)
    place_corner(corners, 0, first, cos_a, sin_a, half_length, half_width)
    place_corner(corners, 1, second, cos_a, sin_a, half_length, half_width)
    n = 2 if corners[RY, 1] <= corners[RY, 0] + simultaneous else 1
    vx, vy, spin, approach = impact_impulses(vx, vy, spin, corners, n, restitution, friction, threshold, inv_mass,
                                             inv_inertia, k)
    if approach <= 0.0:
        return vx, vy, spin, 0, 0.0, False
    leaves = True
    for i in range(n):
        leaves = leaves and vy + spin * corners[RX, i] > threshold
    return vx, vy, spin, n, approach, leaves


@jit_stage
def contact_impact(y, cos_a, sin_a, vx, vy, spin, half_length, half_width, inv_mass, inv_inertia, restitution,
                   friction, threshold, tolerance, located, loaded, corners, k):
    """The impact of a box in contact at this instant: where a corner touching the floor approaches faster
    than the threshold, the touching corners (at most three, the lowest) take ``impact_impulses`` together.
    A corner touches when it is within ``tolerance`` of the floor, is the one ``located`` to arrive now, or
    carried load in the last piece (bit c of ``loaded``: it ended that piece on the floor, up to the
    second-order lift of a rotating step, which must not decide whether it takes part).
    Returns (vx, vy, spin, corners touching, approach speed, 0 if no impact)."""
    n = 0
    for c in range(4):
        rx, ry = vertex_offset(c, cos_a, sin_a, half_length, half_width)
        touches = y + ry <= tolerance or c == located or (loaded >> c) & 1 == 1
        if touches and vy + spin * rx < -threshold:
            n = 1
    if n == 0:
        return vx, vy, spin, 0, 0.0
    n = 0
    for c in range(4):
        rx, ry = vertex_offset(c, cos_a, sin_a, half_length, half_width)
        if y + ry <= tolerance or c == located or (loaded >> c) & 1 == 1:
            if n < MAX_CORNERS:
                corners[RX, n], corners[RY, n] = rx, ry
                n += 1
            else:  # a fourth touching corner (never lower than the others at once): replace the highest
                highest = 0
                for i in range(1, MAX_CORNERS):
                    if corners[RY, i] > corners[RY, highest]:
                        highest = i
                if ry < corners[RY, highest]:
                    corners[RX, highest], corners[RY, highest] = rx, ry
    vx, vy, spin, approach = impact_impulses(vx, vy, spin, corners, n, restitution, friction, threshold, inv_mass,
                                             inv_inertia, k)
    return vx, vy, spin, n, approach


@jit_stage
def restitution_impulses(vx, vy, spin, corners, n, restitution, friction, inv_mass, inv_inertia, k):
    """Poisson's restitution phase: corner i gets the normal impulse e * compression_i (row COMPRESSION),
    with friction clamped to mu e compression_i (it can stop the slip there, never reverse it); then a
    corner pushed towards the floor by another's bounce is held at its target velocity (u_n >= b_i,
    row TARGET). Returns (vx, vy, spin)."""
    for i in range(n):
        corners[SCRATCH, i] = restitution * corners[COMPRESSION, i]
    vy, spin = apply_normal_impulses(vy, spin, corners, n, SCRATCH, inv_mass, inv_inertia)
    if friction > 0.0:
        for i in range(n):
            vx, spin, _ = friction_impulse(vx, spin, corners[RY, i], restitution * corners[COMPRESSION, i], 0.0,
                                           friction, inv_mass, inv_inertia)
    delassus(corners, n, inv_mass, inv_inertia, k)
    for i in range(n):
        corners[IMPULSE, i] = 0.0
    return (vx, *solve_normal_block(vy, spin, corners, n, inv_mass, inv_inertia, k))


@jit_stage
def predicted_height(k, y, cos_a, sin_a, half_length, half_width, fall, spin, h):
    """Height of corner k after a step h at the current velocities, to first order."""
    rx, ry = vertex_offset(k, cos_a, sin_a, half_length, half_width)
    return y + ry + fall + h * spin * rx


@jit_stage
def contact_corners(y, cos_a, sin_a, vy, spin, half_length, half_width, gravity, h, reach, corners, ids):
    """The corners that can touch the floor in a step h, as the first columns of ``corners`` (their indices in
    ``ids``): of the one that would be lowest at the end of the step at the current velocities, its lower
    neighbour (they bound the face that will be down) and its other neighbour (the far end of a thin box's
    long side, whose two lowest corners are the ends of a short side once it tilts by atan(W / L)), those
    within ``reach`` of the floor. Each is constrained only to close its gap, so one that cannot reach the
    floor in the step would get no impulse; leaving out those further than ``reach`` (what any point of the
    box can travel in the step) saves the work. Returns how many there are."""
    fall = h * (vy + gravity * h)
    first, second = lowest_pair(predicted_height(0, y, cos_a, sin_a, half_length, half_width, fall, spin, h),
                                predicted_height(1, y, cos_a, sin_a, half_length, half_width, fall, spin, h),
                                predicted_height(2, y, cos_a, sin_a, half_length, half_width, fall, spin, h),
                                predicted_height(3, y, cos_a, sin_a, half_length, half_width, fall, spin, h))
    third = (first + 1) % 4 if second == (first + 3) % 4 else (first + 3) % 4
    n = 0
    for corner in (first, second, third):
        place_corner(corners, n, corner, cos_a, sin_a, half_length, half_width)
        if y + corners[RY, n] <= reach:
            ids[n] = corner
            n += 1
    return n


@jit_stage
def kinetic_energy(vx, vy, spin, inv_mass, inv_inertia):
    """m |v|^2 / 2 + I omega^2 / 2 [J]."""
    return 0.5 * (vx * vx + vy * vy) / inv_mass + 0.5 * spin * spin / inv_inertia


@jit_stage
def energy_limit_scale(kinetic_before, kinetic_after, potential_rise):
    """The factor s in [0, 1] on the velocities of a contact step that keeps the step from gaining energy.

    Symplectic Euler adds g h to v, the contacts take it back where the floor holds the box, and
    positions move with what is left: where the contacts push the centre up (a rocking or bouncing box)
    it rises h v_y without gravity having slowed it in that step, and kinetic + potential energy can
    grow by up to m |g| h dv_y (18% of the energy of the moment for a thin bouncing box at h = 1/32 s).
    With the velocities scaled by s, the step changes the energy by s^2 A + s B - C, where A is the
    kinetic energy after the contact stages, B = -m g h v_y the potential energy the position update
    adds and C the kinetic energy before the step; s is 1 where that is <= 0, else its root
    s = 2 C / (B + sqrt(B^2 + 4 A C)), the largest s that gains nothing. Scaling the whole velocity keeps
    every contact satisfied (u_n,i >= b_i with b_i <= 0 holds for s u_n,i) and never reverses sliding.
    The correction is O(h) and vanishes where no step would gain (flight, sliding, resting).
    """
    a, b, c = kinetic_after, potential_rise, kinetic_before
    if a + b <= c:
        return 1.0
    root = math.sqrt(b * b + 4.0 * a * c)
    s = 2.0 * c / (b + root) if b > 0.0 else (root - b) / (2.0 * a)
    return min(max(s, 0.0), 1.0)


@jit_stage
def is_finite_state(x, y, angle, vx, vy, spin):
    return (math.isfinite(x) and math.isfinite(y) and math.isfinite(angle) and math.isfinite(vx)
            and math.isfinite(vy) and math.isfinite(spin))


# What ``advance_box`` keeps of a box between calls: one row per box, MEMORY_SIZE columns
IN_FLIGHT, LOCATED, LOADED, LIFT, STILL_FOR, FIRST_CONTACT, REST_TIME, MAX_PENETRATION, N_IMPACTS, N_STEPS, TIME, \
    STATUS, FAIL_STEP = range(13)
MEMORY_SIZE = 13


@jit_stage
def start_memory(memory, i, time):
    """Box i's row of ``advance_box``'s memory for a box starting (in flight) at ``time``."""
    memory[i, :] = 0.0
    memory[i, IN_FLIGHT] = 1.0
    memory[i, LOCATED] = -1.0
    memory[i, FIRST_CONTACT] = math.nan
    memory[i, REST_TIME] = math.nan
    memory[i, TIME] = time
    memory[i, FAIL_STEP] = -1.0


@jit_stage(inline="always")
def read_memory(memory, i):
    """Box i's row of ``memory`` as (in flight, located corner, loaded corners, lift, still for, first contact,
    rest time, max penetration, impacts, steps, time)."""
    return (memory[i, IN_FLIGHT] != 0.0, np.int64(memory[i, LOCATED]), np.int64(memory[i, LOADED]), memory[i, LIFT],
            memory[i, STILL_FOR], memory[i, FIRST_CONTACT], memory[i, REST_TIME], memory[i, MAX_PENETRATION],
            np.int64(memory[i, N_IMPACTS]), np.int64(memory[i, N_STEPS]), memory[i, TIME])


@jit_stage(inline="always")
def write_memory(memory, i, in_flight, located, loaded, lift, still_for, first_contact, rest_time, max_penetration,
                 n_impacts, n_steps, t, status, fail_step):
    """``read_memory``'s inverse, with the status and the failed step."""
    memory[i, IN_FLIGHT] = 1.0 if in_flight else 0.0
    memory[i, LOCATED] = located
    memory[i, LOADED] = loaded
    memory[i, LIFT] = lift
    memory[i, STILL_FOR] = still_for
    memory[i, FIRST_CONTACT] = first_contact
    memory[i, REST_TIME] = rest_time
    memory[i, MAX_PENETRATION] = max_penetration
    memory[i, N_IMPACTS] = n_impacts
    memory[i, N_STEPS] = n_steps
    memory[i, TIME] = t
    memory[i, STATUS] = status
    memory[i, FAIL_STEP] = fail_step


@jit_stage(inline="always")
def fly(i, x, y, angle, vx, vy, spin, hx, hy, gravity, t, n, n_end, dt, tolerance, record, trajectory):
    """Flight in closed form from time t (grid step n) to the first contact with the floor or to grid step
    ``n_end``, whichever comes first, the grid rows passed recorded. Returns the state there, the time flown,
    whether a corner touched, and the last grid row the flight passed."""
    end_time = n_end * dt
    tau, touched = time_to_contact(y, angle, vy, spin, hx, hy, gravity, end_time - t, tolerance, 0.0)
    # grid rows passed in this flight: up to the end, or to the last one before the contact
    last = n_end if not touched else min(np.int64(math.floor((t + tau) / dt)), n_end)
    if record:
        for row in range(n + 1, last + 1):
            xr, yr, ar, vxr, vyr, wr = flight_state(x, y, angle, vx, vy, spin, gravity, row * dt - t)
            store_state(trajectory, row, i, xr, yr, ar, vxr, vyr, wr)
    x, y, angle, vx, vy, spin = flight_state(x, y, angle, vx, vy, spin, gravity, tau)
    return x, y, angle, vx, vy, spin, tau, touched, last


@jit_stage(inline="always")
def solve_piece(y, cos_a, sin_a, vx, vy, spin, left, hx, hy, gravity, tolerance, radius, threshold, friction, inv_mass,
                inv_inertia, located_impacts, corners, k, ids):
    """Stages 1.-3. of a piece of a contact step of at most ``left``: velocities with gravity, the contact
    velocities solved, and, where a corner off the floor was stopped while approaching faster than the
    threshold, the piece shortened to its arrival (that impact is then resolved at the piece's end, stage 0).
    Returns (vx, vy, spin, piece, located corner or -1, located impacts so far, corners in contact, kinetic
    energy at the start)."""
    piece = left
    located = -1
    vx0, vy0, spin0 = vx, vy, spin
    for attempt in range(2):
        vx, vy, spin = vx0, vy0, spin0
        kinetic_before = kinetic_energy(vx, vy, spin, inv_mass, inv_inertia)
        # no point moves faster than sqrt(2 KE (1/m + R^2 / I)) once gravity has acted
        # (Cauchy-Schwarz; contact impulses never add kinetic energy)
        reach = tolerance + piece * math.sqrt(
            2.0 * kinetic_energy(vx, vy + gravity * piece, spin, inv_mass, inv_inertia)
            * (inv_mass + radius * radius * inv_inertia))
        n_corners = contact_corners(y, cos_a, sin_a, vy, spin, hx, hy, gravity, piece, reach,
                                    corners, ids)
        normal_velocities(vy, spin, corners, n_corners, APPROACH)
        # 1. integrate velocities
        vy = vy + gravity * piece
        # 2. contact velocities: each corner may close its gap but not pass it
        for c in range(n_corners):
            corners[TARGET, c] = -max(y + corners[RY, c], 0.0) / piece
        vx, vy, spin = solve_contact_velocities(vx, vy, spin, corners, n_corners, friction, inv_mass, inv_inertia,
                                                FRICTION_ITERATIONS, k)
        if attempt == 1:
            break
        # 3. an impact inside the piece: a corner off the floor stopped while approaching
        # faster than the threshold arrives after gap / approach; the piece is redone up to
        # that instant, where the impact is resolved (0.), not on the grid
        arrival = piece
        hit = -1
        for c in range(n_corners):
            gap = y + corners[RY, c]
            if (corners[IMPULSE, c] > 0.0 and corners[APPROACH, c] < -threshold
                    and gap > tolerance and gap < -arrival * corners[APPROACH, c]):
                arrival = -gap / corners[APPROACH, c]
                hit = ids[c]
        if hit < 0 or located_impacts >= MAX_LOCATED_IMPACTS:
            break
        located_impacts += 1
        located = hit
        piece = arrival
    return vx, vy, spin, piece, located, located_impacts, n_corners, kinetic_before


@jit_stage
def penalty_step(y, angle, vx, vy, spin, first, cos_a, sin_a, hx, hy, slop, stiffness, piece, gravity, inv_mass,
                 inv_inertia, corners, k):
    """Stage 6: the implicit penalty correction of what penetrates beyond the slop, at the lowest corner and its
    neighbours; the potential energy it returns is taken from the kinetic energy. Returns (y, angle, vx, vy,
    spin)."""
    below = 0
    for corner in (first, (first + 1) % 4, (first + 3) % 4):
        place_corner(corners, below, corner, cos_a, sin_a, hx, hy)
        corners[DEPTH, below] = -(y + corners[RY, below]) - slop
        if corners[DEPTH, below] > 0.0:
            below += 1
    lifted = y
    y, angle = correct_penetration(y, angle, corners, below, stiffness, piece, inv_mass, inv_inertia, k)
    kinetic = kinetic_energy(vx, vy, spin, inv_mass, inv_inertia)
    rise = -gravity * (y - lifted) / inv_mass
    if rise > 0.0 and kinetic > 0.0:
        scale = math.sqrt(max(1.0 - rise / kinetic, 0.0))
        vx, vy, spin = scale * vx, scale * vy, scale * spin
    return y, angle, vx, vy, spin


@jit_stage(inline="always")
def fly_to_impact(i, x, y, angle, vx, vy, spin, box, gravity, t, n, n_end, dt, tolerance, simultaneous, threshold,
                  first_contact, n_impacts, record, trajectory, events, corners, k):
    """Flight in closed form from time t (grid step n) to the first contact (``fly``) and the impact there
    (``resolve_impact``), or to grid step ``n_end``. Returns (x, y, angle, vx, vy, spin, cos, sin, t, n, first
    contact, impacts, in flight, whether to go on, status, failed step): a box that leaves the floor flies on; one
    that stays is brought back onto the grid, its contact step of (n + 1) dt - t next (unless ``n_end`` is
    reached); ``box``: (hx, hy, 1/m, 1/I, e, mu, k, radius)."""
    hx, hy, inv_mass, inv_inertia, restitution, friction, _, _ = box
    x, y, angle, vx, vy, spin, tau, touched, last = fly(i, x, y, angle, vx, vy, spin, hx, hy, gravity, t, n, n_end,
                                                        dt, tolerance, record, trajectory)
    cos_a = math.cos(angle)
    sin_a = math.sin(angle)
    if not touched:
        n = n_end
        failed = not is_finite_state(x, y, angle, vx, vy, spin)
        return (x, y, angle, vx, vy, spin, cos_a, sin_a, n_end * dt, n, first_contact, n_impacts, True, False,
                layout.STATUS_NONFINITE if failed else layout.STATUS_OK, n if failed else -1)
    t = t + tau
    if math.isnan(first_contact):
        first_contact = t
    vx, vy, spin, touching, approach, leaves = resolve_impact(
        y, cos_a, sin_a, vx, vy, spin, hx, hy, inv_mass, inv_inertia, restitution,
        friction, threshold, simultaneous, corners, k)
    if touching > 0 and approach > threshold:
        if record:
            record_event(events, i, n_impacts, t, approach, touching)
        n_impacts += 1
    if not is_finite_state(x, y, angle, vx, vy, spin):
        return (x, y, angle, vx, vy, spin, cos_a, sin_a, t, n, first_contact, n_impacts, True, False,
                layout.STATUS_NONFINITE, np.int64(math.floor(t / dt)))
    n = max(n, last)  # rows up to n hold the flight
    if not leaves:
        if (n + 1) * dt <= t and n < n_end:  # the contact fell on grid point n + 1
            n += 1
            if record:
                store_state(trajectory, n, i, x, y, angle, vx, vy, spin)
        if n >= n_end:
            t = n_end * dt
    return (x, y, angle, vx, vy, spin, cos_a, sin_a, t, n, first_contact, n_impacts, leaves, leaves or n < n_end,
            layout.STATUS_OK, -1)


@jit_stage(inline="always")
def contact_step(i, x, y, angle, vx, vy, spin, cos_a, sin_a, h, box, gravity, tolerance, threshold, slop, lift,
                 located, loaded, use_penalty, t, n_impacts, max_penetration, record, events, corners, k, ids):
    """One contact step of length h on the grid, split where the box turns fast and at impacts: stages 0.-6. of
    this module's docstring, piece after piece (``solve_piece``). Returns (x, y, angle, vx, vy, spin, cos, sin,
    located corner, loaded corners, lift, whether a corner held the box, impacts, max penetration)."""
    hx, hy, inv_mass, inv_inertia, restitution, friction, stiffness, radius = box
    n_sub = min(max(np.int64(math.ceil(abs(spin) * h / MAX_ROTATION_PER_STEP)), 1), MAX_SUBSTEPS)
    h_sub = h / n_sub
    held = False
    located_impacts = 0
    elapsed = 0.0  # time advanced in this step
    for _ in range(n_sub):
        left = h_sub
        while left > 0.0:
            # 0. impact at this instant: a touching corner approaching faster than the threshold
            vx, vy, spin, touching, approach = contact_impact(
                y, cos_a, sin_a, vx, vy, spin, hx, hy, inv_mass, inv_inertia, restitution,
                friction, threshold, tolerance + lift, located, loaded, corners, k)
            if approach > 0.0:
                if record:
                    record_event(events, i, n_impacts, t + elapsed, approach, touching)
                n_impacts += 1
            vx, vy, spin, piece, located, located_impacts, n_corners, kinetic_before = solve_piece(
                y, cos_a, sin_a, vx, vy, spin, left, hx, hy, gravity, tolerance, radius, threshold,
                friction, inv_mass, inv_inertia, located_impacts, corners, k, ids)
            loaded = 0
            for c in range(n_corners):
                if corners[IMPULSE, c] > 0.0:
                    loaded |= 1 << ids[c]
            held = held or loaded != 0
            # 4. no energy gained: the velocities scaled where the step would gain (energy_limit_scale)
            scale = energy_limit_scale(kinetic_before, kinetic_energy(vx, vy, spin, inv_mass,
                                                                      inv_inertia),
                                       -gravity * piece * vy / inv_mass)
            vx, vy, spin = scale * vx, scale * vy, scale * spin
            # 5. integrate positions
            x = x + piece * vx
            y = y + piece * vy
            angle = angle + piece * spin
            cos_a = math.cos(angle)
            sin_a = math.sin(angle)
            first, second = lowest_face(cos_a, sin_a, hx, hy)
            rx1, ry1 = vertex_offset(first, cos_a, sin_a, hx, hy)
            penetration = -(y + ry1)
            max_penetration = max(max_penetration, penetration)
            # 6. penalty: implicit correction of what penetrates beyond the slop, at the lowest corner
            # and its neighbours; the potential energy it returns is taken from the kinetic energy
            if use_penalty and penetration > PENALTY_TRIGGER * slop + tolerance:
                y, angle, vx, vy, spin = penalty_step(y, angle, vx, vy, spin, first, cos_a, sin_a, hx, hy, slop,
                                                      stiffness, piece, gravity, inv_mass, inv_inertia, corners, k)
                cos_a = math.cos(angle)
                sin_a = math.sin(angle)
            held = held or penetration > 0.0
            lift = h_sub * h_sub * spin * spin * radius  # how far a rotating substep lifts a held corner
            elapsed += piece
            left = left - piece if piece < left else 0.0
    return x, y, angle, vx, vy, spin, cos_a, sin_a, located, loaded, lift, held, n_impacts, max_penetration


@jit_stage(inline="always")
def lies_still_at(y, cos_a, sin_a, vx, vy, spin, hx, hy, sleep_speed):
    """``kernel_support.lies_still`` for a box whose angle has cosine ``cos_a`` and sine ``sin_a``."""
    first, second = lowest_face(cos_a, sin_a, hx, hy)
    rx1, ry1 = vertex_offset(first, cos_a, sin_a, hx, hy)
    rx2, ry2 = vertex_offset(second, cos_a, sin_a, hx, hy)
    return lies_still(y, ry1, ry2, rx1, rx2, vx, vy, spin, hx, hy, sleep_speed)


@jit_stage
def advance_box(i, state, params, memory, n, n_end, dt, gravity, until_rest, threshold, sleep_speed, sleep_time,
                slop, use_penalty, use_friction, record, corners, k, ids, trajectory, events):
    """Box i against the floor alone, from grid step n (its time ``memory[i, TIME]``) to grid step ``n_end``,
    or until it falls asleep or its state stops being finite: the stage script of this module's docstring.
    What a box carries from one call to the next (its mode, the located corner, its time, its counts) is its
    row of ``memory`` (``start_memory``), so a box advanced in pieces goes on as one advanced in one call
    (the floor-only kernel calls it once per box; the colliding kernel for a box that no other can reach).
    ``corners``, ``k``, ``ids``: work arrays (``contact_solver``). Returns the grid step reached."""
    x, y, angle, vx, vy, spin = (state[i, 0], state[i, 1], state[i, 2],
                                 state[i, 3], state[i, 4], state[i, 5])
    hx = params[i, layout.HALF_LENGTH]
    hy = params[i, layout.HALF_WIDTH]
    radius = math.sqrt(hx * hx + hy * hy)
    box = (hx, hy, 1.0 / params[i, layout.MASS], 1.0 / params[i, layout.INERTIA], params[i, layout.RESTITUTION],
           params[i, layout.FRICTION] if use_friction else 0.0, params[i, layout.STIFFNESS], radius)
    tolerance = CONTACT_TOLERANCE * (1.0 + radius)
    (in_flight, located, loaded, lift, still_for, first_contact, rest_time, max_penetration, n_impacts, n_steps,
     t) = read_memory(memory, i)
    status = layout.STATUS_OK
    fail_step = -1
    cos_a = math.cos(angle)
    sin_a = math.sin(angle)
    while n < n_end:
        if in_flight:
            # ---- flight: closed form up to the first contact, the impact there ----
            (x, y, angle, vx, vy, spin, cos_a, sin_a, t, n, first_contact, n_impacts, in_flight, going_on, status,
             fail_step) = fly_to_impact(i, x, y, angle, vx, vy, spin, box, gravity, t, n, n_end, dt, tolerance,
                                        SIMULTANEOUS_TOLERANCE * (1.0 + radius), threshold, first_contact,
                                        n_impacts, record, trajectory, events, corners, k)
            if not going_on:
                break
            if in_flight:
                continue
            h = (n + 1) * dt - t  # a partial step brings the box back onto the grid
        else:
            h = dt
        # ---- one contact step on the grid, split where the box turns fast and at impacts ----
        (x, y, angle, vx, vy, spin, cos_a, sin_a, located, loaded, lift, held, n_impacts,
         max_penetration) = contact_step(i, x, y, angle, vx, vy, spin, cos_a, sin_a, h, box, gravity, tolerance,
                                         threshold, slop, lift, located, loaded, use_penalty, t, n_impacts,
                                         max_penetration, record, events, corners, k, ids)
        n_steps += 1
        n += 1
        t = n * dt
        if record:
            store_state(trajectory, n, i, x, y, angle, vx, vy, spin)
        if not is_finite_state(x, y, angle, vx, vy, spin):
            status = layout.STATUS_NONFINITE
            fail_step = n
            break
        if until_rest:
            if lies_still_at(y, cos_a, sin_a, vx, vy, spin, hx, hy, sleep_speed):
                still_for += h
                if still_for >= sleep_time:
                    vx, vy, spin = 0.0, 0.0, 0.0
                    rest_time = t
                    if record:
                        store_state(trajectory, n, i, x, y, angle, vx, vy, spin)
                    break
            else:
                still_for = 0.0
        if not held:
            in_flight = True
            located = -1
            loaded = 0
    state[i, 0], state[i, 1], state[i, 2] = x, y, angle
    state[i, 3], state[i, 4], state[i, 5] = vx, vy, spin
    write_memory(memory, i, in_flight, located, loaded, lift, still_for, first_contact, rest_time, max_penetration,
                 n_impacts, n_steps, t, status, fail_step)
    return n


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
        corners = np.zeros((CORNER_ROWS, MAX_CORNERS))  # the corner work array (contact_solver)
        k = np.zeros((MAX_CORNERS, MAX_CORNERS))  # their Delassus matrix
        ids = np.zeros(MAX_CORNERS, np.int64)  # which corner of the box each column is
        memory = np.zeros((state.shape[0], MEMORY_SIZE))
        for i in range(state.shape[0]):
            if RECORD:
                store_state(trajectory, 0, i, state[i, 0], state[i, 1], state[i, 2], state[i, 3], state[i, 4],
                            state[i, 5])
            start_memory(memory, i, 0.0)
            n = advance_box(i, state, params, memory, 0, max_steps, dt, gravity, until_rest, threshold, sleep_speed,
                            sleep_time, slop, PENALTY, FRICTION, RECORD, corners, k, ids, trajectory, events)
            write_stats(stats, i, memory[i, FIRST_CONTACT], np.int64(memory[i, N_IMPACTS]),
                        np.int64(memory[i, N_STEPS]), memory[i, MAX_PENETRATION], memory[i, REST_TIME],
                        memory[i, TIME], np.int64(memory[i, STATUS]), np.int64(memory[i, FAIL_STEP]), n + 1)

    return run
