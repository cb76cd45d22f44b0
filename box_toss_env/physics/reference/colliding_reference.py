"""The seed scheme for scenes whose boxes collide (``Scene(boxes_collide=True, solver="seed")``): our
extension of the demo, which knows only the floor. It uses the reference text's own two-body formulas
and its vertex contacts, generalised from "a corner below y = 0" to "a corner inside another box";
a scene whose boxes cannot meet runs ``reference_solver``'s kernel, exactly the demo.

Per time step:
  1. every box in turn, its corners against the floor exactly as ``reference_solver.reference_step`` (impulse
     at once, then the penalty force and its friction summed into the box's force and torque);
  2. every pair i < j in turn, first the corners of box i inside box j, then those of box j inside
     box i, each corner in the demo's order. A corner c of box 1 inside box 2 (|local x| < hx and
     |local y| < hy in box 2's frame) is a contact whose normal n is the outward normal of box 2's face
     nearest to c and whose depth d is the distance to that face; with r1 = c - x1, r2 = c - x2,
     u_rel = u1 - u2 (u = v + omega x r) and the text's decomposition into u_n = (u_rel . n) n and
     u_t = u_rel - u_n:
        p' = -u_n / (1/m1 + 1/m2 + (r1 x n)^2 / I1 + (r2 x n)^2 / I2),   p = (1 + e) p',
        p += -mu |p| t                           (t = u_t / |u_t| where |u_t| > 1e-4, as the demo),
        if p . n > 0:  v1 += p / m1,  omega1 += (r1 x p) / I1,  v2 -= p / m2,  omega2 -= (r2 x p) / I2,
     and the penalty force f = k d n - mu |k d n| t is added to box 1 (torque r1 x f) and taken from
     box 2 (torque -r2 x f);
  3. symplectic Euler for every box, as the demo.
The pair's material follows the robust solver's mixing (restitution max(e1, e2), friction
sqrt(mu1 mu2), stiffness min(k1, k2)). The scheme keeps the demo's faults (corners one after another,
explicit penalty forces); a corner that passes through a whole box in one step is not seen.
"""

import math

import numpy as np

from .. import layout
from ..compile.compilation import jit_kernel, jit_stage
from ..kernel_support import is_lying_still, read_settings, record_event, rest_timer, store_state, write_stats
from .reference_solver import TANGENT_NORMALISE_MIN


@jit_stage
def seed_contact(b1, b2, cx, cy, nx, ny, depth, vel, force, params, restitution, friction, stiffness,
                 use_impulses, use_penalty, use_friction):
    """One vertex contact of the seed scheme at point c with normal n (pushing b1 out of b2; b2 = -1 for
    the floor): the impulse applied at once, the penalty force and torque added to ``force``."""
    inv_m1 = 1.0 / params[b1, layout.MASS]
    inv_i1 = 1.0 / params[b1, layout.INERTIA]
    r1x = cx - vel[b1, 3]
    r1y = cy - vel[b1, 4]
    ux = vel[b1, 0] - vel[b1, 2] * r1y
    uy = vel[b1, 1] + vel[b1, 2] * r1x
    inv_m2 = 0.0
    inv_i2 = 0.0
    r2x = 0.0
    r2y = 0.0
    if b2 >= 0:
        inv_m2 = 1.0 / params[b2, layout.MASS]
        inv_i2 = 1.0 / params[b2, layout.INERTIA]
        r2x = cx - vel[b2, 3]
        r2y = cy - vel[b2, 4]
        ux -= vel[b2, 0] - vel[b2, 2] * r2y
        uy -= vel[b2, 1] + vel[b2, 2] * r2x
    # 2.2 normal and tangential parts
    u_dot_n = ux * nx + uy * ny
    un_x = u_dot_n * nx
    un_y = u_dot_n * ny
    tx = ux - un_x
    ty = uy - un_y
    if use_friction:
        ut_len = math.sqrt(tx * tx + ty * ty)
        if ut_len > TANGENT_NORMALISE_MIN:
            tx /= ut_len
            ty /= ut_len
    if use_impulses:
        r1n = r1x * ny - r1y * nx
        r2n = r2x * ny - r2y * nx
        inv_mass_eff = inv_m1 + inv_m2 + r1n * r1n * inv_i1 + r2n * r2n * inv_i2
        px = (1.0 + restitution) * (-un_x / inv_mass_eff)
        py = (1.0 + restitution) * (-un_y / inv_mass_eff)
        if use_friction:
            p_len = math.sqrt(px * px + py * py)
            px -= friction * p_len * tx
            py -= friction * p_len * ty
        if px * nx + py * ny > 0.0:
            vel[b1, 0] += px * inv_m1
            vel[b1, 1] += py * inv_m1
            vel[b1, 2] += (r1x * py - r1y * px) * inv_i1
            if b2 >= 0:
                vel[b2, 0] -= px * inv_m2
                vel[b2, 1] -= py * inv_m2
                vel[b2, 2] -= (r2x * py - r2y * px) * inv_i2
    if use_penalty:
        fx = stiffness * depth * nx
        fy = stiffness * depth * ny
        if use_friction:
            f_len = math.sqrt(fx * fx + fy * fy)
            fx -= friction * f_len * tx
            fy -= friction * f_len * ty
        force[b1, 0] += fx
        force[b1, 1] += fy
        force[b1, 2] += r1x * fy - r1y * fx
        if b2 >= 0:
            force[b2, 0] -= fx
            force[b2, 1] -= fy
            force[b2, 2] -= r2x * fy - r2y * fx


