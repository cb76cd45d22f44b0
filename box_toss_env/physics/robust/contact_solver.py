"""The solve contacts stage of the floor-only solver's contact step (and the solves its restitution and relax
stages reuse): impulses on the corners that can touch the floor (at most three: the lowest corner and its two
neighbours), solved together, with clamped Coulomb friction (``solve_contact_velocities``), and the implicit
penalty correction of the relax stage (``correct_penetration``).

Notation for one box with inverse mass 1/m, inverse inertia 1/I, and a corner at lever arm
r = (rx, ry) from the centre of mass; the floor normal is n = (0, 1), the tangent (1, 0):
  normal velocity      u_n = vy + omega rx        tangential velocity  u_t = vx - omega ry
  a normal impulse p n at corner j changes u_n at corner i by K_ij p with
      K_ij = 1/m + rx_i rx_j / I                      (the Delassus matrix, n x n, rank <= 2)
  a tangential impulse q at corner i changes u_t there by (1/m + ry_i^2 / I) q.

Why three corners: the two lowest corners bound the face that is down, except for a thin box tilted
by more than atan(W / L) (0.005 rad at 1:200), whose two lowest corners are the ends of a short side
while the far end of the long side is only L sin(angle) higher. Constraining the lowest corner and
both its neighbours holds every corner that can reach the floor in a step (the fourth, diagonal one
is the highest); a corner that cannot reach it gets no impulse.

Corners travel in a small work array ``corners[row, i]`` (rows below), the first ``n`` columns used.
"""

import math

from ..compile.compilation import jit_stage
from ..contact_law import clamp_friction, friction_bound, friction_slope
from ..geometry import vertex_offset
from ..tunables import CORNER_CONVERGED, CORNER_SWEEPS, LCP_TOLERANCE, PAIR_CONDITION, PENALTY_DAMPING_RATIO

# rows of the corner work array: lever arm, target normal velocity b_i, accumulated normal and friction
# impulses, normal velocity before the step, depth below the floor, compression impulse (Poisson), and
# the LCP's scratch rows (w at zero impulse, new impulses, impulse changes)
(RX, RY, TARGET, IMPULSE, FRICTION_IMPULSE, APPROACH, DEPTH, COMPRESSION, FREE_W, NEW_IMPULSE, SCRATCH) = range(11)
CORNER_ROWS = 11
MAX_CORNERS = 3


@jit_stage
def place_corner(corners, i, k, cos_a, sin_a, half_length, half_width):
    """Corner k of the box as column i of the corner work array (its lever arm)."""
    corners[RX, i], corners[RY, i] = vertex_offset(k, cos_a, sin_a, half_length, half_width)


@jit_stage
def delassus(corners, n, inv_mass, inv_inertia, k):
    """The normal Delassus matrix K_ij = 1/m + rx_i rx_j / I of the first n corners, into k."""
    for i in range(n):
        for j in range(n):
            k[i, j] = inv_mass + corners[RX, i] * corners[RX, j] * inv_inertia


@jit_stage
def free_corners_hold(corners, n, k, p, q, tolerance):
    """Whether every corner r other than p and q keeps w_r = a_r + K_rp x_p + K_rq x_q >= -tolerance
    (a in row FREE_W, x in row NEW_IMPULSE; p = q = -1 for none)."""
    a = corners[FREE_W]
    x = corners[NEW_IMPULSE]
    for r in range(n):
        if r == p or r == q:
            continue
        w = a[r]
        if p >= 0:
            w += k[r, p] * x[p]
        if q >= 0 and q != p:
            w += k[r, q] * x[q]
        if w < -tolerance:
            return False
    return True


@jit_stage
def normal_impulses(u_row, corners, n, k):
    """New accumulated normal impulses x_i >= 0 of the first n corners, solving the contact LCP

        w_i = u_i - b_i + sum_j K_ij (x_j - lam_j) >= 0,  x_i >= 0,  w_i x_i = 0,

    with u_i the normal velocities in ``corners[u_row]``, b_i the targets (row TARGET) and lam_i the
    accumulated impulses (row IMPULSE): after the impulses every corner's normal velocity reaches its
    target or its impulse is zero. K is positive semi-definite of rank <= 2, so the velocities are
    unique and some solution has at most two active corners: it is found by trying the active sets
    (pairs, single corners, none), as Box2D's block solver does for two; a pair whose rows are
    parallel is skipped (one of its corners does). The new impulses are left in row NEW_IMPULSE, w at
    zero impulse in row FREE_W.
    """
    a = corners[FREE_W]
    x = corners[NEW_IMPULSE]
    scale = 0.0
    for i in range(n):
        total = 0.0
        for j in range(n):
            total += k[i, j] * corners[IMPULSE, j]
        a[i] = corners[u_row, i] - corners[TARGET, i] - total
        x[i] = 0.0
        scale = max(scale, abs(a[i]))
    tolerance = LCP_TOLERANCE * scale
    for p in range(n):
        for q in range(p + 1, n):
            det = k[p, p] * k[q, q] - k[p, q] * k[p, q]
            if det > PAIR_CONDITION * k[p, p] * k[q, q]:
                x[p] = (k[p, q] * a[q] - k[q, q] * a[p]) / det
                x[q] = (k[p, q] * a[p] - k[p, p] * a[q]) / det
                if x[p] >= 0.0 and x[q] >= 0.0 and free_corners_hold(corners, n, k, p, q, tolerance):
                    return
                x[p] = x[q] = 0.0
    for p in range(n):
        x[p] = -a[p] / k[p, p]
        if x[p] >= 0.0 and free_corners_hold(corners, n, k, p, p, tolerance):
            return
        x[p] = 0.0
    if free_corners_hold(corners, n, k, -1, -1, tolerance):
        return
    # rows parallel to rounding (a face almost vertical, or the two corners of a thin box's short side)
    for _ in range(CORNER_SWEEPS):
        for p in range(n):
            w = a[p]
            for j in range(n):
                w += k[p, j] * x[j]
            x[p] = max(x[p] - w / k[p, p], 0.0)


