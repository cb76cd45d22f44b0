"""The step script of the robust solver for scenes whose boxes collide (``Scene(boxes_collide=True)``): a grid
step (``advance_step``) takes its substeps with one count or group by group (``advance_substeps``), each substep
(``substep``) running the stages of ``stages.COLLIDING_SUBSTEP``, one stage a line; the kernel (``kernel``) runs
the steps between the wake and the alone stage, and sizes the arrays between them (``stages.COLLIDING_STEP``). What
each stage does is ``stages.STAGES``'s; its formulas are its module's: the contact formulas in ``prepare``, the
penalty in ``relax``, the warm start, the impulse solves and restitution in ``warm_start``, ``solve`` and
``restitution``, bodies alone in ``alone``, groups of their own substeps in ``groups``, the geometry of contacts in
``narrowphase``, pairs in ``broadphase``, sleeping in ``islands``, the substep count in ``substeps``, the step state
in ``state``. The steps allocate nothing and count no references (several times faster for stages handed arrays,
``compilation.jit_stage``).

A grid step dt is split into substeps so that no point of any box moves further than TUNNEL_FRACTION of the
scene's smallest half extent in one relative to what it can touch (the floor or a box of its candidate pairs, at
point speeds |v| + |g| h + |omega| R: ``substeps.contact_speeds``), and no box turns further than
MAX_ROTATION_PER_STEP, up to MAX_SUBSTEPS: one count for all the awake bodies (the fastest decides), or one per
group of bodies that cannot meet within the step (``groups``). No tunnelling: within that bound two boxes cannot
pass through one another in a substep (they move by less than half the thinnest box, and the speculative contacts
stop the gap from closing past zero); the floor's speculative contacts hold at any speed. Beyond MAX_SUBSTEPS the
substeps are capped and only the speculative contacts remain (not guaranteed).

Contacts come from the sort-and-sweep broadphase (``broadphase.candidate_pairs``), which visits the pairs in the
order testing every pair did, so the results are those of the all-pairs search: the step's pairs, found before its
substeps at every body's reach over the step (``groups.step_pairs``), each substep testing those at its own reach
(``broadphase.substep_pairs``). Impacts between boxes are resolved in the substep where the gap closes (not located
in time as the floor-only solver locates a box's impacts with the floor). The restitution stage solves the impacts
again with the solve contacts stage's solve, together with every other contact and with friction (the simultaneous
impulse LCP: a box struck while lying on the floor is held by the floor and tips as friction says; its sweeps start
from the impacted bodies, ``seed_impacts``), then polishes them contact by contact and steps again the contacts the
polish left short (``apply_restitution``); the energy limit then keeps the bodies that took an impulse from
gaining kinetic + potential energy (with several contacts, friction or warm starting the impulses alone could add
energy; one factor on all their velocities keeps every contact satisfied and reverses no slip).
"""

import math

from .. import layout
from ..compile.compilation import jit_stage
from ..contact_law import newton_target
from ..kernel_support import is_finite_state, record_event, store_state
from ..robust.energy_limit import energy_limit_scale
from .broadphase import substep_pairs
from .groups import group_count, keep_group, next_group, plan_substeps, sort_kept
from .islands import fall_asleep, join_contacts, join_islands
from .narrowphase import (
    APPROACH,
    BODY1,
    BODY2,
    FRICTION_IMPULSE,
    GAP,
    IMPULSE,
    KEY,
    NX,
    NY,
    RESTITUTION,
    TARGET,
    find_contacts,
)
from .parallel import (
    PARALLEL_BODIES,
    PARALLEL_CONTACTS,
    approach_on_threads,
    geometry_and_reach,
    gravity_on_threads,
    parallel_find_contacts,
    partition_contacts,
    partitioned_penetrations,
    partitioned_touched,
    positions_on_threads,
    prepare_on_threads,
    store_on_threads,
    targets_on_threads,
)
from .prepare import (
    body_kinetic_energy,
    is_impact_contact,
    note_depth,
    prepare_contacts,
    relative_velocity,
    touch_bodies,
)
from .relax import correct_penetrations, penalty_trigger
from .restitution import apply_restitution
from .solve import solve_velocities
from .warm_start import warm_start


