"""Stage 4 of the robust solver's contact step: no energy gained (``energy_limit_scale``).

Symplectic Euler adds g h to v, the contacts take it back where the floor holds the box, and positions move
with what is left: where the contacts push the centre up (a rocking or bouncing box) it rises h v_y without
gravity having slowed it in that step, so a step can end with more kinetic + potential energy than it began
with. The velocities of such a step are scaled down to exactly what gains nothing; the derivation is
``energy_limit_scale``'s. The colliding solver limits its substeps with the same scale.
"""

import math

from ..compile.compilation import jit_stage


@jit_stage
def kinetic_energy(vx, vy, spin, inv_mass, inv_inertia):
    """m |v|^2 / 2 + I omega^2 / 2 [J]."""
    return 0.5 * (vx * vx + vy * vy) / inv_mass + 0.5 * spin * spin / inv_inertia


@jit_stage
def energy_limit_scale(kinetic_before, kinetic_after, potential_rise):
    """The factor s in [0, 1] on the velocities of a contact step that keeps the step from gaining energy.

    Symplectic Euler adds g h to v, the contacts take it back where the floor holds the box, and
    positions move with what is left: where the contacts push the centre up (a rocking or bouncing box)
    it rises h v_y without gravity having slowed it in that step, and kinetic + potential energy can
    grow by up to m |g| h dv_y (18% of the energy of the moment for a thin bouncing box at h = 1/32 s).
    With the velocities scaled by s, the step changes the energy by s^2 A + s B - C, where A is the
    kinetic energy after the contact stages, B = -m g h v_y the potential energy the position update
    adds and C the kinetic energy before the step; s is 1 where that is <= 0, else its root
    s = 2 C / (B + sqrt(B^2 + 4 A C)), the largest s that gains nothing. Scaling the whole velocity keeps
    every contact satisfied (u_n,i >= b_i with b_i <= 0 holds for s u_n,i) and never reverses sliding.
    The correction is O(h) and vanishes where no step would gain (flight, sliding, resting).
    """
    a, b, c = kinetic_after, potential_rise, kinetic_before
    if a + b <= c:
        return 1.0
    root = math.sqrt(b * b + 4.0 * a * c)
    s = 2.0 * c / (b + root) if b > 0.0 else (root - b) / (2.0 * a)
    return min(max(s, 0.0), 1.0)


@jit_stage(inline="always")
def limit_energy(vx, vy, spin, kinetic_before, h, gravity, inv_mass, inv_inertia):
    """Stage 4: the velocities after the contact stages of a piece h, scaled by ``energy_limit_scale`` so that the
    piece (with its position update, B = -m g h v_y) gains no energy over ``kinetic_before``. Returns (vx, vy,
    spin)."""
    scale = energy_limit_scale(
        kinetic_before, kinetic_energy(vx, vy, spin, inv_mass, inv_inertia), -gravity * h * vy / inv_mass
    )
    return scale * vx, scale * vy, scale * spin
