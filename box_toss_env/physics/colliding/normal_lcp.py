"""The exact solve of the normal impulses (stage solve, up to DIRECT_LIMIT contacts): the LCP
w p + free >= 0, p >= 0, complementary, on the dense Delassus matrix W_cd = J_c M^-1 J_d^T of the normals
(``delassus_matrix``), by an active set (``normal_lcp``, ``solve_active``): a stack's load passes through
every box at once, whatever the mass ratio.
"""

import math

from ..compile.compilation import jit_stage
from ..tunables import LCP_TOLERANCE, REGULARISATION
from .joint_contact_solve import delassus_entry
from .narrowphase import NX, NY


@jit_stage
def delassus_matrix(contacts, ids, count, inv_mass, inv_inertia, w):
    """The normal Delassus matrix W_cd = J_c M^-1 J_d^T of the first ``count`` contacts into w: how a unit
    normal impulse at contact d changes u_rel . n at contact c (nonzero where they share a body)."""
    for c in range(count):
        for d in range(c, count):
            value = delassus_entry(
                contacts,
                ids,
                c,
                contacts[c, NX],
                contacts[c, NY],
                d,
                contacts[d, NX],
                contacts[d, NY],
                inv_mass,
                inv_inertia,
            )
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