# -- find contacts -----------------------------------------------------------------------------------
@jit_stage(inline="always")
def contact_reach(bodies, sweep, include, h, context):
    """Each included body's bounding box and how far it can reach in the substep (``geometry_and_reach``: its own
    travel plus half the fastest body's); against the floor a body reaches a whole fastest body's travel further
    (a struck box moves further than its own speed says)."""
    fastest = geometry_and_reach(bodies, include, h, context, sweep)  # on threads for many bodies
    for b in range(bodies.pose.shape[0]):
        sweep.floor_reach[b] = sweep.reach[b] + fastest


@jit_stage(inline="always")
def find_substep_contacts(context, bodies, sweep, contacts, include, h, pairs, previous):
    """Find contacts: broadphase and narrowphase, the contacts within what the included bodies can travel in the substep
    (``contact_reach``), among the step's candidate pairs (``pairs``: how many, and whether they are this
    substep's own search already, ``groups.step_pairs``; else ``broadphase.substep_pairs``,
    ``narrowphase.find_contacts``; from PARALLEL_BODIES bodies up on threads, ``parallel.parallel_find_contacts``: the
    same contacts); from PARALLEL_CONTACTS contacts up, their blocks for the sweeps (``parallel.partition_contacts``).
    Returns how many."""
    n_pairs, searched = pairs
    keys = sweep.pairs
    if not searched:
        contact_reach(bodies, sweep, include, h, context)
        n_pairs = substep_pairs(bodies.pose, sweep, n_pairs, include)
        keys = sweep.substep_pairs
    if bodies.pose.shape[0] >= PARALLEL_BODIES:
        count = parallel_find_contacts(bodies, sweep, keys, n_pairs, include, contacts, previous)
    else:
        count = find_contacts(bodies, sweep, keys, n_pairs, include, contacts, previous)
    if count >= PARALLEL_CONTACTS:
        partition_contacts(contacts.ids, count, sweep.order, sweep.spread.block, contacts.partition)
    return count


@jit_stage(inline="always")
def note_penetration(contacts, count, max_penetration):
    """The deepest penetration each body has had (-gap of its contacts), for the stats; returns the deepest of the
    substep's contacts (0 if none). On threads from PARALLEL_CONTACTS contacts up (the same values)."""
    if count >= PARALLEL_CONTACTS:
        return partitioned_penetrations(contacts, max_penetration)
    deepest = 0.0
    for c in range(count):
        deepest = max(deepest, note_depth(c, contacts.rows, contacts.ids, max_penetration))
    return deepest


# -- before the solve: energies, approach speeds; integrate velocities --------------------------
@jit_stage(inline="always")
def approach_speeds(contacts, count, bodies, kinetic_before):
    """Each body's kinetic energy and each contact's approach speed u_rel . n before the substep's impulses (on
    threads from PARALLEL_CONTACTS contacts up)."""
    rows, ids, vel = contacts.rows, contacts.ids, bodies.vel
    if count >= PARALLEL_CONTACTS:
        approach_on_threads(rows, ids, count, vel, bodies.params, kinetic_before)
        return
    for b in range(vel.shape[0]):
        kinetic_before[b] = body_kinetic_energy(vel, b, bodies.params)
    for c in range(count):
        ux, uy = relative_velocity(c, rows, ids, vel)
        rows[c, APPROACH] = ux * rows[c, NX] + uy * rows[c, NY]


@jit_stage(inline="always")
def integrate_velocities(vel, include, h, gravity):
    """v += h g for the included bodies (a sleeping body does not fall); on threads from PARALLEL_BODIES up."""
    if vel.shape[0] >= PARALLEL_BODIES:
        gravity_on_threads(vel, include, h, gravity)
        return
    for b in range(vel.shape[0]):
        if include[b]:
            vel[b, 1] += h * gravity


