"""How finely a grid step of the colliding solver is cut: the substep count that keeps every point's travel in one
substep within TUNNEL_FRACTION of the thinnest box (no tunnelling) and every turn within MAX_ROTATION_PER_STEP
(``substeps``, ``substep_count``), and what each body can travel in a time h (its reach: ``body_reach``), which
bounds the contacts and pairs a substep looks for.
"""

import math

import numpy as np

from ..compile.compilation import jit_stage
from ..tunables import MAX_ROTATION_PER_STEP, MAX_SUBSTEPS, TUNNEL_FRACTION


@jit_stage
def substeps(vel, radius, include, smallest_half, dt, gravity):
    """How many substeps a grid step needs for the included bodies (``substep_count`` for the fastest point
    speed |v| + |g| dt + |omega| R and turn rate among them)."""
    speed = 0.0
    turn = 0.0
    for b in range(vel.shape[0]):
        if not include[b]:
            continue
        speed = max(speed, point_speed(vel, radius, b, dt, gravity))
        turn = max(turn, abs(vel[b, 2]))
    return substep_count(speed, turn, smallest_half, dt)


@jit_stage(inline="always")
def point_speed(vel, radius, b, dt, gravity):
    """A bound on the speed of body b's points over a step dt: |v| + |g| dt + |omega| R."""
    return math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(gravity) * dt + abs(vel[b, 2]) * radius[b]


@jit_stage
def substep_count(speed, turn, smallest_half, dt):
    """How many substeps a grid step needs at point speed ``speed`` and turn rate ``turn``: no point moves further
    than TUNNEL_FRACTION of the smallest half extent, no box turns further than MAX_ROTATION_PER_STEP (at most
    MAX_SUBSTEPS)."""
    by_speed = math.ceil(2.0 * speed * dt / (TUNNEL_FRACTION * smallest_half))
    by_turn = math.ceil(turn * dt / MAX_ROTATION_PER_STEP)
    if not (by_speed < MAX_SUBSTEPS and by_turn < MAX_SUBSTEPS):  # also for a non-finite state
        return MAX_SUBSTEPS
    return max(max(np.int64(by_speed), np.int64(by_turn)), 1)


@jit_stage
def body_reach(vel, radius, awake, h, gravity, tolerance, reach):
    """What each awake body can travel in a time h, |v| h + |g| h^2 + |omega| R h (plus the contact
    tolerance), into ``reach`` (a sleeping body: the tolerance); returns the largest."""
    fastest = 0.0
    for b in range(vel.shape[0]):
        reach[b] = tolerance
        if awake[b]:
            reach[b] += travel(vel, radius, b, h, gravity)
            fastest = max(fastest, reach[b])
    return fastest


@jit_stage(inline="always")
def travel(vel, radius, b, h, gravity):
    """|v| h + |g| h^2 + |omega| R h: how far body b's points can travel in a time h (``body_reach``)."""
    return h * (math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(gravity) * h + abs(vel[b, 2]) * radius[b])
