"""The robust solver for scenes whose boxes collide (``Scene(boxes_collide=True)``): every box of the
scene is stepped together, since a contact between two boxes couples them. A scene whose boxes cannot
meet runs ``robust_solver``'s kernel instead, which compiles none of this.

Contacts (``narrowphase``) push body 1 out of body 2 along n at a point with lever arms r1, r2. The
two-body formulas of the reference text: with u_rel = u1 - u2, u = v + omega x r, a normal impulse
p n applied +p n to body 1 and -p n to body 2 changes u_rel . n by K_n p with the effective mass

    K_n = 1/m1 + 1/m2 + (r1 x n)^2 / I1 + (r2 x n)^2 / I2       (the floor: 1/m2 = 1/I2 = 0),

and a tangential impulse q t changes u_rel . t by K_t q, K_t the same with t for n. So the impulse
that stops the approach is p = -u_rel . n / K_n, and an impact with restitution e gets
p = -(1 + e) u_rel . n / K_n in total (the text's p = (1 + e) p' for two bodies).

The stages below are called, in the order of the method, by the step script in ``step``
(whose docstring gives the script); this module holds the contact impulses, the penalty and the stages
that advance bodies alone.

Material of a box-box contact (Box2D's mixing rules): restitution max(e1, e2), friction sqrt(mu1 mu2),
penalty stiffness min(k1, k2); box-floor contacts use the box's own.
"""

import math

import numpy as np

from .. import layout
from ..compile.compilation import jit_stage
from ..kernel_support import store_state
from ..robust.contact_solver import penalty_correction_share
from ..robust.flight import time_to_contact
from ..robust.robust_solver import (
    FIRST_CONTACT,
    IN_FLIGHT,
    MAX_PENETRATION,
    MAX_ROTATION_PER_STEP,
    N_IMPACTS,
    N_STEPS,
    PENALTY_TRIGGER,
    REST_TIME,
    STATUS,
    STILL_FOR,
    advance_box,
    start_memory,
)
from .broadphase import box_bound, time_apart
from .islands import islands_deeper_than
from .joint_contact_solve import HISTORY, JOINT_LIMIT, JOINT_ROUNDS, delassus_entry, full_delassus, joint_impulses
from .narrowphase import (
    APPROACH,
    BODY1,
    BODY2,
    FRICTION,
    FRICTION_IMPULSE,
    GAP,
    IMPULSE,
    KEY,
    NORMAL_MASS,
    NX,
    NY,
    PSEUDO_IMPULSE,
    R1X,
    R1Y,
    R2X,
    R2Y,
    RESTITUTION,
    STIFFNESS,
    TANGENT_MASS,
    TARGET,
)

TUNNEL_FRACTION = 0.5  # [-] of the smallest half extent: the most any point moves in one substep
MAX_SUBSTEPS = 256
VELOCITY_ITERATIONS = 64  # rounds of exact normal solve and friction sweep at most per substep
RESTITUTION_ITERATIONS = 16
PENALTY_ITERATIONS = 16  # the penalty's Gauss-Seidel sweeps at most (fewer if the scene's solver_iterations is)
CONVERGED = 1e-9  # sweeps stop when the impulses change by less than this share of their sum
SINGLE_CHANGE = 100.0  # [-] and none by more than this many times that share of their mean (``gauss_seidel``)
CONTACT_TOLERANCE = 1e-12  # [m per m of size + 1 m] penetration below this is not corrected
MIN_CAPACITY = 16
DIRECT_LIMIT = 64  # contacts: up to this many, the normal impulses are solved exactly (``normal_lcp``)
assert DIRECT_LIMIT >= HISTORY + JOINT_ROUNDS  # the solves' ``index`` also holds ``joint_impulses``'s rounds
REGULARISATION = 1e-12  # share of W_cc added to the diagonal of the exact solve (redundant contacts)
LCP_TOLERANCE = 1e-12  # share of the largest |free velocity|: a contact left free may approach by this much
SUPPORT_SLOPE = 0.5  # [-] |n_y| above which a contact carries weight in a cold start's guess (``resting_loads``)
ALONE_LIMIT = 8  # awake bodies at most for which whole steps alone against the floor are looked for (steps_alone)
ALONE_LOWEST = 0.5  # [share of the smaller half extent] a box's centre is taken never to sink below this height


