"""How finely a grid step of the colliding solver is cut: the substep count that keeps the travel of every point
relative to what it can touch within TUNNEL_FRACTION of the thinnest box's half extent in one substep (no
tunnelling) and every turn within MAX_ROTATION_PER_STEP (``substep_count``): a bound before the step's pairs are
known (``substeps``), and each body's relative speed once they are (``contact_speeds``); and what each body can travel
in a time h (its reach: ``body_reach``), which bounds the contacts and pairs a substep looks for.
"""

import math

import numpy as np

from ..compile.compilation import jit_stage
from ..tunables import MAX_ROTATION_PER_STEP, MAX_SUBSTEPS, TUNNEL_FRACTION


@jit_stage
def substeps(vel, radius, include, smallest_half, dt, gravity):
    """How many substeps a grid step needs for the included bodies at most, before its pairs are known
    (``substep_count`` for twice the fastest point speed |v| + |g| dt + |omega| R among them, two such points
    meeting head on, and the fastest turn rate). ``contact_speeds`` gives the count once the pairs are known, never
    more than this one."""
    speed = 0.0
    turn = 0.0
    for b in range(vel.shape[0]):
        if not include[b]:
            continue
        speed = max(speed, point_speed(vel, radius, b, dt, gravity))
        turn = max(turn, abs(vel[b, 2]))
    return substep_count(2.0 * speed, turn, smallest_half, dt)


@jit_stage(inline="always")
def point_speed(vel, radius, b, dt, gravity):
    """A bound on the speed of body b's points over a step dt: |v| + |g| dt + |omega| R."""
    return math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(gravity) * dt + abs(vel[b, 2]) * radius[b]


@jit_stage
def substep_count(speed, turn, smallest_half, dt):
    """How many substeps a grid step needs at relative point speed ``speed`` (of a point against what it can touch)
    and turn rate ``turn``: no point moves further than TUNNEL_FRACTION of the smallest half extent relative to what
    it can touch, no box turns further than MAX_ROTATION_PER_STEP (at most MAX_SUBSTEPS)."""
    by_speed = math.ceil(speed * dt / (TUNNEL_FRACTION * smallest_half))
    by_turn = math.ceil(turn * dt / MAX_ROTATION_PER_STEP)
    if not (by_speed < MAX_SUBSTEPS and by_turn < MAX_SUBSTEPS):  # also for a non-finite state
        return MAX_SUBSTEPS
    return max(max(np.int64(by_speed), np.int64(by_turn)), 1)


@jit_stage
def contact_speeds(bodies, sweep, awake, n_pairs, dt, gravity, speed_turn):
    """Into ``speed_turn``, each awake body's fastest point speed relative to what it can touch within the step dt and
    its turn rate |omega|, which set its substeps (``substep_count``); returns the fastest of each. What it can touch:
    the floor, where its box at its reach (``sweep.bound``, ``sweep.reach``, as the step's pair search left them)
    meets y = 0, at its point speed s = |v| + |g| dt + |omega| R; and the boxes of its candidate pairs (``sweep.pairs``,
    the first ``n_pairs``), at s_i + s_j - |g| dt: either box may be stopped, or bounce back (no faster than it came),
    within the step, and gravity pulls both alike but for one held up. A body that can touch nothing in the step: 0
    (it flies). Before, every body counted twice the fastest point speed of the scene: a box thrown at 100 m/s into a
    resting pile took 32 substeps, not 16, and resting boxes of a millimetre 3, not 2. Pairs counted at their relative
    speed |v_i - v_j| (or either's own) instead left the tiny boxes' drop 2.6 um deep, not 1.1 um: boxes falling side
    by side, one bouncing off the floor into the other."""
    vel, radius, pose = bodies.vel, bodies.radius, bodies.pose
    bound, reach, keys = sweep.bound, sweep.reach, sweep.pairs
    n, fall = vel.shape[0], abs(gravity) * dt
    for b in range(n):
        touches_floor = awake[b] and pose[b, 1] - bound[b, 1] <= reach[b]
        speed_turn[b, 0] = point_speed(vel, radius, b, dt, gravity) if touches_floor else 0.0
        speed_turn[b, 1] = abs(vel[b, 2])
    for p in range(n_pairs):
        i = keys[p] // n
        j = keys[p] - i * n
        speed = point_speed(vel, radius, i, dt, gravity) + point_speed(vel, radius, j, dt, gravity) - fall
        speed_turn[i, 0] = max(speed_turn[i, 0], speed)
        speed_turn[j, 0] = max(speed_turn[j, 0], speed)
    fastest, turn = 0.0, 0.0
    for b in range(n):
        if awake[b]:
            fastest, turn = max(fastest, speed_turn[b, 0]), max(turn, speed_turn[b, 1])
    return fastest, turn


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