@jit_stage
def apply_normal_impulses(vy, spin, corners, n, row, inv_mass, inv_inertia):
    """v += sum_i p_i n / m, omega += sum_i rx_i p_i / I for the normal impulses p_i in ``corners[row]``."""
    force = 0.0
    torque = 0.0
    for i in range(n):
        force += corners[row, i]
        torque += corners[RX, i] * corners[row, i]
    return vy + force * inv_mass, spin + torque * inv_inertia


@jit_stage
def normal_velocities(vy, spin, corners, n, row):
    """u_n,i = vy + omega rx_i of the first n corners, into ``corners[row]``."""
    for i in range(n):
        corners[row, i] = vy + spin * corners[RX, i]


@jit_stage
def friction_impulse(vx, spin, ry, normal_impulse, accumulated, friction, inv_mass, inv_inertia):
    """Coulomb friction at one corner: the tangential impulse that would stop sliding there,
    -u_t / (1/m + ry^2 / I), added to the accumulated one and clamped to |q| <= mu lam_n.

    Clamping the accumulated impulse can bring u_t to zero but never past it, so friction never
    reverses sliding. Returns (vx, spin, accumulated).
    """
    slip = vx - spin * ry
    total = accumulated - slip / (inv_mass + ry * ry * inv_inertia)
    total = clamp_friction(total, friction_bound(friction, normal_impulse))
    change = total - accumulated
    return vx + change * inv_mass, spin - ry * change * inv_inertia, total


@jit_stage
def solve_normal_block(vy, spin, corners, n, inv_mass, inv_inertia, k):
    """Solve the normal LCP from the accumulated impulses (row IMPULSE, targets in row TARGET) and apply
    the change: the new totals are left in row IMPULSE, the changes in row SCRATCH. Returns (vy, spin)."""
    normal_velocities(vy, spin, corners, n, SCRATCH)
    normal_impulses(SCRATCH, corners, n, k)
    for i in range(n):
        corners[SCRATCH, i] = corners[NEW_IMPULSE, i] - corners[IMPULSE, i]
        corners[IMPULSE, i] = corners[NEW_IMPULSE, i]
    return apply_normal_impulses(vy, spin, corners, n, SCRATCH, inv_mass, inv_inertia)


@jit_stage
def solve_one_corner(vx, vy, spin, corners, friction, inv_mass, inv_inertia):
    """The exact contact impulse (lam normal, q tangential) at one corner with Coulomb friction: with
    u_n = vy + omega rx, u_t = vx - omega ry and the impulse changing them by

        du_n = K_nn lam + K_nt q,  du_t = K_nt lam + K_tt q,
        K_nn = 1/m + rx^2 / I,  K_tt = 1/m + ry^2 / I,  K_nt = -rx ry / I,

    the first of these that holds: no impulse (u_n >= b already); sticking (u_n' = b, u_t' = 0, |q| <= mu lam);
    sliding on (q = -s mu lam, s the sign of the slip, u_n' = b, and the slip keeps its sign: friction never
    reverses it). Returns (vx, vy, spin, solved); ``solved`` is False only where none holds (K_nn - s mu K_nt
    <= 0: friction so high that pushing the corner out would press it in), left to Gauss-Seidel."""
    rx = corners[RX, 0]
    ry = corners[RY, 0]
    u_n = vy + spin * rx
    u_t = vx - spin * ry
    b = corners[TARGET, 0]
    corners[IMPULSE, 0] = 0.0
    if u_n >= b:
        return vx, vy, spin, True
    k_nn = inv_mass + rx * rx * inv_inertia
    k_tt = inv_mass + ry * ry * inv_inertia
    k_nt = -rx * ry * inv_inertia
    lam = -1.0
    q = 0.0
    det = k_nn * k_tt - k_nt * k_nt
    if det > 0.0:  # sticking
        lam = ((b - u_n) * k_tt + u_t * k_nt) / det
        q = (-u_t * k_nn - (b - u_n) * k_nt) / det
        if not (lam >= 0.0 and abs(q) <= friction_bound(friction, lam)):
            lam = -1.0
    if lam < 0.0:
        sign = 1.0 if u_t > 0.0 else -1.0
        for _ in range(2):  # sliding on, then (a slip that reverses under the normal impulse) the other way
            denominator = k_nn - sign * friction_slope(friction) * k_nt
            if denominator > 0.0:
                lam = (b - u_n) / denominator
                q = -sign * friction_bound(friction, lam)
                if lam >= 0.0 and sign * (u_t + k_nt * lam + k_tt * q) >= 0.0:
                    break
            lam = -1.0
            sign = -sign
    if lam < 0.0:
        return vx, vy, spin, False
    corners[IMPULSE, 0] = lam
    return vx + q * inv_mass, vy + lam * inv_mass, spin + (rx * lam - ry * q) * inv_inertia, True


