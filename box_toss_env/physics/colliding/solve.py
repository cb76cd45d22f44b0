"""The solve contacts stage of the colliding solver (``stages.COLLIDING_SUBSTEP``): the contact impulses, by the
cheapest method that is exact for the contact set (``solve_velocities``): none where the warm start already solves a
small set (``warm_start_holds``), normal and friction together up to JOINT_LIMIT contacts (``solve_jointly``,
``joint_contact_solve``), the normals exactly with friction sweeps up to DIRECT_LIMIT where boxes of unlike masses
meet (``exact_pays``, ``normal_lcp``, ``sweeps``), projected Gauss-Seidel otherwise (``sweeps.gauss_seidel``), after
solving exactly each island of unlike masses small enough (``solve_unlike_islands``): the choice is made island by
island, not by the count of the whole scene.
"""

from ..compile.compilation import jit_stage
from ..contact_law import friction_bound, tangent
from ..tunables import (
    DIRECT_LIMIT,
    EXACT_CONVERGED,
    EXACT_MASS_RATIO,
    JOINT_LIMIT,
    VELOCITY_ITERATIONS,
    WARM_START_RESIDUAL,
)
from .islands import find_root, join_islands
from .joint_contact_solve import full_delassus, joint_impulses
from .narrowphase import (
    BODY1,
    BODY2,
    CONTACT_COLUMNS,
    FRICTION,
    FRICTION_IMPULSE,
    ID_COLUMNS,
    IMPULSE,
    NORMAL_MASS,
    NX,
    NY,
    TANGENT_MASS,
    TARGET,
)
from .normal_lcp import delassus_matrix, normal_lcp
from .parallel import PARALLEL_CONTACTS, partitioned_gauss_seidel
from .prepare import apply_impulse, relative_velocity
from .sweeps import friction_sweep, gauss_seidel


@jit_stage(inline="always")
def solve_velocities(contacts, count, bodies, exact, context, seeded=False):
    """Solve contacts: the contact impulses of the first ``count`` contacts. Up to DIRECT_LIMIT contacts whose warm
    start already solves them (``warm_start_holds``: a stack at rest, kept awake), nothing more. Up to JOINT_LIMIT
    contacts with friction, normal and friction impulses are solved together, exactly (``joint_contact_solve``); up
    to DIRECT_LIMIT contacts where boxes of unlike masses meet (``exact_pays``; or if the joint solve does not
    settle), the normal impulses are solved exactly together (``alternate``); otherwise, or if the exact solve fails,
    projected Gauss-Seidel (``gauss_seidel``, with the scene's ``solver_tolerance`` and ``solver_iterations``; from
    PARALLEL_CONTACTS contacts up block by block, on threads: ``parallel.partitioned_gauss_seidel``), each island of
    unlike masses of at most DIRECT_LIMIT contacts solved exactly first (``solve_unlike_islands``). With ``seeded``
    (the restitution solve), the sweeps start from the bodies set in ``exact.moved[0]`` (``sweeps.gauss_seidel``).
    ``exact``: ``state.ExactWork``; ``context``: ``state.StepContext``."""
    if count == 0:
        return
    if count >= PARALLEL_CONTACTS:
        solve_unlike_islands(contacts, count, bodies, exact, context.use_friction)
        partitioned_gauss_seidel(
            contacts, count, bodies, context.use_friction, context.sweeps, context.sweep_tolerance, exact.moved, seeded
        )
        return
    use_friction = context.use_friction
    if (
        not seeded
        and count <= DIRECT_LIMIT
        and warm_start_holds(contacts.rows, contacts.ids, count, bodies.vel, use_friction)
    ):
        return
    if use_friction and count <= JOINT_LIMIT and solve_jointly(contacts, count, bodies, exact):
        return
    if exact_pays(contacts.ids, count, bodies.inv_mass, use_friction):
        if alternate(contacts.rows, contacts.ids, count, bodies, exact, use_friction):
            return
    else:
        solve_unlike_islands(contacts, count, bodies, exact, use_friction)
    gauss_seidel(
        contacts.rows,
        contacts.ids,
        count,
        bodies.vel,
        bodies.inv_mass,
        bodies.inv_inertia,
        use_friction,
        context.sweeps,
        context.sweep_tolerance,
        exact.moved,
        seeded,
    )


