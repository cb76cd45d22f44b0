"""The relax stage of the colliding solver (``stages.COLLIDING_SUBSTEP``): penetration deeper than the slop
removed by the critically damped penalty spring with backward Euler, as pseudo-velocities (the split impulse
of ``robust.penalty``, now between two bodies), island by island (``correct_penetrations``,
``penalty_sweeps``).
"""

import math

from .. import layout
from ..compile.compilation import jit_stage
from ..tunables import CONTACT_TOLERANCE, PENALTY_FLOOR, PENALTY_ITERATIONS, PENALTY_TRIGGER
from .islands import islands_deeper_than
from .narrowphase import GAP, NX, NY, PSEUDO_IMPULSE, TARGET
from .normal_lcp import delassus_matrix, normal_lcp
from .parallel import (
    PARALLEL_CONTACTS,
    partitioned_penalty_sweeps,
    penalty_target,
    penalty_targets_on_threads,
    pseudo_gap,
    pseudo_gaps_on_threads,
)
from .prepare import apply_impulse, body_kinetic_energy
from .solve import exact_pays, gather_island, mark_unlike_islands
from .sweeps import normal_step


@jit_stage(inline="always")
def penalty_trigger(context):
    """[m] the penetration from which the penalty starts: PENALTY_TRIGGER slops past the contact tolerance, and
    never less than PENALTY_FLOOR (rounding) at the scene's size."""
    floor = PENALTY_FLOOR / CONTACT_TOLERANCE * context.tolerance
    return max(PENALTY_TRIGGER * context.slop + context.tolerance, floor)


@jit_stage(inline="always")
def deepest_penetration(rows, count):
    """[m] the deepest penetration -gap among the first ``count`` contacts (0 if none is deeper)."""
    deepest = 0.0
    for c in range(count):
        deepest = max(deepest, -rows[c, GAP])
    return deepest


@jit_stage
def correct_penetrations(contacts, count, bodies, work, exact, h, context):
    """Stage 2, island by island (bodies joined by box-box contacts): in the islands holding a contact deeper
    than PENALTY_TRIGGER slops and than PENALTY_FLOOR (rounding, ``islands.islands_deeper_than``),
    pseudo-velocities that remove the penalty's share of each penetration deeper than the slop (normal impulses
    >= 0 with targets ERP depth / h; the other contacts, and every contact of the other islands, may close their
    gap but not pass it: their impulses stay zero unless pressed, so the sweeps leave out the other islands'
    contacts, the same result), moved into the positions (``pseudo_impulses``, ``move_by_pseudo_velocities``);
    the gaps of every contact follow to first order, and the potential energy gained is taken from the kinetic
    energy of the moved bodies. Returns the deepest penetration (0 if none)."""
    rows, ids = contacts.rows, contacts.ids
    slop = context.slop
    trigger = penalty_trigger(context)
    deepest = deepest_penetration(rows, count)
    if deepest <= trigger:
        return deepest
    n = bodies.pose.shape[0]
    pseudo = work.pseudo
    for b in range(n):
        pseudo[b, 0] = 0.0
        pseudo[b, 1] = 0.0
        pseudo[b, 2] = 0.0
    deep_island = contacts.deep
    islands_deeper_than(rows, ids, count, trigger, work.root, work.marked, deep_island)
    if count >= PARALLEL_CONTACTS:  # each contact at once, the same values
        penalty_targets_on_threads(rows, count, deep_island, slop, context.tolerance, h)
    else:
        for c in range(count):
            penalty_target(c, rows, deep_island, slop, context.tolerance, h)
    pseudo_impulses(contacts, count, bodies, pseudo, exact, deep_island, context)
    if count >= PARALLEL_CONTACTS:
        pseudo_gaps_on_threads(rows, ids, count, pseudo, h)
    else:
        for c in range(count):
            pseudo_gap(c, rows, ids, pseudo, h)
    move_by_pseudo_velocities(bodies, pseudo, h, context.gravity)
    return deepest


