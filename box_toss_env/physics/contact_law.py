"""The contact law, once for every solver: how two materials mix, how far friction may go, which way it acts, and
what an impact aims at. The solvers' tiers (the floor corners' exact solve and sweeps, the colliding solver's joint
LCP, its alternation, its Gauss-Seidel sweeps, its warm start's guess, restitution) and the seed scheme all read
the law from here, so changing it is a change to this module (``tests/physics/test_contact_law.py`` swaps in a
frictionless one and sees every solver follow).

Coulomb friction with coefficient mu: a contact's friction impulse q (along the tangent t = (-n_y, n_x), n the
normal pushing body 1 out of body 2) is bounded by |q| <= mu p, p its normal impulse (``friction_bound``,
``clamp_friction``), and a sliding contact takes q = -s mu p, s the sign of its slip (``friction_slope``, which the
exact solves write into their systems). A box-box contact takes the mixed material of Box2D's rules: friction
sqrt(mu_1 mu_2), restitution max(e_1, e_2), penalty stiffness min(k_1, k_2); a box-floor contact the box's own
(``floor_friction``). An impact is a contact approaching faster than the restitution threshold; Newton's law aims
its normal velocity at u_n+ = -e u_n- (``newton_target``, the colliding solver), Poisson's gives it e times its
compression impulse (``poisson_impulse``, the floor-only solver, which never creates energy with friction).
"""

import math

from .compile.compilation import jit_stage


@jit_stage(inline="always")
def mixed_friction(mu_1, mu_2):
    """The Coulomb coefficient of a contact between two boxes: sqrt(mu_1 mu_2)."""
    return math.sqrt(mu_1 * mu_2)


@jit_stage(inline="always")
def floor_friction(mu):
    """The Coulomb coefficient of a contact between a box of coefficient mu and the floor: mu."""
    return mu


@jit_stage(inline="always")
def mixed_restitution(e_1, e_2):
    """The restitution of a contact between two boxes: max(e_1, e_2)."""
    return max(e_1, e_2)


@jit_stage(inline="always")
def mixed_stiffness(k_1, k_2):
    """The penalty stiffness of a contact between two boxes [N/m]: min(k_1, k_2)."""
    return min(k_1, k_2)


@jit_stage(inline="always")
def friction_slope(mu):
    """The friction impulse a sliding contact takes per unit of normal impulse: mu (Coulomb). The exact solves
    write a sliding contact's friction as this times its normal impulse (q = -s slope p, s the sign of the slip)."""
    return mu


@jit_stage(inline="always")
def friction_bound(mu, normal_impulse):
    """The most friction impulse a contact can take: mu p (Coulomb, ``friction_slope`` times p)."""
    return friction_slope(mu) * normal_impulse


@jit_stage(inline="always")
def clamp_friction(friction_impulse, bound):
    """A friction impulse held within [-bound, bound] (accumulated, so clamping stops a slip and never reverses
    it)."""
    return min(max(friction_impulse, -bound), bound)


@jit_stage(inline="always")
def tangent(nx, ny):
    """The tangent t = (-n_y, n_x) along which a contact of normal n takes friction (counter-clockwise of n)."""
    return -ny, nx


@jit_stage(inline="always")
def is_impact(approach, threshold):
    """Whether a contact whose normal velocity is ``approach`` (u_rel . n, < 0 approaching) hits: faster than the
    restitution threshold."""
    return approach < -threshold


@jit_stage(inline="always")
def newton_target(restitution, approach):
    """The normal velocity an impact aims at after it (Newton): u_n+ = -e u_n-."""
    return -restitution * approach


@jit_stage(inline="always")
def poisson_impulse(restitution, compression):
    """The restitution impulse of an impact (Poisson): e times the impulse that stopped its approach."""
    return restitution * compression