@jit_stage(inline="always")
def relative_velocity(c, contacts, ids, vel):
    """u_rel = u1 - u2 at contact c, u = v + omega x r = (vx - omega ry, vy + omega rx)."""
    b1 = ids[c, BODY1]
    b2 = ids[c, BODY2]
    ux = vel[b1, 0] - vel[b1, 2] * contacts[c, R1Y]
    uy = vel[b1, 1] + vel[b1, 2] * contacts[c, R1X]
    if b2 >= 0:
        ux -= vel[b2, 0] - vel[b2, 2] * contacts[c, R2Y]
        uy -= vel[b2, 1] + vel[b2, 2] * contacts[c, R2X]
    return ux, uy


@jit_stage(inline="always")
def apply_impulse(c, px, py, contacts, ids, vel, inv_mass, inv_inertia):
    """The impulse P at contact c: +P on body 1 (v1 += P / m1, omega1 += (r1 x P) / I1), -P on body 2."""
    b1 = ids[c, BODY1]
    b2 = ids[c, BODY2]
    vel[b1, 0] += px * inv_mass[b1]
    vel[b1, 1] += py * inv_mass[b1]
    vel[b1, 2] += (contacts[c, R1X] * py - contacts[c, R1Y] * px) * inv_inertia[b1]
    if b2 >= 0:
        vel[b2, 0] -= px * inv_mass[b2]
        vel[b2, 1] -= py * inv_mass[b2]
        vel[b2, 2] -= (contacts[c, R2X] * py - contacts[c, R2Y] * px) * inv_inertia[b2]


@jit_stage
def prepare_contacts(contacts, ids, count, params, inv_mass, inv_inertia):
    """Effective masses 1 / K_n, 1 / K_t and the mixed material of each contact."""
    for c in range(count):
        b1 = ids[c, BODY1]
        b2 = ids[c, BODY2]
        nx, ny = contacts[c, NX], contacts[c, NY]
        rn1 = contacts[c, R1X] * ny - contacts[c, R1Y] * nx
        rt1 = contacts[c, R1X] * nx + contacts[c, R1Y] * ny  # r1 x t with t = (-ny, nx)
        k_n = inv_mass[b1] + rn1 * rn1 * inv_inertia[b1]
        k_t = inv_mass[b1] + rt1 * rt1 * inv_inertia[b1]
        if b2 >= 0:
            rn2 = contacts[c, R2X] * ny - contacts[c, R2Y] * nx
            rt2 = contacts[c, R2X] * nx + contacts[c, R2Y] * ny
            k_n += inv_mass[b2] + rn2 * rn2 * inv_inertia[b2]
            k_t += inv_mass[b2] + rt2 * rt2 * inv_inertia[b2]
            contacts[c, RESTITUTION] = max(params[b1, layout.RESTITUTION], params[b2, layout.RESTITUTION])
            contacts[c, FRICTION] = math.sqrt(params[b1, layout.FRICTION] * params[b2, layout.FRICTION])
            contacts[c, STIFFNESS] = min(params[b1, layout.STIFFNESS], params[b2, layout.STIFFNESS])
        else:
            contacts[c, RESTITUTION] = params[b1, layout.RESTITUTION]
            contacts[c, FRICTION] = params[b1, layout.FRICTION]
            contacts[c, STIFFNESS] = params[b1, layout.STIFFNESS]
        contacts[c, NORMAL_MASS] = 1.0 / k_n
        contacts[c, TANGENT_MASS] = 1.0 / k_t


