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
from ..tunables import PENALTY_TRIGGER
from .contact_solver import DEPTH, RY, correct_penetration, place_corner
from .energy_limit import kinetic_energy
from .state import Motion


@jit_stage
def penalty_step(motion, first, box, slop, piece, gravity, work):
    """Stage 6: the implicit penalty correction of what penetrates beyond the slop, at the lowest corner ``first``
    and its neighbours; the potential energy it returns is taken from the kinetic energy. Returns (y, angle, vx, vy,
    spin)."""
    y, vx, vy, spin = motion.y, motion.vx, motion.vy, motion.spin
    corners = work.corners
    below = 0
    for corner in (first, (first + 1) % 4, (first + 3) % 4):
        place_corner(corners, below, corner, motion.cos_a, motion.sin_a, box.hx, box.hy)
        corners[DEPTH, below] = -(y + corners[RY, below]) - slop
        if corners[DEPTH, below] > 0.0:
            below += 1
    lifted = y
    y, angle = correct_penetration(
        y, motion.angle, corners, below, box.stiffness, piece, box.inv_mass, box.inv_inertia, work.k
    )
    kinetic = kinetic_energy(vx, vy, spin, box.inv_mass, box.inv_inertia)
    rise = -gravity * (y - lifted) / box.inv_mass
    if rise > 0.0 and kinetic > 0.0:
        scale = math.sqrt(max(1.0 - rise / kinetic, 0.0))
        vx, vy, spin = scale * vx, scale * vy, scale * spin
    return y, angle, vx, vy, spin


@jit_stage(inline="always")
def relax(motion, box, settings, h, work):
    """Stage 6 after a piece h: the penetration of the lowest corner, and (with ``settings.use_penalty``) where it is
    deeper than PENALTY_TRIGGER slops, ``penalty_step`` at that corner and its neighbours. Returns (motion,
    penetration before the correction)."""
    first, _ = lowest_face(motion.cos_a, motion.sin_a, box.hx, box.hy)
    _, ry1 = vertex_offset(first, motion.cos_a, motion.sin_a, box.hx, box.hy)
    penetration = -(motion.y + ry1)
    if settings.use_penalty and penetration > PENALTY_TRIGGER * settings.slop + box.tolerance:
        y, angle, vx, vy, spin = penalty_step(motion, first, box, settings.slop, h, settings.gravity, work)
        motion = Motion(motion.x, y, angle, vx, vy, spin, math.cos(angle), math.sin(angle))
    return motion, penetration
