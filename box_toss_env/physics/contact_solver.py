"""Contact stages of the robust solver: impulses on the (at most two) corners of the face that
is down, solved together, with clamped Coulomb friction and implicit penalty correction.

Notation for one box with inverse mass 1/m, inverse inertia 1/I, and a corner at lever arm
r = (rx, ry) from the centre of mass; the floor normal is n = (0, 1), the tangent (1, 0):
  normal velocity      u_n = vy + omega rx        tangential velocity  u_t = vx - omega ry
  a normal impulse p n at corner j changes u_n at corner i by K_ij p with
      K_ij = 1/m + rx_i rx_j / I                      (the Delassus matrix, 2 x 2)
  a tangential impulse q at corner i changes u_t there by (1/m + ry_i^2 / I) q.
"""


import math

from .compilation import jit_stage

PAIR_CONDITION = 1e-9  # det(K) below this fraction of K11 K22: the two rows are parallel
CONVERGED = 1e-12  # Gauss-Seidel stops when the impulses change by less than this share
PENALTY_DAMPING_RATIO = 1.0  # zeta of the penalty spring: critically damped


@jit_stage
def delassus(rx1, rx2, inv_mass, inv_inertia):
    """Entries K11, K12, K22 of the normal Delassus matrix of two corners."""
    return (inv_mass + rx1 * rx1 * inv_inertia, inv_mass + rx1 * rx2 * inv_inertia,
            inv_mass + rx2 * rx2 * inv_inertia)


@jit_stage
def normal_impulses(u1, u2, b1, b2, lam1, lam2, k11, k12, k22, use1, use2):
    """Accumulated normal impulses (lam1, lam2) >= 0 solving the contact LCP of the used corners:

        w_i = u_i - b_i + sum_j K_ij (lam_j' - lam_j) >= 0,  lam_i' >= 0,  w_i lam_i' = 0,

    i.e. after the impulses every used corner's normal velocity reaches its target b_i or its
    impulse is zero. A 2 x 2 LCP with K positive definite has one solution; it is found by trying
    the four active sets (both, first, second, none), as Box2D's block solver does. An unused
    corner keeps its impulse.
    """
    if use1 and use2:
        a1 = u1 - b1 - (k11 * lam1 + k12 * lam2)  # w at zero impulse
        a2 = u2 - b2 - (k12 * lam1 + k22 * lam2)
        det = k11 * k22 - k12 * k12
        if det > PAIR_CONDITION * k11 * k22:
            x1 = (k12 * a2 - k22 * a1) / det
            x2 = (k12 * a1 - k11 * a2) / det
            if x1 >= 0.0 and x2 >= 0.0:
                return x1, x2
        x1 = -a1 / k11
        if x1 >= 0.0 and a2 + k12 * x1 >= 0.0:
            return x1, 0.0
        x2 = -a2 / k22
        if x2 >= 0.0 and a1 + k12 * x2 >= 0.0:
            return 0.0, x2
        if a1 >= 0.0 and a2 >= 0.0:
            return 0.0, 0.0
        # nearly parallel rows (a face almost vertical): one Gauss-Seidel sweep
        x1 = max(-a1 / k11, 0.0)
        return x1, max(-(a2 + k12 * x1) / k22, 0.0)
    if use1:
        lam1 = max(lam1 - (u1 - b1) / k11, 0.0)
    if use2:
        lam2 = max(lam2 - (u2 - b2) / k22, 0.0)
    return lam1, lam2


@jit_stage
def apply_normal_impulses(vy, spin, d1, d2, rx1, rx2, inv_mass, inv_inertia):
    """v += (p1 + p2) n / m, omega += (rx1 p1 + rx2 p2) / I."""
    return vy + (d1 + d2) * inv_mass, spin + (rx1 * d1 + rx2 * d2) * inv_inertia


@jit_stage
def friction_impulse(vx, spin, ry, normal_impulse, accumulated, friction, inv_mass, inv_inertia):
    """Coulomb friction at one corner: the tangential impulse that would stop sliding there,
    -u_t / (1/m + ry^2 / I), added to the accumulated one and clamped to |q| <= mu lam_n.

    Clamping the accumulated impulse can bring u_t to zero but never past it, so friction never
    reverses sliding. Returns (vx, spin, accumulated).
    """
    slip = vx - spin * ry
    total = accumulated - slip / (inv_mass + ry * ry * inv_inertia)
    limit = friction * normal_impulse
    total = min(max(total, -limit), limit)
    change = total - accumulated
    return vx + change * inv_mass, spin - ry * change * inv_inertia, total


