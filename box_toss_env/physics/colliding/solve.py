"""The solve contacts stage of the colliding solver (``stages.COLLIDING_SUBSTEP``): the contact impulses, by the
cheapest method that is exact for the contact set (``solve_velocities``): normal and friction together up to
JOINT_LIMIT contacts (``solve_jointly``, ``joint_contact_solve``), the normals exactly with friction sweeps up
to DIRECT_LIMIT where boxes of unlike masses meet (``exact_pays``, ``normal_lcp``, ``sweeps``), projected
Gauss-Seidel otherwise (``sweeps.gauss_seidel``).
"""

from ..compile.compilation import jit_stage
from ..contact_law import tangent
from ..tunables import DIRECT_LIMIT, EXACT_CONVERGED, EXACT_MASS_RATIO, JOINT_LIMIT, VELOCITY_ITERATIONS
from .joint_contact_solve import full_delassus, joint_impulses
from .narrowphase import BODY1, BODY2, FRICTION_IMPULSE, IMPULSE, NX, NY, TARGET
from .normal_lcp import delassus_matrix, normal_lcp
from .parallel import PARALLEL_CONTACTS, partitioned_gauss_seidel
from .prepare import apply_impulse, relative_velocity
from .sweeps import friction_sweep, gauss_seidel


@jit_stage
def solve_velocities(contacts, count, bodies, exact, context):
    """Solve contacts: the contact impulses of the first ``count`` contacts. Up to JOINT_LIMIT contacts with friction,
    normal and friction impulses are solved together, exactly (``joint_contact_solve``); up to DIRECT_LIMIT contacts
    where boxes of unlike masses meet (``exact_pays``; or if the joint solve does not settle), the normal impulses
    are solved exactly together (``alternate``); otherwise, or if the exact solve fails, projected Gauss-Seidel
    (``gauss_seidel``, with the scene's ``solver_tolerance`` and ``solver_iterations``; from PARALLEL_CONTACTS
    contacts up block by block, on threads: ``parallel.partitioned_gauss_seidel``).
    ``exact``: ``state.ExactWork``; ``context``: ``state.StepContext``."""
    if count == 0:
        return
    if count >= PARALLEL_CONTACTS:
        partitioned_gauss_seidel(
            contacts, count, bodies, context.use_friction, context.sweeps, context.sweep_tolerance, exact.moved
        )
        return
    use_friction = context.use_friction
    if use_friction and count <= JOINT_LIMIT and solve_jointly(contacts, count, bodies, exact):
        return
    if exact_pays(contacts.ids, count, bodies.inv_mass, use_friction):
        if alternate(contacts, count, bodies, exact, use_friction):
            return
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
    )


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
        b2 = ids[c, BODY2]
        if b2 >= 0:
            a, b = inv_mass[ids[c, BODY1]], inv_mass[b2]
            if a > EXACT_MASS_RATIO * b or b > EXACT_MASS_RATIO * a:
                return True
    return False


@jit_stage(inline="always")
def alternate(contacts, count, bodies, exact, use_friction):
    """The normal impulses solved exactly together (``normal_lcp``: a stack's load passes through every box at once,
    whatever the mass ratio), alternating with a friction sweep until the impulses change by less than
    EXACT_CONVERGED of their sum (at most VELOCITY_ITERATIONS rounds). Returns False if the exact solve failed (the
    caller sweeps instead)."""
    rows, ids = contacts.rows, contacts.ids
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
