"""The robust default solver: the seed's ingredients (impulses with restitution, Coulomb
friction, a penalty for penetration, symplectic Euler), arranged so they stay right.

A box is in one of two modes; ``advance_box`` is the script that runs them, a module a stage.

Flight (``flight``): no stepping at all. The motion is the closed-form parabola with constant spin,
and conservative advancement finds the first time a corner reaches y = 0, so flights and bounces are
exact whatever the time step and however fast the box moves (no tunnelling). At that instant an
impact is resolved (``restitution.resolve_impact``): the touching corners together, compression then
restitution (Poisson: e times the compression impulse, which is Newton's u_n+ = -e u_n- for one
frictionless corner and never creates energy with friction) for corners approaching faster than the
restitution threshold, friction clamped to mu times the normal impulse. A box that leaves the floor
flies on; one that stays goes to

Contact (``contact_step``): time-stepping on the grid t_n = n dt, each step (or piece of one) running the stages of
``stages.FLOOR_PIECE`` (restitution at this instant, find contacts, integrate velocities, solve contacts, locate
impacts, store impulses, energy limit, integrate positions, relax; ``contact_step``'s docstring says what each does
here), split into substeps where the box would turn more than MAX_ROTATION_PER_STEP. The box flies again when no
corner is loaded or below the floor, and sleeps (velocities set to zero, stepping stops) once it has lain still on a
face for ``sleep_time`` (``kernel_support.lies_still_at``, ``kernel_support.rest_timer``): the grid step is
``stages.FLOOR_STEP``.
What a box carries from one call to the next is its row of ``memory``.

What this fixes in the seed scheme (measured on it): corners resolved one after another make
a flat drop spin and bounce low; friction applied corner after corner makes a resting box creep
(13 cm in 10 s with mu = 0.5, none with mu = 0);
a friction impulse of mu |p| can reverse sliding; an explicit penalty spring blows up beyond
omega dt = 2; time-stepped flight and impacts move the landing pose with the step size.
"""

import math

import numpy as np

from .. import layout
from ..compile.compilation import jit_kernel, jit_stage
from ..contact_law import floor_friction
from ..kernel_support import is_finite_state, lies_still_at, read_settings, rest_timer, store_state, write_stats
from ..tunables import CONTACT_TOLERANCE, SIMULTANEOUS_TOLERANCE
from .contact_solver import CORNER_ROWS, MAX_CORNERS
from .contact_step import contact_step
from .flight import fly_to_impact
from .memory import MEMORY_SIZE, Corners, Progress, Tally, read_memory, start_memory, write_memory
from .state import BoxConstants, CornerWork, FloorSettings, Motion, Recording


@jit_stage(inline="always")
def box_constants(params, i, use_friction):
    """Box i's constants as the stages take them (``state.BoxConstants``; friction 0 without friction)."""
    hx = params[i, layout.HALF_LENGTH]
    hy = params[i, layout.HALF_WIDTH]
    radius = math.sqrt(hx * hx + hy * hy)
    return BoxConstants(
        hx,
        hy,
        1.0 / params[i, layout.MASS],
        1.0 / params[i, layout.INERTIA],
        params[i, layout.RESTITUTION],
        floor_friction(params[i, layout.FRICTION]) if use_friction else 0.0,
        params[i, layout.STIFFNESS],
        radius,
        CONTACT_TOLERANCE * (1.0 + radius),
        SIMULTANEOUS_TOLERANCE * (1.0 + radius),
    )


@jit_stage(inline="always")
def floor_settings(settings, use_penalty, use_friction, record):
    """The settings array (``layout``) and the kernel's switches as the floor-only stages read them."""
    dt, gravity, _, until_rest, threshold, sleep_speed, sleep_time, slop = read_settings(settings)
    return FloorSettings(
        dt, gravity, until_rest, threshold, sleep_speed, sleep_time, slop, use_penalty, use_friction, record
    )


@jit_stage(inline="always")
def falls_asleep(motion, box, settings, still_for, h):
    """Sleep: the sleep timer after a contact step of length h (``kernel_support.rest_timer``: still on a face,
    ``lies_still_at``) and whether the box rests now."""
    still = lies_still_at(
        motion.y, motion.cos_a, motion.sin_a, motion.vx, motion.vy, motion.spin, box.hx, box.hy, settings.sleep_speed
    )
    return rest_timer(still, still_for, h, settings.sleep_time)