# -- warm start, solve contacts, store impulses ----------------------------------------------------
@jit_stage(inline="always")
def speculative_targets(rows, count, h):
    """u_rel . n >= -max(gap, 0) / h: each gap may close within the substep but not pass (on threads from
    PARALLEL_CONTACTS contacts up)."""
    if count >= PARALLEL_CONTACTS:
        targets_on_threads(rows, count, h)
        return
    for c in range(count):
        rows[c, TARGET] = -max(rows[c, GAP], 0.0) / h


@jit_stage(inline="always")
def store_impulses(contacts, count, keys, impulses):
    """Keep the solved impulses by contact key for the next substep's warm start; returns how many (on threads from
    PARALLEL_CONTACTS contacts up)."""
    rows, ids = contacts.rows, contacts.ids
    if count >= PARALLEL_CONTACTS:
        store_on_threads(rows, ids, count, keys, impulses)
        return count
    for c in range(count):
        keys[c] = ids[c, KEY]
        impulses[c, 0] = rows[c, IMPULSE]
        impulses[c, 1] = rows[c, FRICTION_IMPULSE]
    return count


# -- restitution -------------------------------------------------------------------------------------
@jit_stage(inline="always")
def restitution_targets(rows, count, threshold):
    """u_rel . n >= -e u0 for the contacts that approached faster than the threshold and took an impulse;
    returns how many (the impacts)."""
    impacts = 0
    for c in range(count):
        if is_impact_contact(c, rows, threshold):
            rows[c, TARGET] = newton_target(rows[c, RESTITUTION], rows[c, APPROACH])
            impacts += 1
    return impacts


@jit_stage(inline="always")
def seed_impacts(contacts, count, threshold, seed):
    """The bodies of the impacts (``restitution_targets``' contacts) set in ``seed``, the rest cleared: where the
    restitution solve's sweeps start. The contacts were solved just before and only the impacts' targets changed, so
    a contact no chain of changed impulses reaches keeps the solve's impulses, as in a substep without an impact:
    a throw into a pile of 100 at 30 m/s spent 43% less a contact in this solve, the dropped pile of 100 26% less
    (at 100 m/s, where the changed impulses reach every contact, 5% more; cycle counters around each stage, a
    scratch build: docs/methodology/notes.md)."""
    rows, ids = contacts.rows, contacts.ids
    seed[:] = False
    for c in range(count):
        if is_impact_contact(c, rows, threshold):
            seed[ids[c, BODY1]] = True
            if ids[c, BODY2] >= 0:
                seed[ids[c, BODY2]] = True


# -- energy limit ------------------------------------------------------------------------------------
@jit_stage(inline="always")
def mark_touched(contacts, count, impacts, threshold, work):
    """Which bodies took an impulse in the substep, and at how many impacts each (``prepare.touch_bodies``); on
    threads from PARALLEL_CONTACTS contacts up (the same values)."""
    rows, ids, touched, impacted = contacts.rows, contacts.ids, work.touched, work.impacted
    if count >= PARALLEL_CONTACTS:
        partitioned_touched(rows, ids, contacts.partition, impacts, threshold, touched, impacted)
        return
    for b in range(touched.shape[0]):
        touched[b] = False
        impacted[b] = 0
    for c in range(count):
        touch_bodies(c, rows, ids, impacts, threshold, touched, impacted)


@jit_stage(inline="always")  # into limit_energy
def count_impacts(contacts, count, stats, work, t, record):
    """Each touched body is supported from now on in the step, its first contact noted; each impacted one's impact
    counted (and with ``record`` logged, with its fastest approach)."""
    rows, ids = contacts.rows, contacts.ids
    for b in range(work.touched.shape[0]):
        if work.touched[b]:
            stats.supported[b] = True
            if math.isnan(stats.first_contact[b]):
                stats.first_contact[b] = t
        if work.impacted[b] > 0:
            if record:
                approach = 0.0
                for c in range(count):
                    if ids[c, BODY1] == b or ids[c, BODY2] == b:
                        approach = max(approach, -rows[c, APPROACH])
                record_event(stats.events, b, stats.n_impacts[b], t, approach, work.impacted[b])
            stats.n_impacts[b] += 1