@jit_stage
def corners_inside(b1, b2, vel, force, params, restitution, friction, stiffness, use_impulses, use_penalty,
                   use_friction):
    """The corners of box b1 inside box b2 (demo corner order), each a ``seed_contact``. Returns a bit mask
    of the corners inside."""
    c1, s1 = math.cos(vel[b1, 5]), math.sin(vel[b1, 5])
    c2, s2 = math.cos(vel[b2, 5]), math.sin(vel[b2, 5])
    hx1, hy1 = params[b1, layout.HALF_LENGTH], params[b1, layout.HALF_WIDTH]
    hx2, hy2 = params[b2, layout.HALF_LENGTH], params[b2, layout.HALF_WIDTH]
    inside = 0
    for k in range(4):
        bx = layout.SEED_SIGN_X[k] * hx1
        by = layout.SEED_SIGN_Y[k] * hy1
        cx = vel[b1, 3] + c1 * bx - s1 * by
        cy = vel[b1, 4] + s1 * bx + c1 * by
        dx = cx - vel[b2, 3]
        dy = cy - vel[b2, 4]
        lx = c2 * dx + s2 * dy  # in box b2's frame
        ly = -s2 * dx + c2 * dy
        depth_x = hx2 - abs(lx)
        depth_y = hy2 - abs(ly)
        if depth_x <= 0.0 or depth_y <= 0.0:
            continue
        inside |= 1 << k
        if depth_x < depth_y:
            sign = 1.0 if lx >= 0.0 else -1.0
            nx, ny, depth = sign * c2, sign * s2, depth_x
        else:
            sign = 1.0 if ly >= 0.0 else -1.0
            nx, ny, depth = -sign * s2, sign * c2, depth_y
        seed_contact(b1, b2, cx, cy, nx, ny, depth, vel, force, params, restitution, friction, stiffness,
                     use_impulses, use_penalty, use_friction)
    return inside


@jit_stage(inline="always")
def floor_contacts(body, force, params, below_before, first_contact, n_impacts, max_penetration, n, dt,
                   use_impulses, use_penalty, use_friction, record, events):
    """1. Every box against the floor, corner after corner, as ``reference_solver.reference_step``; a corner newly
    below the floor is an impact."""
    for b in range(body.shape[0]):
        cos_a, sin_a = math.cos(body[b, 5]), math.sin(body[b, 5])
        below = 0
        lowest = math.inf
        for k in range(4):
            bx = layout.SEED_SIGN_X[k] * params[b, layout.HALF_LENGTH]
            by = layout.SEED_SIGN_Y[k] * params[b, layout.HALF_WIDTH]
            cx = body[b, 3] + cos_a * bx - sin_a * by
            cy = body[b, 4] + sin_a * bx + cos_a * by
            lowest = min(lowest, cy)
            if cy >= 0.0:
                continue
            below |= 1 << k
            seed_contact(b, -1, cx, cy, 0.0, 1.0, -cy, body, force, params, params[b, layout.RESTITUTION],
                         params[b, layout.FRICTION], params[b, layout.STIFFNESS], use_impulses, use_penalty,
                         use_friction)
        if below != 0:
            if math.isnan(first_contact[b]):
                first_contact[b] = n * dt
            max_penetration[b] = max(max_penetration[b], -lowest)
            if below & ~below_before[b]:
                if record:
                    record_event(events, b, n_impacts[b], n * dt, math.nan, 1)
                n_impacts[b] += 1
        below_before[b] = below


