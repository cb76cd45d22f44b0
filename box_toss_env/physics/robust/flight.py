"""Free flight in closed form, and the time of the first floor contact.

Between contacts a box under gravity g (along y) follows
    x(t) = x0 + vx t,  y(t) = y0 + vy t + g t^2 / 2,  alpha(t) = alpha0 + omega t,
exactly, so the robust solver does not time-step a flight: it finds when the lowest corner
reaches y = 0 and jumps there.
"""

import math

from ..compile.compilation import jit_stage
from ..geometry import vertex_offset

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

