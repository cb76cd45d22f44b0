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
from typing import NamedTuple

import numpy as np

from .. import layout
from ..compile.compilation import jit_kernel, jit_stage
from ..contact_law import floor_friction, friction_bound, mixed_friction, mixed_restitution, mixed_stiffness
from ..kernel_support import is_lying_still, record_event, rest_timer, store_state, write_stats
from ..tunables import TANGENT_NORMALISE_MIN
from .reference_solver import SeedMaterial, SeedSwitches, seed_settings


class SeedBodies(NamedTuple):
    """The bodies of a seed-scheme scene: ``body`` (vx, vy, omega, x, y, angle) a row (velocities first, as the
    contact code indexes them), the force and torque summed in a step, and the parameters (``layout``)."""

    body: np.ndarray  # (n, 6)
    force: np.ndarray  # (n, 3)
    params: np.ndarray  # (n, PARAM_SIZE)


class SeedTouches(NamedTuple):
    """Which corners were below the floor (bit mask per body) and which boxes each box touched (bit j % 62 for box
    j), in the last step and in this one: a new touch is an impact."""

    below_before: np.ndarray  # (n,) int64
    inside_before: np.ndarray  # (n,) int64
    inside_now: np.ndarray  # (n,) int64


class SeedStats(NamedTuple):
    """Per body: first contact [s] (nan: none), impacts, deepest penetration [m]."""

    first_contact: np.ndarray
    n_impacts: np.ndarray
    max_penetration: np.ndarray


@jit_stage
def seed_contact(b1, b2, point, normal, depth, bodies, material, switches):
    """One vertex contact of the seed scheme at ``point`` with normal n (pushing b1 out of b2; b2 = -1 for
    the floor): the impulse applied at once, the penalty force and torque added to ``bodies.force``."""
    vel, force, params = bodies
    cx, cy = point
    nx, ny = normal
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
    if switches.use_friction:
        ut_len = math.sqrt(tx * tx + ty * ty)
        if ut_len > TANGENT_NORMALISE_MIN:
            tx /= ut_len
            ty /= ut_len
    if switches.use_impulses:
        r1n = r1x * ny - r1y * nx
        r2n = r2x * ny - r2y * nx
        inv_mass_eff = inv_m1 + inv_m2 + r1n * r1n * inv_i1 + r2n * r2n * inv_i2
        px = (1.0 + material.restitution) * (-un_x / inv_mass_eff)
        py = (1.0 + material.restitution) * (-un_y / inv_mass_eff)
        if switches.use_friction:
            bound = friction_bound(material.friction, math.sqrt(px * px + py * py))
            px -= bound * tx
            py -= bound * ty
        if px * nx + py * ny > 0.0:
            vel[b1, 0] += px * inv_m1
            vel[b1, 1] += py * inv_m1
            vel[b1, 2] += (r1x * py - r1y * px) * inv_i1
            if b2 >= 0:
                vel[b2, 0] -= px * inv_m2
                vel[b2, 1] -= py * inv_m2
                vel[b2, 2] -= (r2x * py - r2y * px) * inv_i2
    if switches.use_penalty:
        fx = material.stiffness * depth * nx
        fy = material.stiffness * depth * ny
        if switches.use_friction:
            bound = friction_bound(material.friction, math.sqrt(fx * fx + fy * fy))
            fx -= bound * tx
            fy -= bound * ty
        force[b1, 0] += fx
        force[b1, 1] += fy
        force[b1, 2] += r1x * fy - r1y * fx
        if b2 >= 0:
            force[b2, 0] -= fx
            force[b2, 1] -= fy
            force[b2, 2] -= r2x * fy - r2y * fx


@jit_stage
def corners_inside(b1, b2, bodies, material, switches):
    """The corners of box b1 inside box b2 (demo corner order), each a ``seed_contact``. Returns a bit mask
    of the corners inside."""
    vel, params = bodies.body, bodies.params
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
        seed_contact(b1, b2, (cx, cy), (nx, ny), depth, bodies, material, switches)
    return inside