@jit_stage(inline="always")
def limit_energy(contacts, count, bodies, stats, work, h, t, context):
    """Scale the touched bodies' velocities by the one s in [0, 1] that keeps their kinetic + potential energy
    from rising in the substep (``energy_limit_scale``), and count their contacts and impacts (``count_impacts``)."""
    count_impacts(contacts, count, stats, work, t, context.record)
    vel, params, touched, gravity = bodies.vel, bodies.params, work.touched, context.gravity
    before = 0.0
    after = 0.0
    rise = 0.0
    for b in range(vel.shape[0]):
        if touched[b]:
            before += work.kinetic_before[b]
            after += body_kinetic_energy(vel, b, params)
            rise += -gravity * h * vel[b, 1] * params[b, layout.MASS]
    if after > 0.0:
        scale = energy_limit_scale(before, after, rise)
        if scale < 1.0:
            for b in range(vel.shape[0]):
                if touched[b]:
                    vel[b, 0] *= scale
                    vel[b, 1] *= scale
                    vel[b, 2] *= scale


# -- integrate positions -----------------------------------------------------------------------------
@jit_stage(inline="always")
def integrate_positions(pose, vel, include, touched, h, gravity):
    """The exact parabola out of contact (x += h v - h^2 g / 2, v at the end of the substep), symplectic
    Euler in contact (x += h v). On threads from PARALLEL_BODIES bodies up."""
    if pose.shape[0] >= PARALLEL_BODIES:
        positions_on_threads(pose, vel, include, touched, h, gravity)
        return
    for b in range(pose.shape[0]):
        if include[b]:
            pose[b, 0] += h * vel[b, 0]
            pose[b, 1] += h * vel[b, 1]
            if not touched[b]:
                pose[b, 1] -= 0.5 * h * h * gravity
            pose[b, 2] += h * vel[b, 2]


# -- the substep: stages.COLLIDING_SUBSTEP --------------------------------------------------------
@jit_stage(inline="always")  # into the steps below (a call cost 4% of an OnBox throw)
def substep(context, bodies, sweep, contacts, stats, scratch, include, h, t, pairs, warm_from, store_into):
    """The stages of a substep (``stages.COLLIDING_SUBSTEP``) of length h starting at time t over the ``include``d
    bodies, warm-started from ``warm_from`` (keys, impulses, their count and substep length); returns (its contacts, how
    many impulses it keeps) the impulses kept by key into ``store_into`` (keys, impulses; may be ``warm_from``'s
    arrays), for the next substep's warm start. ``pairs``: the step's candidate pairs (how many, and whether they are
    this substep's own search, ``groups.step_pairs``)."""
    gravity, threshold, vel, work, exact = context.gravity, context.threshold, bodies.vel, scratch.work, scratch.exact
    # find contacts
    count = find_substep_contacts(context, bodies, sweep, contacts, include, h, pairs, (warm_from[0], warm_from[2]))
    if count >= PARALLEL_CONTACTS:
        prepare_on_threads(contacts.rows, contacts.ids, count, bodies.params, bodies.inv_mass, bodies.inv_inertia)
    else:
        prepare_contacts(contacts, count, bodies)
    deepest = note_penetration(contacts, count, stats.max_penetration)
    # relax: split-impulse correction of penetrations deeper than the slop (tested here: a stage's call passes
    # each array of its structures as separate values, about 300 for this one, which in a substep of two boxes
    # costs more than the test; with the sleep stage inlined and the split test below, OnBox throws 5-7% faster)
    if context.use_penalty and deepest > penalty_trigger(context):
        correct_penetrations(contacts, count, bodies, work, exact, h, context)
    approach_speeds(contacts, count, bodies, work.kinetic_before)
    # integrate velocities
    integrate_velocities(vel, include, h, gravity)
    # warm start: the speculative targets, each contact's impulses of the last substep
    speculative_targets(contacts.rows, count, h)
    warm_start(contacts, count, warm_from, bodies, h, context)
    # solve contacts
    solve_velocities(contacts, count, bodies, exact, context)
    # store impulses: for the next substep's warm start
    n_stored = store_impulses(contacts, count, store_into[0], store_into[1])
    # restitution: for impacts only, solved with every contact and friction, then polished
    impacts = restitution_targets(contacts.rows, count, threshold)
    if impacts > 0:
        seed_impacts(contacts, count, threshold, exact.moved[0])
        solve_velocities(contacts, count, bodies, exact, context, True)
        apply_restitution(contacts, count, bodies, threshold, exact.moved)
    # energy limit: no energy gained by the bodies that took an impulse
    mark_touched(contacts, count, impacts, threshold, work)
    limit_energy(contacts, count, bodies, stats, work, h, t, context)
    # integrate positions
    integrate_positions(bodies.pose, vel, include, work.touched, h, gravity)
    return count, n_stored


