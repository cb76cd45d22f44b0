"""Free flight in closed form, and the time of the first floor contact.

Between contacts a box under gravity g (along y) follows
    x(t) = x0 + vx t,  y(t) = y0 + vy t + g t^2 / 2,  alpha(t) = alpha0 + omega t,
exactly, so the robust solver does not time-step a flight: it finds when the lowest corner
reaches y = 0 and jumps there (``time_to_contact``, conservative advancement, so no contact is skipped
however fast the box moves: no tunnelling), recording the grid rows it passes (``fly``), and resolves the
impact at that instant (``fly_to_impact``, with ``restitution.resolve_impact``): the flight mode of
``robust_solver.advance_box``.
"""

import math

import numpy as np

from .. import layout
from ..compile.compilation import jit_stage
from ..geometry import vertex_offset
from ..kernel_support import is_finite_state, record_event, store_state
from ..tunables import MAX_ADVANCE_ITERATIONS
from .memory import Tally
from .restitution import resolve_impact
from .state import Motion


@jit_stage
def flight_state(x, y, angle, vx, vy, spin, gravity, tau):
    """The state a time ``tau`` after (x, y, angle, vx, vy, spin), in free flight."""
    return (x + vx * tau, y + vy * tau + 0.5 * gravity * tau * tau, angle + spin * tau, vx, vy + gravity * tau, spin)


@jit_stage
def safe_flight_time(height, speed, bound):
    """Largest tau for which a corner at ``height`` >= 0 with vertical speed ``speed`` provably
    stays above the floor, given that its vertical acceleration is >= -``bound``.

    The corner's height is at least the parabola height + speed tau - bound tau^2 / 2; tau is
    that parabola's positive root, written without cancellation.
    """
    root = math.sqrt(speed * speed + 2.0 * bound * height)
    if speed <= 0.0:
        denominator = root - speed
        return 2.0 * height / denominator if denominator > 0.0 else math.inf
    return (speed + root) / bound if bound > 0.0 else math.inf


@jit_stage
def time_to_contact(y, angle, vy, spin, half_length, half_width, gravity, horizon, tolerance, resolution):
    """First time tau in [0, horizon] at which a corner touches the floor, by conservative
    advancement on the lowest corners. Returns (tau, touched).

    A corner k of a flying box has height y_k(t) = y(t) + r_k,y(t); its vertical acceleration
    is g - omega^2 r_k,y >= -(max(-g, 0) + omega^2 R) = -A, with R = sqrt(hx^2 + hy^2) the
    corner radius. From the current heights and speeds, every corner is above the floor for at
    least ``safe_flight_time(y_k, u_k, A)``; stepping by the smallest of these never skips a
    contact, and the steps shrink quadratically as a corner closes in (the bound is exact to
    first order). Stops when a corner is within ``tolerance`` of y = 0 and not separating, or
    below the floor by more than ``tolerance`` (a box started inside it). With ``resolution`` > 0 it
    also stops, not touched, once a step is shorter than that: the contact is no earlier than the tau
    returned. A caller that needs only a lower bound passes one, since a box lying on the floor with a
    separating speed of 1e-200 m/s would otherwise take MAX_ADVANCE_ITERATIONS steps of 1e-200 s.
    """
    radius = math.sqrt(half_length * half_length + half_width * half_width)
    bound = max(-gravity, 0.0) + spin * spin * radius
    tau = 0.0
    for _ in range(MAX_ADVANCE_ITERATIONS):
        height_centre = y + vy * tau + 0.5 * gravity * tau * tau
        speed_centre = vy + gravity * tau
        cos_a = math.cos(angle + spin * tau)
        sin_a = math.sin(angle + spin * tau)
        step = math.inf
        for k in range(4):
            rx, ry = vertex_offset(k, cos_a, sin_a, half_length, half_width)
            height = height_centre + ry
            speed = speed_centre + spin * rx
            if height < -tolerance or (height <= tolerance and speed <= 0.0):
                return tau, True
            step = min(step, safe_flight_time(max(height, 0.0), speed, bound))
        if tau + step >= horizon:
            return horizon, False
        if step < resolution:
            return tau, False
        tau += step
    return tau, True