@jit_stage(inline="always")
def floor_contacts(bodies, touches, stats, n, dt, switches, record, events):
    """1. Every box against the floor, corner after corner, as ``reference_solver.reference_step``; a corner newly
    below the floor is an impact."""
    body, params = bodies.body, bodies.params
    for b in range(body.shape[0]):
        cos_a, sin_a = math.cos(body[b, 5]), math.sin(body[b, 5])
        material = SeedMaterial(
            params[b, layout.RESTITUTION], floor_friction(params[b, layout.FRICTION]), params[b, layout.STIFFNESS]
        )
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
            seed_contact(b, -1, (cx, cy), (0.0, 1.0), -cy, bodies, material, switches)
        if below != 0:
            if math.isnan(stats.first_contact[b]):
                stats.first_contact[b] = n * dt
            stats.max_penetration[b] = max(stats.max_penetration[b], -lowest)
            if below & ~touches.below_before[b]:
                if record:
                    record_event(events, b, stats.n_impacts[b], n * dt, math.nan, 1)
                stats.n_impacts[b] += 1
        touches.below_before[b] = below


@jit_stage(inline="always")
def pair_contacts(bodies, inside_now, switches):
    """2. Every pair i < j whose boxes can overlap: the corners of i inside j, then those of j inside i
    (``corners_inside``), the pair's material mixed (``contact_law``); ``inside_now`` marks the boxes each box
    touches."""
    body, params = bodies.body, bodies.params
    nb = body.shape[0]
    for i in range(nb):
        xi, yi, ri = body[i, 3], body[i, 4], params[i, 0] + params[i, 1]  # the contacts change no position
        for j in range(i + 1, nb):
            reach = ri + params[j, 0] + params[j, 1]
            if abs(xi - body[j, 3]) > reach or abs(yi - body[j, 4]) > reach:
                continue
            material = SeedMaterial(
                mixed_restitution(params[i, layout.RESTITUTION], params[j, layout.RESTITUTION]),
                mixed_friction(params[i, layout.FRICTION], params[j, layout.FRICTION]),
                mixed_stiffness(params[i, layout.STIFFNESS], params[j, layout.STIFFNESS]),
            )
            if corners_inside(i, j, bodies, material, switches) != 0:
                inside_now[i] |= 1 << (j % 62)
                inside_now[j] |= 1 << (i % 62)
            if corners_inside(j, i, bodies, material, switches) != 0:
                inside_now[i] |= 1 << (j % 62)
                inside_now[j] |= 1 << (i % 62)


@jit_stage(inline="always")
def count_box_impacts(touches, stats, n, dt, record, events):
    """A box newly touching another is an impact."""
    inside_now, inside_before = touches.inside_now, touches.inside_before
    for b in range(inside_now.shape[0]):
        if inside_now[b] & ~inside_before[b]:
            if math.isnan(stats.first_contact[b]):
                stats.first_contact[b] = n * dt
            if record:
                record_event(events, b, stats.n_impacts[b], n * dt, math.nan, 1)
            stats.n_impacts[b] += 1
        inside_before[b] = inside_now[b]


@jit_stage(inline="always")
def symplectic_euler(bodies, dt, gravity):
    """3. v += dt (f / m + g), omega += dt tau / I, then x += dt v, angle += dt omega, as the demo."""
    body, force, params = bodies
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
def finite_and_still(bodies, inside_now, n, settings, record, trajectory):
    """After step n: record it, and say (whether every body is finite, whether every body is still: slower than
    ``sleep_speed`` at every point and lying on a face or touching another box)."""
    body, params = bodies.body, bodies.params
    sleep_speed = settings.sleep_speed
    if record:
        record_step(trajectory, n, body)
    finite = True
    still = True
    for b in range(body.shape[0]):
        for c in range(6):
            finite = finite and math.isfinite(body[b, c])
        if settings.until_rest:
            speed = math.sqrt(body[b, 0] ** 2 + body[b, 1] ** 2) + abs(body[b, 2]) * math.sqrt(
                params[b, 0] ** 2 + params[b, 1] ** 2
            )
            resting = is_lying_still(
                body[b, 4], body[b, 5], body[b, 0], body[b, 1], body[b, 2], params[b, 0], params[b, 1], sleep_speed
            )
            still = still and speed <= sleep_speed and (resting or inside_now[b] != 0)
    return finite, still


