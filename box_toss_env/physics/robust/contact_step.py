"""One contact step of the floor-only robust solver on the grid t_n = n dt, as the script of its stages
(``contact_step``, the order of ``stages.FLOOR_PIECE``).

A step of length h is split into substeps where the box would turn more than MAX_ROTATION_PER_STEP, and each
substep into pieces at the impacts located inside it; each piece runs
  restitution (``restitution.contact_impact``): where a corner touching the floor approaches faster than the
     restitution threshold, the touching corners take an impact at this instant;
  find contacts (``prepare_contacts``): the corners that can reach the floor in the piece (``contact_corners``: the
     lowest, and both its neighbours, a thin box's far end too), with their normal velocities before it;
  integrate velocities: v += h g;
  solve contacts (``solve_contacts``): those corners together (an LCP of up to three corners, one corner with
     friction exactly, ``contact_solver``), each may close its gap but not pass it (speculative:
     u_n >= -max(y_i, 0) / h), with clamped friction that never reverses sliding;
  locate impacts (``locate_impact``): a corner off the floor that this solve had to stop while it approached
     faster than the threshold would hit inside the piece, after gap / approach: the piece is redone up to that
     instant (integrate velocities and solve contacts again) and the impact resolved there by the next piece's
     restitution, so impacts in contact are not tied to the grid;
  store impulses (``loaded_corners``): which corners carried load, so that they take part in the next impact;
  energy limit (``energy_limit.limit_energy``): no step gains kinetic + potential energy;
  integrate positions (``integrate_positions``): x += h v, alpha += h omega (symplectic Euler);
  relax (``penalty.relax``): penetration beyond the slop removed by the implicit penalty, as a pseudo-velocity.
"""

import math

import numpy as np

from ..compile.compilation import jit_stage
from ..geometry import lowest_pair, vertex_offset
from ..kernel_support import record_event
from ..tunables import FRICTION_ITERATIONS, MAX_LOCATED_IMPACTS, MAX_ROTATION_PER_STEP, MAX_ROTATION_SUBSTEPS
from .contact_solver import APPROACH, IMPULSE, RY, TARGET, normal_velocities, place_corner, solve_contact_velocities
from .energy_limit import kinetic_energy, limit_energy
from .memory import Corners, Tally
from .penalty import relax
from .restitution import contact_impact
from .state import Motion


@jit_stage
def predicted_height(k, motion, box, fall, h):
    """Height of corner k after a step h at the current velocities, to first order (``fall``: the centre's)."""
    rx, ry = vertex_offset(k, motion.cos_a, motion.sin_a, box.hx, box.hy)
    return motion.y + ry + fall + h * motion.spin * rx


@jit_stage
def contact_corners(motion, box, gravity, h, reach, work):
    """The corners that can touch the floor in a step h, as the first columns of ``work.corners`` (their indices in
    ``work.ids``): of the one that would be lowest at the end of the step at the current velocities, its lower
    neighbour (they bound the face that will be down) and its other neighbour (the far end of a thin box's
    long side, whose two lowest corners are the ends of a short side once it tilts by atan(W / L)), those
    within ``reach`` of the floor. Each is constrained only to close its gap, so one that cannot reach the
    floor in the step would get no impulse; leaving out those further than ``reach`` (what any point of the
    box can travel in the step) saves the work. Returns how many there are."""
    fall = h * (motion.vy + gravity * h)
    first, second = lowest_pair(
        predicted_height(0, motion, box, fall, h),
        predicted_height(1, motion, box, fall, h),
        predicted_height(2, motion, box, fall, h),
        predicted_height(3, motion, box, fall, h),
    )
    third = (first + 1) % 4 if second == (first + 3) % 4 else (first + 3) % 4
    n = 0
    for corner in (first, second, third):
        place_corner(work.corners, n, corner, motion.cos_a, motion.sin_a, box.hx, box.hy)
        if motion.y + work.corners[RY, n] <= reach:
            work.ids[n] = corner
            n += 1
    return n


@jit_stage(inline="always")
def prepare_contacts(motion, h, box, gravity, work):
    """Find contacts for a piece h: the corners that can reach the floor in it (``contact_corners``), with their normal
    velocities before it in row APPROACH. Returns how many there are.

    No point of the box moves faster than sqrt(2 KE (1/m + R^2 / I)) once gravity has acted (Cauchy-Schwarz;
    contact impulses never add kinetic energy), so no corner further than ``tolerance`` + h times that (the
    reach) can touch the floor in the piece."""
    reach = box.tolerance + h * math.sqrt(
        2.0
        * kinetic_energy(motion.vx, motion.vy + gravity * h, motion.spin, box.inv_mass, box.inv_inertia)
        * (box.inv_mass + box.radius * box.radius * box.inv_inertia)
    )
    n = contact_corners(motion, box, gravity, h, reach, work)
    normal_velocities(motion.vy, motion.spin, work.corners, n, APPROACH)
    return n


@jit_stage(inline="always")
def solve_contacts(y, vx, vy, spin, h, n, box, work):
    """Stage 2: the contact velocities of the first n corners solved together, each corner i allowed to close its
    gap in the piece h but not to pass it (speculative contact: u_n,i >= b_i = -max(y_i, 0) / h). Returns (vx, vy,
    spin)."""
    corners = work.corners
    for c in range(n):
        corners[TARGET, c] = -max(y + corners[RY, c], 0.0) / h
    return solve_contact_velocities(
        vx, vy, spin, corners, n, box.friction, box.inv_mass, box.inv_inertia, FRICTION_ITERATIONS, work.k
    )