@jit_stage(inline="always")
def fly(i, motion, box, settings, t, n, n_end, trajectory):
    """Flight in closed form from time t (grid step n) to the first contact with the floor or to grid step
    ``n_end``, whichever comes first, the grid rows passed recorded. Returns the motion there, the time flown,
    whether a corner touched, and the last grid row the flight passed."""
    dt, gravity = settings.dt, settings.gravity
    x, y, angle, vx, vy, spin = motion.x, motion.y, motion.angle, motion.vx, motion.vy, motion.spin
    end_time = n_end * dt
    tau, touched = time_to_contact(y, angle, vy, spin, box.hx, box.hy, gravity, end_time - t, box.tolerance, 0.0)
    # grid rows passed in this flight: up to the end, or to the last one before the contact
    last = n_end if not touched else min(np.int64(math.floor((t + tau) / dt)), n_end)
    if settings.record:
        for row in range(n + 1, last + 1):
            xr, yr, ar, vxr, vyr, wr = flight_state(x, y, angle, vx, vy, spin, gravity, row * dt - t)
            store_state(trajectory, row, i, xr, yr, ar, vxr, vyr, wr)
    x, y, angle, vx, vy, spin = flight_state(x, y, angle, vx, vy, spin, gravity, tau)
    return Motion(x, y, angle, vx, vy, spin, math.cos(angle), math.sin(angle)), tau, touched, last


@jit_stage(inline="always")
def fly_to_impact(i, motion, box, settings, t, n, n_end, tally, recording, work):
    """Flight in closed form from time t (grid step n) to the first contact (``fly``) and the impact there
    (``resolve_impact``), or to grid step ``n_end``. Returns (motion, t, n, tally, in flight, whether to go on,
    status, failed step): a box that leaves the floor flies on; one that stays is brought back onto the grid, its
    contact step of (n + 1) dt - t next (unless ``n_end`` is reached)."""
    dt = settings.dt
    first_contact, n_impacts, max_penetration, n_steps = tally
    motion, tau, touched, last = fly(i, motion, box, settings, t, n, n_end, recording.trajectory)
    if not touched:
        failed = not is_finite_state(motion.x, motion.y, motion.angle, motion.vx, motion.vy, motion.spin)
        return (
            motion,
            n_end * dt,
            n_end,
            tally,
            True,
            False,
            layout.STATUS_NONFINITE if failed else layout.STATUS_OK,
            n_end if failed else -1,
        )
    t = t + tau
    if math.isnan(first_contact):
        first_contact = t
    vx, vy, spin, touching, approach, leaves = resolve_impact(motion, box, settings.threshold, work)
    motion = Motion(motion.x, motion.y, motion.angle, vx, vy, spin, motion.cos_a, motion.sin_a)
    if touching > 0 and approach > settings.threshold:
        if settings.record:
            record_event(recording.events, i, n_impacts, t, approach, touching)
        n_impacts += 1
    tally = Tally(first_contact, n_impacts, max_penetration, n_steps)
    if not is_finite_state(motion.x, motion.y, motion.angle, vx, vy, spin):
        return motion, t, n, tally, True, False, layout.STATUS_NONFINITE, np.int64(math.floor(t / dt))
    n = max(n, last)  # rows up to n hold the flight
    if not leaves:
        if (n + 1) * dt <= t and n < n_end:  # the contact fell on grid point n + 1
            n += 1
            if settings.record:
                store_state(recording.trajectory, n, i, motion.x, motion.y, motion.angle, vx, vy, spin)
        if n >= n_end:
            t = n_end * dt
    return motion, t, n, tally, leaves, leaves or n < n_end, layout.STATUS_OK, -1