@jit_stage
def advance_box(i, state, params, memory, n, n_end, settings, work, recording):
    """Box i against the floor alone, from grid step n (its time in its ``memory`` row) to grid step ``n_end``,
    or until it falls asleep or its state stops being finite: the stage script of this module's docstring.
    What a box carries from one call to the next (its mode, the located corner, its time, its counts) is its
    row of ``memory`` (``memory.start_memory``), so a box advanced in pieces goes on as one advanced in one call
    (the floor-only kernel calls it once per box; the colliding kernel for a box that no other can reach).
    ``settings``: ``state.FloorSettings``; ``work``: ``state.CornerWork``; ``recording``: ``state.Recording``.
    Returns the grid step reached."""
    dt = settings.dt
    angle = state[i, 2]
    motion = Motion(
        state[i, 0], state[i, 1], angle, state[i, 3], state[i, 4], state[i, 5], math.cos(angle), math.sin(angle)
    )
    box = box_constants(params, i, settings.use_friction)
    progress, corners, tally = read_memory(memory, i)
    in_flight, t, still_for, rest_time = progress.in_flight, progress.t, progress.still_for, progress.rest_time
    status, fail_step = layout.STATUS_OK, -1
    while n < n_end:
        if in_flight:
            # ---- flight: closed form up to the first contact, the impact there ----
            motion, t, n, tally, in_flight, going_on, status, fail_step = fly_to_impact(
                i, motion, box, settings, t, n, n_end, tally, recording, work
            )
            if not going_on:
                break
            if in_flight:
                continue
            h = (n + 1) * dt - t  # a partial step brings the box back onto the grid
        else:
            h = dt
        # ---- substeps: one contact step on the grid (stages.FLOOR_PIECE), split where the box turns fast ----
        motion, corners, held, tally = contact_step(
            i, motion, h, box, settings, corners, t, tally, recording.events, work
        )
        tally = Tally(tally.first_contact, tally.n_impacts, tally.max_penetration, tally.n_steps + 1)
        n += 1
        t = n * dt
        if settings.record:
            store_state(recording.trajectory, n, i, motion.x, motion.y, motion.angle, motion.vx, motion.vy, motion.spin)
        if not is_finite_state(motion.x, motion.y, motion.angle, motion.vx, motion.vy, motion.spin):
            status = layout.STATUS_NONFINITE
            fail_step = n
            break
        # ---- sleep: still on a face for sleep_time ----
        if settings.until_rest:
            still_for, rests = falls_asleep(motion, box, settings, still_for, h)
            if rests:
                motion = Motion(motion.x, motion.y, motion.angle, 0.0, 0.0, 0.0, motion.cos_a, motion.sin_a)
                rest_time = t
                if settings.record:
                    store_state(recording.trajectory, n, i, motion.x, motion.y, motion.angle, 0.0, 0.0, 0.0)
                break
        if not held:
            in_flight = True
            corners = Corners(-1, 0, corners.lift)
    state[i, 0], state[i, 1], state[i, 2] = motion.x, motion.y, motion.angle
    state[i, 3], state[i, 4], state[i, 5] = motion.vx, motion.vy, motion.spin
    write_memory(memory, i, Progress(in_flight, t, still_for, rest_time, status, fail_step), corners, tally)
    return n


def make_robust_kernel(use_penalty: bool, use_friction: bool, record: bool, source_digest: int):
    """Build the robust kernel for exactly the stages a scene uses (flags are compile-time).

    ``run(state, params, settings, stats, trajectory, events)`` advances every body in place up
    to ``settings[MAX_STEPS]`` grid steps, or until it sleeps when ``settings[UNTIL_REST]``.
    """
    PENALTY, FRICTION, RECORD, DIGEST = use_penalty, use_friction, record, source_digest

    @jit_kernel
    def run(state, params, settings, stats, trajectory, events):
        # numba keys its on-disk cache on this file and the closure values: the digest of every engine
        # source must be a closure value, or a kernel compiled with an older stage would be loaded
        _ = DIGEST
        context = floor_settings(settings, PENALTY, FRICTION, RECORD)
        max_steps = np.int64(settings[layout.MAX_STEPS])
        work = CornerWork(
            np.zeros((CORNER_ROWS, MAX_CORNERS)), np.zeros((MAX_CORNERS, MAX_CORNERS)), np.zeros(MAX_CORNERS, np.int64)
        )
        recording = Recording(trajectory, events)
        memory = np.zeros((state.shape[0], MEMORY_SIZE))
        for i in range(state.shape[0]):
            if RECORD:
                store_state(
                    trajectory, 0, i, state[i, 0], state[i, 1], state[i, 2], state[i, 3], state[i, 4], state[i, 5]
                )
            start_memory(memory, i, 0.0)
            n = advance_box(i, state, params, memory, 0, max_steps, context, work, recording)
            progress, _, tally = read_memory(memory, i)
            write_stats(
                stats,
                i,
                tally.first_contact,
                tally.n_impacts,
                tally.n_steps,
                tally.max_penetration,
                progress.rest_time,
                progress.t,
                progress.status,
                progress.fail_step,
                n + 1,
            )

    return run
