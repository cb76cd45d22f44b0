"""The seed's scheme, exactly as the reference text (restated in docs/engine.md) describes it.

Per time step and per box:
  1. detect contacts: every corner b_global = R b_local + x with y < 0;
  2. for each such corner, in the demo's corner order (-L/2, -W/2), (-L/2, +W/2), (+L/2, +W/2),
     (+L/2, -W/2) (``layout.SEED_SIGN_X``, ``SEED_SIGN_Y``), an impulse p = -(1 + e) u_n / (1/m + (r x n)^2 / I)
     plus the friction impulse -mu |p| t, applied at once (v += p/m, omega += (r x p)/I) when
     p . n > 0, so a later corner sees the velocity an earlier one produced;
  3. for each such corner a penalty force f_n = k d n (d = -y) and its friction -mu |f_n| t,
     summed into the force and the torque (r x f);
  4. symplectic Euler: v += dt (f/m + g), x += dt v, omega += dt tau/I, alpha += dt omega.
The tangent t = u_t / |u_t| is normalised only when |u_t| > 1e-4, as in the demo.

This scheme is kept as it is, faults included (see ``robust_solver`` for what they are). One of
them: a box resting on the floor creeps sideways, driven by friction (corner impulses and penalty
friction in a fixed order), not by restitution: over 10 s at dt 0.005 s the 2 x 1 m box of
``scenes.resting`` moves 0 with mu = 0, 7 mm with mu = 0.02 and 13 cm with mu = 0.5 (14 cm with
e = 0, so restitution is not what drives it).
"""

import math
from typing import NamedTuple

from .. import layout
from ..compile.compilation import jit_kernel, jit_stage
from ..contact_law import floor_friction, friction_bound
from ..kernel_support import (
    is_finite_state,
    is_lying_still,
    read_settings,
    record_event,
    rest_timer,
    store_state,
    write_stats,
)
from ..tunables import TANGENT_NORMALISE_MIN


class SeedSwitches(NamedTuple):
    """The seed scheme's compile-time switches: impulses, the penalty force, friction."""

    use_impulses: bool
    use_penalty: bool
    use_friction: bool


class SeedMaterial(NamedTuple):
    """A contact's material in the seed scheme (a box's own against the floor, mixed between boxes)."""

    restitution: float  # [-]
    friction: float  # [-]
    stiffness: float  # [N/m]


class SeedSettings(NamedTuple):
    """The scene's settings as the seed kernels read them."""

    dt: float  # [s]
    gravity: float  # [m/s^2]
    max_steps: int
    until_rest: bool
    sleep_speed: float  # [m/s]
    sleep_time: float  # [s]


@jit_stage(inline="always")
def seed_settings(settings):
    """``SeedSettings`` from the settings array (``layout``)."""
    dt, gravity, max_steps, until_rest, _, sleep_speed, sleep_time, _ = read_settings(settings)
    return SeedSettings(dt, gravity, max_steps, until_rest, sleep_speed, sleep_time)


@jit_stage(inline="always")
def corner_impulse(velocity, lever, normal, normal_velocity, tangent, mass, inertia, material, use_friction):
    """2.3-2.5 for a corner at lever arm r with normal velocity u_n and tangent t: the impulse
    p = (1 + e) p', p' = -u_n / (1/m + (r x n)^2 / I), with the friction impulse -mu |p| t added, applied
    at once (v += p/m, omega += (r x p)/I) if it pushes out of the floor (p . n > 0). Returns (vx, vy, spin)."""
    vx, vy, spin = velocity
    rx, ry = lever
    nx, ny = normal
    un_x, un_y = normal_velocity
    tx, ty = tangent
    # 2.3 p' = -u_n / (1/m + (r x n)^2 / I), p = (1 + e) p'
    r_cross_n = rx * ny - ry * nx
    inv_mass_eff = 1.0 / mass + r_cross_n * r_cross_n / inertia
    px = (1.0 + material.restitution) * (-un_x / inv_mass_eff)
    py = (1.0 + material.restitution) * (-un_y / inv_mass_eff)
    if use_friction:
        # 2.5 p_friction = -mu |p| t, added before the test of 2.4
        bound = friction_bound(material.friction, math.sqrt(px * px + py * py))
        px = px - bound * tx
        py = py - bound * ty
    # 2.4 apply only if the impulse pushes out of the floor
    if px * nx + py * ny > 0.0:
        vx = vx + px / mass
        vy = vy + py / mass
        spin = spin + (rx * py - ry * px) / inertia
    return vx, vy, spin