@jit_stage
def solve_contact_velocities(vx, vy, spin, corners, n, friction, inv_mass, inv_inertia, iterations, k):
    """Velocities after the normal impulses (targets u_n,i >= b_i, row TARGET) and, with ``friction`` > 0,
    the friction impulses of the first n corners: the exact normal block, then projected Gauss-Seidel
    sweeps over friction and the normal block, until the impulses change by less than CORNER_CONVERGED of the
    normal impulse (at most ``iterations`` sweeps); a single corner is solved exactly (``solve_one_corner``).
    The normal impulses are left in row IMPULSE.
    Returns (vx, vy, spin)."""
    if n == 1 and friction > 0.0:
        vx1, vy1, spin1, solved = solve_one_corner(vx, vy, spin, corners, friction, inv_mass, inv_inertia)
        if solved:
            return vx1, vy1, spin1
    delassus(corners, n, inv_mass, inv_inertia, k)
    for i in range(n):
        corners[IMPULSE, i] = 0.0
        corners[FRICTION_IMPULSE, i] = 0.0
    vy, spin = solve_normal_block(vy, spin, corners, n, inv_mass, inv_inertia, k)
    if friction <= 0.0:
        return vx, vy, spin
    for _ in range(iterations):
        change = 0.0
        total = 0.0
        for i in range(n):
            before = corners[FRICTION_IMPULSE, i]
            vx, spin, corners[FRICTION_IMPULSE, i] = friction_impulse(
                vx, spin, corners[RY, i], corners[IMPULSE, i], before, friction, inv_mass, inv_inertia
            )
            change += abs(corners[FRICTION_IMPULSE, i] - before)
        vy, spin = solve_normal_block(vy, spin, corners, n, inv_mass, inv_inertia, k)
        for i in range(n):
            change += abs(corners[SCRATCH, i])
            total += corners[IMPULSE, i]
        if change <= CORNER_CONVERGED * total:
            break
    return vx, vy, spin


@jit_stage
def penalty_correction_share(stiffness, k_ii, h):
    """Share of a penetration depth d removed in one step of length h by the penalty spring k d,
    critically damped, integrated with backward Euler (the error reduction parameter of a soft
    constraint with spring k and damper c):

        ERP = h k / (h k + c),  c = 2 zeta sqrt(k m_eff),  m_eff = 1 / K_ii,  omega = sqrt(k K_ii)
            = h omega / (h omega + 2 zeta),  zeta = 1.

    It lies in [0, 1) for every k >= 0 and h > 0, so the correction is unconditionally stable and
    never overshoots (the seed scheme's explicit spring needs h omega < 2), and for small h it
    removes the depth at the rate omega / 2 per second whatever the step, as the spring would."""
    omega_h = h * math.sqrt(stiffness * k_ii)
    if omega_h == math.inf:  # k K_ii beyond float64 (any finite stiffness is allowed): the limit, all of it
        return 1.0
    return omega_h / (omega_h + 2.0 * PENALTY_DAMPING_RATIO)


@jit_stage
def correct_penetration(y, angle, corners, n, stiffness, h, inv_mass, inv_inertia, k):
    """Push the first n corners (each below the floor by ``corners[DEPTH, i]`` > 0) out by the penalty's
    share of their depths, as a pseudo-velocity (split impulse): positions move, the real velocities do
    not, so resolving a penetration adds no kinetic energy and cannot launch the box. Returns (y, angle)."""
    if n == 0:
        return y, angle
    delassus(corners, n, inv_mass, inv_inertia, k)
    for i in range(n):
        corners[TARGET, i] = penalty_correction_share(stiffness, k[i, i], h) * corners[DEPTH, i] / h
        corners[IMPULSE, i] = 0.0
    pseudo_vy, pseudo_spin = solve_normal_block(0.0, 0.0, corners, n, inv_mass, inv_inertia, k)
    return y + h * pseudo_vy, angle + h * pseudo_spin
