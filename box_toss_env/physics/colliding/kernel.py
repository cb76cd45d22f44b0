"""The colliding robust kernel: it builds the step state once (``state``), runs the grid steps (``advance_steps``,
``stages.COLLIDING_STEP``: wake, alone, quiet, the substeps of ``step`` over all awake bodies or group by group, sleep),
sizing the arrays between steps, and writes the results back. A step's substeps never stop half-way: before each step
its candidate pairs are found at every body's reach over the whole step (``groups.step_pairs``, the pair array grown
until they fit) and the contact rows are grown to hold every contact those pairs and the floor can give (two a pair,
four a body); the substeps search only among those pairs."""

import numpy as np

from .. import layout
from ..compile.compilation import jit_kernel, jit_stage
from ..kernel_support import is_finite_state, write_stats
from ..tunables import ALONE_LIMIT
from .alone import advance_alone, count_awake, steps_alone
from .broadphase import sweep_axis
from .groups import step_pairs, step_substeps
from .islands import keep_sleeping, restore_sleeping, sleep_placed, sleeps_through, wake_touched
from .narrowphase import update_geometry
from .quiet import masses_alike, quiet_context, quiet_stride
from .state import (
    grown_sweep,
    initial_capacity,
    make_bodies,
    make_contacts,
    make_scratch,
    make_sleep,
    make_stats,
    make_sweep,
    room_for_contacts,
    step_context,
    with_axis,
)
from .step import advance_step, record_states
from .substeps import body_reach
from .threads import restore_threads, use_threads


# -- before the steps --------------------------------------------------------------------------------
@jit_stage(inline="always")  # into start_steps (it sorts: numba's sort needs its runtime)
def start_sweep(bodies, sweep, everyone):
    """Every box's geometry (``update_geometry``), the sweep's axis (returned) and the boxes in order along it
    (into ``sweep.order``), for the broadphase's first search."""
    update_geometry(bodies.pose, bodies.half, everyone, sweep.trig, sweep.bound)
    axis = sweep_axis(bodies.pose, everyone)
    sweep.order[:] = np.argsort(bodies.pose[:, axis])
    return axis


@jit_stage(inline="always")  # into the kernel (it grows the pair array: numba's runtime)
def start_steps(context, bodies, sweep, sleep, warm):
    """Before the first step: the islands asleep at the end of the last call asleep again (``restore_sleeping``,
    with sleeping on), the sweep's axis and order, the bodies placed at rest asleep (``sleep_placed``), and the
    islands the others can reach in the first step awake (``wake``). Returns (the sweep, how many bodies are
    awake)."""
    n_awake = bodies.pose.shape[0]
    if context.sleeping:
        n_awake -= restore_sleeping(warm, bodies, sleep)
    if n_awake > 0:  # all asleep: no sweep
        sweep = with_axis(sweep, start_sweep(bodies, sweep, sleep.everyone))
    if context.sleeping and n_awake > 0:
        slept = sleep_placed(bodies, sweep, sleep, context)
        while slept < 0:
            sweep = grown_sweep(sweep)
            slept = sleep_placed(bodies, sweep, sleep, context)
        n_awake -= slept
    if 0 < n_awake < bodies.pose.shape[0] and context.max_steps > 0:  # wake, for the first step
        n_awake = wake(context, bodies, sweep, sleep)
    return sweep, n_awake


@jit_stage
def load_warm_start(warm, n, impulses, dt):
    """The contacts' impulses a caller kept from its last call (``layout.WARM_START_SIZE``: row 0 holds the
    contact count, the substep length and the body count k, then WARM_BODY_ROWS a body, ``islands.keep_sleeping``,
    then a row per contact: key, normal and friction impulse), into ``impulses.keys``, ``impulses``; returns (count,
    substep length). An empty ``warm`` (none kept), or one kept from a scene of another number of bodies than
    this one's ``n`` (a contact's key names its bodies by their number among n), starts cold: (0, dt)."""
    if warm.shape[0] == 0 or np.int64(warm[0, 2]) != n:
        return 0, dt
    first = 1 + layout.WARM_BODY_ROWS * n
    count = min(np.int64(warm[0, 0]), warm.shape[0] - first, impulses.keys.shape[0])
    for c in range(count):
        impulses.keys[c] = np.int64(warm[first + c, 0])
        impulses.impulses[c, 0] = warm[first + c, 1]
        impulses.impulses[c, 1] = warm[first + c, 2]
    return count, warm[0, 1] if count > 0 else dt


