"""Stage prepare of the colliding solver: each contact's effective masses and material, and the two-body
impulse formulas every later stage uses (``relative_velocity``, ``apply_impulse``).

Contacts (``narrowphase``) push body 1 out of body 2 along n at a point with lever arms r1, r2. The
two-body formulas of the reference text: with u_rel = u1 - u2, u = v + omega x r, a normal impulse
p n applied +p n to body 1 and -p n to body 2 changes u_rel . n by K_n p with the effective mass

    K_n = 1/m1 + 1/m2 + (r1 x n)^2 / I1 + (r2 x n)^2 / I2       (the floor: 1/m2 = 1/I2 = 0),

and a tangential impulse q t changes u_rel . t by K_t q, K_t the same with t for n. So the impulse
that stops the approach is p = -u_rel . n / K_n, and an impact with restitution e gets
p = -(1 + e) u_rel . n / K_n in total (the text's p = (1 + e) p' for two bodies).

Material of a contact: the contact law's (``contact_law``: a box-box contact mixes the two boxes' materials,
a box-floor contact takes the box's own).
"""

from .. import layout
from ..compile.compilation import jit_stage
from ..contact_law import (
    floor_friction,
    is_impact,
    mixed_friction,
    mixed_restitution,
    mixed_stiffness,
    newton_target,
    tangent,
)
from .narrowphase import (
    APPROACH,
    BODY1,
    BODY2,
    FRICTION,
    FRICTION_IMPULSE,
    GAP,
    IMPULSE,
    KEY,
    NORMAL_MASS,
    NX,
    NY,
    R1X,
    R1Y,
    R2X,
    R2Y,
    RESTITUTION,
    STIFFNESS,
    TANGENT_MASS,
    TARGET,
)


@jit_stage(inline="always")
def relative_velocity(c, contacts, ids, vel):
    """u_rel = u1 - u2 at contact c, u = v + omega x r = (vx - omega ry, vy + omega rx)."""
    b1 = ids[c, BODY1]
    b2 = ids[c, BODY2]
    ux = vel[b1, 0] - vel[b1, 2] * contacts[c, R1Y]
    uy = vel[b1, 1] + vel[b1, 2] * contacts[c, R1X]
    if b2 >= 0:
        ux -= vel[b2, 0] - vel[b2, 2] * contacts[c, R2Y]
        uy -= vel[b2, 1] + vel[b2, 2] * contacts[c, R2X]
    return ux, uy


@jit_stage(inline="always")
def apply_impulse(c, px, py, contacts, ids, vel, inv_mass, inv_inertia):
    """The impulse P at contact c: +P on body 1 (v1 += P / m1, omega1 += (r1 x P) / I1), -P on body 2."""
    b1 = ids[c, BODY1]
    b2 = ids[c, BODY2]
    vel[b1, 0] += px * inv_mass[b1]
    vel[b1, 1] += py * inv_mass[b1]
    vel[b1, 2] += (contacts[c, R1X] * py - contacts[c, R1Y] * px) * inv_inertia[b1]
    if b2 >= 0:
        vel[b2, 0] -= px * inv_mass[b2]
        vel[b2, 1] -= py * inv_mass[b2]
        vel[b2, 2] -= (contacts[c, R2X] * py - contacts[c, R2Y] * px) * inv_inertia[b2]


@jit_stage(inline="always")
def apply_contact_impulses(c, rows, ids, vel, inv_mass, inv_inertia):
    """Contact c's normal and friction impulses (p, q: its IMPULSE, FRICTION_IMPULSE) applied to its bodies as the
    one impulse p n + q t, t = (-n_y, n_x)."""
    p, q = rows[c, IMPULSE], rows[c, FRICTION_IMPULSE]
    nx, ny = rows[c, NX], rows[c, NY]
    tx, ty = tangent(nx, ny)
    apply_impulse(c, p * nx + q * tx, p * ny + q * ty, rows, ids, vel, inv_mass, inv_inertia)


@jit_stage(inline="always")
def take_kept_impulses(c, rows, ids, kept, at, ratio):
    """Contact c's impulses from those the last substep kept (``kept``: their keys, increasing, impulses and count),
    searched from position ``at`` on: ``ratio`` times its key's, or zero where its key was not kept. The contacts'
    keys increase too, so one pass over both lists pairs them. Returns (the position reached, whether it was kept)."""
    keys, impulses, n_kept = kept
    rows[c, IMPULSE] = 0.0
    rows[c, FRICTION_IMPULSE] = 0.0
    while at < n_kept and keys[at] < ids[c, KEY]:
        at += 1
    found = at < n_kept and keys[at] == ids[c, KEY]
    if found:
        rows[c, IMPULSE] = ratio * impulses[at, 0]
        rows[c, FRICTION_IMPULSE] = ratio * impulses[at, 1]
    return at, found


@jit_stage(inline="always")
def note_depth(c, rows, ids, max_penetration):
    """Contact c's penetration -gap, kept as the deepest each of its bodies has had if deeper; returns it."""
    depth = -rows[c, GAP]
    b1 = ids[c, BODY1]
    b2 = ids[c, BODY2]
    max_penetration[b1] = max(max_penetration[b1], depth)
    if b2 >= 0:
        max_penetration[b2] = max(max_penetration[b2], depth)
    return depth


