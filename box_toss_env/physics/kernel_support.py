"""Small pieces every kernel shares: the rest test and the sleep timer, the finite test, and writing results into
the output arrays."""

import math

import numpy as np

from . import layout
from .compile.compilation import cache_location, jit_stage
from .geometry import lowest_face, vertex_offset
from .tunables import FLAT_TOLERANCE, TOUCH_TOLERANCE


@jit_stage
def lies_still(y, ry1, ry2, rx1, rx2, vx, vy, spin, half_length, half_width, sleep_speed):
    """True when the box lies on a face (the face's corners level within FLAT_TOLERANCE and touching
    the floor) and every point of it moves slower than ``sleep_speed``:
    |v| <= s and |omega| sqrt(hx^2 + hy^2) <= s."""
    if vx * vx + vy * vy > sleep_speed * sleep_speed:
        return False
    if spin * spin * (half_length * half_length + half_width * half_width) > sleep_speed * sleep_speed:
        return False
    if y + min(ry1, ry2) > TOUCH_TOLERANCE * (half_length + half_width):
        return False
    return abs(ry2 - ry1) <= FLAT_TOLERANCE * math.sqrt((rx2 - rx1) ** 2 + (ry2 - ry1) ** 2)


@jit_stage(inline="always")
def lies_still_at(y, cos_a, sin_a, vx, vy, spin, half_length, half_width, sleep_speed):
    """``lies_still`` for a box whose angle has cosine ``cos_a`` and sine ``sin_a``."""
    first, second = lowest_face(cos_a, sin_a, half_length, half_width)
    rx1, ry1 = vertex_offset(first, cos_a, sin_a, half_length, half_width)
    rx2, ry2 = vertex_offset(second, cos_a, sin_a, half_length, half_width)
    return lies_still(y, ry1, ry2, rx1, rx2, vx, vy, spin, half_length, half_width, sleep_speed)


@jit_stage
def is_lying_still(y, angle, vx, vy, spin, half_length, half_width, sleep_speed):
    """``lies_still`` for a box at ``angle``."""
    return lies_still_at(y, math.cos(angle), math.sin(angle), vx, vy, spin, half_length, half_width, sleep_speed)


@jit_stage(inline="always")
def rest_timer(still, still_for, h, sleep_time):
    """The sleep timer of a step of length h: how long the body (or the scene) has been still, ``still_for`` + h
    if ``still`` else 0, and whether that reaches ``sleep_time`` (it rests). Returns (still for, rests)."""
    if not still:
        return 0.0, False
    still_for += h
    return still_for, still_for >= sleep_time


@jit_stage(inline="always")
def is_finite_state(x, y, angle, vx, vy, spin):
    """Whether every coordinate of the state is finite."""
    return (
        math.isfinite(x)
        and math.isfinite(y)
        and math.isfinite(angle)
        and math.isfinite(vx)
        and math.isfinite(vy)
        and math.isfinite(spin)
    )


@jit_stage
def read_settings(settings):
    """The scene-wide settings array as (dt, gravity, max_steps, until_rest, restitution_threshold,
    sleep_speed, sleep_time, penetration_slop); the colliding solver reads its two more itself
    (``colliding.solve.solver_settings``)."""
    return (
        settings[layout.DT],
        settings[layout.GRAVITY],
        np.int64(settings[layout.MAX_STEPS]),
        settings[layout.UNTIL_REST] != 0.0,
        settings[layout.RESTITUTION_THRESHOLD],
        settings[layout.SLEEP_SPEED],
        settings[layout.SLEEP_TIME],
        settings[layout.PENETRATION_SLOP],
    )


@jit_stage
def store_state(trajectory, row, body, x, y, angle, vx, vy, spin):
    trajectory[row, body, 0] = x
    trajectory[row, body, 1] = y
    trajectory[row, body, 2] = angle
    trajectory[row, body, 3] = vx
    trajectory[row, body, 4] = vy
    trajectory[row, body, 5] = spin


@jit_stage
def record_event(events, body, index, time, approach_speed, n_contacts):
    if index < events.shape[1]:
        events[body, index, layout.EVENT_TIME] = time
        events[body, index, layout.EVENT_APPROACH_SPEED] = approach_speed
        events[body, index, layout.EVENT_CONTACTS] = n_contacts


@jit_stage
def write_stats(
    stats, body, first_contact, n_impacts, n_steps, max_penetration, rest_time, end_time, status, fail_step, n_recorded
):
    stats[body, layout.FIRST_CONTACT_TIME] = first_contact
    stats[body, layout.N_IMPACTS] = n_impacts
    stats[body, layout.N_STEPS] = n_steps
    stats[body, layout.MAX_PENETRATION] = max_penetration
    stats[body, layout.REST_TIME] = rest_time
    stats[body, layout.END_TIME] = end_time
    stats[body, layout.STATUS] = status
    stats[body, layout.FAIL_STEP] = fail_step
    stats[body, layout.N_RECORDED] = n_recorded


def engine_cache_location() -> str | None:
    """The directory numba caches the engine's compiled code in (None: compiled in memory only)."""
    return cache_location(write_stats)