# -- the grid steps ---------------------------------------------------------------------------------
@jit_stage
def wake(context, bodies, sweep, sleep):
    """Wake: the sleeping islands an awake body can reach in the coming step (``islands.wake_touched``, at each
    awake body's reach over dt, and the fastest's beyond it). Returns how many bodies are awake."""
    update_geometry(bodies.pose, bodies.half, sleep.awake, sweep.trig, sweep.bound)
    fastest = body_reach(
        bodies.vel, bodies.radius, sleep.awake, context.dt, context.gravity, context.tolerance, sweep.reach
    )
    wake_touched(bodies.pose, bodies.half, sweep, sleep, fastest)
    return count_awake(sleep.awake)


@jit_stage
def advance_steps(context, bodies, sweep, contacts, impulses, sleep, stats, scratch, progress, quiet):
    """The grid steps while a body is awake, from ``progress`` (the step reached, the bodies awake, the impulses kept
    in ``contacts``: their count and substep length), each: alone (each awake body alone against the floor while no
    two can meet, ``alone``), or the step's candidate pairs (``groups.step_pairs``) and, if the arrays hold them,
    the substeps and sleep (``step.advance_step``), QUIET_STRIDE grid steps as one where the scene is quiet
    (``quiet``: whether the scene allows it, ``quiet.quiet_stride``; the step's context ``quiet.quiet_context``);
    then wake for the next step. Where the arrays cannot hold a step's pairs or its contacts, it returns before the step
    (nothing of it done) for the kernel to grow them and call again. Returns (progress, status, failing step, rows
    needed: 0 done, -1 more pairs, else contacts)."""
    n, n_awake, n_previous, h_previous = progress
    nb, quiet_step = bodies.pose.shape[0], quiet_context(context)
    while n < context.max_steps and n_awake > 0:
        # alone: whole steps of each awake body against the floor alone while no two boxes can meet
        k = steps_alone(bodies, sleep, context, context.max_steps - n) if n_awake <= ALONE_LIMIT else 0
        if k > 0:
            n, slept, failed = advance_alone(k, n, context, bodies, sleep, stats, scratch.alone)
            n_previous = 0  # the contacts of the substeps before are gone
            if failed >= 0:
                return (n, n_awake, n_previous, h_previous), layout.STATUS_NONFINITE, n, 0
            n_awake -= slept
        else:
            # quiet: QUIET_STRIDE grid steps as one where every awake body is nearly still (``quiet``)
            stride = quiet_stride(context, bodies, sleep.awake, n, quiet)
            step_context = quiet_step if stride > 1 else context
            if stride > 1 and n_awake < nb:  # wake again at the longer step's reach
                n_awake = wake(step_context, bodies, sweep, sleep)
            n_sub = step_substeps(step_context, bodies, sleep)
            n_pairs = step_pairs(step_context, bodies, sweep, sleep, n_sub)
            rows = 4 * nb + 2 * n_pairs  # two contacts a pair, four a body against the floor
            if n_pairs < 0 or rows > contacts.rows.shape[0]:
                return (n, n_awake, n_previous, h_previous), layout.STATUS_OK, -1, -1 if n_pairs < 0 else rows
            finite, n_awake, (n_previous, h_previous) = advance_step(
                step_context,
                bodies,
                sweep,
                contacts,
                impulses,
                sleep,
                stats,
                scratch,
                (n, stride),
                (n_sub, n_pairs),
                n_awake,
                (n_previous, h_previous),
            )
            n += stride
            if not finite:
                return (n, n_awake, n_previous, h_previous), layout.STATUS_NONFINITE, n, 0
        if 0 < n_awake < nb and n < context.max_steps:  # wake, for the next step
            n_awake = wake(context, bodies, sweep, sleep)
    if not context.until_rest and n < context.max_steps:  # every body asleep: at rest to the end of the run
        if context.record:
            for row in range(n + 1, context.max_steps + 1):
                record_states(stats.trajectory, row, bodies.pose, bodies.vel)
        n = context.max_steps
    return (n, n_awake, n_previous, h_previous), layout.STATUS_OK, -1, 0


