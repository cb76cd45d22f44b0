"""Stage warm start of the colliding solver: each contact starts from its impulse of the last substep
(``warm_start``), or, in a cold start of many contacts, from a guess of a resting pile's loads
(``resting_loads``, split by the lever rule, ``lever_shares``).
"""

import numpy as np

from ..compile.compilation import jit_stage
from ..contact_law import clamp_friction, friction_bound, tangent
from ..tunables import LEVER_SPREAD, SUPPORT_SLOPE
from .narrowphase import BODY1, BODY2, FRICTION, FRICTION_IMPULSE, GAP, IMPULSE, NX, NY, R1X, R2X
from .parallel import PARALLEL_CONTACTS, partitioned_warm_start
from .prepare import apply_contact_impulses, apply_impulse, take_kept_impulses
from .solve import exact_pays


@jit_stage(nrt=True)  # it allocates its work arrays (once a cold start)
def resting_loads(contacts, count, bodies, h, gravity):
    """A first guess at the impulses of a resting scene, for a cold start (no warm start kept). From the
    highest body down, each body's vertical load F (its weight m |g| h and what rests on it) acts along the
    line x_F = sum(F_i x_i) / F; the contacts that hold the body up (|n_y| > SUPPORT_SLOPE, the body above
    on the side n points to, and near: a gap that a body at rest closes within the substep, |g| h^2), at
    points x_i, share it as a statics problem would: F_i = F (1/k + (x_i - xbar)(x_F - xbar) / sum (x_j - xbar)^2),
    the linear split whose forces add up to F and whose moment about any point is F's (lever rule), or, where
    that split has a negative share, all on the two outermost points by the lever rule, x_F clamped between
    them. Each contact gets the normal and friction impulses whose sum is vertical, p = F_i |n_y|,
    q = F_i n_x sign(n_y) (q within mu p), applied to the velocities; F_i passes on, at x_i, to the body
    below. The solve then corrects the guess: from zero, Gauss-Seidel needs a sweep per layer to carry a
    load down a pile (a column of 40 boxes, cold, sank 0.24 m/s in its first step of 1/60 s; with the
    guess it stays at rest). Returns how many contacts got an impulse."""
    rows, ids = contacts.rows, contacts.ids
    pose, vel, inv_mass, inv_inertia = bodies.pose, bodies.vel, bodies.inv_mass, bodies.inv_inertia
    n = pose.shape[0]
    load = np.empty(n)
    moment = np.empty(n)  # sum of F_i x_i over the loads on a body
    first = np.zeros(n + 1, np.int64)
    near = -gravity * h * h  # what a body at rest falls in the substep
    for b in range(n):
        load[b] = -gravity * h / inv_mass[b]
        moment[b] = load[b] * pose[b, 0]
    for c in range(count):
        rows[c, IMPULSE] = 0.0
        rows[c, FRICTION_IMPULSE] = 0.0
        ny = rows[c, NY]
        if rows[c, GAP] <= near and abs(ny) > SUPPORT_SLOPE:
            first[1 + (ids[c, BODY1] if ny > 0.0 else ids[c, BODY2])] += 1
    for b in range(n):
        first[b + 1] += first[b]
    held = np.empty(first[n], np.int64)  # the contacts that hold each body up, body by body
    at_x = np.empty(first[n])  # [m] where each holds it
    filled = first[:n].copy()
    for c in range(count):
        ny = rows[c, NY]
        if rows[c, GAP] <= near and abs(ny) > SUPPORT_SLOPE:
            upper = ids[c, BODY1] if ny > 0.0 else ids[c, BODY2]
            held[filled[upper]] = c
            at_x[filled[upper]] = pose[upper, 0] + (rows[c, R1X] if ny > 0.0 else rows[c, R2X])
            filled[upper] += 1
    share = np.empty(first[n])
    for b in np.argsort(-pose[:, 1]):
        lever_shares(at_x, first[b], first[b + 1], moment[b] / load[b], share)
        for i in range(first[b], first[b + 1]):
            c = held[i]
            force = load[b] * share[i]
            ny = rows[c, NY]
            p = force * abs(ny)
            q = clamp_friction(force * rows[c, NX] * (1.0 if ny > 0.0 else -1.0), friction_bound(rows[c, FRICTION], p))
            rows[c, IMPULSE] = p
            rows[c, FRICTION_IMPULSE] = q
            tx, ty = tangent(rows[c, NX], ny)
            apply_impulse(c, p * rows[c, NX] + q * tx, p * ny + q * ty, rows, ids, vel, inv_mass, inv_inertia)
            lower = ids[c, BODY2] if ny > 0.0 else ids[c, BODY1]
            if lower >= 0:
                load[lower] += force
                moment[lower] += force * at_x[i]
    return first[n]


@jit_stage(inline="always")
def lever_shares(x, begin, end, centre, share):
    """Shares share[begin:end] of a vertical load along x = ``centre`` among supports at x[begin:end] that
    add up to 1 and balance its moment (``resting_loads``' split)."""
    k = end - begin
    if k == 0:
        return
    mean = 0.0
    low, high = begin, begin
    for i in range(begin, end):
        mean += x[i]
        if x[i] < x[low]:
            low = i
        if x[i] > x[high]:
            high = i
    mean /= k
    spread = 0.0
    for i in range(begin, end):
        spread += (x[i] - mean) ** 2
    if x[high] - x[low] <= LEVER_SPREAD:
        for i in range(begin, end):
            share[i] = 1.0 / k
        return
    centre = min(max(centre, x[low]), x[high])
    lowest = 1.0
    for i in range(begin, end):
        share[i] = 1.0 / k + (x[i] - mean) * (centre - mean) / spread
        lowest = min(lowest, share[i])
    if lowest >= 0.0:
        return
    for i in range(begin, end):
        share[i] = 0.0
    share[high] = (centre - x[low]) / (x[high] - x[low])
    share[low] = 1.0 - share[high]


@jit_stage(inline="always")  # into the substep: a call passes each array of its structures apart (changelog)
def warm_start(contacts, count, warm_from, bodies, h, context):
    """Start each contact from the impulses its key had in the last substep (``warm_from``: keys, impulses, their
    count and substep length h', scaled by h / h'), applied to the velocities; new contacts start from zero. Both
    lists of keys increase (``find_contacts``' order), so one pass over them together pairs them; from
    PARALLEL_CONTACTS contacts up on threads (``parallel.partitioned_warm_start``). A cold start (none kept) of
    contacts the sweeps solve (``solve.exact_pays`` false), under a gravity that pulls down, starts from
    ``resting_loads``' guess instead."""
    previous_keys, previous_impulses, n_previous, h_previous = warm_from
    if (
        n_previous == 0
        and context.gravity < 0.0
        and not exact_pays(contacts.ids, count, bodies.inv_mass, context.use_friction)
    ):
        resting_loads(contacts, count, bodies, h, context.gravity)
        return
    ratio = h / h_previous
    if count >= PARALLEL_CONTACTS:
        partitioned_warm_start(contacts, count, (previous_keys, previous_impulses, n_previous), bodies, ratio)
        return
    rows, ids = contacts.rows, contacts.ids
    vel, inv_mass, inv_inertia = bodies.vel, bodies.inv_mass, bodies.inv_inertia
    at = 0
    for c in range(count):
        at, kept = take_kept_impulses(c, rows, ids, (previous_keys, previous_impulses, n_previous), at, ratio)
        if kept:
            apply_contact_impulses(c, rows, ids, vel, inv_mass, inv_inertia)
