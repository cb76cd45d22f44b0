"""The robust solver for scenes whose boxes collide (``Scene(boxes_collide=True)``): every box of the
scene is stepped together, since a contact between two boxes couples them. A scene whose boxes cannot
meet runs ``robust_solver``'s kernel instead, which compiles none of this.

The stages are a module each, called in the order of the method by the step script in ``step`` (whose
docstring gives the script): ``prepare`` (effective masses, material, the two-body impulse formulas),
``relax`` (the penalty), ``warm_start``, ``solve`` (with ``joint_contact_solve``, ``normal_lcp`` and
``sweeps``), ``restitution``, ``alone`` (bodies advanced alone against the floor); their limits in
``limits``. This module holds the substep count and the bodies' reach, and names every stage for the code
that imports them from here.
"""

import math

import numpy as np

from ..compile.compilation import jit_stage
from ..robust.contact_step import MAX_ROTATION_PER_STEP
from .alone import advance_alone, bounds_touch, count_awake, energy_speed, steps_alone
from .limits import (
    ALONE_LIMIT,
    ALONE_LOWEST,
    CONTACT_TOLERANCE,
    CONVERGED,
    DIRECT_LIMIT,
    LCP_TOLERANCE,
    MAX_SUBSTEPS,
    MIN_CAPACITY,
    PENALTY_ITERATIONS,
    REGULARISATION,
    RESTITUTION_ITERATIONS,
    SINGLE_CHANGE,
    SUPPORT_SLOPE,
    TUNNEL_FRACTION,
    VELOCITY_ITERATIONS,
)
from .normal_lcp import delassus_matrix, normal_lcp, solve_active
from .prepare import apply_impulse, body_kinetic_energy, prepare_contacts, relative_velocity
from .relax import correct_penetrations, penalty_sweeps
from .restitution import apply_restitution
from .solve import solve_jointly, solve_velocities, solver_settings
from .sweeps import friction_step, friction_sweep, gauss_seidel, mark_moved, normal_step
from .warm_start import lever_shares, resting_loads, warm_start

__all__ = [
    "ALONE_LIMIT", "ALONE_LOWEST", "CONTACT_TOLERANCE", "CONVERGED", "DIRECT_LIMIT", "LCP_TOLERANCE",
    "MAX_SUBSTEPS", "MIN_CAPACITY", "PENALTY_ITERATIONS", "REGULARISATION", "RESTITUTION_ITERATIONS",
    "SINGLE_CHANGE", "SUPPORT_SLOPE", "TUNNEL_FRACTION", "VELOCITY_ITERATIONS", "advance_alone",
    "apply_impulse", "apply_restitution", "body_kinetic_energy", "bounds_touch", "correct_penetrations",
    "count_awake", "delassus_matrix", "energy_speed", "friction_step", "friction_sweep", "gauss_seidel",
    "lever_shares", "mark_moved", "normal_lcp", "normal_step", "penalty_sweeps", "prepare_contacts",
    "relative_velocity", "resting_loads", "solve_active", "solve_jointly", "solve_velocities",
    "solver_settings", "steps_alone", "warm_start", "body_reach", "point_speed", "substep_count", "substeps"
]


@jit_stage
def substeps(vel, radius, include, smallest_half, dt, gravity):
    """How many substeps a grid step needs for the included bodies (``substep_count`` for the fastest point
    speed |v| + |g| dt + |omega| R and turn rate among them)."""
    speed = 0.0
    turn = 0.0
    for b in range(vel.shape[0]):
        if not include[b]:
            continue
        speed = max(speed, point_speed(vel, radius, b, dt, gravity))
        turn = max(turn, abs(vel[b, 2]))
    return substep_count(speed, turn, smallest_half, dt)


@jit_stage(inline="always")
def point_speed(vel, radius, b, dt, gravity):
    """A bound on the speed of body b's points over a step dt: |v| + |g| dt + |omega| R."""
    return math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(gravity) * dt + abs(vel[b, 2]) * radius[b]


@jit_stage
def substep_count(speed, turn, smallest_half, dt):
    """How many substeps a grid step needs at point speed ``speed`` and turn rate ``turn``: no point moves further
    than TUNNEL_FRACTION of the smallest half extent, no box turns further than MAX_ROTATION_PER_STEP (at most
    MAX_SUBSTEPS)."""
    by_speed = math.ceil(2.0 * speed * dt / (TUNNEL_FRACTION * smallest_half))
    by_turn = math.ceil(turn * dt / MAX_ROTATION_PER_STEP)
    if not (by_speed < MAX_SUBSTEPS and by_turn < MAX_SUBSTEPS):  # also for a non-finite state
        return MAX_SUBSTEPS
    return max(max(np.int64(by_speed), np.int64(by_turn)), 1)


@jit_stage
def body_reach(vel, radius, awake, h, gravity, tolerance, reach):
    """What each awake body can travel in a time h, |v| h + |g| h^2 + |omega| R h (plus the contact
    tolerance), into ``reach`` (a sleeping body: the tolerance); returns the largest."""
    fastest = 0.0
    for b in range(vel.shape[0]):
        reach[b] = tolerance
        if awake[b]:
            reach[b] += h * (math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(gravity) * h
                             + abs(vel[b, 2]) * radius[b])
            fastest = max(fastest, reach[b])
    return fastest