@jit_stage(inline="always")
def locate_impact(y, n, h, threshold, tolerance, work):
    """Stage 3: the first arrival inside a piece h of a corner off the floor (gap > ``tolerance``) that the solve
    stopped (impulse > 0) while it approached faster than the threshold: it would have hit after
    gap / approach. Returns (arrival, the corner's index), (h, -1) if none."""
    corners = work.corners
    arrival = h
    hit = -1
    for c in range(n):
        gap = y + corners[RY, c]
        if (
            corners[IMPULSE, c] > 0.0
            and corners[APPROACH, c] < -threshold
            and gap > tolerance
            and gap < -arrival * corners[APPROACH, c]
        ):
            arrival = -gap / corners[APPROACH, c]
            hit = work.ids[c]
    return arrival, hit


@jit_stage(inline="always")
def loaded_corners(corners, n, ids):
    """Store impulses: the corners of the first n columns that took a normal impulse, as a bit mask of their
    indices (bit c for corner c), for the next impact (``restitution.contact_impact``)."""
    loaded = 0
    for c in range(n):
        if corners[IMPULSE, c] > 0.0:
            loaded |= 1 << ids[c]
    return loaded


@jit_stage(inline="always")
def integrate_positions(motion, h):
    """Stage 5, symplectic Euler's position update: x += h v, alpha += h omega (the velocities stay)."""
    angle = motion.angle + h * motion.spin
    return Motion(
        motion.x + h * motion.vx,
        motion.y + h * motion.vy,
        angle,
        motion.vx,
        motion.vy,
        motion.spin,
        math.cos(angle),
        math.sin(angle),
    )


@jit_stage(inline="always")
def solve_piece(motion, left, box, gravity, threshold, located_impacts, work):
    """Find contacts, integrate velocities, solve contacts and locate impacts for a piece of a contact step of at most
    ``left``: velocities with gravity, the contact velocities solved, and, where a corner off the floor was stopped
    while approaching faster than the threshold, the piece shortened to its arrival (that impact is then resolved at the
    piece's end, by restitution). Returns (vx, vy, spin, piece, located corner or -1, located impacts so far, corners in
    contact, kinetic energy at the start)."""
    piece = left
    located = -1
    for attempt in range(2):
        kinetic_before = kinetic_energy(motion.vx, motion.vy, motion.spin, box.inv_mass, box.inv_inertia)
        # find contacts: the corners that can reach the floor in the piece
        n_corners = prepare_contacts(motion, piece, box, gravity, work)
        # integrate velocities
        vy = motion.vy + gravity * piece
        # solve contacts: each corner may close its gap but not pass it
        vx, vy, spin = solve_contacts(motion.y, motion.vx, vy, motion.spin, piece, n_corners, box, work)
        if attempt == 1:
            break
        # locate impacts: the piece is redone up to the first arrival inside it
        arrival, hit = locate_impact(motion.y, n_corners, piece, threshold, box.tolerance, work)
        if hit < 0 or located_impacts >= MAX_LOCATED_IMPACTS:
            break
        located_impacts += 1
        located = hit
        piece = arrival
    return vx, vy, spin, piece, located, located_impacts, n_corners, kinetic_before


@jit_stage(inline="always")
def contact_step(i, motion, h, box, settings, corners, t, tally, events, work):
    """One contact step of length h on the grid, split where the box turns fast and at impacts: the stages of
    this module's docstring, piece after piece. ``corners``: what the last step left (``memory.Corners``),
    ``tally``: the box's counts (``memory.Tally``). Returns (motion, corners, whether a corner held the box,
    tally)."""
    gravity, threshold = settings.gravity, settings.threshold
    located, loaded, lift = corners
    first_contact, n_impacts, max_penetration, n_steps = tally
    n_sub = min(max(np.int64(math.ceil(abs(motion.spin) * h / MAX_ROTATION_PER_STEP)), 1), MAX_ROTATION_SUBSTEPS)
    h_sub = h / n_sub
    held = False
    located_impacts = 0
    elapsed = 0.0  # time advanced in this step
    for _ in range(n_sub):
        left = h_sub
        while left > 0.0:
            # restitution: a touching corner approaching faster than the threshold takes one at this instant
            vx, vy, spin, touching, approach = contact_impact(
                motion, box, threshold, box.tolerance + lift, located, loaded, work
            )
            motion = Motion(motion.x, motion.y, motion.angle, vx, vy, spin, motion.cos_a, motion.sin_a)
            if approach > 0.0:
                if settings.record:
                    record_event(events, i, n_impacts, t + elapsed, approach, touching)
                n_impacts += 1
            # find contacts, integrate velocities, solve contacts, locate impacts (the piece ends at one)
            vx, vy, spin, piece, located, located_impacts, n_corners, kinetic_before = solve_piece(
                motion, left, box, gravity, threshold, located_impacts, work
            )
            # store impulses: the corners that held the box take part in the next impact
            loaded = loaded_corners(work.corners, n_corners, work.ids)
            held = held or loaded != 0
            # energy limit: the velocities scaled where the piece would gain energy
            vx, vy, spin = limit_energy(vx, vy, spin, kinetic_before, piece, gravity, box.inv_mass, box.inv_inertia)
            # integrate positions
            motion = integrate_positions(
                Motion(motion.x, motion.y, motion.angle, vx, vy, spin, motion.cos_a, motion.sin_a), piece
            )
            # relax: the implicit penalty on what penetrates beyond the slop
            motion, penetration = relax(motion, box, settings, piece, work)
            max_penetration = max(max_penetration, penetration)
            held = held or penetration > 0.0
            lift = h_sub * h_sub * motion.spin * motion.spin * box.radius  # how far a rotating substep lifts a corner
            elapsed += piece
            left = left - piece if piece < left else 0.0
    return motion, Corners(located, loaded, lift), held, Tally(first_contact, n_impacts, max_penetration, n_steps)