@jit_stage
def advance_seed(bodies, touches, stats, settings, switches, record, trajectory, events):
    """The seed scheme's steps (this module's docstring, 1.-3.) until ``max_steps`` or, with ``until_rest``,
    until every box has been still for ``sleep_time``. Returns (steps taken, status, failed step, rest time)."""
    dt = settings.dt
    status, fail_step, rest_time, still_for, n = layout.STATUS_OK, -1, math.nan, 0.0, 0
    while n < settings.max_steps:
        bodies.force[:] = 0.0
        touches.inside_now[:] = 0
        floor_contacts(bodies, touches, stats, n, dt, switches, record, events)
        pair_contacts(bodies, touches.inside_now, switches)
        count_box_impacts(touches, stats, n, dt, record, events)
        symplectic_euler(bodies, dt, settings.gravity)
        n += 1
        finite, still = finite_and_still(bodies, touches.inside_now, n, settings, record, trajectory)
        if not finite:
            status = layout.STATUS_NONFINITE
            fail_step = n
            break
        if settings.until_rest:
            still_for, rests = rest_timer(still, still_for, dt, settings.sleep_time)
            if rests:
                rest_time = n * dt
                break
    return n, status, fail_step, rest_time


def make_colliding_reference_kernel(
    use_impulses: bool, use_penalty: bool, use_friction: bool, record: bool, source_digest: int
):
    """Build the seed kernel for scenes whose boxes collide (flags compile-time, as ``reference_solver``'s; it
    takes the robust kernel's arguments and leaves ``warm`` as it is: the seed scheme keeps no contacts)."""
    IMPULSES, PENALTY, FRICTION, RECORD, DIGEST = use_impulses, use_penalty, use_friction, record, source_digest

    @jit_kernel
    def run(state, params, settings, stats, trajectory, events, warm):
        _ = DIGEST  # the on-disk cache key includes every engine source (see reference_solver)
        nb = state.shape[0]
        body = np.empty((nb, 6))
        for b in range(nb):
            body[b, 0], body[b, 1], body[b, 2] = state[b, 3], state[b, 4], state[b, 5]
            body[b, 3], body[b, 4], body[b, 5] = state[b, 0], state[b, 1], state[b, 2]
        tally = SeedStats(np.full(nb, math.nan), np.zeros(nb, np.int64), np.zeros(nb))
        if RECORD:
            record_step(trajectory, 0, body)
        touches = SeedTouches(np.zeros(nb, np.int64), np.zeros(nb, np.int64), np.zeros(nb, np.int64))
        n, status, fail_step, rest_time = advance_seed(
            SeedBodies(body, np.zeros((nb, 3)), params),
            touches,
            tally,
            seed_settings(settings),
            SeedSwitches(IMPULSES, PENALTY, FRICTION),
            RECORD,
            trajectory,
            events,
        )
        dt = settings[layout.DT]
        for b in range(nb):
            state[b, 0], state[b, 1], state[b, 2] = body[b, 3], body[b, 4], body[b, 5]
            state[b, 3], state[b, 4], state[b, 5] = body[b, 0], body[b, 1], body[b, 2]
            body_status = layout.STATUS_OK
            if status != layout.STATUS_OK:
                for c in range(6):
                    if not math.isfinite(body[b, c]):
                        body_status = status
            write_stats(
                stats,
                b,
                tally.first_contact[b],
                tally.n_impacts[b],
                n,
                tally.max_penetration[b],
                rest_time,
                n * dt,
                body_status,
                fail_step if body_status != layout.STATUS_OK else -1,
                n + 1,
            )

    return run
