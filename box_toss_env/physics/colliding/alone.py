"""Bodies advanced alone against the floor (the "alone" stage of ``step``'s script): how many whole
steps every awake body can take with the floor-only solver before two boxes could meet (``steps_alone``, by
the exact parabolas or by an energy bound, ``energy_speed``; none while two boxes' bounds touch,
``bounds_touch``), and those steps (``advance_alone``, ``robust_solver.advance_box``).
"""

import math

import numpy as np

from .. import layout
from ..compile.compilation import jit_stage
from ..kernel_support import store_state
from ..robust.flight import time_to_contact
from ..robust.memory import (
    FIRST_CONTACT,
    IN_FLIGHT,
    MAX_PENETRATION,
    N_IMPACTS,
    N_STEPS,
    REST_TIME,
    STATUS,
    STILL_FOR,
    start_memory,
)
from ..robust.robust_solver import advance_box
from ..robust.state import FloorSettings, Recording
from ..tunables import ALONE_LOWEST
from .broadphase import box_bound, time_apart
from .prepare import body_kinetic_energy


@jit_stage
def energy_speed(vel, b, params, y, gravity):
    """A bound on the speed of every point of body b from now on, while it meets only the floor:
    sqrt(2 E (1/m + R^2 / I)) with E its kinetic energy plus m |g| (y - ALONE_LOWEST min(hx, hy)), the
    potential energy it can give up before its centre reaches that height. By Cauchy-Schwarz
    (|v| + |omega| R)^2 <= (m |v|^2 + I omega^2) (1/m + R^2 / I), and the floor's contacts never add energy
    (``robust_solver``: impulses, the energy limit and the penalty's energy all take, never give)."""
    mass = params[b, layout.MASS]
    half = min(params[b, layout.HALF_LENGTH], params[b, layout.HALF_WIDTH])
    energy = body_kinetic_energy(vel, b, params) + mass * abs(gravity) * max(y - ALONE_LOWEST * half, 0.0)
    radius2 = params[b, layout.HALF_LENGTH] ** 2 + params[b, layout.HALF_WIDTH] ** 2
    return math.sqrt(2.0 * energy * (1.0 / mass + radius2 / params[b, layout.INERTIA]))


@jit_stage
def bounds_touch(pose, half, radius, awake):
    """Whether the bounding box of an awake box touches or overlaps another box's (``broadphase.time_apart``'s gap
    max(|dx| - b_x - b'_x, |dy| - b_y - b'_y) <= 0 now; the boxes' circles first, which hold their bounds)."""
    n = pose.shape[0]
    for b in range(n):
        if not awake[b]:
            continue
        bx, by = box_bound(math.cos(pose[b, 2]), math.sin(pose[b, 2]), half[b, 0], half[b, 1])
        for o in range(n):
            if o == b:
                continue
            dx, dy = abs(pose[o, 0] - pose[b, 0]), abs(pose[o, 1] - pose[b, 1])
            if max(dx, dy) > radius[b] + radius[o]:
                continue
            ox, oy = box_bound(math.cos(pose[o, 2]), math.sin(pose[o, 2]), half[o, 0], half[o, 1])
            if max(dx - bx - ox, dy - by - oy) <= 0.0:
                return True
    return False


@jit_stage
def steps_alone(bodies, sleep, context, steps_left):
    """How many whole time steps every awake body can be advanced alone against the floor
    (``robust_solver.advance_box``: flight in closed form, impacts located in time) before any two boxes could
    meet; the larger of two safe counts:
      - flight: no awake body touches the floor (``flight.time_to_contact``) and each stays apart from every
        other box on the exact parabolas (``broadphase.time_apart``), the steps a thrown box flies;
      - energy: every body stays within its circumscribed circle (radius R) of its centre, and no point moves
        faster than ``energy_speed``, so the gap max(|dx| - R - b'_x, |dy| - R - b'_y) between an awake box's
        circle and another box's bounds (its circle if awake, its box if asleep) closes no faster than the
        sum of their speed bounds: a box bouncing or sliding on the floor far from the others.
    Both give none while an awake box's bounding box touches another's (``bounds_touch``), which is asked first:
    a box resting on another costs no search."""
    pose, vel, half, radius, params, awake = (
        bodies.pose,
        bodies.vel,
        bodies.half,
        bodies.radius,
        bodies.params,
        sleep.awake,
    )
    dt, gravity, tolerance = context.dt, context.gravity, context.tolerance
    if bounds_touch(pose, half, radius, awake):
        return 0
    horizon = steps_left * dt
    flight = horizon
    for b in range(pose.shape[0]):
        if awake[b]:
            tau, _ = time_to_contact(
                pose[b, 1],
                pose[b, 2],
                vel[b, 1],
                vel[b, 2],
                half[b, 0],
                half[b, 1],
                gravity,
                flight,
                tolerance,
                0.25 * dt,
            )
            flight = min(flight, tau)
            if flight < dt:
                break
            flight = min(flight, time_apart(b, pose, vel, half, radius, awake, gravity, flight, 0.25 * dt))
            if flight < dt:
                break
    energy = horizon
    if flight < horizon:
        for b in range(pose.shape[0]):
            if not awake[b]:
                continue
            speed_b = energy_speed(vel, b, params, pose[b, 1], gravity)
            for o in range(pose.shape[0]):
                if o == b or (awake[o] and o < b):  # a pair of awake boxes once
                    continue
                speed = speed_b
                if awake[o]:
                    ox = oy = radius[o]
                    speed += energy_speed(vel, o, params, pose[o, 1], gravity)
                else:
                    ox, oy = box_bound(math.cos(pose[o, 2]), math.sin(pose[o, 2]), half[o, 0], half[o, 1])
                gap = max(abs(pose[o, 0] - pose[b, 0]) - radius[b] - ox, abs(pose[o, 1] - pose[b, 1]) - radius[b] - oy)
                if gap <= speed * dt:
                    return np.int64(math.floor(flight / dt))
                if speed > 0.0:
                    energy = min(energy, gap / speed)
    return min(np.int64(math.floor(max(flight, energy) / dt)), steps_left)