@jit_stage(inline="always")
def pseudo_impulses(contacts, count, bodies, pseudo, exact, deep_island, context):
    """The penalty's pseudo-impulses (column PSEUDO_IMPULSE, targets in column TARGET) into ``pseudo``: solved exactly
    where the velocities' exact solve pays (``solve.exact_pays``, ``normal_lcp``: Gauss-Seidel leaves a light box
    between heavy ones turning), otherwise exactly in each deep island of unlike masses small enough
    (``exact_islands``) and by Gauss-Seidel over the other deep islands' contacts (the scene's ``solver_tolerance``,
    at most PENALTY_ITERATIONS or ``solver_iterations`` sweeps, ``penalty_sweeps``; from PARALLEL_CONTACTS contacts
    up block by block, on threads: ``parallel.partitioned_penalty_sweeps``)."""
    rows, ids = contacts.rows, contacts.ids
    inv_mass, inv_inertia = bodies.inv_mass, bodies.inv_inertia
    if exact_pays(ids, count, inv_mass, context.use_friction):
        if exact_pseudo_impulses(rows, ids, count, bodies, pseudo, exact):
            return
    exact_islands(contacts, count, bodies, pseudo, exact, deep_island)
    if count >= PARALLEL_CONTACTS:
        iterations = min(context.sweeps, PENALTY_ITERATIONS)
        partitioned_penalty_sweeps(contacts, pseudo, bodies, iterations, context.sweep_tolerance)
        return
    listed = contacts.listed  # the deep islands' contacts: the sweeps leave the others out
    n_listed = 0
    for c in range(count):
        if deep_island[c]:
            listed[n_listed] = c
            n_listed += 1
    penalty_sweeps(
        rows,
        ids,
        listed,
        n_listed,
        pseudo,
        inv_mass,
        inv_inertia,
        min(context.sweeps, PENALTY_ITERATIONS),
        context.sweep_tolerance,
    )


@jit_stage
def exact_islands(contacts, count, bodies, pseudo, exact, deep_island):
    """The pseudo-impulses of each deep island that ``solve.mark_unlike_islands`` marks (unlike masses, at most
    DIRECT_LIMIT contacts), solved exactly on its own as ``pseudo_impulses`` solves a small contact set, and its
    contacts taken out of the deep ones the sweeps then visit (no other island's contact touches its bodies).
    Returns the number of islands so solved."""
    rows, ids = contacts.rows, contacts.ids
    if not mark_unlike_islands(ids, count, bodies.inv_mass, exact, contacts.listed):  # listed: free until the sweeps
        return 0
    solved = 0
    for c in range(count):  # an island's first contact gathers it
        if not deep_island[c]:
            continue
        k = gather_island(rows, ids, c, exact, contacts.listed)
        if k == 0:
            continue
        if exact_pseudo_impulses(exact.rows, exact.ids, k, bodies, pseudo, exact):
            for j in range(k):
                rows[exact.listed[j], PSEUDO_IMPULSE] = exact.rows[j, PSEUDO_IMPULSE]
                deep_island[exact.listed[j]] = False
            solved += 1
    return solved


@jit_stage(inline="always")
def exact_pseudo_impulses(rows, ids, count, bodies, pseudo, exact):
    """The pseudo-impulses of ``count`` contacts solved exactly together (``normal_lcp`` on their W, targets in
    column TARGET: x >= 0, W x - target >= 0, complementary), kept in column PSEUDO_IMPULSE and applied to
    ``pseudo``; returns False (nothing changed) if the solve failed."""
    inv_mass, inv_inertia = bodies.inv_mass, bodies.inv_inertia
    delassus_matrix(rows, ids, count, inv_mass, inv_inertia, exact.w)
    for c in range(count):
        exact.free[c] = -rows[c, TARGET]
        exact.active[c] = exact.free[c] < 0.0
    if not normal_lcp(exact.w, exact.free, exact.x, exact.active, count, exact.factor, exact.index, exact.y):
        return False
    x = exact.x
    for c in range(count):
        rows[c, PSEUDO_IMPULSE] = x[c]
        if x[c] != 0.0:
            apply_impulse(c, x[c] * rows[c, NX], x[c] * rows[c, NY], rows, ids, pseudo, inv_mass, inv_inertia)
    return True


@jit_stage(inline="always")
def move_by_pseudo_velocities(bodies, pseudo, h, gravity):
    """The positions moved by h times the pseudo-velocities, and the potential energy that gains taken from the
    kinetic energy of the moved bodies (their velocities scaled by sqrt(1 - rise / KE), as far as they have it)."""
    pose, vel, params = bodies.pose, bodies.vel, bodies.params
    n = pose.shape[0]
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