@jit_stage(nrt=True)  # it allocates its work arrays (once a cold start)
def resting_loads(contacts, ids, count, pose, vel, inv_mass, inv_inertia, h, gravity):
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
    n = pose.shape[0]
    load = np.empty(n)
    moment = np.empty(n)  # sum of F_i x_i over the loads on a body
    first = np.zeros(n + 1, np.int64)
    near = -gravity * h * h  # what a body at rest falls in the substep
    for b in range(n):
        load[b] = -gravity * h / inv_mass[b]
        moment[b] = load[b] * pose[b, 0]
    for c in range(count):
        contacts[c, IMPULSE] = 0.0
        contacts[c, FRICTION_IMPULSE] = 0.0
        ny = contacts[c, NY]
        if contacts[c, GAP] <= near and abs(ny) > SUPPORT_SLOPE:
            first[1 + (ids[c, BODY1] if ny > 0.0 else ids[c, BODY2])] += 1
    for b in range(n):
        first[b + 1] += first[b]
    held = np.empty(first[n], np.int64)  # the contacts that hold each body up, body by body
    at_x = np.empty(first[n])  # [m] where each holds it
    filled = first[:n].copy()
    for c in range(count):
        ny = contacts[c, NY]
        if contacts[c, GAP] <= near and abs(ny) > SUPPORT_SLOPE:
            upper = ids[c, BODY1] if ny > 0.0 else ids[c, BODY2]
            held[filled[upper]] = c
            at_x[filled[upper]] = pose[upper, 0] + (contacts[c, R1X] if ny > 0.0 else contacts[c, R2X])
            filled[upper] += 1
    share = np.empty(first[n])
    for b in np.argsort(-pose[:, 1]):
        lever_shares(at_x, first[b], first[b + 1], moment[b] / load[b], share)
        for i in range(first[b], first[b + 1]):
            c = held[i]
            force = load[b] * share[i]
            ny = contacts[c, NY]
            p = force * abs(ny)
            q = force * contacts[c, NX] * (1.0 if ny > 0.0 else -1.0)
            bound = contacts[c, FRICTION] * p
            q = min(max(q, -bound), bound)
            contacts[c, IMPULSE] = p
            contacts[c, FRICTION_IMPULSE] = q
            apply_impulse(c, p * contacts[c, NX] - q * ny, p * ny + q * contacts[c, NX], contacts, ids, vel,
                          inv_mass, inv_inertia)
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
    if x[high] - x[low] <= 1e-9:
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


@jit_stage
def warm_start(contacts, ids, count, previous_keys, previous_impulses, n_previous, ratio, vel, inv_mass,
               inv_inertia, pose, h, gravity):
    """Start each contact from the impulses its key had in the last substep (times ``ratio``, the ratio
    of the substep lengths), applied to the velocities; new contacts start from zero. Both lists of keys
    increase (``find_contacts``' order), so one pass over them together pairs them. A cold start (none kept)
    of more contacts than the exact solves take, under a gravity that pulls down, starts from ``resting_loads``'
    guess instead."""
    if n_previous == 0 and count > DIRECT_LIMIT and gravity < 0.0:
        resting_loads(contacts, ids, count, pose, vel, inv_mass, inv_inertia, h, gravity)
        return
    at = 0
    for c in range(count):
        contacts[c, IMPULSE] = 0.0
        contacts[c, FRICTION_IMPULSE] = 0.0
        while at < n_previous and previous_keys[at] < ids[c, KEY]:
            at += 1
        if at < n_previous and previous_keys[at] == ids[c, KEY]:
            p = ratio * previous_impulses[at, 0]
            q = ratio * previous_impulses[at, 1]
            contacts[c, IMPULSE] = p
            contacts[c, FRICTION_IMPULSE] = q
            nx, ny = contacts[c, NX], contacts[c, NY]
            apply_impulse(c, p * nx - q * ny, p * ny + q * nx, contacts, ids, vel, inv_mass, inv_inertia)


@jit_stage
def delassus_matrix(contacts, ids, count, inv_mass, inv_inertia, w):
    """The normal Delassus matrix W_cd = J_c M^-1 J_d^T of the first ``count`` contacts into w: how a unit
    normal impulse at contact d changes u_rel . n at contact c (nonzero where they share a body)."""
    for c in range(count):
        for d in range(c, count):
            value = delassus_entry(contacts, ids, c, contacts[c, NX], contacts[c, NY], d, contacts[d, NX],
                                   contacts[d, NY], inv_mass, inv_inertia)
            w[c, d] = value
            w[d, c] = value


@jit_stage
def solve_active(w, free, active, count, x, factor, index, y):
    """x on the active contacts solving W_AA x_A = -free_A (Cholesky, with a relative regularisation
    REGULARISATION on the diagonal for redundant contacts), 0 elsewhere (``index``, ``y``: work arrays).
    Returns False if the active block is not positive definite."""
    m = 0
    for c in range(count):
        x[c] = 0.0
        if active[c]:
            index[m] = c
            m += 1
    for p in range(m):
        for q in range(p + 1):
            value = w[index[p], index[q]]
            if p == q:
                value += REGULARISATION * w[index[p], index[p]]
            for r in range(q):
                value -= factor[p, r] * factor[q, r]
            if p == q:
                if value <= 0.0:
                    return False
                factor[p, p] = math.sqrt(value)
            else:
                factor[p, q] = value / factor[q, q]
    for p in range(m):
        value = -free[index[p]]
        for r in range(p):
            value -= factor[p, r] * y[r]
        y[p] = value / factor[p, p]
    for p in range(m - 1, -1, -1):
        value = y[p]
        for r in range(p + 1, m):
            value -= factor[r, p] * x[index[r]]
        x[index[p]] = value / factor[p, p]
    return True


