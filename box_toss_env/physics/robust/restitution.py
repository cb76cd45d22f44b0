"""The restitution stage of the floor-only solver (``stages.FLOOR_PIECE``: a whole impact law): the touching
corners of a box take an impact together, in Poisson's two phases.

  compression: the impulses lam_c that stop every approaching corner (u_n+ >= 0), solved together as in the
    solve contacts stage (``contact_solver.solve_contact_velocities``, target b_i = 0), friction clamped to mu
    lam_c;
  restitution: each corner that hit faster than the restitution threshold gets e lam_c more along the
    normal, friction clamped to mu e lam_c, then the corners pushed towards the floor by another's bounce
    are held at their targets.

For one frictionless corner this is Newton's u_n+ = -e u_n-; unlike Newton's law with friction it never
creates energy: compression removes 1/2 lam_c^T K lam_c (K the Delassus matrix, ``contact_solver``),
restitution returns e^2 of it, and clamped friction only removes energy.

A flying box takes its impact at the instant a corner reaches the floor (``resolve_impact``, called from
``flight.fly_to_impact``); a box in contact at the start of each piece of a contact step, where a touching
corner approaches faster than the threshold (``contact_impact``), which is at a located arrival (the locate
impacts stage) rather than on the grid.
"""

from ..compile.compilation import jit_stage
from ..contact_law import poisson_impulse
from ..geometry import lowest_face, vertex_offset
from ..tunables import FRICTION_ITERATIONS
from .contact_solver import (
    APPROACH,
    COMPRESSION,
    IMPULSE,
    MAX_CORNERS,
    RX,
    RY,
    SCRATCH,
    TARGET,
    apply_normal_impulses,
    delassus,
    friction_impulse,
    normal_velocities,
    place_corner,
    solve_contact_velocities,
    solve_normal_block,
)


@jit_stage
def impact_impulses(vx, vy, spin, corners, n, restitution, friction, threshold, inv_mass, inv_inertia, k):
    """Impulses of an impact at this instant on the first n corners (those touching the floor), in
    Poisson's two phases:
      compression: the impulses lam_c that stop every approaching corner (u_n+ >= 0), with friction
        clamped to mu lam_c;
      restitution: each corner that hit faster than the threshold gets e lam_c more along the
        normal, with friction clamped to mu e lam_c.
    For a frictionless single corner this is Newton's law u_n+ = -e u_n-; unlike Newton's law with
    friction, it never creates energy: compression removes 1/2 lam_c^T K lam_c and restitution
    returns e^2 of it, and clamped friction only removes energy. A touching corner that is not
    approaching (one the box rests or pivots on) takes part in the compression: it holds.
    Returns (vx, vy, spin, approach speed of the fastest corner, 0 if none approaches).
    """
    normal_velocities(vy, spin, corners, n, APPROACH)
    approach = 0.0
    for i in range(n):
        approach = max(approach, -corners[APPROACH, i])
        corners[TARGET, i] = 0.0
    if approach <= 0.0:
        return vx, vy, spin, 0.0
    # compression
    vx, vy, spin = solve_contact_velocities(
        vx, vy, spin, corners, n, friction, inv_mass, inv_inertia, FRICTION_ITERATIONS, k
    )
    # restitution
    for i in range(n):
        corners[COMPRESSION, i] = corners[IMPULSE, i] if corners[APPROACH, i] < -threshold else 0.0
    vx, vy, spin = restitution_impulses(vx, vy, spin, corners, n, restitution, friction, inv_mass, inv_inertia, k)
    return vx, vy, spin, approach


@jit_stage
def restitution_impulses(vx, vy, spin, corners, n, restitution, friction, inv_mass, inv_inertia, k):
    """Poisson's restitution phase: corner i gets the normal impulse e * compression_i (row COMPRESSION),
    with friction clamped to mu e compression_i (it can stop the slip there, never reverse it); then a
    corner pushed towards the floor by another's bounce is held at its target velocity (u_n >= b_i,
    row TARGET). Returns (vx, vy, spin)."""
    for i in range(n):
        corners[SCRATCH, i] = poisson_impulse(restitution, corners[COMPRESSION, i])
    vy, spin = apply_normal_impulses(vy, spin, corners, n, SCRATCH, inv_mass, inv_inertia)
    if friction > 0.0:
        for i in range(n):
            vx, spin, _ = friction_impulse(
                vx,
                spin,
                corners[RY, i],
                poisson_impulse(restitution, corners[COMPRESSION, i]),
                0.0,
                friction,
                inv_mass,
                inv_inertia,
            )
    delassus(corners, n, inv_mass, inv_inertia, k)
    for i in range(n):
        corners[IMPULSE, i] = 0.0
    return (vx, *solve_normal_block(vy, spin, corners, n, inv_mass, inv_inertia, k))


