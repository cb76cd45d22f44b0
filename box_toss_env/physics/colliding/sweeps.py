"""Projected Gauss-Seidel over the contacts (stage solve beyond the exact solves; Box2D's sequential
impulses): at each contact the friction impulse that stops the slip, clamped to mu times the normal impulse
(``friction_step``), then the normal impulse that meets the contact's target, kept >= 0 (``normal_step``);
after the first sweep only the contacts of bodies that moved (``gauss_seidel``, ``mark_moved``).
"""

from ..compile.compilation import jit_stage
from ..contact_law import clamp_friction, friction_bound, tangent
from ..tunables import SINGLE_CHANGE
from .narrowphase import BODY1, BODY2, FRICTION, FRICTION_IMPULSE, IMPULSE, NORMAL_MASS, NX, NY, TANGENT_MASS, TARGET
from .prepare import apply_impulse, relative_velocity


@jit_stage
def friction_sweep(contacts, ids, count, vel, inv_mass, inv_inertia):
    """One Gauss-Seidel sweep of friction: at each contact the tangential impulse that stops the slip, added
    to the accumulated one and clamped to mu times the normal impulse. Returns the sum of the changes."""
    change = 0.0
    for c in range(count):
        if contacts[c, FRICTION] <= 0.0:
            continue
        change += abs(friction_step(c, contacts, ids, vel, inv_mass, inv_inertia))
    return change


@jit_stage(inline="always")
def friction_step(c, contacts, ids, vel, inv_mass, inv_inertia):
    """Contact c's friction: the tangential impulse that stops the slip, added to the accumulated one and clamped
    to mu times the normal impulse, applied to ``vel``; returns the change dq."""
    tx, ty = tangent(contacts[c, NX], contacts[c, NY])
    ux, uy = relative_velocity(c, contacts, ids, vel)
    slip = ux * tx + uy * ty  # u_rel . t
    before = contacts[c, FRICTION_IMPULSE]
    bound = friction_bound(contacts[c, FRICTION], contacts[c, IMPULSE])
    after = clamp_friction(before - slip * contacts[c, TANGENT_MASS], bound)
    contacts[c, FRICTION_IMPULSE] = after
    dq = after - before
    if dq != 0.0:
        apply_impulse(c, dq * tx, dq * ty, contacts, ids, vel, inv_mass, inv_inertia)
    return dq


@jit_stage(inline="always")
def normal_step(c, column, contacts, ids, vel, inv_mass, inv_inertia):
    """Contact c's normal impulse (accumulated in ``contacts[c, column]``): >= 0 with u_rel . n >= target, applied to
    ``vel``; returns the change dp."""
    nx, ny = contacts[c, NX], contacts[c, NY]
    ux, uy = relative_velocity(c, contacts, ids, vel)
    before = contacts[c, column]
    after = max(before - (ux * nx + uy * ny - contacts[c, TARGET]) * contacts[c, NORMAL_MASS], 0.0)
    contacts[c, column] = after
    dp = after - before
    if dp != 0.0:
        apply_impulse(c, dp * nx, dp * ny, contacts, ids, vel, inv_mass, inv_inertia)
    return dp


@jit_stage
def gauss_seidel(contacts, ids, count, vel, inv_mass, inv_inertia, use_friction, iterations, tolerance, moved, seeded):
    """Projected Gauss-Seidel over the contacts (Box2D's sequential impulses), at most ``iterations`` sweeps,
    stopping once a sweep changes the impulses by less than ``tolerance`` of their sum and none of them by more
    than SINGLE_CHANGE ``tolerance`` times their mean: friction clamped to mu times the normal impulse, then the
    normal impulse >= 0 with u_rel . n >= target (column TARGET), applied to ``vel``. The sum alone, among
    thousands of contacts, let a sweep stop with a few of them far from solved: awake, the wide pile of 5,000
    (``benchmarks.engine_scale``, 1e-4), where a box topples off the top, reached 1.5 mm of penetration, 0.26 mm
    with both. The penalty's pseudo-velocities have their own sweeps (``penalty_sweeps``).

    After the first sweep, a sweep visits only the contacts of bodies that ``moved``: took an impulse larger than
    ``tolerance`` times the mean in the sweep before or in this one so far. Any other contact was solved against
    velocities that have changed by less since, so it would change by less too: where a box topples off a pile,
    the sweeps it needs visit its neighbourhood, not every contact of the pile. ``moved``: (2, bodies) work. With
    ``seeded`` the first sweep too visits only the contacts of the bodies set in ``moved[0]`` (the restitution
    solve: the contacts were solved just before, and only the impacts' targets have changed since)."""
    total = 0.0
    for c in range(count):
        total += contacts[c, IMPULSE]
    for sweep in range(iterations):
        quiet = tolerance * total / count  # [N s] tolerance x the last sweep's mean impulse (first the warm start's)
        before_sweep, this_sweep = moved[sweep % 2], moved[(sweep + 1) % 2]
        this_sweep[:] = False
        change = 0.0
        total = 0.0
        largest = 0.0
        for c in range(count):
            b1 = ids[c, BODY1]
            b2 = ids[c, BODY2]
            if (sweep > 0 or seeded) and not touches_moved(before_sweep, this_sweep, b1, b2):
                total += contacts[c, IMPULSE]
                continue
            if use_friction and contacts[c, FRICTION] > 0.0:
                dq = friction_step(c, contacts, ids, vel, inv_mass, inv_inertia)
                change += abs(dq)
                largest = max(largest, abs(dq))
                if abs(dq) > quiet:
                    mark_moved(this_sweep, b1, b2)
            dp = normal_step(c, IMPULSE, contacts, ids, vel, inv_mass, inv_inertia)
            change += abs(dp)
            largest = max(largest, abs(dp))
            if abs(dp) > quiet:
                mark_moved(this_sweep, b1, b2)
            total += contacts[c, IMPULSE]
        if change <= tolerance * total and largest * count <= SINGLE_CHANGE * tolerance * total:
            break


@jit_stage(inline="always")
def touches_moved(before, now, b1, b2):
    """Whether body b1 or b2 (b2 < 0: the floor) is set in ``before`` (the sweep before) or in ``now`` (this one so
    far): whether a contact of theirs is stepped in a sweep after the first (``gauss_seidel``)."""
    return before[b1] or now[b1] or (b2 >= 0 and (before[b2] or now[b2]))


@jit_stage(inline="always")
def mark_moved(moved, b1, b2):
    """Note that bodies b1 and b2 (b2 < 0: the floor) took an impulse (``gauss_seidel``)."""
    moved[b1] = True
    if b2 >= 0:
        moved[b2] = True
