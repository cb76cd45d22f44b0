"""Stage relax of the colliding solver (stage 2 of ``step``'s script): penetration deeper than the slop
removed by the critically damped penalty spring with backward Euler, as pseudo-velocities (the split impulse
of ``robust.penalty``, now between two bodies), island by island (``correct_penetrations``,
``penalty_sweeps``).
"""

import math

import numpy as np

from .. import layout
from ..compile.compilation import jit_stage
from ..robust.contact_solver import penalty_correction_share
from ..robust.penalty import PENALTY_TRIGGER
from .islands import islands_deeper_than
from .limits import CONVERGED, DIRECT_LIMIT, PENALTY_ITERATIONS
from .narrowphase import GAP, NORMAL_MASS, NX, NY, PSEUDO_IMPULSE, STIFFNESS, TARGET
from .normal_lcp import delassus_matrix, normal_lcp
from .prepare import apply_impulse, body_kinetic_energy, relative_velocity
from .solve import solver_settings
from .sweeps import normal_step


@jit_stage(nrt=True)  # it allocates its work arrays (when the penalty runs)
def correct_penetrations(contacts, ids, count, pose, vel, pseudo, inv_mass, inv_inertia, h, settings, tolerance,
                         gravity, params, w, factor, free, x, active, index, y):
    """Stage 2, island by island (bodies joined by box-box contacts): in the islands holding a contact deeper
    than PENALTY_TRIGGER slops (``islands.islands_deeper_than``), pseudo-velocities that remove the penalty's
    share of each penetration deeper than the slop (normal impulses >= 0 with targets ERP depth / h; the other
    contacts, and every contact of the other islands, may close their gap but not pass it: their impulses stay
    zero unless pressed, so the sweeps leave out the other islands' contacts, the same result), moved into the
    positions; the gaps of every contact follow to first order, and the potential
    energy gained is taken from the kinetic energy of the moved bodies. Up to DIRECT_LIMIT contacts the
    impulses are solved exactly (``normal_lcp``, as the velocities: Gauss-Seidel leaves a light box
    between heavy ones turning), beyond that, or at a looser tolerance as the velocities, by Gauss-Seidel (the
    scene's ``solver_tolerance``, at most PENALTY_ITERATIONS or ``solver_iterations`` sweeps). ``settings``
    gives the slop and the sweeps.
    Returns the deepest penetration (0 if none)."""
    slop = settings[layout.PENETRATION_SLOP]
    deepest = 0.0
    for c in range(count):
        deepest = max(deepest, -contacts[c, GAP])
    if deepest <= PENALTY_TRIGGER * slop + tolerance:
        return deepest
    n = pose.shape[0]
    for b in range(n):
        pseudo[b, 0] = 0.0
        pseudo[b, 1] = 0.0
        pseudo[b, 2] = 0.0
    parent, marked, deep_island = np.empty(n, np.int64), np.empty(n, np.bool_), np.empty(count, np.bool_)
    islands_deeper_than(contacts, ids, count, PENALTY_TRIGGER * slop + tolerance, parent, marked, deep_island)
    for c in range(count):
        depth = -contacts[c, GAP] - slop
        contacts[c, PSEUDO_IMPULSE] = 0.0
        if depth > tolerance and deep_island[c]:
            share = penalty_correction_share(contacts[c, STIFFNESS], 1.0 / contacts[c, NORMAL_MASS], h)
            contacts[c, TARGET] = share * depth / h
        else:
            contacts[c, TARGET] = -max(contacts[c, GAP], 0.0) / h
    solved = False
    sweep_tolerance, sweeps = solver_settings(settings)
    if count <= DIRECT_LIMIT and sweep_tolerance <= CONVERGED:
        delassus_matrix(contacts, ids, count, inv_mass, inv_inertia, w)
        for c in range(count):
            free[c] = -contacts[c, TARGET]
            active[c] = free[c] < 0.0
        solved = normal_lcp(w, free, x, active, count, factor, index, y)
        if solved:
            for c in range(count):
                contacts[c, PSEUDO_IMPULSE] = x[c]
                if x[c] != 0.0:
                    apply_impulse(c, x[c] * contacts[c, NX], x[c] * contacts[c, NY], contacts, ids, pseudo, inv_mass,
                                  inv_inertia)
    if not solved:
        listed = np.empty(count, np.int64)  # the deep islands' contacts: the sweeps leave the others out
        n_listed = 0
        for c in range(count):
            if deep_island[c]:
                listed[n_listed] = c
                n_listed += 1
        penalty_sweeps(contacts, ids, listed, n_listed, pseudo, inv_mass, inv_inertia,
                       min(sweeps, PENALTY_ITERATIONS), sweep_tolerance)
    for c in range(count):
        ux, uy = relative_velocity(c, contacts, ids, pseudo)
        contacts[c, GAP] += h * (ux * contacts[c, NX] + uy * contacts[c, NY])
    rise = 0.0
    kinetic = 0.0
    for b in range(n):
        if pseudo[b, 0] != 0.0 or pseudo[b, 1] != 0.0 or pseudo[b, 2] != 0.0:
            pose[b, 0] += h * pseudo[b, 0]
            pose[b, 1] += h * pseudo[b, 1]
            pose[b, 2] += h * pseudo[b, 2]
            rise += -gravity * h * pseudo[b, 1] * params[b, layout.MASS]
            kinetic += body_kinetic_energy(vel, b, params)
    if rise > 0.0 and kinetic > 0.0:
        scale = math.sqrt(max(1.0 - rise / kinetic, 0.0))
        for b in range(n):
            if pseudo[b, 0] != 0.0 or pseudo[b, 1] != 0.0 or pseudo[b, 2] != 0.0:
                vel[b, 0] *= scale
                vel[b, 1] *= scale
                vel[b, 2] *= scale
    return deepest


@jit_stage
def penalty_sweeps(contacts, ids, listed, n_listed, pseudo, inv_mass, inv_inertia, iterations, tolerance):
    """``gauss_seidel`` on the penalty's pseudo-velocities (column PSEUDO_IMPULSE, no friction) over the contacts
    ``listed[:n_listed]`` alone: the deep islands', about 40 of the wide pile of 1,000's thousands of contacts when
    its penalty runs (counted), so a sweep no longer steps through a mask of every contact."""
    for _ in range(iterations):
        change = 0.0
        total = 0.0
        for i in range(n_listed):
            c = listed[i]
            change += abs(normal_step(c, PSEUDO_IMPULSE, contacts, ids, pseudo, inv_mass, inv_inertia))
            total += contacts[c, PSEUDO_IMPULSE]
        if change <= tolerance * total:
            break