@jit_stage
def solve_normal_velocities(vy, spin, rx1, rx2, use2, b1, b2, inv_mass, inv_inertia):
    """Velocities after the normal impulses that bring u_n,i to at least b_i at the lowest corner
    and, if ``use2``, its neighbour, solved together (exact). Returns (vy, spin, lam1, lam2)."""
    k11, k12, k22 = delassus(rx1, rx2, inv_mass, inv_inertia)
    lam1, lam2 = normal_impulses(vy + spin * rx1, vy + spin * rx2, b1, b2, 0.0, 0.0, k11, k12, k22, True, use2)
    vy, spin = apply_normal_impulses(vy, spin, lam1, lam2, rx1, rx2, inv_mass, inv_inertia)
    return vy, spin, lam1, lam2


@jit_stage
def solve_contact_velocities(vx, vy, spin, rx1, ry1, rx2, ry2, use2, b1, b2, friction, inv_mass,
                             inv_inertia, iterations):
    """Velocities after the normal impulses (targets u_n,i >= b_i) and the friction impulses of the
    lowest corner and, if ``use2``, its neighbour: the exact 2 x 2 normal block, then projected
    Gauss-Seidel sweeps over friction and the normal block, until the impulses change by less than
    CONVERGED of the normal impulse (at most ``iterations`` sweeps).
    Returns (vx, vy, spin, lam1, lam2)."""
    k11, k12, k22 = delassus(rx1, rx2, inv_mass, inv_inertia)
    lam1, lam2 = normal_impulses(vy + spin * rx1, vy + spin * rx2, b1, b2, 0.0, 0.0, k11, k12, k22, True, use2)
    vy, spin = apply_normal_impulses(vy, spin, lam1, lam2, rx1, rx2, inv_mass, inv_inertia)
    fric1 = 0.0
    fric2 = 0.0
    for _ in range(iterations):
        before1, before2, before_fric1, before_fric2 = lam1, lam2, fric1, fric2
        vx, spin, fric1 = friction_impulse(vx, spin, ry1, lam1, fric1, friction, inv_mass, inv_inertia)
        if use2:
            vx, spin, fric2 = friction_impulse(vx, spin, ry2, lam2, fric2, friction, inv_mass, inv_inertia)
        new1, new2 = normal_impulses(vy + spin * rx1, vy + spin * rx2, b1, b2, lam1, lam2,
                                     k11, k12, k22, True, use2)
        vy, spin = apply_normal_impulses(vy, spin, new1 - lam1, new2 - lam2, rx1, rx2, inv_mass,
                                         inv_inertia)
        lam1 = new1
        lam2 = new2
        change = (abs(lam1 - before1) + abs(lam2 - before2) + abs(fric1 - before_fric1)
                  + abs(fric2 - before_fric2))
        if change <= CONVERGED * (lam1 + lam2):
            break
    return vx, vy, spin, lam1, lam2


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
def correct_penetration(y, angle, depth1, depth2, rx1, rx2, stiffness, h, inv_mass, inv_inertia):
    """Push the corners out of the floor by the penalty's share of their depths, as a
    pseudo-velocity (split impulse): positions move, the real velocities do not, so resolving a
    penetration adds no kinetic energy and cannot launch the box. Returns (y, angle)."""
    use1 = depth1 > 0.0
    use2 = depth2 > 0.0
    if not use1 and not use2:
        return y, angle
    k11, k12, k22 = delassus(rx1, rx2, inv_mass, inv_inertia)
    target1 = penalty_correction_share(stiffness, k11, h) * depth1 / h if use1 else 0.0
    target2 = penalty_correction_share(stiffness, k22, h) * depth2 / h if use2 else 0.0
    p1, p2 = normal_impulses(0.0, 0.0, target1, target2, 0.0, 0.0, k11, k12, k22, use1, use2)
    pseudo_vy, pseudo_spin = apply_normal_impulses(0.0, 0.0, p1, p2, rx1, rx2, inv_mass, inv_inertia)
    return y + h * pseudo_vy, angle + h * pseudo_spin