@jit_stage
def normal_lcp(w, free, x, active, count, factor, index, y):
    """The normal impulses x >= 0 with W x + free >= 0 and x_c (W x + free)_c = 0 (free: u_rel . n - target
    at zero impulse), by an active set on the dense W: solve the active block, drop the contacts that
    would pull, add the one that penetrates most, until neither happens. ``active`` holds the first guess
    (the contacts that carried load). Returns False if it does not settle (the caller falls back to
    Gauss-Seidel)."""
    scale = 0.0
    for c in range(count):
        scale = max(scale, abs(free[c]))
    tolerance = LCP_TOLERANCE * scale
    for _ in range(3 * count + 3):
        if not solve_active(w, free, active, count, x, factor, index, y):
            return False
        dropped = False
        for c in range(count):
            if active[c] and x[c] < 0.0:
                active[c] = False
                dropped = True
        if dropped:
            continue
        worst = -tolerance
        add = -1
        for c in range(count):
            if not active[c]:
                value = free[c]
                for d in range(count):
                    value += w[c, d] * x[d]
                if value < worst:
                    worst = value
                    add = c
        if add < 0:
            return True
        active[add] = True
    return False


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
    nx, ny = contacts[c, NX], contacts[c, NY]
    ux, uy = relative_velocity(c, contacts, ids, vel)
    slip = -ux * ny + uy * nx  # u_rel . t, t = (-ny, nx)
    before = contacts[c, FRICTION_IMPULSE]
    limit = contacts[c, FRICTION] * contacts[c, IMPULSE]
    after = min(max(before - slip * contacts[c, TANGENT_MASS], -limit), limit)
    contacts[c, FRICTION_IMPULSE] = after
    dq = after - before
    if dq != 0.0:
        apply_impulse(c, -dq * ny, dq * nx, contacts, ids, vel, inv_mass, inv_inertia)
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
def gauss_seidel(contacts, ids, count, vel, inv_mass, inv_inertia, use_friction, iterations, tolerance, moved):
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
    the sweeps it needs visit its neighbourhood, not every contact of the pile. ``moved``: (2, bodies) work."""
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
            if sweep > 0 and not (before_sweep[b1] or this_sweep[b1]
                                  or (b2 >= 0 and (before_sweep[b2] or this_sweep[b2]))):
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
def mark_moved(moved, b1, b2):
    """Note that bodies b1 and b2 (b2 < 0: the floor) took an impulse (``gauss_seidel``)."""
    moved[b1] = True
    if b2 >= 0:
        moved[b2] = True


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


@jit_stage
def apply_restitution(contacts, ids, count, vel, inv_mass, inv_inertia, threshold):
    """Stage 5's polish, after the impacts were solved with every contact and friction: contact by contact,
    u_rel . n >= -e u0 for the contacts that approached faster than the threshold and took an impulse (the
    normal impulse stays >= 0; a single contact gets the closed form to rounding); the floor's other contacts
    join with their speculative target less the threshold, their impulse only growing. Returns how many
    contacts are impacts."""
    impacts = 0
    for c in range(count):
        if contacts[c, APPROACH] < -threshold and contacts[c, IMPULSE] > 0.0:
            impacts += 1
    if impacts == 0:
        return 0
    for _ in range(RESTITUTION_ITERATIONS):
        change = 0.0
        total = 0.0
        for c in range(count):
            if contacts[c, APPROACH] < -threshold and contacts[c, IMPULSE] > 0.0:
                target = -contacts[c, RESTITUTION] * contacts[c, APPROACH]
                least = 0.0
            elif ids[c, BODY2] < 0:  # the floor's other contacts: an impact may not drive a corner into the
                target = contacts[c, TARGET] - threshold  # floor faster than the threshold, nor release it
                least = contacts[c, IMPULSE]
            else:
                continue
            nx, ny = contacts[c, NX], contacts[c, NY]
            ux, uy = relative_velocity(c, contacts, ids, vel)
            before = contacts[c, IMPULSE]
            after = max(before - (ux * nx + uy * ny - target) * contacts[c, NORMAL_MASS], least)
            contacts[c, IMPULSE] = after
            dp = after - before
            if dp != 0.0:
                apply_impulse(c, dp * nx, dp * ny, contacts, ids, vel, inv_mass, inv_inertia)
            change += abs(dp)
            total += after
        if change <= CONVERGED * total:
            break
    return impacts


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
def body_kinetic_energy(vel, b, params):
    """m |v|^2 / 2 + I omega^2 / 2 of body b [J]."""
    return 0.5 * (params[b, layout.MASS] * (vel[b, 0] ** 2 + vel[b, 1] ** 2)
                  + params[b, layout.INERTIA] * vel[b, 2] ** 2)


@jit_stage
def substeps(vel, radius, smallest_half, dt, gravity):
    """How many substeps a grid step needs: no point moves further than TUNNEL_FRACTION of the smallest
    half extent, no box turns further than MAX_ROTATION_PER_STEP (at most MAX_SUBSTEPS)."""
    speed = 0.0
    turn = 0.0
    for b in range(vel.shape[0]):
        speed = max(speed, math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(gravity) * dt
                    + abs(vel[b, 2]) * radius[b])
        turn = max(turn, abs(vel[b, 2]))
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


@jit_stage
def energy_speed(vel, b, params, y, gravity):
    """A bound on the speed of every point of body b from now on, while it meets only the floor:
    sqrt(2 E (1/m + R^2 / I)) with E its kinetic energy plus m |g| (y - ALONE_LOWEST min(hx, hy)), the
    potential energy it can give up before its centre reaches that height. By Cauchy-Schwarz
    (|v| + |omega| R)^2 <= (m |v|^2 + I omega^2) (1/m + R^2 / I), and the floor's contacts never add energy
    (``robust_solver``: impulses, the energy limit and the penalty's energy all take, never give)."""
    mass = params[b, layout.MASS]
    half = min(params[b, layout.HALF_LENGTH], params[b, layout.HALF_WIDTH])
    energy = (body_kinetic_energy(vel, b, params)
              + mass * abs(gravity) * max(y - ALONE_LOWEST * half, 0.0))
    radius2 = params[b, layout.HALF_LENGTH] ** 2 + params[b, layout.HALF_WIDTH] ** 2
    return math.sqrt(2.0 * energy * (1.0 / mass + radius2 / params[b, layout.INERTIA]))


@jit_stage
def bounds_touch(pose, half, radius, awake):
    """Whether the bounding box of an awake box touches or overlaps another box's (``broadphase.time_apart``'s gap
    max(|dx| - b_x - b'_x, |dy| - b_y - b'_y) <= 0 now; the boxes' circles first, which hold their bounds)."""
    n = pose.shape[0]
    for b in range(n):
        if not awake[b]:
            continue
        bx, by = box_bound(math.cos(pose[b, 2]), math.sin(pose[b, 2]), half[b, 0], half[b, 1])
        for o in range(n):
            if o == b:
                continue
            dx, dy = abs(pose[o, 0] - pose[b, 0]), abs(pose[o, 1] - pose[b, 1])
            if max(dx, dy) > radius[b] + radius[o]:
                continue
            ox, oy = box_bound(math.cos(pose[o, 2]), math.sin(pose[o, 2]), half[o, 0], half[o, 1])
            if max(dx - bx - ox, dy - by - oy) <= 0.0:
                return True
    return False


@jit_stage
def steps_alone(pose, vel, half, radius, awake, params, gravity, tolerance, dt, steps_left):
    """How many whole time steps every awake body can be advanced alone against the floor
    (``robust_solver.advance_box``: flight in closed form, impacts located in time) before any two boxes could
    meet; the larger of two safe counts:
      - flight: no awake body touches the floor (``flight.time_to_contact``) and each stays apart from every
        other box on the exact parabolas (``broadphase.time_apart``), the steps a thrown box flies;
      - energy: every body stays within its circumscribed circle (radius R) of its centre, and no point moves
        faster than ``energy_speed``, so the gap max(|dx| - R - b'_x, |dy| - R - b'_y) between an awake box's
        circle and another box's bounds (its circle if awake, its box if asleep) closes no faster than the
        sum of their speed bounds: a box bouncing or sliding on the floor far from the others.
    Both give none while an awake box's bounding box touches another's (``bounds_touch``), which is asked first:
    a box resting on another costs no search."""
    if bounds_touch(pose, half, radius, awake):
        return 0
    horizon = steps_left * dt
    flight = horizon
    for b in range(pose.shape[0]):
        if awake[b]:
            tau, _ = time_to_contact(pose[b, 1], pose[b, 2], vel[b, 1], vel[b, 2], half[b, 0], half[b, 1], gravity,
                                     flight, tolerance, 0.25 * dt)
            flight = min(flight, tau)
            if flight < dt:
                break
            flight = min(flight, time_apart(b, pose, vel, half, radius, awake, gravity, flight, 0.25 * dt))
            if flight < dt:
                break
    energy = horizon
    if flight < horizon:
        for b in range(pose.shape[0]):
            if not awake[b]:
                continue
            speed_b = energy_speed(vel, b, params, pose[b, 1], gravity)
            for o in range(pose.shape[0]):
                if o == b or (awake[o] and o < b):  # a pair of awake boxes once
                    continue
                speed = speed_b
                if awake[o]:
                    ox = oy = radius[o]
                    speed += energy_speed(vel, o, params, pose[o, 1], gravity)
                else:
                    ox, oy = box_bound(math.cos(pose[o, 2]), math.sin(pose[o, 2]), half[o, 0], half[o, 1])
                gap = max(abs(pose[o, 0] - pose[b, 0]) - radius[b] - ox, abs(pose[o, 1] - pose[b, 1]) - radius[b] - oy)
                if gap <= speed * dt:
                    return np.int64(math.floor(flight / dt))
                if speed > 0.0:
                    energy = min(energy, gap / speed)
    return min(np.int64(math.floor(max(flight, energy) / dt)), steps_left)


@jit_stage
def advance_alone(k, n, state_pose, vel, params, awake, supported, alone, memory, stepped, n_impacts, first_contact,
                  max_penetration, still_for, island, rest_time, work, dt, gravity, until_rest, threshold,
                  sleep_speed, sleep_time, slop, use_penalty, use_friction, record, corners, delassus, corner_ids,
                  trajectory, events):
    """Every awake body advanced alone against the floor for k grid steps from step n
    (``robust_solver.advance_box``, its memory row carried on while the body stays alone: ``alone``), a body
    that falls asleep on the floor taking an island of its own; the trajectory rows of the others filled.
    Returns (the step reached, the number of bodies that fell asleep, the failing body or -1)."""
    nb = state_pose.shape[0]
    reached = n
    slept = 0
    for b in range(nb):
        if not awake[b]:
            continue
        if not alone[b]:  # a body that the colliding substeps moved starts a new memory row from their state
            start_memory(memory, b, n * dt)
            memory[b, IN_FLIGHT] = 0.0 if supported[b] else 1.0
            memory[b, N_IMPACTS] = n_impacts[b]
            memory[b, N_STEPS] = stepped[b]
            memory[b, FIRST_CONTACT] = first_contact[b]
            memory[b, MAX_PENETRATION] = max_penetration[b]
            alone[b] = True
        for c in range(3):
            work[b, c] = state_pose[b, c]
            work[b, 3 + c] = vel[b, c]
        end = advance_box(b, work, params, memory, n, n + k, dt, gravity, until_rest, threshold, sleep_speed,
                          sleep_time, slop, use_penalty, use_friction, record, corners, delassus, corner_ids,
                          trajectory, events)
        for c in range(3):
            state_pose[b, c] = work[b, c]
            vel[b, c] = work[b, 3 + c]
        n_impacts[b] = np.int64(memory[b, N_IMPACTS])
        stepped[b] = np.int64(memory[b, N_STEPS])
        first_contact[b] = memory[b, FIRST_CONTACT]
        max_penetration[b] = memory[b, MAX_PENETRATION]
        still_for[b] = memory[b, STILL_FOR]
        if memory[b, STATUS] != layout.STATUS_OK:
            return end, slept, b
        if not math.isnan(memory[b, REST_TIME]):
            awake[b] = False
            alone[b] = False  # woken later, it starts a new memory row
            island[b] = b
            rest_time[b] = memory[b, REST_TIME]
            slept += 1
        reached = max(reached, end)
    if slept > 0 and count_awake(awake) == 0:
        k = reached - n  # every body sleeps: the run ends where the last fell asleep
    if record:
        for b in range(nb):
            first = n + 1
            if not awake[b] and not math.isnan(rest_time[b]) and rest_time[b] > n * dt:
                first = np.int64(round(rest_time[b] / dt)) + 1  # advance_box recorded it up to its rest
            elif awake[b]:
                continue
            for row in range(first, n + k + 1):
                store_state(trajectory, row, b, state_pose[b, 0], state_pose[b, 1], state_pose[b, 2], 0.0, 0.0, 0.0)
    return n + k, slept, -1


@jit_stage
def count_awake(awake):
    count = 0
    for b in range(awake.shape[0]):
        count += awake[b]
    return count