@jit_stage(inline="always")
def touch_bodies(c, rows, ids, impacts, threshold, touched, impacted):
    """If contact c took an impulse, its bodies are touched, and, when the substep has ``impacts`` and c approached
    faster than ``threshold``, impacted once more."""
    if rows[c, IMPULSE] > 0.0:
        b1 = ids[c, BODY1]
        b2 = ids[c, BODY2]
        touched[b1] = True
        if b2 >= 0:
            touched[b2] = True
        if impacts > 0 and is_impact(rows[c, APPROACH], threshold):
            impacted[b1] += 1
            if b2 >= 0:
                impacted[b2] += 1


@jit_stage(inline="always")
def is_impact_contact(c, rows, threshold):
    """Whether contact c is an impact: it approached faster than ``threshold`` before the substep
    (``contact_law.is_impact``) and took an impulse."""
    return is_impact(rows[c, APPROACH], threshold) and rows[c, IMPULSE] > 0.0


@jit_stage(inline="always")
def polish_target(c, rows, threshold):
    """Contact c's target in the restitution polish and the least impulse it may keep: an impact (approaching faster
    than ``threshold``, with an impulse) u_rel . n >= -e u0, its impulse >= 0; any other contact, with the floor or
    between boxes, its speculative target less the threshold, its impulse only growing (an impact may not drive a
    corner into the floor or into another box faster than the threshold, nor release it)."""
    if is_impact_contact(c, rows, threshold):
        return newton_target(rows[c, RESTITUTION], rows[c, APPROACH]), 0.0
    return rows[c, TARGET] - threshold, rows[c, IMPULSE]


@jit_stage(inline="always")
def short_of_target(c, rows, ids, vel, threshold):
    """Whether contact c approaches faster than its polish target (``polish_target``) by more than ``threshold``:
    what ``restitution.hold_targets`` steps again."""
    target, _ = polish_target(c, rows, threshold)
    ux, uy = relative_velocity(c, rows, ids, vel)
    return ux * rows[c, NX] + uy * rows[c, NY] < target - threshold


@jit_stage(inline="always")
def restitution_step(c, rows, ids, vel, inv_mass, inv_inertia, threshold):
    """One contact of the restitution polish: its normal impulse that meets its target, no less than its least
    (``polish_target``). Returns (|change|, impulse after)."""
    target, least = polish_target(c, rows, threshold)
    nx, ny = rows[c, NX], rows[c, NY]
    ux, uy = relative_velocity(c, rows, ids, vel)
    before = rows[c, IMPULSE]
    after = max(before - (ux * nx + uy * ny - target) * rows[c, NORMAL_MASS], least)
    rows[c, IMPULSE] = after
    dp = after - before
    if dp != 0.0:
        apply_impulse(c, dp * nx, dp * ny, rows, ids, vel, inv_mass, inv_inertia)
    return abs(dp), after


@jit_stage
def prepare_contacts(contacts, count, bodies):
    """Effective masses 1 / K_n, 1 / K_t and the material (``contact_law``) of each of the first ``count`` contacts
    (``contacts``: ``state.Contacts``; ``bodies``: ``state.Bodies``)."""
    rows, ids = contacts.rows, contacts.ids
    for c in range(count):
        prepare_contact(c, rows, ids, bodies.params, bodies.inv_mass, bodies.inv_inertia)


@jit_stage(inline="always")
def prepare_contact(c, rows, ids, params, inv_mass, inv_inertia):
    """Contact c's effective masses 1 / K_n, 1 / K_t and material (``prepare_contacts``)."""
    b1 = ids[c, BODY1]
    b2 = ids[c, BODY2]
    nx, ny = rows[c, NX], rows[c, NY]
    rn1 = rows[c, R1X] * ny - rows[c, R1Y] * nx
    rt1 = rows[c, R1X] * nx + rows[c, R1Y] * ny  # r1 x t with t = (-ny, nx)
    k_n = inv_mass[b1] + rn1 * rn1 * inv_inertia[b1]
    k_t = inv_mass[b1] + rt1 * rt1 * inv_inertia[b1]
    if b2 >= 0:
        rn2 = rows[c, R2X] * ny - rows[c, R2Y] * nx
        rt2 = rows[c, R2X] * nx + rows[c, R2Y] * ny
        k_n += inv_mass[b2] + rn2 * rn2 * inv_inertia[b2]
        k_t += inv_mass[b2] + rt2 * rt2 * inv_inertia[b2]
        rows[c, RESTITUTION] = mixed_restitution(params[b1, layout.RESTITUTION], params[b2, layout.RESTITUTION])
        rows[c, FRICTION] = mixed_friction(params[b1, layout.FRICTION], params[b2, layout.FRICTION])
        rows[c, STIFFNESS] = mixed_stiffness(params[b1, layout.STIFFNESS], params[b2, layout.STIFFNESS])
    else:
        rows[c, RESTITUTION] = params[b1, layout.RESTITUTION]
        rows[c, FRICTION] = floor_friction(params[b1, layout.FRICTION])
        rows[c, STIFFNESS] = params[b1, layout.STIFFNESS]
    rows[c, NORMAL_MASS] = 1.0 / k_n
    rows[c, TANGENT_MASS] = 1.0 / k_t


@jit_stage
def body_kinetic_energy(vel, b, params):
    """m |v|^2 / 2 + I omega^2 / 2 of body b [J]."""
    return 0.5 * (
        params[b, layout.MASS] * (vel[b, 0] ** 2 + vel[b, 1] ** 2) + params[b, layout.INERTIA] * vel[b, 2] ** 2
    )