@jit_stage
def advance_alone(k, n, context, bodies, sleep, stats, work):
    """Every awake body advanced alone against the floor for k grid steps from step n
    (``robust_solver.advance_box``, its memory row carried on while the body stays alone: ``work.alone``), a body
    that falls asleep on the floor taking an island of its own; the trajectory rows of the others filled.
    ``work``: ``state.AloneWork``. Returns (the step reached, the number of bodies that fell asleep, the failing body
    or -1)."""
    awake, rest_time = sleep.awake, sleep.rest_time
    settings = FloorSettings(
        context.dt,
        context.gravity,
        context.sleeping,
        context.threshold,
        context.sleep_speed,
        context.sleep_time,
        context.slop,
        context.use_penalty,
        context.use_friction,
        context.record,
    )
    recording = Recording(stats.trajectory, stats.events)
    reached = n
    slept = 0
    for b in range(bodies.pose.shape[0]):
        if not awake[b]:
            continue
        end = advance_one_alone(b, k, n, bodies, stats, work, settings, recording)
        sleep.still_for[b] = work.memory[b, STILL_FOR]
        if work.memory[b, STATUS] != layout.STATUS_OK:
            return end, slept, b
        if not math.isnan(work.memory[b, REST_TIME]):
            awake[b] = False
            work.alone[b] = False  # woken later, it starts a new memory row
            sleep.island[b] = b
            rest_time[b] = work.memory[b, REST_TIME]
            slept += 1
        reached = max(reached, end)
    if slept > 0 and count_awake(awake) == 0:
        k = reached - n  # every body sleeps: the run ends where the last fell asleep
    if context.record:
        fill_resting_rows(bodies.pose, awake, rest_time, n, k, context.dt, stats.trajectory)
    return n + k, slept, -1


@jit_stage(inline="always")
def advance_one_alone(b, k, n, bodies, stats, work, settings, recording):
    """Body b advanced alone for k grid steps from step n (``advance_box``), its stats carried into and out of its
    memory row (a body the colliding substeps moved starts a new row from their state). Returns the step reached."""
    memory, pose, vel = work.memory, bodies.pose, bodies.vel
    if not work.alone[b]:
        start_memory(memory, b, n * settings.dt)
        memory[b, IN_FLIGHT] = 0.0 if stats.supported[b] else 1.0
        memory[b, N_IMPACTS] = stats.n_impacts[b]
        memory[b, N_STEPS] = stats.n_stepped[b]
        memory[b, FIRST_CONTACT] = stats.first_contact[b]
        memory[b, MAX_PENETRATION] = stats.max_penetration[b]
        work.alone[b] = True
    for c in range(3):
        work.state[b, c] = pose[b, c]
        work.state[b, 3 + c] = vel[b, c]
    end = advance_box(b, work.state, bodies.params, memory, n, n + k, settings, work.corners, recording)
    for c in range(3):
        pose[b, c] = work.state[b, c]
        vel[b, c] = work.state[b, 3 + c]
    stats.n_impacts[b] = np.int64(memory[b, N_IMPACTS])
    stats.n_stepped[b] = np.int64(memory[b, N_STEPS])
    stats.first_contact[b] = memory[b, FIRST_CONTACT]
    stats.max_penetration[b] = memory[b, MAX_PENETRATION]
    return end


@jit_stage(inline="always")
def fill_resting_rows(pose, awake, rest_time, n, k, dt, trajectory):
    """The trajectory rows n + 1 to n + k of the bodies asleep: those that fell asleep in these steps from their
    rest on (``advance_box`` recorded them up to it), the others all."""
    for b in range(pose.shape[0]):
        first = n + 1
        if not awake[b] and not math.isnan(rest_time[b]) and rest_time[b] > n * dt:
            first = np.int64(round(rest_time[b] / dt)) + 1  # advance_box recorded it up to its rest
        elif awake[b]:
            continue
        for row in range(first, n + k + 1):
            store_state(trajectory, row, b, pose[b, 0], pose[b, 1], pose[b, 2], 0.0, 0.0, 0.0)


@jit_stage
def count_awake(awake):
    count = 0
    for b in range(awake.shape[0]):
        count += awake[b]
    return count
