"""The normal and friction impulses of a small contact set solved together, exactly: the 2D Coulomb contact
LCP by an active set over the contacts' states (free, sticking, sliding one way or the other).

Each contact c has a normal impulse p_c and a friction impulse q_c along t_c = (-n_y, n_x). Stacked as
lambda = (p_0, q_0, p_1, q_1, ...), they change the contacts' relative velocities by the full Delassus
matrix, u = u_0 + W lambda with W_ij = J_i M^-1 J_j^T: for rows i, j with directions d_i, d_j (n or t) at
lever arms r_i, r_j on a shared body of mass m and inertia I,

    W_ij += +-(d_i . d_j / m + (r_i x d_i)(r_j x d_j) / I)        (+ when both are body 1 or both body 2).

The impulses sought (u_n: the normal speed less its target, u_t: the slip):
  - normal: p >= 0, u_n >= 0, p u_n = 0;
  - friction (Coulomb, maximal dissipation): |q| <= mu p; sticking (|q| < mu p) means u_t = 0; sliding with
    q = +mu p (SLIDE_PLUS) means u_t <= 0, with q = -mu p (SLIDE_MINUS) u_t >= 0 (the friction opposes the slip).
Given each contact's state the conditions are linear: a free contact has p = q = 0; an active one adds
the row u_n = 0 for p; a sticking one adds u_t = 0 for q; a sliding one has no unknown q, its column folds
+-mu into p's (W's p column plus +-mu times its q column, so the system is not symmetric: Gaussian
elimination with partial pivoting, the diagonal regularised by REGULARISATION of W_ii as the normal-only
solve's, for redundant contacts: a box flat on the floor sticks at two corners with one slip). After each
solve the first violated condition changes a state: a pulling normal frees its contact, a sticking
friction beyond mu p slides the way it pushed, a sliding contact whose slip turned sticks, a free contact
that would penetrate becomes active (sticking). This ends in a few solves where alternating an exact
normal solve with friction sweeps took about ten rounds a substep while a box rocked on another.
A state that does not settle within JOINT_ROUNDS solves, or a singular system, returns False and the
caller solves by alternation instead.
"""

from ..compile.compilation import jit_stage
from ..contact_law import friction_bound, friction_slope, tangent
from ..tunables import DIRECT_LIMIT, FRICTION_CONE_ROUNDING, JOINT_LIMIT, JOINT_ROUNDS, LCP_TOLERANCE, REGULARISATION
from .narrowphase import BODY1, FRICTION, FRICTION_IMPULSE, IMPULSE, NX, NY, R1X, R1Y, R2X, R2Y

HISTORY = 2 * JOINT_LIMIT  # where ``joint_impulses`` keeps each round's states in ``index`` (after the unknowns')
assert DIRECT_LIMIT >= HISTORY + JOINT_ROUNDS  # the solves' ``index`` (DIRECT_LIMIT long) also holds the rounds

FREE, STICK, SLIDE_PLUS, SLIDE_MINUS, FRICTIONLESS = 0, 1, 2, 3, 4  # contact states (SLIDE_PLUS: q = +mu p)


@jit_stage(inline="always")
def direction(contacts, c, row):
    """The unit vector of row ``row`` (0: normal n, 1: tangent t = (-n_y, n_x)) of contact c."""
    nx, ny = contacts[c, NX], contacts[c, NY]
    if row == 0:
        return nx, ny
    return tangent(nx, ny)


@jit_stage(inline="always")
def delassus_entry(contacts, ids, c, dcx, dcy, d, ddx, ddy, inv_mass, inv_inertia):
    """W_ij for direction (dcx, dcy) at contact c and (ddx, ddy) at contact d: the module docstring's sum over
    the bodies they share (``normal_lcp.delassus_matrix`` takes it on the normals alone)."""
    value = 0.0
    for side_c in range(2):
        b = ids[c, BODY1 + side_c]
        if b < 0:
            continue
        rcx = contacts[c, R1X] if side_c == 0 else contacts[c, R2X]
        rcy = contacts[c, R1Y] if side_c == 0 else contacts[c, R2Y]
        for side_d in range(2):
            if ids[d, BODY1 + side_d] != b:
                continue
            rdx = contacts[d, R1X] if side_d == 0 else contacts[d, R2X]
            rdy = contacts[d, R1Y] if side_d == 0 else contacts[d, R2Y]
            sign = 1.0 if side_c == side_d else -1.0
            turn = (rcx * dcy - rcy * dcx) * (rdx * ddy - rdy * ddx)
            value += sign * ((dcx * ddx + dcy * ddy) * inv_mass[b] + turn * inv_inertia[b])
    return value