# -- after the steps ---------------------------------------------------------------------------------
@jit_stage
def store_warm_start(warm, impulses, previous, bodies, sleep):
    """Into ``warm`` for the next call (``load_warm_start``'s layout; nothing if it is empty): each body's sleep
    (``islands.keep_sleeping``), then the last substep's impulses by contact key (``previous``: their count and
    substep length), as many as it has rows for (the keys are sorted, so a prefix is a warm start too)."""
    if warm.shape[0] == 0:
        return
    n_previous, h_previous = previous
    first = 1 + layout.WARM_BODY_ROWS * keep_sleeping(warm, bodies, sleep)
    count = min(n_previous, warm.shape[0] - first)
    warm[0, 0] = count
    warm[0, 1] = h_previous
    for c in range(count):
        warm[first + c, 0] = impulses.keys[c]
        warm[first + c, 1] = impulses.impulses[c, 0]
        warm[first + c, 2] = impulses.impulses[c, 1]


@jit_stage
def write_back(state, stats, bodies, tally, rest_time, outcome):
    """The bodies' final states and stats (``outcome``: the step reached, dt, the status and the failing step; a
    failure is reported on the bodies that are not finite)."""
    n, dt, status, fail_step = outcome
    pose, vel = bodies.pose, bodies.vel
    for b in range(state.shape[0]):
        state[b, 0], state[b, 1], state[b, 2] = pose[b, 0], pose[b, 1], pose[b, 2]
        state[b, 3], state[b, 4], state[b, 5] = vel[b, 0], vel[b, 1], vel[b, 2]
        body_status = layout.STATUS_OK
        if status != layout.STATUS_OK and not (
            is_finite_state(pose[b, 0], pose[b, 1], pose[b, 2], vel[b, 0], vel[b, 1], vel[b, 2])
        ):
            body_status = status
        write_stats(
            stats,
            b,
            tally.first_contact[b],
            tally.n_impacts[b],
            tally.n_stepped[b],
            tally.max_penetration[b],
            rest_time[b],
            n * dt,
            body_status,
            fail_step if body_status != layout.STATUS_OK else -1,
            n + 1,
        )


def make_colliding_robust_kernel(use_penalty: bool, use_friction: bool, record: bool, source_digest: int):
    """Build the robust kernel for scenes whose boxes collide (flags are compile-time, as
    ``robust_solver.make_robust_kernel``'s): ``run(state, params, settings, stats, trajectory, events, warm)``
    advances every body of the scene together, in place."""
    PENALTY, FRICTION_ON, RECORD, DIGEST = use_penalty, use_friction, record, source_digest

    @jit_kernel
    def run(state, params, settings, stats, trajectory, events, warm):
        _ = DIGEST  # the on-disk cache key includes every engine source (see robust_solver)
        nb = state.shape[0]
        end_step = 0 if settings[layout.UNTIL_REST] != 0.0 else np.int64(settings[layout.MAX_STEPS])
        if (
            settings[layout.SLEEP] != 0.0
            and not RECORD
            and sleeps_through(warm, state, params, settings[layout.DT], initial_capacity(nb), stats, end_step)
        ):
            return  # every body kept asleep and untouched: nothing to set up
        threads_before = use_threads(settings)  # numba's count at the run's (``threads``)
        bodies = make_bodies(state, params)
        context = step_context(settings, bodies.half, bodies.radius, PENALTY, FRICTION_ON, RECORD)
        (contacts, impulses), sleep = make_contacts(initial_capacity(nb)), make_sleep(nb)
        tally = make_stats(nb, trajectory, events)
        n_previous, h_previous = load_warm_start(warm, nb, impulses, context.dt)  # from the last call
        if RECORD:
            record_states(trajectory, 0, bodies.pose, bodies.vel)
        sweep, n_awake = start_steps(context, bodies, make_sweep(nb), sleep, warm)
        scratch, progress, need = make_scratch(nb), (0, n_awake, n_previous, h_previous), -1
        quiet = settings[layout.QUIET_STEPS] != 0.0 and masses_alike(params)
        while need != 0:  # the steps, the arrays grown between two where a step needs more room
            progress, status, fail_step, need = advance_steps(
                context, bodies, sweep, contacts, impulses, sleep, tally, scratch, progress, quiet
            )
            if need < 0:
                sweep = grown_sweep(sweep)
            elif need > 0:
                contacts, impulses = room_for_contacts(contacts, impulses, need, progress[2])
        n, _, n_previous, h_previous = progress
        store_warm_start(warm, impulses, (n_previous, h_previous), bodies, sleep)
        write_back(state, stats, bodies, tally, sleep.rest_time, (n, context.dt, status, fail_step))
        restore_threads(settings, threads_before)

    return run