@jit_stage
def resolve_impact(motion, box, threshold, work):
    """The impact of a flying box at the instant a corner reaches the floor (``impact_impulses``) on the
    touching corners: the lowest one, and its neighbour if within ``box.simultaneous`` of the same height.
    Returns (vx, vy, spin, corners hit, approach speed, leaves), ``leaves`` being True when every
    touching corner separates faster than the threshold.
    """
    corners, cos_a, sin_a = work.corners, motion.cos_a, motion.sin_a
    first, second = lowest_face(cos_a, sin_a, box.hx, box.hy)
    place_corner(corners, 0, first, cos_a, sin_a, box.hx, box.hy)
    place_corner(corners, 1, second, cos_a, sin_a, box.hx, box.hy)
    n = 2 if corners[RY, 1] <= corners[RY, 0] + box.simultaneous else 1
    vx, vy, spin, approach = impact_impulses(
        motion.vx,
        motion.vy,
        motion.spin,
        corners,
        n,
        box.restitution,
        box.friction,
        threshold,
        box.inv_mass,
        box.inv_inertia,
        work.k,
    )
    if approach <= 0.0:
        return vx, vy, spin, 0, 0.0, False
    leaves = True
    for i in range(n):
        leaves = leaves and vy + spin * corners[RX, i] > threshold
    return vx, vy, spin, n, approach, leaves


@jit_stage(inline="always")
def touches(motion, c, box, tolerance, located, loaded):
    """Whether corner c touches the floor: within ``tolerance`` of it, the one ``located`` to arrive now, or one that
    carried load in the last piece (bit c of ``loaded``). Returns (touching, its lever arm rx, ry)."""
    rx, ry = vertex_offset(c, motion.cos_a, motion.sin_a, box.hx, box.hy)
    return motion.y + ry <= tolerance or c == located or (loaded >> c) & 1 == 1, rx, ry


@jit_stage
def contact_impact(motion, box, threshold, tolerance, located, loaded, work):
    """The impact of a box in contact at this instant: where a corner touching the floor approaches faster
    than the threshold, the touching corners (at most three, the lowest) take ``impact_impulses`` together.
    A corner touches when it is within ``tolerance`` of the floor, is the one ``located`` to arrive now, or
    carried load in the last piece (bit c of ``loaded``: it ended that piece on the floor, up to the
    second-order lift of a rotating step, which must not decide whether it takes part).
    Returns (vx, vy, spin, corners touching, approach speed, 0 if no impact)."""
    vx, vy, spin, corners = motion.vx, motion.vy, motion.spin, work.corners
    n = 0
    for c in range(4):
        touching, rx, _ = touches(motion, c, box, tolerance, located, loaded)
        if touching and vy + spin * rx < -threshold:
            n = 1
    if n == 0:
        return vx, vy, spin, 0, 0.0
    n = 0
    for c in range(4):
        touching, rx, ry = touches(motion, c, box, tolerance, located, loaded)
        if touching:
            if n < MAX_CORNERS:
                corners[RX, n], corners[RY, n] = rx, ry
                n += 1
            else:  # a fourth touching corner (never lower than the others at once): replace the highest
                highest = 0
                for i in range(1, MAX_CORNERS):
                    if corners[RY, i] > corners[RY, highest]:
                        highest = i
                if ry < corners[RY, highest]:
                    corners[RX, highest], corners[RY, highest] = rx, ry
    vx, vy, spin, approach = impact_impulses(
        vx, vy, spin, corners, n, box.restitution, box.friction, threshold, box.inv_mass, box.inv_inertia, work.k
    )
    return vx, vy, spin, n, approach
