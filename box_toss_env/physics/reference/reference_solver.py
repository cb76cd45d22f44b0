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

from .. import layout
from ..compile.compilation import jit_kernel, jit_stage
from ..kernel_support import (
    is_finite_state,
    is_lying_still,
    read_settings,
    record_event,
    rest_timer,
    store_state,
    write_stats,
)

TANGENT_NORMALISE_MIN = 1e-4  # the demo normalises u_t only above this length


@jit_stage(inline="always")
def corner_impulse(vx, vy, spin, rx, ry, nx, ny, un_x, un_y, tx, ty, mass, inertia, restitution, friction,
                   use_friction):
    """2.3-2.5 for a corner at lever arm r with normal velocity u_n and tangent t: the impulse
    p = (1 + e) p', p' = -u_n / (1/m + (r x n)^2 / I), with the friction impulse -mu |p| t added, applied
    at once (v += p/m, omega += (r x p)/I) if it pushes out of the floor (p . n > 0). Returns (vx, vy, spin)."""
    # 2.3 p' = -u_n / (1/m + (r x n)^2 / I), p = (1 + e) p'
    r_cross_n = rx * ny - ry * nx
    inv_mass_eff = 1.0 / mass + r_cross_n * r_cross_n / inertia
    px = (1.0 + restitution) * (-un_x / inv_mass_eff)
    py = (1.0 + restitution) * (-un_y / inv_mass_eff)
    if use_friction:
        # 2.5 p_friction = -mu |p| t, added before the test of 2.4
        p_len = math.sqrt(px * px + py * py)
        px = px - friction * p_len * tx
        py = py - friction * p_len * ty
    # 2.4 apply only if the impulse pushes out of the floor
    if px * nx + py * ny > 0.0:
        vx = vx + px / mass
        vy = vy + py / mass
        spin = spin + (rx * py - ry * px) / inertia
    return vx, vy, spin


@jit_stage(inline="always")
def penalty_force(depth, rx, ry, nx, ny, tx, ty, stiffness, friction, use_friction):
    """3. The penalty force of a corner ``depth`` below the floor, f_n = k d n, with its friction
    f_friction = -mu |f_n| t. Returns (f_x, f_y, its torque r x f)."""
    fn_x = stiffness * depth * nx
    fn_y = stiffness * depth * ny
    f_x = fn_x
    f_y = fn_y
    if use_friction:
        fn_len = math.sqrt(fn_x * fn_x + fn_y * fn_y)
        f_x = fn_x - friction * fn_len * tx
        f_y = fn_y - friction * fn_len * ty
    return f_x, f_y, rx * f_y - ry * f_x


@jit_stage(inline="always")
def reference_step(x, y, angle, vx, vy, spin, half_length, half_width, mass, inertia, restitution,
              friction, stiffness, dt, gravity, use_impulses, use_penalty, use_friction):
    """One step of the seed scheme for one box (this module's docstring, 1.-4.). Returns the new state,
    the lowest corner height before the step and a bit mask of the corners that were below the floor."""
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
        # 2.1 point velocity u = v + omega x r, with omega x r = (-omega r_y, omega r_x)
        ux = vx - spin * ry
        uy = vy + spin * rx
        # 2.2 normal and tangential parts
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
        if use_impulses:
            # 2.3-2.5 the corner's impulse, applied at once
            vx, vy, spin = corner_impulse(vx, vy, spin, rx, ry, nx, ny, un_x, un_y, tx, ty, mass, inertia,
                                          restitution, friction, use_friction)
        if use_penalty:
            # 3. f_n = k d n, f_friction = -mu |f_n| t, tau += r x (f_n + f_friction)
            f_x, f_y, corner_torque = penalty_force(-corner_y, rx, ry, nx, ny, tx, ty, stiffness, friction,
                                                    use_friction)
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
    return x, y, angle, vx, vy, spin, lowest_y, below


@jit_stage(inline="always")
def advance_seed_box(i, state, params, stats, dt, gravity, max_steps, until_rest, sleep_speed, sleep_time,
                     use_impulses, use_penalty, use_friction, record, trajectory, events):
    """Box i by the seed scheme (``reference_step``) for ``max_steps`` steps, or until it has lain still on a face
    for ``sleep_time`` when ``until_rest``, or until its state stops being finite; its state and stats written
    back. A corner newly below the floor is an impact."""
    x, y, angle, vx, vy, spin = (state[i, 0], state[i, 1], state[i, 2],
                                 state[i, 3], state[i, 4], state[i, 5])
    hx = params[i, layout.HALF_LENGTH]
    hy = params[i, layout.HALF_WIDTH]
    mass = params[i, layout.MASS]
    inertia = params[i, layout.INERTIA]
    first_contact = math.nan
    rest_time = math.nan
    max_penetration = 0.0
    n_impacts = 0
    status = layout.STATUS_OK
    fail_step = -1
    still_for = 0.0
    below_before = 0
    if record:
        store_state(trajectory, 0, i, x, y, angle, vx, vy, spin)
    n = 0
    while n < max_steps:
        x, y, angle, vx, vy, spin, lowest_y, below = reference_step(
            x, y, angle, vx, vy, spin, hx, hy, mass, inertia,
            params[i, layout.RESTITUTION], params[i, layout.FRICTION], params[i, layout.STIFFNESS],
            dt, gravity, use_impulses, use_penalty, use_friction)
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
        if record:
            store_state(trajectory, n, i, x, y, angle, vx, vy, spin)
        if not is_finite_state(x, y, angle, vx, vy, spin):
            status = layout.STATUS_NONFINITE
            fail_step = n
            break
        if until_rest:
            still_for, rests = rest_timer(is_lying_still(y, angle, vx, vy, spin, hx, hy, sleep_speed), still_for,
                                          dt, sleep_time)
            if rests:
                rest_time = n * dt
                break
    state[i, 0], state[i, 1], state[i, 2] = x, y, angle
    state[i, 3], state[i, 4], state[i, 5] = vx, vy, spin
    write_stats(stats, i, first_contact, n_impacts, n, max_penetration, rest_time, n * dt,
                status, fail_step, n + 1)


def make_reference_kernel(use_impulses: bool, use_penalty: bool, use_friction: bool, record: bool,
                     source_digest: int):
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
        dt, gravity, max_steps, until_rest, _, sleep_speed, sleep_time, _ = read_settings(settings)
        for i in range(state.shape[0]):
            advance_seed_box(i, state, params, stats, dt, gravity, max_steps, until_rest, sleep_speed, sleep_time,
                             IMPULSES, PENALTY, FRICTION, RECORD, trajectory, events)

    return run