# -- the substeps of a grid step ---------------------------------------------------------------------
@jit_stage(inline="always")  # into advance_step
def advance_substeps(state, start, plan, pairs, previous):
    """The substeps of the grid step from time ``start``. With one count (``group`` < 0): n_sub substeps over every
    awake body, the first warm-started from ``previous`` (the last substep's impulses kept in ``impulses.keys``,
    ``impulses.impulses``: their count and substep length), each next one from the one before. Group by group
    (``groups``), from group ``group`` (its smallest body): each group's count is its own (``groups.group_count``);
    its first substep is warm-started from ``previous``, the next from its own (``impulses.group_keys``,
    ``group_impulses``); its last impulses are appended to the step's kept rows (``keep_group``) and its box-box
    contacts joined in ``sleep.parent`` (the islands to sleep), and at the end all of them are put in key order for the
    next step (``sort_kept``). ``state``: (context, bodies, sweep, contacts, impulses, sleep, stats, scratch); ``plan``:
    (n_sub, group); ``pairs``: the step's candidate pairs (how many, and whether they are its one substep's, found by
    ``groups.step_pairs``). Returns (the last substep's contacts, impulses kept for the next step, their substep
    length)."""
    context, bodies, sweep, contacts, impulses, sleep, stats, scratch = state
    n_sub, group = plan
    n_pairs, searched = pairs
    group_of, in_group = scratch.groups.group_of, scratch.groups.in_group
    n_previous, h_previous = previous
    one_count, nb, n_kept, count = group < 0, bodies.pose.shape[0], 0, 0
    while group < nb:
        if one_count:
            include, own = sleep.awake, (impulses.keys, impulses.impulses)
        else:
            for b in range(nb):
                in_group[b] = group_of[b] == group
            n_sub = group_count(scratch.groups, group)
            include, own = in_group, (impulses.group_keys, impulses.group_impulses)
        h, n_own = context.dt / n_sub, 0
        for sub in range(n_sub):
            warm_from = (
                (impulses.keys, impulses.impulses, n_previous, h_previous)
                if sub == 0 or one_count
                else (own[0], own[1], n_own, h)
            )
            count, n_own = substep(
                context,
                bodies,
                sweep,
                contacts,
                stats,
                scratch,
                include,
                h,
                start + sub * h,
                (n_pairs, searched),
                warm_from,
                own,
            )
            if one_count:
                n_previous, h_previous = n_own, h
        if one_count:
            return count, n_previous, h_previous
        join_contacts(contacts.ids, count, sleep.parent)
        n_kept = keep_group(impulses, n_own, h, n_kept)
        group = next_group(group_of, group)
    return count, n_kept, sort_kept(impulses, n_kept, context.dt)