@jit_stage(inline="always")
def penalty_force(depth, lever, normal, tangent, material, use_friction):
    """3. The penalty force of a corner ``depth`` below the floor, f_n = k d n, with its friction
    f_friction = -mu |f_n| t. Returns (f_x, f_y, its torque r x f)."""
    rx, ry = lever
    nx, ny = normal
    tx, ty = tangent
    fn_x = material.stiffness * depth * nx
    fn_y = material.stiffness * depth * ny
    f_x = fn_x
    f_y = fn_y
    if use_friction:
        bound = friction_bound(material.friction, math.sqrt(fn_x * fn_x + fn_y * fn_y))
        f_x = fn_x - bound * tx
        f_y = fn_y - bound * ty
    return f_x, f_y, rx * f_y - ry * f_x


@jit_stage(inline="always")
def slip_direction(ux, uy, nx, ny, use_friction):
    """2.2 The normal part u_n = (u . n) n of a point velocity u and the direction t of its tangential part
    u_t = u - u_n, normalised where |u_t| > TANGENT_NORMALISE_MIN (with friction; as the demo). Returns (u_n, t)."""
    u_dot_n = ux * nx + uy * ny
    un_x = u_dot_n * nx
    un_y = u_dot_n * ny
    ut_x = ux - un_x
    ut_y = uy - un_y
    tx = ut_x
    ty = ut_y
    if use_friction:
        ut_len = math.sqrt(ut_x * ut_x + ut_y * ut_y)
        if ut_len > TANGENT_NORMALISE_MIN:
            tx = ut_x / ut_len
            ty = ut_y / ut_len
    return (un_x, un_y), (tx, ty)


@jit_stage(inline="always")
def reference_step(motion, box, material, dt, gravity, switches):
    """One step of the seed scheme for one box (this module's docstring, 1.-4.): ``motion`` (x, y, angle, vx, vy,
    spin), ``box`` (hx, hy, m, I). Returns the new motion, the lowest corner height before the step and a bit mask
    of the corners that were below the floor."""
    x, y, angle, vx, vy, spin = motion
    half_length, half_width, mass, inertia = box
    nx, ny = 0.0, 1.0  # floor normal
    cos_a = math.cos(angle)
    sin_a = math.sin(angle)
    force_x = 0.0
    force_y = 0.0
    torque = 0.0
    lowest_y = math.inf
    below = 0
    for k in range(4):
        # 1. detect contacts: the corner b_global = R b_local + x below the floor
        bx = layout.SEED_SIGN_X[k] * half_length
        by = layout.SEED_SIGN_Y[k] * half_width
        rx = cos_a * bx - sin_a * by  # r_k = R(alpha) b_k
        ry = sin_a * bx + cos_a * by
        corner_y = ry + y
        lowest_y = min(lowest_y, corner_y)
        if corner_y >= 0.0:
            continue
        below |= 1 << k
        # 2.1 point velocity u = v + omega x r, with omega x r = (-omega r_y, omega r_x); 2.2 its parts
        normal_velocity, tangent = slip_direction(vx - spin * ry, vy + spin * rx, nx, ny, switches.use_friction)
        if switches.use_impulses:
            # 2.3-2.5 the corner's impulse, applied at once
            vx, vy, spin = corner_impulse(
                (vx, vy, spin),
                (rx, ry),
                (nx, ny),
                normal_velocity,
                tangent,
                mass,
                inertia,
                material,
                switches.use_friction,
            )
        if switches.use_penalty:
            # 3. f_n = k d n, f_friction = -mu |f_n| t, tau += r x (f_n + f_friction)
            f_x, f_y, corner_torque = penalty_force(
                -corner_y, (rx, ry), (nx, ny), tangent, material, switches.use_friction
            )
            force_x = force_x + f_x
            force_y = force_y + f_y
            torque = torque + corner_torque
    # 4. symplectic Euler, gravity in the velocity update
    vx = vx + dt * (force_x / mass)
    vy = vy + dt * (force_y / mass + gravity)
    spin = spin + dt * (torque / inertia)
    x = x + dt * vx
    y = y + dt * vy
    angle = angle + dt * spin
    return (x, y, angle, vx, vy, spin), lowest_y, below