@jit_stage
def full_delassus(contacts, ids, count, inv_mass, inv_inertia, w):
    """W (2 count x 2 count) into w: row 2c + 0 is contact c's normal, 2c + 1 its tangent."""
    for i in range(2 * count):
        c, row_c = i // 2, i % 2
        dcx, dcy = direction(contacts, c, row_c)
        for j in range(i, 2 * count):
            d, row_d = j // 2, j % 2
            ddx, ddy = direction(contacts, d, row_d)
            value = delassus_entry(contacts, ids, c, dcx, dcy, d, ddx, ddy, inv_mass, inv_inertia)
            w[i, j] = value
            w[j, i] = value


@jit_stage
def eliminate(a, k, x):
    """x solving the k x k system in a[:k, :k] with right-hand side a[:k, k] (Gaussian elimination with
    partial pivoting, in place). Returns False if a pivot vanishes."""
    for col in range(k):
        pivot = col
        for r in range(col + 1, k):
            if abs(a[r, col]) > abs(a[pivot, col]):
                pivot = r
        if not abs(a[pivot, col]) > 0.0:
            return False
        if pivot != col:
            for j in range(col, k + 1):
                a[col, j], a[pivot, j] = a[pivot, j], a[col, j]
        for r in range(col + 1, k):
            factor = a[r, col] / a[col, col]
            if factor != 0.0:
                for j in range(col, k + 1):
                    a[r, j] -= factor * a[col, j]
    for r in range(k - 1, -1, -1):
        value = a[r, k]
        for j in range(r + 1, k):
            value -= a[r, j] * x[j]
        x[r] = value / a[r, r]
    return True


@jit_stage
def solve_states(contacts, count, w, u0, state, a, index, x, impulse):
    """The impulses (p_c, q_c into ``impulse``) that meet the linear conditions of the contacts' states.
    Returns False if the system is singular."""
    k = 0
    for c in range(count):  # unknowns: p of every non-free contact, q of the sticking ones
        if state[c] != FREE:
            index[k] = 2 * c
            k += 1
            if state[c] == STICK:
                index[k] = 2 * c + 1
                k += 1
    for r in range(k):
        i = index[r]
        for col in range(k):
            j = index[col]
            value = w[i, j]
            if j % 2 == 0:  # p_d's column: a sliding contact's friction +-mu p_d folds in
                d = j // 2
                if state[d] == SLIDE_PLUS:
                    value += friction_slope(contacts[d, FRICTION]) * w[i, j + 1]
                elif state[d] == SLIDE_MINUS:
                    value -= friction_slope(contacts[d, FRICTION]) * w[i, j + 1]
            a[r, col] = value
        a[r, r] += REGULARISATION * w[i, i]
        a[r, k] = -u0[i]
    if not eliminate(a, k, x):
        return False
    for i in range(2 * count):
        impulse[i] = 0.0
    for r in range(k):
        impulse[index[r]] = x[r]
    for c in range(count):
        if state[c] == SLIDE_PLUS:
            impulse[2 * c + 1] = friction_bound(contacts[c, FRICTION], impulse[2 * c])
        elif state[c] == SLIDE_MINUS:
            impulse[2 * c + 1] = -friction_bound(contacts[c, FRICTION], impulse[2 * c])
    return True


