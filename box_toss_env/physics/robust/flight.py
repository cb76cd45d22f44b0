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
from .restitution import resolve_impact

MAX_ADVANCE_ITERATIONS = 100_000  # a grazing approach past this many steps is handed to stepping


@jit_stage
def flight_state(x, y, angle, vx, vy, spin, gravity, tau):
    """The state a time ``tau`` after (x, y, angle, vx, vy, spin), in free flight."""
    return (x + vx * tau, y + vy * tau + 0.5 * gravity * tau * tau, angle + spin * tau,
            vx, vy + gravity * tau, spin)


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
def fly(i, x, y, angle, vx, vy, spin, hx, hy, gravity, t, n, n_end, dt, tolerance, record, trajectory):
    """Flight in closed form from time t (grid step n) to the first contact with the floor or to grid step
    ``n_end``, whichever comes first, the grid rows passed recorded. Returns the state there, the time flown,
    whether a corner touched, and the last grid row the flight passed."""
    end_time = n_end * dt
    tau, touched = time_to_contact(y, angle, vy, spin, hx, hy, gravity, end_time - t, tolerance, 0.0)
    # grid rows passed in this flight: up to the end, or to the last one before the contact
    last = n_end if not touched else min(np.int64(math.floor((t + tau) / dt)), n_end)
    if record:
        for row in range(n + 1, last + 1):
            xr, yr, ar, vxr, vyr, wr = flight_state(x, y, angle, vx, vy, spin, gravity, row * dt - t)
            store_state(trajectory, row, i, xr, yr, ar, vxr, vyr, wr)
    x, y, angle, vx, vy, spin = flight_state(x, y, angle, vx, vy, spin, gravity, tau)
    return x, y, angle, vx, vy, spin, tau, touched, last


@jit_stage(inline="always")
def fly_to_impact(i, x, y, angle, vx, vy, spin, box, gravity, t, n, n_end, dt, tolerance, simultaneous, threshold,
                  first_contact, n_impacts, record, trajectory, events, corners, k):
    """Flight in closed form from time t (grid step n) to the first contact (``fly``) and the impact there
    (``resolve_impact``), or to grid step ``n_end``. Returns (x, y, angle, vx, vy, spin, cos, sin, t, n, first
    contact, impacts, in flight, whether to go on, status, failed step): a box that leaves the floor flies on; one
    that stays is brought back onto the grid, its contact step of (n + 1) dt - t next (unless ``n_end`` is
    reached); ``box``: (hx, hy, 1/m, 1/I, e, mu, k, radius)."""
    hx, hy, inv_mass, inv_inertia, restitution, friction, _, _ = box
    x, y, angle, vx, vy, spin, tau, touched, last = fly(i, x, y, angle, vx, vy, spin, hx, hy, gravity, t, n, n_end,
                                                        dt, tolerance, record, trajectory)
    cos_a = math.cos(angle)
    sin_a = math.sin(angle)
    if not touched:
        n = n_end
        failed = not is_finite_state(x, y, angle, vx, vy, spin)
        return (x, y, angle, vx, vy, spin, cos_a, sin_a, n_end * dt, n, first_contact, n_impacts, True, False,
                layout.STATUS_NONFINITE if failed else layout.STATUS_OK, n if failed else -1)
    t = t + tau
    if math.isnan(first_contact):
        first_contact = t
    vx, vy, spin, touching, approach, leaves = resolve_impact(
        y, cos_a, sin_a, vx, vy, spin, hx, hy, inv_mass, inv_inertia, restitution,
        friction, threshold, simultaneous, corners, k)
    if touching > 0 and approach > threshold:
        if record:
            record_event(events, i, n_impacts, t, approach, touching)
        n_impacts += 1
    if not is_finite_state(x, y, angle, vx, vy, spin):
        return (x, y, angle, vx, vy, spin, cos_a, sin_a, t, n, first_contact, n_impacts, True, False,
                layout.STATUS_NONFINITE, np.int64(math.floor(t / dt)))
    n = max(n, last)  # rows up to n hold the flight
    if not leaves:
        if (n + 1) * dt <= t and n < n_end:  # the contact fell on grid point n + 1
            n += 1
            if record:
                store_state(trajectory, n, i, x, y, angle, vx, vy, spin)
        if n >= n_end:
            t = n_end * dt
    return (x, y, angle, vx, vy, spin, cos_a, sin_a, t, n, first_contact, n_impacts, leaves, leaves or n < n_end,
            layout.STATUS_OK, -1)