@jit_stage(inline="always")
def pair_contacts(body, force, params, inside_now, use_impulses, use_penalty, use_friction):
    """2. Every pair i < j whose boxes can overlap: the corners of i inside j, then those of j inside i
    (``corners_inside``), the pair's material mixed (e = max, mu = sqrt(mu_i mu_j), k = min); ``inside_now``
    marks the boxes each box touches."""
    nb = body.shape[0]
    for i in range(nb):
        xi, yi, ri = body[i, 3], body[i, 4], params[i, 0] + params[i, 1]  # the contacts change no position
        for j in range(i + 1, nb):
            reach = ri + params[j, 0] + params[j, 1]
            if abs(xi - body[j, 3]) > reach or abs(yi - body[j, 4]) > reach:
                continue
            e = max(params[i, layout.RESTITUTION], params[j, layout.RESTITUTION])
            mu = math.sqrt(params[i, layout.FRICTION] * params[j, layout.FRICTION])
            k = min(params[i, layout.STIFFNESS], params[j, layout.STIFFNESS])
            if corners_inside(i, j, body, force, params, e, mu, k, use_impulses, use_penalty, use_friction) != 0:
                inside_now[i] |= 1 << (j % 62)
                inside_now[j] |= 1 << (i % 62)
            if corners_inside(j, i, body, force, params, e, mu, k, use_impulses, use_penalty, use_friction) != 0:
                inside_now[i] |= 1 << (j % 62)
                inside_now[j] |= 1 << (i % 62)


@jit_stage(inline="always")
def count_box_impacts(inside_now, inside_before, first_contact, n_impacts, n, dt, record, events):
    """A box newly touching another is an impact."""
    for b in range(inside_now.shape[0]):
        if inside_now[b] & ~inside_before[b]:
            if math.isnan(first_contact[b]):
                first_contact[b] = n * dt
            if record:
                record_event(events, b, n_impacts[b], n * dt, math.nan, 1)
            n_impacts[b] += 1
        inside_before[b] = inside_now[b]


@jit_stage(inline="always")
def symplectic_euler(body, force, params, dt, gravity):
    """3. v += dt (f / m + g), omega += dt tau / I, then x += dt v, angle += dt omega, as the demo."""
    for b in range(body.shape[0]):
        body[b, 0] += dt * force[b, 0] / params[b, layout.MASS]
        body[b, 1] += dt * (force[b, 1] / params[b, layout.MASS] + gravity)
        body[b, 2] += dt * force[b, 2] / params[b, layout.INERTIA]
        body[b, 3] += dt * body[b, 0]
        body[b, 4] += dt * body[b, 1]
        body[b, 5] += dt * body[b, 2]


@jit_stage
def record_step(trajectory, row, body):
    """Every body's state into row ``row`` of ``trajectory``."""
    for b in range(body.shape[0]):
        store_state(trajectory, row, b, body[b, 3], body[b, 4], body[b, 5], body[b, 0], body[b, 1], body[b, 2])


@jit_stage(inline="always")
def finite_and_still(body, params, inside_now, n, until_rest, sleep_speed, record, trajectory):
    """After step n: record it, and say (whether every body is finite, whether every body is still: slower than
    ``sleep_speed`` at every point and lying on a face or touching another box)."""
    if record:
        record_step(trajectory, n, body)
    finite = True
    still = True
    for b in range(body.shape[0]):
        for c in range(6):
            finite = finite and math.isfinite(body[b, c])
        if until_rest:
            speed = (math.sqrt(body[b, 0] ** 2 + body[b, 1] ** 2)
                     + abs(body[b, 2]) * math.sqrt(params[b, 0] ** 2 + params[b, 1] ** 2))
            resting = is_lying_still(body[b, 4], body[b, 5], body[b, 0], body[b, 1], body[b, 2],
                                     params[b, 0], params[b, 1], sleep_speed)
            still = still and speed <= sleep_speed and (resting or inside_now[b] != 0)
    return finite, still


