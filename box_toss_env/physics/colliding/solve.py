"""Stage solve of the colliding solver (stage 4 of ``step``'s script): the contact impulses, by the
cheapest method that is exact for the contact set (``solve_velocities``): normal and friction together up to
JOINT_LIMIT contacts (``solve_jointly``, ``joint_contact_solve``), the normals exactly with friction sweeps up
to DIRECT_LIMIT (``normal_lcp``, ``sweeps``), projected Gauss-Seidel beyond (``sweeps.gauss_seidel``).
"""

import numpy as np

from .. import layout
from ..compile.compilation import jit_stage
from .joint_contact_solve import JOINT_LIMIT, full_delassus, joint_impulses
from .limits import CONVERGED, DIRECT_LIMIT, VELOCITY_ITERATIONS
from .narrowphase import FRICTION_IMPULSE, IMPULSE, NX, NY, TARGET
from .normal_lcp import delassus_matrix, normal_lcp
from .prepare import apply_impulse, relative_velocity
from .sweeps import friction_sweep, gauss_seidel


@jit_stage
def solver_settings(settings):
    """(solver_tolerance, solver_iterations) of the scene: where the Gauss-Seidel sweeps stop."""
    return settings[layout.SOLVER_TOLERANCE], np.int64(settings[layout.SOLVER_ITERATIONS])


@jit_stage
def solve_velocities(contacts, ids, count, vel, inv_mass, inv_inertia, use_friction, w, factor, free, x, active,
                     index, y, state, moved, settings):
    """Stage 4: the contact impulses. Up to JOINT_LIMIT contacts with friction, normal and friction impulses
    are solved together, exactly (``joint_contact_solve``); up to DIRECT_LIMIT contacts (or if that does not
    settle), the normal impulses are solved exactly together (``normal_lcp``: a stack's load passes through
    every box at once, whatever the mass ratio), alternating with a friction sweep until the impulses settle;
    beyond that, if the exact solve fails, or if the scene's ``solver_tolerance`` is looser than CONVERGED (it
    chose the sweeps' speed: the exact solve's pivots on tens of contacts, the last islands of a settling pile
    awake, cost more than its sweeps), projected Gauss-Seidel (``gauss_seidel``, with the scene's
    ``solver_tolerance`` and ``solver_iterations`` from ``settings``)."""
    if count == 0:
        return
    if use_friction and count <= JOINT_LIMIT and solve_jointly(contacts, ids, count, vel, inv_mass, inv_inertia, w,
                                                               factor, free, x, y, index, state):
        return
    sweep_tolerance, sweeps = solver_settings(settings)
    if count <= DIRECT_LIMIT and sweep_tolerance <= CONVERGED:
        delassus_matrix(contacts, ids, count, inv_mass, inv_inertia, w)
        for c in range(count):
            active[c] = contacts[c, IMPULSE] > 0.0
        solved = True
        for _ in range(VELOCITY_ITERATIONS if use_friction else 1):
            for c in range(count):
                ux, uy = relative_velocity(c, contacts, ids, vel)
                value = ux * contacts[c, NX] + uy * contacts[c, NY] - contacts[c, TARGET]
                for d in range(count):
                    value -= w[c, d] * contacts[d, IMPULSE]
                free[c] = value
                if free[c] < 0.0:
                    active[c] = True
            if not normal_lcp(w, free, x, active, count, factor, index, y):
                solved = False
                break
            change = 0.0
            total = 0.0
            for c in range(count):
                dp = x[c] - contacts[c, IMPULSE]
                contacts[c, IMPULSE] = x[c]
                if dp != 0.0:
                    apply_impulse(c, dp * contacts[c, NX], dp * contacts[c, NY], contacts, ids, vel, inv_mass,
                                  inv_inertia)
                change += abs(dp)
                total += x[c]
            if use_friction:
                change += friction_sweep(contacts, ids, count, vel, inv_mass, inv_inertia)
            if change <= CONVERGED * total:
                break
        if solved:
            return
    gauss_seidel(contacts, ids, count, vel, inv_mass, inv_inertia, use_friction, sweeps, sweep_tolerance, moved)


@jit_stage
def solve_jointly(contacts, ids, count, vel, inv_mass, inv_inertia, w, a, u, x, impulse, index, state):
    """The normal and friction impulses of the contacts solved together (``joint_impulses``), applied to the
    velocities and kept in the contacts; returns False (nothing changed) if that solve did not settle."""
    full_delassus(contacts, ids, count, inv_mass, inv_inertia, w)
    for c in range(count):
        ux, uy = relative_velocity(c, contacts, ids, vel)
        nx, ny = contacts[c, NX], contacts[c, NY]
        u[2 * c] = ux * nx + uy * ny - contacts[c, TARGET]
        u[2 * c + 1] = -ux * ny + uy * nx  # u_rel . t, t = (-ny, nx)
    if not joint_impulses(contacts, count, w, u, state, a, index, x, impulse):
        return False
    for c in range(count):
        dp = impulse[2 * c] - contacts[c, IMPULSE]
        dq = impulse[2 * c + 1] - contacts[c, FRICTION_IMPULSE]
        contacts[c, IMPULSE] = impulse[2 * c]
        contacts[c, FRICTION_IMPULSE] = impulse[2 * c + 1]
        if dp != 0.0 or dq != 0.0:
            nx, ny = contacts[c, NX], contacts[c, NY]
            apply_impulse(c, dp * nx - dq * ny, dp * ny + dq * nx, contacts, ids, vel, inv_mass, inv_inertia)
    return True
