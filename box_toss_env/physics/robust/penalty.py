"""Stage 6 of the robust solver's contact step, relax: the penalty removes what penetrates beyond the slop.

The penetration beyond the slop is removed by the critically damped penalty spring integrated with backward
Euler, as a pseudo-velocity (split impulse: positions move, the real velocities do not), stable for every
stiffness and step (``contact_solver.penalty_correction_share``: ERP = h omega / (h omega + 2 zeta),
omega = sqrt(k K_ii), zeta = 1, so 0 <= ERP < 1). Lifting the centre by dy returns potential energy
-m g dy; that much is taken from the kinetic energy (the velocities scaled by sqrt(1 - rise / KE)), so the
correction never gains energy either.
"""

import math

from ..compile.compilation import jit_stage
from ..geometry import lowest_face, vertex_offset
from .contact_solver import DEPTH, RY, correct_penetration, place_corner
from .energy_limit import kinetic_energy

PENALTY_TRIGGER = 2.0  # [slops] the penalty starts once a corner is this deep, then removes what lies beyond one slop
# (a band, as Box2D 2.x's position solver stops within 3 slops: a pile whose looser solve lets corners creep to
# the slop would otherwise run the penalty at every step)


@jit_stage
def penalty_step(y, angle, vx, vy, spin, first, cos_a, sin_a, hx, hy, slop, stiffness, piece, gravity, inv_mass,
                 inv_inertia, corners, k):
    """Stage 6: the implicit penalty correction of what penetrates beyond the slop, at the lowest corner and its
    neighbours; the potential energy it returns is taken from the kinetic energy. Returns (y, angle, vx, vy,
    spin)."""
    below = 0
    for corner in (first, (first + 1) % 4, (first + 3) % 4):
        place_corner(corners, below, corner, cos_a, sin_a, hx, hy)
        corners[DEPTH, below] = -(y + corners[RY, below]) - slop
        if corners[DEPTH, below] > 0.0:
            below += 1
    lifted = y
    y, angle = correct_penetration(y, angle, corners, below, stiffness, piece, inv_mass, inv_inertia, k)
    kinetic = kinetic_energy(vx, vy, spin, inv_mass, inv_inertia)
    rise = -gravity * (y - lifted) / inv_mass
    if rise > 0.0 and kinetic > 0.0:
        scale = math.sqrt(max(1.0 - rise / kinetic, 0.0))
        vx, vy, spin = scale * vx, scale * vy, scale * spin
    return y, angle, vx, vy, spin


@jit_stage(inline="always")
def relax(y, angle, vx, vy, spin, cos_a, sin_a, hx, hy, slop, stiffness, h, gravity, inv_mass, inv_inertia, tolerance,
          use_penalty, corners, k):
    """Stage 6 after a piece h: the penetration of the lowest corner, and (with ``use_penalty``) where it is
    deeper than PENALTY_TRIGGER slops, ``penalty_step`` at that corner and its neighbours. Returns (y, angle, vx,
    vy, spin, cos, sin, penetration before the correction)."""
    first, _ = lowest_face(cos_a, sin_a, hx, hy)
    _, ry1 = vertex_offset(first, cos_a, sin_a, hx, hy)
    penetration = -(y + ry1)
    if use_penalty and penetration > PENALTY_TRIGGER * slop + tolerance:
        y, angle, vx, vy, spin = penalty_step(y, angle, vx, vy, spin, first, cos_a, sin_a, hx, hy, slop,
                                              stiffness, h, gravity, inv_mass, inv_inertia, corners, k)
        cos_a = math.cos(angle)
        sin_a = math.sin(angle)
    return y, angle, vx, vy, spin, cos_a, sin_a, penetration