@jit_stage
def warm_start_holds(rows, ids, count, vel, use_friction):
    """Whether the warm-started impulses already solve the contact LCP, so the exact solves have nothing to do: a
    step of Gauss-Seidel from here would change the impulses by no more than WARM_START_RESIDUAL of their sum, summed
    over every contact: with r = u_rel . n - target, |r| m_n where p > 0 and max(-r, 0) m_n where p = 0; with the slip
    s = u_rel . t, |s| m_t where friction sticks (|q| < mu p), and only a slip the friction would resist further,
    max(s, 0) m_t at q = mu p and max(-s, 0) m_t at q = -mu p, where it slides. These are the LCP's conditions
    (p >= 0, r >= 0, p r = 0, and Coulomb's), met by these velocities to that share."""
    total = 0.0
    residual = 0.0
    for c in range(count):
        p = rows[c, IMPULSE]
        total += p
        ux, uy = relative_velocity(c, rows, ids, vel)
        nx, ny = rows[c, NX], rows[c, NY]
        r = ux * nx + uy * ny - rows[c, TARGET]
        residual += (abs(r) if p > 0.0 else max(-r, 0.0)) * rows[c, NORMAL_MASS]
        if use_friction and rows[c, FRICTION] > 0.0:
            bound = friction_bound(rows[c, FRICTION], p)
            if bound > 0.0:
                tx, ty = tangent(nx, ny)
                slip = ux * tx + uy * ty
                q = rows[c, FRICTION_IMPULSE]
                if q >= bound:
                    slip = max(slip, 0.0)
                elif q <= -bound:
                    slip = min(slip, 0.0)
                residual += abs(slip) * rows[c, TANGENT_MASS]
    return total > 0.0 and residual <= WARM_START_RESIDUAL * total


@jit_stage(inline="always")
def exact_pays(ids, count, inv_mass, use_friction):
    """Whether the exact normal solve pays for these ``count`` contacts: at most JOINT_LIMIT of them (a small system);
    or at most DIRECT_LIMIT and either no friction (one solve, no rounds of friction sweeps to alternate with) or one
    contact joining two boxes whose masses differ by more than EXACT_MASS_RATIO (Gauss-Seidel passes a heavy box's
    load through a light one a little at a sweep; among like masses its sweeps hold as well, for far less)."""
    if count <= JOINT_LIMIT or (count <= DIRECT_LIMIT and not use_friction):
        return True
    if count > DIRECT_LIMIT:
        return False
    for c in range(count):
        if unlike_masses(ids, c, inv_mass):
            return True
    return False


@jit_stage(inline="always")
def unlike_masses(ids, c, inv_mass):
    """Whether contact c joins two boxes whose masses differ by more than EXACT_MASS_RATIO."""
    b2 = ids[c, BODY2]
    if b2 < 0:
        return False
    a, b = inv_mass[ids[c, BODY1]], inv_mass[b2]
    return a > EXACT_MASS_RATIO * b or b > EXACT_MASS_RATIO * a


@jit_stage
def solve_unlike_islands(contacts, count, bodies, exact, use_friction):
    """Among more contacts than the exact solve takes together: each island (bodies joined by box-box contacts, with
    their floor contacts) that holds a contact between boxes of unlike masses and at most DIRECT_LIMIT contacts
    (``mark_unlike_islands``), solved exactly on its own (``alternate``, on its contacts gathered by
    ``gather_island`` and put back). The sweeps that follow over every contact find these at their solution.
    Without it the count of the whole scene decided: a heavy box on light ones beside a pile went to the sweeps,
    which pass its load through the light boxes a little at a sweep, and a 1000:1 stack dropped 5 cm beside a
    pyramid collapsed and threw its boxes 3 m. Returns the number of islands so solved."""
    rows = contacts.rows
    if not mark_unlike_islands(contacts.ids, count, bodies.inv_mass, exact, contacts.listed):
        return 0
    solved = 0
    for c in range(count):  # an island's first contact gathers it
        k = gather_island(rows, contacts.ids, c, exact, contacts.listed)
        if k == 0:
            continue
        alternate(exact.rows, exact.ids, k, bodies, exact, use_friction)
        for j in range(k):
            rows[exact.listed[j], IMPULSE] = exact.rows[j, IMPULSE]
            rows[exact.listed[j], FRICTION_IMPULSE] = exact.rows[j, FRICTION_IMPULSE]
        solved += 1
    return solved


@jit_stage
def mark_unlike_islands(ids, count, inv_mass, exact, order):
    """The islands of the contacts (``exact.root``, a union-find joined by the box-box contacts) to solve exactly
    among many: per root, ``exact.tally`` minus its number of contacts where the island holds a contact between
    unlike masses (``unlike_masses``) and at most DIRECT_LIMIT contacts, >= 0 otherwise; the marked islands'
    contacts listed island by island in ``order`` (``order_marked``). Returns whether any contact joins unlike masses
    (if none, nothing is marked, at the cost of one pass over the contacts)."""
    first = -1
    for c in range(count):
        if unlike_masses(ids, c, inv_mass):
            first = c
            break
    if first < 0:
        return False
    root, tally = exact.root, exact.tally
    join_islands(ids, count, root)
    for b in range(tally.shape[0]):
        tally[b] = 0
    for c in range(count):
        tally[find_root(root, ids[c, BODY1])] += 1
    for c in range(first, count):
        r = find_root(root, ids[c, BODY1])
        if 0 < tally[r] <= DIRECT_LIMIT and unlike_masses(ids, c, inv_mass):
            tally[r] = -tally[r]
    order_marked(ids, count, exact, order)
    return True