@jit_stage
def change_state(contacts, count, w, u0, state, impulse, tolerance):
    """Change the state of the first contact whose condition the impulses violate (in the order: a pulling
    normal, a friction beyond the cone, a slip that turned, a penetrating free contact); returns False if
    every condition holds."""
    worst, at = 0.0, -1
    for c in range(count):  # the most pulling normal frees its contact
        if state[c] != FREE and impulse[2 * c] < worst:
            worst, at = impulse[2 * c], c
    if at >= 0:
        state[at] = FREE
        return True
    for c in range(count):  # a sticking friction beyond mu p slides the way it pushed
        if state[c] == STICK:
            q, limit = impulse[2 * c + 1], friction_bound(contacts[c, FRICTION], impulse[2 * c])
            if abs(q) > limit * (1.0 + FRICTION_CONE_ROUNDING):
                state[c] = SLIDE_PLUS if q > 0.0 else SLIDE_MINUS
                return True
    for c in range(count):
        if state[c] == FREE or state[c] == SLIDE_PLUS or state[c] == SLIDE_MINUS:
            normal = u0[2 * c]
            slip = u0[2 * c + 1]
            for j in range(2 * count):
                normal += w[2 * c, j] * impulse[j]
                slip += w[2 * c + 1, j] * impulse[j]
            if state[c] == FREE and normal < -tolerance:  # a free contact that would penetrate: it sticks, or
                if contacts[c, FRICTION] <= 0.0:  # if it slips, slides against the slip
                    state[c] = FRICTIONLESS
                elif abs(slip) <= tolerance:
                    state[c] = STICK
                else:
                    state[c] = SLIDE_MINUS if slip > 0.0 else SLIDE_PLUS
                return True
            # sliding with q = +mu p needs u_t <= 0, with q = -mu p u_t >= 0
            if (state[c] == SLIDE_PLUS and slip > tolerance) or (state[c] == SLIDE_MINUS and slip < -tolerance):
                state[c] = STICK
                return True
    return False


@jit_stage
def joint_impulses(contacts, count, w, u, state, a, index, x, impulse):
    """The normal and friction impulses (p_c, q_c into ``impulse``) of at most JOINT_LIMIT contacts that meet
    the conditions of the module's docstring, from W (``full_delassus``, in w) and the contacts' speeds u
    (u_n less its target and u_t, rows as W's) with the impulses they hold (IMPULSE, FRICTION_IMPULSE; u is
    made the speeds without them), the first states guessed from those impulses. Returns False if the
    states do not settle within JOINT_ROUNDS solves or a system is singular. A round's states are a function
    of the states before it (W and u stay), so states that come round again cycle for good: the solve gives
    up at once (a box rocking on another, whose two contacts' frictions are nearly redundant, cycled through
    six states to the last round). ``index`` holds the unknowns' rows, then from HISTORY on each round's
    states (``states_code``)."""
    scale = 0.0
    for i in range(2 * count):
        for c in range(count):
            u[i] -= w[i, 2 * c] * contacts[c, IMPULSE] + w[i, 2 * c + 1] * contacts[c, FRICTION_IMPULSE]
        scale = max(scale, abs(u[i]))
    tolerance = LCP_TOLERANCE * scale
    for c in range(count):
        p, q, mu = contacts[c, IMPULSE], contacts[c, FRICTION_IMPULSE], contacts[c, FRICTION]
        if p <= 0.0 and u[2 * c] >= 0.0:
            state[c] = FREE
        elif mu <= 0.0:
            state[c] = FRICTIONLESS
        elif p > 0.0 and abs(q) >= friction_bound(mu, p):
            state[c] = SLIDE_PLUS if q > 0.0 else SLIDE_MINUS
        else:
            state[c] = STICK
    for r in range(JOINT_ROUNDS):
        code = states_code(state, count)
        for earlier in range(r):  # the states came round again: they cycle, and would to the last round
            if index[HISTORY + earlier] == code:
                return False
        index[HISTORY + r] = code
        if not solve_states(contacts, count, w, u, state, a, index, x, impulse):
            return False
        if not change_state(contacts, count, w, u, state, impulse, tolerance):
            return True
    return False


@jit_stage(inline="always")
def states_code(state, count):
    """The contacts' states as one number (digits in base 5, one a contact)."""
    code = 0
    for c in range(count):
        code = 5 * code + state[c]
    return code