@jit_stage(inline="always")
def advance_seed_box(i, state, params, stats, settings, switches, record, trajectory, events):
    """Box i by the seed scheme (``reference_step``) for ``max_steps`` steps, or until it has lain still on a face
    for ``sleep_time`` when ``until_rest``, or until its state stops being finite; its state and stats written
    back. A corner newly below the floor is an impact."""
    dt = settings.dt
    motion = (state[i, 0], state[i, 1], state[i, 2], state[i, 3], state[i, 4], state[i, 5])
    box = (
        params[i, layout.HALF_LENGTH],
        params[i, layout.HALF_WIDTH],
        params[i, layout.MASS],
        params[i, layout.INERTIA],
    )
    material = SeedMaterial(
        params[i, layout.RESTITUTION], floor_friction(params[i, layout.FRICTION]), params[i, layout.STIFFNESS]
    )
    first_contact, rest_time, max_penetration, n_impacts = math.nan, math.nan, 0.0, 0
    status, fail_step, still_for, below_before = layout.STATUS_OK, -1, 0.0, 0
    if record:
        store_state(trajectory, 0, i, motion[0], motion[1], motion[2], motion[3], motion[4], motion[5])
    n = 0
    while n < settings.max_steps:
        motion, lowest_y, below = reference_step(motion, box, material, dt, settings.gravity, switches)
        if below != 0:
            if math.isnan(first_contact):
                first_contact = n * dt
            max_penetration = max(max_penetration, -lowest_y)
            if below & ~below_before:  # a corner newly below the floor: an impact
                if record:
                    record_event(events, i, n_impacts, n * dt, math.nan, 1)
                n_impacts += 1
        below_before = below
        n += 1
        x, y, angle, vx, vy, spin = motion
        if record:
            store_state(trajectory, n, i, x, y, angle, vx, vy, spin)
        if not is_finite_state(x, y, angle, vx, vy, spin):
            status = layout.STATUS_NONFINITE
            fail_step = n
            break
        if settings.until_rest:
            still_for, rests = rest_timer(
                is_lying_still(y, angle, vx, vy, spin, box[0], box[1], settings.sleep_speed),
                still_for,
                dt,
                settings.sleep_time,
            )
            if rests:
                rest_time = n * dt
                break
    state[i, 0], state[i, 1], state[i, 2], state[i, 3], state[i, 4], state[i, 5] = motion
    write_stats(stats, i, first_contact, n_impacts, n, max_penetration, rest_time, n * dt, status, fail_step, n + 1)


def make_reference_kernel(use_impulses: bool, use_penalty: bool, use_friction: bool, record: bool, source_digest: int):
    """Build the seed kernel for exactly the stages a scene uses (flags are compile-time).

    ``run(state, params, settings, stats, trajectory, events)`` advances every body in place for
    ``settings[MAX_STEPS]`` steps, or until it lies still on a face when ``settings[UNTIL_REST]``.
    """
    IMPULSES, PENALTY, FRICTION, RECORD, DIGEST = use_impulses, use_penalty, use_friction, record, source_digest

    @jit_kernel
    def run(state, params, settings, stats, trajectory, events):
        # numba keys its on-disk cache on this file and the closure values: the digest of every engine
        # source must be a closure value, or a kernel compiled with an older stage would be loaded
        _ = DIGEST
        context = seed_settings(settings)
        switches = SeedSwitches(IMPULSES, PENALTY, FRICTION)
        for i in range(state.shape[0]):
            advance_seed_box(i, state, params, stats, context, switches, RECORD, trajectory, events)

    return run