@jit_stage(inline="always")
def order_marked(ids, count, exact, order):
    """The contacts of the islands ``mark_unlike_islands`` marked, listed in ``order`` island by island (a counting
    sort: islands in the order of their first contact, each island's contacts in their own order), one pass over
    the contacts: island root r's contacts are ``order[exact.start[r] + tally[r] : exact.start[r]]`` (tally[r] < 0
    its count), so gathering k islands costs their contacts, not k passes over the scene's."""
    root, tally, start = exact.root, exact.tally, exact.start
    for b in range(start.shape[0]):
        start[b] = -1
    filled = 0
    for c in range(count):
        r = find_root(root, ids[c, BODY1])
        if tally[r] < 0:
            if start[r] < 0:
                start[r] = filled
                filled -= tally[r]
            order[start[r]] = c
            start[r] += 1


@jit_stage
def gather_island(rows, ids, c, exact, order):
    """If contact c is the first of an island marked by ``mark_unlike_islands`` not gathered yet: the island's
    contacts (listed in ``order`` by ``order_marked``) copied into ``exact.rows`` and ``exact.ids``, where each came
    from into ``exact.listed``, the island marked gathered; returns how many (0 for any other contact)."""
    r = find_root(exact.root, ids[c, BODY1])
    k = -exact.tally[r]
    if k <= 0:
        return 0
    exact.tally[r] = 0
    begin = exact.start[r] - k
    for j in range(k):
        d = order[begin + j]
        for column in range(CONTACT_COLUMNS):
            exact.rows[j, column] = rows[d, column]
        for column in range(ID_COLUMNS):
            exact.ids[j, column] = ids[d, column]
        exact.listed[j] = d
    return k


@jit_stage(inline="always")
def alternate(rows, ids, count, bodies, exact, use_friction):
    """The normal impulses solved exactly together (``normal_lcp``: a stack's load passes through every box at once,
    whatever the mass ratio), alternating with a friction sweep until the impulses change by less than
    EXACT_CONVERGED of their sum (at most VELOCITY_ITERATIONS rounds). Returns False if the exact solve failed (the
    caller sweeps instead)."""
    vel, inv_mass, inv_inertia = bodies.vel, bodies.inv_mass, bodies.inv_inertia
    w, free, x, active = exact.w, exact.free, exact.x, exact.active
    delassus_matrix(rows, ids, count, inv_mass, inv_inertia, w)
    for c in range(count):
        active[c] = rows[c, IMPULSE] > 0.0
    for _ in range(VELOCITY_ITERATIONS if use_friction else 1):
        for c in range(count):
            ux, uy = relative_velocity(c, rows, ids, vel)
            value = ux * rows[c, NX] + uy * rows[c, NY] - rows[c, TARGET]
            for d in range(count):
                value -= w[c, d] * rows[d, IMPULSE]
            free[c] = value
            if free[c] < 0.0:
                active[c] = True
        if not normal_lcp(w, free, x, active, count, exact.factor, exact.index, exact.y):
            return False
        change = 0.0
        total = 0.0
        for c in range(count):
            dp = x[c] - rows[c, IMPULSE]
            rows[c, IMPULSE] = x[c]
            if dp != 0.0:
                apply_impulse(c, dp * rows[c, NX], dp * rows[c, NY], rows, ids, vel, inv_mass, inv_inertia)
            change += abs(dp)
            total += x[c]
        if use_friction:
            change += friction_sweep(rows, ids, count, vel, inv_mass, inv_inertia)
        if change <= EXACT_CONVERGED * total:
            break
    return True


@jit_stage
def solve_jointly(contacts, count, bodies, exact):
    """The normal and friction impulses of the contacts solved together (``joint_impulses``), applied to the
    velocities and kept in the contacts; returns False (nothing changed) if that solve did not settle."""
    rows, ids = contacts.rows, contacts.ids
    vel, inv_mass, inv_inertia = bodies.vel, bodies.inv_mass, bodies.inv_inertia
    w, u, impulse = exact.w, exact.free, exact.y
    full_delassus(rows, ids, count, inv_mass, inv_inertia, w)
    for c in range(count):
        ux, uy = relative_velocity(c, rows, ids, vel)
        nx, ny = rows[c, NX], rows[c, NY]
        tx, ty = tangent(nx, ny)
        u[2 * c] = ux * nx + uy * ny - rows[c, TARGET]
        u[2 * c + 1] = ux * tx + uy * ty  # u_rel . t
    if not joint_impulses(rows, count, w, u, exact.state, exact.factor, exact.index, exact.x, impulse):
        return False
    for c in range(count):
        dp = impulse[2 * c] - rows[c, IMPULSE]
        dq = impulse[2 * c + 1] - rows[c, FRICTION_IMPULSE]
        rows[c, IMPULSE] = impulse[2 * c]
        rows[c, FRICTION_IMPULSE] = impulse[2 * c + 1]
        if dp != 0.0 or dq != 0.0:
            nx, ny = rows[c, NX], rows[c, NY]
            tx, ty = tangent(nx, ny)
            apply_impulse(c, dp * nx + dq * tx, dp * ny + dq * ty, rows, ids, vel, inv_mass, inv_inertia)
    return True