@jit_stage
def advance_seed(body, force, params, settings, below_before, inside_before, inside_now, first_contact, n_impacts,
                 max_penetration, use_impulses, use_penalty, use_friction, record, trajectory, events):
    """The seed scheme's steps (this module's docstring, 1.-3.) until ``max_steps`` or, with ``until_rest``,
    until every box has been still for ``sleep_time``; ``body``: (vx, vy, omega, x, y, angle) a row. Returns
    (steps taken, status, failed step, rest time)."""
    dt, gravity, max_steps, until_rest, _, sleep_speed, sleep_time, _ = read_settings(settings)
    status, fail_step, rest_time, still_for, n = layout.STATUS_OK, -1, math.nan, 0.0, 0
    while n < max_steps:
        for b in range(body.shape[0]):
            force[b, 0] = 0.0
            force[b, 1] = 0.0
            force[b, 2] = 0.0
            inside_now[b] = 0
        floor_contacts(body, force, params, below_before, first_contact, n_impacts, max_penetration, n, dt,
                       use_impulses, use_penalty, use_friction, record, events)
        pair_contacts(body, force, params, inside_now, use_impulses, use_penalty, use_friction)
        count_box_impacts(inside_now, inside_before, first_contact, n_impacts, n, dt, record, events)
        symplectic_euler(body, force, params, dt, gravity)
        n += 1
        finite, still = finite_and_still(body, params, inside_now, n, until_rest, sleep_speed, record, trajectory)
        if not finite:
            status = layout.STATUS_NONFINITE
            fail_step = n
            break
        if until_rest:
            still_for, rests = rest_timer(still, still_for, dt, sleep_time)
            if rests:
                rest_time = n * dt
                break
    return n, status, fail_step, rest_time


def make_colliding_reference_kernel(use_impulses: bool, use_penalty: bool, use_friction: bool, record: bool,
                               source_digest: int):
    """Build the seed kernel for scenes whose boxes collide (flags compile-time, as ``reference_solver``'s; it
    takes the robust kernel's arguments and leaves ``warm`` as it is: the seed scheme keeps no contacts)."""
    IMPULSES, PENALTY, FRICTION, RECORD, DIGEST = use_impulses, use_penalty, use_friction, record, source_digest

    @jit_kernel
    def run(state, params, settings, stats, trajectory, events, warm):
        _ = DIGEST  # the on-disk cache key includes every engine source (see reference_solver)
        nb = state.shape[0]
        # body work array: vx, vy, omega, x, y, angle (velocities first, as the contact code indexes them)
        body = np.empty((nb, 6))
        for b in range(nb):
            body[b, 0], body[b, 1], body[b, 2] = state[b, 3], state[b, 4], state[b, 5]
            body[b, 3], body[b, 4], body[b, 5] = state[b, 0], state[b, 1], state[b, 2]
        first_contact = np.full(nb, math.nan)
        n_impacts = np.zeros(nb, np.int64)
        max_penetration = np.zeros(nb)
        if RECORD:
            record_step(trajectory, 0, body)
        n, status, fail_step, rest_time = advance_seed(
            body, np.zeros((nb, 3)), params, settings, np.zeros(nb, np.int64), np.zeros(nb, np.int64),
            np.zeros(nb, np.int64), first_contact, n_impacts, max_penetration, IMPULSES, PENALTY, FRICTION, RECORD,
            trajectory, events)
        dt = settings[layout.DT]
        for b in range(nb):
            state[b, 0], state[b, 1], state[b, 2] = body[b, 3], body[b, 4], body[b, 5]
            state[b, 3], state[b, 4], state[b, 5] = body[b, 0], body[b, 1], body[b, 2]
            body_status = layout.STATUS_OK
            if status != layout.STATUS_OK:
                for c in range(6):
                    if not math.isfinite(body[b, c]):
                        body_status = status
            write_stats(stats, b, first_contact[b], n_impacts[b], n, max_penetration[b], rest_time, n * dt,
                        body_status, fail_step if body_status != layout.STATUS_OK else -1, n + 1)

    return run