# -- a grid step -------------------------------------------------------------------------------------
@jit_stage(inline="always")  # into kernel.advance_steps (a call a grid step cost OnBox throws 3-6%)
def advance_step(context, bodies, sweep, contacts, impulses, sleep, stats, scratch, grid, plan, n_awake, previous):
    """The step from grid step n over ``stride`` grid steps (``grid``: both; 1, or QUIET_STRIDE for a quiet
    step, ``quiet``, whose ``context.dt`` is their length) after the wake and the alone stage
    (``kernel.advance_steps``): the substeps over every awake body with one count, or group by group
    (``groups.plan_substeps``), among the step's candidate pairs (``plan``: the step's substep count at most,
    ``groups.step_substeps``, and its candidate pairs, ``groups.step_pairs``); then the step counted and recorded, and
    sleep. ``previous``: the impulses kept in ``impulses`` (their count and substep length). Returns (whether every
    body is still finite, how many bodies are awake, the impulses kept)."""
    n, stride = grid
    n_sub, n_pairs = plan
    searched = n_sub == 1  # the step's pairs are its one substep's (``groups.step_pairs``)
    group = -1
    if n_sub > 1:  # tested before the call (see the relax stage's test in ``substep``)
        n_sub, group = plan_substeps(context, bodies, sweep, sleep, scratch.groups, n_pairs, n_awake)
    stats.supported[:] = False
    scratch.alone.alone[:] = False
    step_state = (context, bodies, sweep, contacts, impulses, sleep, stats, scratch)
    # substeps: over every awake body with one count, or group by group, each with its own
    start = n * (context.dt / stride)
    count, n_previous, h_previous = advance_substeps(step_state, start, (n_sub, group), (n_pairs, searched), previous)
    if not end_step(bodies, sleep.awake, stats, n + stride, context.record):
        return False, n_awake, (n_previous, h_previous)
    if context.sleeping:  # sleep
        if group < 0:
            join_islands(contacts.ids, count, sleep.parent)
        n_awake -= sleep_islands(bodies, sleep, stats, context, (n + stride, (n + stride) * (context.dt / stride)))
    return True, n_awake, (n_previous, h_previous)


@jit_stage
def record_states(trajectory, row, pose, vel):
    for b in range(pose.shape[0]):
        store_state(trajectory, row, b, pose[b, 0], pose[b, 1], pose[b, 2], vel[b, 0], vel[b, 1], vel[b, 2])


@jit_stage
def end_step(bodies, awake, stats, n, record):
    """Count the step for the awake bodies, record it (as row n), and say whether every body is still finite."""
    pose, vel = bodies.pose, bodies.vel
    if record:
        record_states(stats.trajectory, n, pose, vel)
    finite = True
    for b in range(pose.shape[0]):
        stats.n_stepped[b] += awake[b]
        if not is_finite_state(pose[b, 0], pose[b, 1], pose[b, 2], vel[b, 0], vel[b, 1], vel[b, 2]):
            finite = False
    return finite


@jit_stage(inline="always")
def sleep_islands(bodies, sleep, stats, context, end):
    """Sleep: the islands (``sleep.parent``, joined by the last substep's box-box contacts) whose bodies have all been
    supported and slower than ``sleep_speed`` at every point for ``sleep_time`` fall asleep
    (``islands.fall_asleep``) at the end of the step (``end``: its grid step and time); returns how many bodies did."""
    n, t = end
    pose, vel, awake, still_for = bodies.pose, bodies.vel, sleep.awake, sleep.still_for
    for b in range(pose.shape[0]):
        if awake[b]:
            speed = math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(vel[b, 2]) * bodies.radius[b]
            still = stats.supported[b] and speed <= context.sleep_speed
            still_for[b] = still_for[b] + context.dt if still else 0.0
    slept = fall_asleep(sleep, context.sleep_time, vel)
    if slept > 0:
        for b in range(pose.shape[0]):
            if not awake[b] and math.isnan(sleep.rest_time[b]):
                sleep.rest_time[b] = t
                if context.record:
                    store_state(stats.trajectory, n, b, pose[b, 0], pose[b, 1], pose[b, 2], 0.0, 0.0, 0.0)
    return slept
