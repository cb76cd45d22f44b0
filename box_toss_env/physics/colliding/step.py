"""The step script of the robust solver for scenes whose boxes collide (``Scene(boxes_collide=True)``):
``make_colliding_robust_kernel`` builds the kernel, which sets up the work arrays and runs the grid steps
(``advance_steps``: 0. wake, alone, groups, the substeps, 8. sleep), each substep being stage 1
(``find_substep_contacts``) then stages 2.-7. (``solve_substep``), one stage a line; the contact formulas in
``prepare``, the penalty in ``relax``, the warm start, the impulse solves and restitution in ``warm_start``,
``solve`` and ``restitution`` (``colliding_solver`` names them all), bodies alone in ``alone``, groups of their
own substeps in ``groups``, the geometry of contacts in ``narrowphase``, pairs in ``broadphase``, sleeping in
``islands``. The steps allocate nothing and count no references (several times faster for stages handed arrays,
``compilation.jit_stage``): where the pairs or contacts outgrow their arrays, ``advance_steps`` returns with its
progress, and the kernel grows them and calls it again.

The stage script of one substep of length h:
  1. find contacts: every box-box point whose gap the two bodies could close within h, every box-floor
     corner within the box's reach plus the scene's largest (a struck box moves further than its own
     speed says) (speculative contacts, ``narrowphase.find_contacts``); each starts from its impulse of
     the last substep when the same feature touched (warm starting), so a stack's load is carried from
     step to step rather than rebuilt by the iterations; and from run to run when the caller keeps the
     ``warm`` array (``load_warm_start``, ``store_warm_start``: in chunks as in one run); a cold start of
     more than DIRECT_LIMIT contacts starts from a guess of a resting pile's loads (``resting_loads``);
  2. penalty, island by island: in an island holding a contact deeper than twice the slop, penetration deeper
     than the slop is removed by the critically damped penalty spring with
     backward Euler, as a pseudo-velocity (``robust_solver``'s split impulse, now between two bodies:
     ERP = h omega / (h omega + 2), omega = sqrt(k K_n)); positions move, velocities do not, and the
     potential energy it returns is taken from the kinetic energy of the bodies it moved, as far as
     they have it (the one place a substep can gain energy: a box pushed up out of an overlap while at
     rest; the scene's energy still never exceeds what it started with in our tests);
  3. integrate velocities: v += h g;
  4. solve contact velocities: the normal impulses stay >= 0 and let each gap close but not pass
     (u_rel . n >= -max(gap, 0) / h); each contact's accumulated friction impulse is clamped to mu times
     its normal impulse (it can bring the slip at a contact to zero, never drive it the other way). Up to
     JOINT_LIMIT contacts, normal and friction impulses are solved exactly together (the Coulomb contact
     LCP by an active set over each contact's stick / slide / free state, ``joint_contact_solve``); up to
     DIRECT_LIMIT contacts, or if those states do not settle, the normal impulses are solved exactly
     together (an active set on the dense Delassus matrix, ``normal_lcp``: a stack's load passes through
     every box at once, whatever the mass ratio), alternating with friction sweeps until the impulses
     change by less than CONVERGED of their sum (at most VELOCITY_ITERATIONS rounds); beyond that,
     projected Gauss-Seidel over the contacts (Box2D's sequential impulses, friction then normal at each,
     until a sweep changes the impulses by less than the scene's ``solver_tolerance`` of their sum, at
     most ``solver_iterations`` sweeps);
  5. restitution, only for impacts: a contact that approached faster than the restitution threshold
     before this substep (u0 = u_rel . n < -threshold) and took an impulse gets the target
     u_rel . n >= -e u0 (Newton's law with the approach speed before the solve, as Box2D v3), so a
     single frictionless contact takes p = -(1 + e) u0 / K_n in all, the closed form, in the substep
     its gap closes (also for e = 0: the impact is not spread over the speculative steps); resting
     contacts (slower than the threshold) get none. The impacts are solved again with stage 4's solve,
     together with every other contact and with friction (the simultaneous impulse LCP: a box struck
     while lying on the floor is held by the floor and tips as friction says), then polished contact by
     contact (``apply_restitution``). Restitution solved alone, without the floor or friction, drove a
     box struck from above 1.3 cm into the floor at 200 m/s and made a box dropped on a box nearly
     frictionless at its impact;
  6. no energy gained: the bodies that took an impulse are scaled by the one factor s in [0, 1] that
     keeps their kinetic + potential energy from rising in the substep (``energy_limit_scale``; with
     several contacts, friction or warm starting the impulses alone could add energy). Scaling every
     velocity by s keeps every contact satisfied and reverses no slip;
  7. integrate positions: a body that took no impulse moves on its exact parabola
     (x += h v - h^2 g / 2 with v already at the end of the substep), one in contact with symplectic
     Euler (x += h v).
A grid step dt is split into substeps so that no point of any box moves further than
TUNNEL_FRACTION / 2 of the scene's smallest half extent in one (the point speed bound
|v| + |g| h + |omega| R), so two boxes move by at most TUNNEL_FRACTION of it relative to one another,
and no box turns further than MAX_ROTATION_PER_STEP, up to MAX_SUBSTEPS: one count for all the awake bodies
(the fastest decides), or one per group of bodies that cannot meet within the step (below). No tunnelling: within that
bound two boxes cannot pass through one another in a substep (they move by less than half the
thinnest box, and the speculative contacts stop the gap from closing past zero); the floor's
speculative contacts hold at any speed. The bound holds up to a relative speed of
MAX_SUBSTEPS * TUNNEL_FRACTION * min(hx, hy) / dt (3,300 m/s for 10 cm thick boxes at dt = 1/256 s);
beyond it the substeps are capped and only the speculative contacts remain (not guaranteed).

What a grid step does before and after the substeps, so that a scene pays only for what moves:
  0. wake: with ``until_rest``, every sleeping island that an awake body can reach within the step wakes
     (``islands.wake_touched``; the islands asleep at the end of the last call, kept in ``warm``, sleep from
     the start, ``islands.restore_sleeping``, and so do the bodies placed at rest, ``islands.sleep_placed``);
     sleeping bodies are left out of everything below;
  alone: while at most ALONE_LIMIT bodies are awake, the whole steps for which no two boxes can meet
     (``steps_alone``: on the exact parabolas while every awake body flies, or by a bound on every point's
     speed from the body's energy, ``energy_speed``, while they bounce or slide on the floor apart) are
     taken by each awake body alone against the floor with the floor-only solver (``robust_solver.advance_box``:
     flight in closed form, impacts located in time, its own sleep), in one jump: a box thrown over a
     sleeping one, or settling on the floor beside it, costs what a floor throw costs until they get close;
  groups: where the awake bodies need different substep counts (and the step has more than one), the bodies
     that cannot meet within the step (chains of candidate pairs at each body's reach over dt plus the
     fastest's, ``groups.find_groups``) are grouped by the count they need; where that saves at least
     SPLIT_SAVING body-substeps and pays for the passes over every body that each group's substeps make, each
     group takes its own substeps (``advance_groups``: a box thrown fast far from a pile leaves the pile its
     own count), else all take the fastest's, as with one group;
  1.-7. the substeps above, over the awake bodies (or a group's) only; contacts come from the sort-and-sweep
     broadphase (``broadphase.candidate_pairs``), which visits the pairs in the order testing every pair did,
     so the results are those of the all-pairs search;
  8. sleep: with ``until_rest``, an island (bodies joined by box-box contacts) whose bodies have all been
     supported and slower than ``sleep_speed`` at every point for ``sleep_time`` falls asleep
     (``islands.fall_asleep``: velocities zero, no cost until touched); the run stops once every body sleeps.
Impacts between boxes are resolved in the substep where the gap closes (not located in time as the
floor-only solver locates a box's impacts with the floor).
"""

import math

import numpy as np

from .. import layout
from ..compile.compilation import jit_kernel, jit_stage
from ..kernel_support import read_settings, record_event, store_state, write_stats
from ..robust.contact_solver import CORNER_ROWS, MAX_CORNERS
from ..robust.robust_solver import MEMORY_SIZE, energy_limit_scale
from .alone import advance_alone, count_awake, steps_alone
from .broadphase import candidate_pairs, sweep_axis
from .colliding_solver import body_reach, substeps
from .groups import keep_group, next_group, sort_kept, step_groups
from .islands import (
    fall_asleep,
    join_contacts,
    join_islands,
    keep_sleeping,
    restore_sleeping,
    sleep_placed,
    sleeps_through,
    wake_touched,
)
from .limits import ALONE_LIMIT, CONTACT_TOLERANCE, DIRECT_LIMIT, MAX_SUBSTEPS, MIN_CAPACITY
from .narrowphase import (
    APPROACH,
    BODY1,
    BODY2,
    CONTACT_COLUMNS,
    FRICTION_IMPULSE,
    GAP,
    ID_COLUMNS,
    IMPULSE,
    KEY,
    NX,
    NY,
    RESTITUTION,
    TARGET,
    find_contacts,
    update_geometry,
)
from .prepare import body_kinetic_energy, prepare_contacts, relative_velocity
from .relax import correct_penetrations
from .restitution import apply_restitution
from .solve import solve_velocities
from .warm_start import warm_start


# -- 1. broadphase and narrowphase -------------------------------------------------------------------
@jit_stage
def contact_reach(pose, half, vel, radius, awake, h, gravity, tolerance, trig, bound, reach, floor_reach):
    """Each awake body's bounding box and how far it can travel in the substep (``body_reach``); against
    the floor a body reaches its own distance plus the fastest body's (a struck box moves further than its
    own speed says)."""
    update_geometry(pose, half, awake, trig, bound)
    fastest = body_reach(vel, radius, awake, h, gravity, tolerance, reach)
    for b in range(pose.shape[0]):
        floor_reach[b] = reach[b] + fastest


@jit_stage
def note_penetration(contacts, ids, count, max_penetration):
    """The deepest penetration each body has had (-gap of its contacts), for the stats."""
    for c in range(count):
        depth = -contacts[c, GAP]
        b1 = ids[c, BODY1]
        b2 = ids[c, BODY2]
        max_penetration[b1] = max(max_penetration[b1], depth)
        if b2 >= 0:
            max_penetration[b2] = max(max_penetration[b2], depth)


@jit_stage(nrt=True)  # it sorts (numba's sort keeps a stack array)
def start_sweep(pose, half, everyone, trig, bound, order):
    """Every box's geometry (``update_geometry``), the sweep's axis (returned) and the boxes in order along it
    (into ``order``), for the broadphase's first search."""
    update_geometry(pose, half, everyone, trig, bound)
    axis = sweep_axis(pose, everyone)
    order[:] = np.argsort(pose[:, axis])
    return axis


# -- 2.-3. before the solve: energies, approach speeds, gravity ------------------------------------
@jit_stage
def approach_speeds(contacts, ids, count, vel, params, kinetic_before):
    """Each body's kinetic energy and each contact's approach speed u_rel . n before the substep's impulses."""
    for b in range(vel.shape[0]):
        kinetic_before[b] = body_kinetic_energy(vel, b, params)
    for c in range(count):
        ux, uy = relative_velocity(c, contacts, ids, vel)
        contacts[c, APPROACH] = ux * contacts[c, NX] + uy * contacts[c, NY]


@jit_stage
def integrate_velocities(vel, awake, h, gravity):
    """v += h g for the awake bodies (a sleeping body does not fall)."""
    for b in range(vel.shape[0]):
        if awake[b]:
            vel[b, 1] += h * gravity


# -- 4. warm start and solve -------------------------------------------------------------------------
@jit_stage
def speculative_targets(contacts, count, h):
    """u_rel . n >= -max(gap, 0) / h: each gap may close within the substep but not pass."""
    for c in range(count):
        contacts[c, TARGET] = -max(contacts[c, GAP], 0.0) / h


@jit_stage
def store_impulses(contacts, ids, count, previous_keys, previous_impulses):
    """Keep the solved impulses by contact key for the next substep's warm start; returns how many."""
    for c in range(count):
        previous_keys[c] = ids[c, KEY]
        previous_impulses[c, 0] = contacts[c, IMPULSE]
        previous_impulses[c, 1] = contacts[c, FRICTION_IMPULSE]
    return count


# -- 5. restitution ----------------------------------------------------------------------------------
@jit_stage
def restitution_targets(contacts, count, threshold):
    """u_rel . n >= -e u0 for the contacts that approached faster than the threshold and took an impulse;
    returns how many (the impacts)."""
    impacts = 0
    for c in range(count):
        if contacts[c, APPROACH] < -threshold and contacts[c, IMPULSE] > 0.0:
            contacts[c, TARGET] = -contacts[c, RESTITUTION] * contacts[c, APPROACH]
            impacts += 1
    return impacts


# -- 6. no energy gained -----------------------------------------------------------------------------
@jit_stage
def mark_touched(contacts, ids, count, impacts, threshold, touched, impacted):
    """Which bodies took an impulse in the substep, and at how many impacts each."""
    for b in range(touched.shape[0]):
        touched[b] = False
        impacted[b] = 0
    for c in range(count):
        if contacts[c, IMPULSE] > 0.0:
            b1 = ids[c, BODY1]
            b2 = ids[c, BODY2]
            touched[b1] = True
            if b2 >= 0:
                touched[b2] = True
            if impacts > 0 and contacts[c, APPROACH] < -threshold:
                impacted[b1] += 1
                if b2 >= 0:
                    impacted[b2] += 1


@jit_stage
def limit_energy(contacts, ids, count, vel, params, kinetic_before, touched, impacted, supported, first_contact,
                 n_impacts, h, t, gravity, record, events):
    """Scale the touched bodies' velocities by the one s in [0, 1] that keeps their kinetic + potential energy
    from rising in the substep (``energy_limit_scale``); count (and with ``record`` log) each body's impacts."""
    before = 0.0
    after = 0.0
    rise = 0.0
    for b in range(vel.shape[0]):
        if touched[b]:
            supported[b] = True
            if math.isnan(first_contact[b]):
                first_contact[b] = t
            before += kinetic_before[b]
            after += body_kinetic_energy(vel, b, params)
            rise += -gravity * h * vel[b, 1] * params[b, layout.MASS]
        if impacted[b] > 0:
            if record:
                approach = 0.0
                for c in range(count):
                    if ids[c, BODY1] == b or ids[c, BODY2] == b:
                        approach = max(approach, -contacts[c, APPROACH])
                record_event(events, b, n_impacts[b], t, approach, impacted[b])
            n_impacts[b] += 1
    if after > 0.0:
        scale = energy_limit_scale(before, after, rise)
        if scale < 1.0:
            for b in range(vel.shape[0]):
                if touched[b]:
                    vel[b, 0] *= scale
                    vel[b, 1] *= scale
                    vel[b, 2] *= scale


# -- 7. integrate positions --------------------------------------------------------------------------
@jit_stage
def integrate_positions(pose, vel, awake, touched, h, gravity):
    """The exact parabola out of contact (x += h v - h^2 g / 2, v at the end of the substep), symplectic
    Euler in contact (x += h v)."""
    for b in range(pose.shape[0]):
        if awake[b]:
            pose[b, 0] += h * vel[b, 0]
            pose[b, 1] += h * vel[b, 1]
            if not touched[b]:
                pose[b, 1] -= 0.5 * h * h * gravity
            pose[b, 2] += h * vel[b, 2]


# -- after the step: record, check, sleep ------------------------------------------------------------
@jit_stage
def record_states(trajectory, row, pose, vel):
    for b in range(pose.shape[0]):
        store_state(trajectory, row, b, pose[b, 0], pose[b, 1], pose[b, 2], vel[b, 0], vel[b, 1], vel[b, 2])


@jit_stage
def end_step(pose, vel, awake, n_stepped, n, record, trajectory):
    """Count the step for the awake bodies, record it, and say whether every body is still finite."""
    if record:
        record_states(trajectory, n, pose, vel)
    finite = True
    for b in range(pose.shape[0]):
        n_stepped[b] += awake[b]
        if not (math.isfinite(pose[b, 0]) and math.isfinite(pose[b, 1]) and math.isfinite(pose[b, 2])
                and math.isfinite(vel[b, 0]) and math.isfinite(vel[b, 1]) and math.isfinite(vel[b, 2])):
            finite = False
    return finite


@jit_stage
def sleep_islands(pose, vel, radius, awake, supported, still_for, sleep_speed, sleep_time, parent, ready, island,
                  rest_time, n, dt, record, trajectory):
    """8. The islands (``parent``, joined by the last substep's box-box contacts) whose bodies have all been
    supported and slower than ``sleep_speed`` at every point for ``sleep_time`` fall asleep
    (``islands.fall_asleep``); returns how many bodies did."""
    for b in range(pose.shape[0]):
        if awake[b]:
            speed = math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(vel[b, 2]) * radius[b]
            still_for[b] = still_for[b] + dt if supported[b] and speed <= sleep_speed else 0.0
    slept = fall_asleep(awake, still_for, sleep_time, parent, ready, island, vel)
    if slept > 0:
        for b in range(pose.shape[0]):
            if not awake[b] and math.isnan(rest_time[b]):
                rest_time[b] = n * dt
                if record:
                    store_state(trajectory, n, b, pose[b, 0], pose[b, 1], pose[b, 2], 0.0, 0.0, 0.0)
    return slept


@jit_stage
def load_warm_start(warm, n, previous_keys, previous_impulses, dt):
    """The contacts' impulses a caller kept from its last call (``layout.WARM_START_SIZE``: row 0 holds the
    contact count, the substep length and the body count k, then WARM_BODY_ROWS a body, ``islands.keep_sleeping``,
    then a row per contact: key, normal and friction impulse), into the kernel's arrays; returns (count,
    substep length). An empty ``warm`` (none kept), or one kept from a scene of another number of bodies than
    this one's ``n`` (a contact's key names its bodies by their number among n), starts cold: (0, dt)."""
    if warm.shape[0] == 0 or np.int64(warm[0, 2]) != n:
        return 0, dt
    first = 1 + layout.WARM_BODY_ROWS * n
    count = min(np.int64(warm[0, 0]), warm.shape[0] - first, previous_keys.shape[0])
    for c in range(count):
        previous_keys[c] = np.int64(warm[first + c, 0])
        previous_impulses[c, 0] = warm[first + c, 1]
        previous_impulses[c, 1] = warm[first + c, 2]
    return count, warm[0, 1] if count > 0 else dt


@jit_stage
def store_warm_start(warm, previous_keys, previous_impulses, n_previous, h_previous, pose, params, awake, island,
                     still_for):
    """Into ``warm`` for the next call (``load_warm_start``'s layout; nothing if it is empty): each body's sleep
    (``islands.keep_sleeping``), then the last substep's impulses by contact key, as many as it has rows for
    (the keys are sorted, so a prefix is a warm start too)."""
    if warm.shape[0] == 0:
        return
    first = 1 + layout.WARM_BODY_ROWS * keep_sleeping(warm, pose, params, awake, island, still_for)
    count = min(n_previous, warm.shape[0] - first)
    warm[0, 0] = count
    warm[0, 1] = h_previous
    for c in range(count):
        warm[first + c, 0] = previous_keys[c]
        warm[first + c, 1] = previous_impulses[c, 0]
        warm[first + c, 2] = previous_impulses[c, 1]


@jit_stage
def write_back(state, stats, pose, vel, first_contact, n_impacts, n_stepped, max_penetration, rest_time, n, dt,
               status, fail_step, warm, previous_keys, previous_impulses, n_previous, h_previous, awake, island,
               still_for, params):
    """The bodies' final states and stats (a failure is reported on the bodies that are not finite), and the
    bodies' sleep and the last substep's impulses into ``warm`` for the next call (``store_warm_start``)."""
    store_warm_start(warm, previous_keys, previous_impulses, n_previous, h_previous, pose, params, awake, island,
                     still_for)
    for b in range(state.shape[0]):
        state[b, 0], state[b, 1], state[b, 2] = pose[b, 0], pose[b, 1], pose[b, 2]
        state[b, 3], state[b, 4], state[b, 5] = vel[b, 0], vel[b, 1], vel[b, 2]
        body_status = layout.STATUS_OK
        if status != layout.STATUS_OK and not (math.isfinite(pose[b, 0]) and math.isfinite(pose[b, 1])
                                               and math.isfinite(pose[b, 2]) and math.isfinite(vel[b, 0])
                                               and math.isfinite(vel[b, 1]) and math.isfinite(vel[b, 2])):
            body_status = status
        write_stats(stats, b, first_contact[b], n_impacts[b], n_stepped[b], max_penetration[b], rest_time[b],
                    n * dt, body_status, fail_step if body_status != layout.STATUS_OK else -1, n + 1)


@jit_stage(nrt=True)  # it allocates the larger arrays (rarely: each doubling is kept for the rest of the run)
def grown_contacts(contacts, ids, previous_keys, previous_impulses, n_previous):
    """The contact arrays at twice their rows, the last substep's impulses kept (for the warm start)."""
    capacity = 2 * contacts.shape[0]
    keys = np.zeros(capacity, np.int64)
    keys[:n_previous] = previous_keys[:n_previous]
    impulses = np.zeros((capacity, 2))
    impulses[:n_previous] = previous_impulses[:n_previous]
    return np.zeros((capacity, CONTACT_COLUMNS)), np.zeros((capacity, ID_COLUMNS), np.int64), keys, impulses


@jit_stage(nrt=True)  # as grown_contacts
def grown_rows(keys, rows, count):
    """``keys`` and ``rows`` at twice their rows, the first ``count`` kept."""
    grown_keys = np.zeros(2 * keys.shape[0], np.int64)
    grown_keys[:count] = keys[:count]
    grown = np.zeros((2 * rows.shape[0], rows.shape[1]))
    grown[:count] = rows[:count]
    return grown_keys, grown


@jit_stage(nrt=True)  # it allocates (once a run)
def group_arrays(nb, capacity):
    """The groups' arrays of a step (``groups``): each body's group, the mask of the one stepped, their work, its
    impulses (keys, impulses) and every group's (keys, impulses with h), for ``capacity`` contacts."""
    group_work = (np.zeros((nb, 2)), np.zeros((nb, 2), np.int64), np.zeros(MAX_SUBSTEPS + 1, np.int64))
    group_kept = (np.empty(capacity, np.int64), np.empty((capacity, 2)))
    kept = (np.empty(capacity, np.int64), np.empty((capacity, 3)))
    return np.full(nb, -1, np.int64), np.zeros(nb, np.bool_), group_work, group_kept, kept


@jit_stage(nrt=True)  # it allocates (once a run)
def exact_work(nb):
    """The exact solves' work arrays (``solve_substep``'s ``exact``: W, its factor, free velocities, x, the active
    set, index, y, the contacts' states) and the sweeps' (``gauss_seidel``'s moved)."""
    return (np.zeros((DIRECT_LIMIT, DIRECT_LIMIT)), np.zeros((DIRECT_LIMIT, DIRECT_LIMIT)), np.zeros(DIRECT_LIMIT),
            np.zeros(DIRECT_LIMIT), np.zeros(DIRECT_LIMIT, np.bool_), np.zeros(DIRECT_LIMIT, np.int64),
            np.zeros(DIRECT_LIMIT), np.zeros(DIRECT_LIMIT, np.int64), np.zeros((2, nb), np.bool_))


# a grid step's progress, for the kernel to resume ``advance_steps`` where it left off to make room
NEW_STEP = 0  # a grid step starts: wake, alone, substeps
WAKING = 1  # the wake's search ran out of room for pairs (the islands it woke stay awake; no new reach)
IN_SUBSTEPS = 2  # a substep's contacts ran out of room: its stage 1 is redone (the same pairs and contacts)
DONE, MORE_PAIRS, MORE_CONTACTS = 0, 1, 2  # what the kernel is to do when ``advance_steps`` returns


@jit_stage(inline="always")  # into advance_steps
def find_substep_contacts(pose, half, vel, radius, awake, h, gravity, tolerance, trig, bound, reach, floor_reach,
                          axis, order, low, pair_keys, contacts, ids):
    """1. broadphase and narrowphase: the contacts within what the bodies can travel in the substep
    (``contact_reach``, ``broadphase.candidate_pairs``, ``narrowphase.find_contacts``); returns how many, or
    -MORE_PAIRS / -MORE_CONTACTS when ``pair_keys`` / ``contacts`` is full (each search is repeated as it was:
    the sweep order it repairs is sorted already)."""
    contact_reach(pose, half, vel, radius, awake, h, gravity, tolerance, trig, bound, reach, floor_reach)
    n_pairs = candidate_pairs(pose, bound, reach, awake, awake, axis, order, low, pair_keys)
    if n_pairs < 0:
        return -MORE_PAIRS
    count = find_contacts(pose, trig, half, reach, floor_reach, pair_keys, n_pairs, awake, contacts, ids)
    return count if count >= 0 else -MORE_CONTACTS


@jit_stage(inline="always")  # into advance_steps, which counts no references
def solve_substep(contacts, ids, count, pose, vel, pseudo, params, settings, inv_mass, inv_inertia, awake, h, t,
                  tolerance, warm_from, store_into, kinetic_before, max_penetration, touched, impacted, supported,
                  first_contact, n_impacts, use_penalty, use_friction, record, events, exact):
    """Stages 2.-7. of a substep of length h starting at time t, over the ``count`` contacts found (stage 1),
    warm-started from ``warm_from`` (keys, impulses, their count and substep length); returns how many impulses
    it keeps, by key into ``store_into`` (keys, impulses; may be ``warm_from``'s arrays), for the next substep's
    warm start. ``exact``: the solves' work arrays (``normal_lcp``, ``joint_contact_solve``, ``gauss_seidel``).
    (At most 30 arguments: numba inlines no call of more.)"""
    gravity, threshold = settings[layout.GRAVITY], settings[layout.RESTITUTION_THRESHOLD]
    previous_keys, previous_impulses, n_previous, h_previous = warm_from
    kept_keys, kept_impulses = store_into
    w, factor, free, x, active, index, lcp_y, contact_state, moved = exact
    prepare_contacts(contacts, ids, count, params, inv_mass, inv_inertia)
    note_penetration(contacts, ids, count, max_penetration)
    # 2. relax: split-impulse correction of penetrations deeper than the slop
    if use_penalty and count > 0:
        correct_penetrations(contacts, ids, count, pose, vel, pseudo, inv_mass, inv_inertia, h, settings, tolerance,
                             gravity, params, w, factor, free, x, active, index, lcp_y)
    approach_speeds(contacts, ids, count, vel, params, kinetic_before)
    # 3. integrate velocities
    integrate_velocities(vel, awake, h, gravity)
    # 4. warm start, solve (speculative targets), store impulses for the next substep
    speculative_targets(contacts, count, h)
    warm_start(contacts, ids, count, previous_keys, previous_impulses, n_previous, h / h_previous, vel, inv_mass,
               inv_inertia, pose, h, gravity)
    solve_velocities(contacts, ids, count, vel, inv_mass, inv_inertia, use_friction, w, factor, free, x, active,
                     index, lcp_y, contact_state, moved, settings)
    n_stored = store_impulses(contacts, ids, count, kept_keys, kept_impulses)
    # 5. restitution for impacts only: solved with every contact and friction, then polished
    impacts = restitution_targets(contacts, count, threshold)
    if impacts > 0:
        solve_velocities(contacts, ids, count, vel, inv_mass, inv_inertia, use_friction, w, factor, free, x, active,
                         index, lcp_y, contact_state, moved, settings)
        apply_restitution(contacts, ids, count, vel, inv_mass, inv_inertia, threshold)
    # 6. no energy gained by the bodies that took an impulse
    mark_touched(contacts, ids, count, impacts, threshold, touched, impacted)
    limit_energy(contacts, ids, count, vel, params, kinetic_before, touched, impacted, supported, first_contact,
                 n_impacts, h, t, gravity, record, events)
    # 7. integrate positions
    integrate_positions(pose, vel, awake, touched, h, gravity)
    return n_stored


@jit_stage(inline="always")  # into advance_steps, as the substeps were before groups (a call cost 4% of an OnBox throw)
def advance_substeps(n, n_sub, first_sub, n_previous, h_previous, awake, pose, half, vel, radius, params, settings,
                     inv_mass, inv_inertia, tolerance, sweep, body_work, pair_keys, contacts, ids, previous_keys,
                     previous_impulses, exact, flags, events):
    """The substeps 1.-7. of grid step n over every awake body, from substep first_sub of n_sub, each warm-started
    from the last (``previous_keys``, ``previous_impulses``: n_previous of substep length h_previous). ``sweep``:
    (axis, trig, bound, reach, floor_reach, low, order), ``body_work``: (pseudo, kinetic_before, max_penetration,
    touched, impacted, supported, first_contact, n_impacts), ``flags``: (use_penalty, use_friction, record) (numba
    inlines no call of more than 30 arguments). Returns (substep reached, its contacts, impulses kept, their substep
    length, DONE), or where it stopped and MORE_PAIRS / MORE_CONTACTS when ``pair_keys`` / ``contacts`` is full (the
    kernel grows them and calls again)."""
    axis, trig, bound, reach, floor_reach, low, order = sweep
    pseudo, kinetic_before, max_penetration, touched, impacted, supported, first_contact, n_impacts = body_work
    use_penalty, use_friction, record = flags
    dt, gravity = settings[layout.DT], settings[layout.GRAVITY]
    h, count = dt / n_sub, 0
    for sub in range(first_sub, n_sub):
        count = find_substep_contacts(pose, half, vel, radius, awake, h, gravity, tolerance, trig, bound, reach,
                                      floor_reach, axis, order, low, pair_keys, contacts, ids)
        if count < 0:
            return sub, 0, n_previous, h_previous, -count
        # 2.-7. relax, integrate velocities, warm start, solve, restitution, no energy gained, integrate positions
        n_previous = solve_substep(
            contacts, ids, count, pose, vel, pseudo, params, settings, inv_mass, inv_inertia, awake, h,
            n * dt + sub * h, tolerance, (previous_keys, previous_impulses, n_previous, h_previous),
            (previous_keys, previous_impulses), kinetic_before, max_penetration, touched, impacted, supported,
            first_contact, n_impacts, use_penalty, use_friction, record, events, exact)
        h_previous = h
    return n_sub, count, n_previous, h_previous, DONE


@jit_stage
def advance_groups(n, group, n_sub, first_sub, n_group, n_kept, group_of, in_group, pose, half, vel, radius, params,
                   settings, inv_mass, inv_inertia, tolerance, axis, trig, bound, reach, floor_reach, pseudo,
                   kinetic_before, max_penetration, touched, impacted, supported, first_contact, n_impacts, parent, low,
                   order, pair_keys, contacts, ids, previous, group_kept, kept, exact, use_penalty, use_friction,
                   record, events):
    """The substeps 1.-7. of grid step n group by group (``groups``), from group ``group`` (its smallest body) at
    substep first_sub of its n_sub (0: not counted yet): each group's count is its own (``substeps`` over its
    bodies); its first substep is warm-started from ``previous`` (the last step's keys, impulses, their count and
    substep length), the next from its own (``group_kept``: keys, impulses; n_group kept); its last impulses are
    appended to ``kept`` (keys, impulses with h; n_kept kept, ``keep_group``) and its box-box contacts joined in
    ``parent`` (the islands to sleep). Returns (group, n_sub, first_sub, n_group, n_kept, DONE), or where it
    stopped and MORE_CONTACTS when ``contacts`` or ``kept`` is full (the kernel grows them and calls again)."""
    dt, gravity = settings[layout.DT], settings[layout.GRAVITY]
    nb, smallest_half = pose.shape[0], half.min()
    group_keys, group_impulses = group_kept
    kept_keys, kept_impulses = kept
    while group < nb:
        for b in range(nb):
            in_group[b] = group_of[b] == group
        if n_sub == 0:
            n_sub = substeps(vel, radius, in_group, smallest_half, dt, gravity)
        h = dt / n_sub
        count = 0
        for sub in range(first_sub, n_sub):
            count = find_substep_contacts(pose, half, vel, radius, in_group, h, gravity, tolerance, trig, bound,
                                          reach, floor_reach, axis, order, low, pair_keys, contacts, ids)
            if count < 0:
                return group, n_sub, sub, n_group, n_kept, -count
            warm_from = previous if sub == 0 else (group_keys, group_impulses, n_group, h)
            n_group = solve_substep(
                contacts, ids, count, pose, vel, pseudo, params, settings, inv_mass, inv_inertia, in_group, h,
                n * dt + sub * h, tolerance, warm_from, group_kept, kinetic_before, max_penetration, touched,
                impacted, supported, first_contact, n_impacts, use_penalty, use_friction, record, events, exact)
        join_contacts(ids, count, parent)  # (none when resumed only to keep its impulses: joined already)
        kept_now = keep_group(group_keys, group_impulses, n_group, h, kept_keys, kept_impulses, n_kept)
        if kept_now < 0:
            return group, n_sub, n_sub, n_group, n_kept, MORE_CONTACTS
        group, n_sub, first_sub, n_group, n_kept = next_group(group_of, group), 0, 0, 0, kept_now
    return group, n_sub, first_sub, n_group, n_kept, DONE


@jit_stage
def advance_steps(progress, pose, vel, half, params, settings, inv_mass, inv_inertia, radius, tolerance, axis, trig,
                  bound, reach, floor_reach, pseudo, work, kinetic_before, max_penetration, touched, supported,
                  impacted, n_impacts, n_stepped, first_contact, everyone, awake, island, still_for, rest_time,
                  parent, ready, low, order, pair_keys, memory, alone, corners, corner_delassus, corner_ids, contacts,
                  ids, previous_keys, previous_impulses, group_of, in_group, group_work, group_kept, kept, exact,
                  use_penalty, use_friction, record, trajectory, events):
    """The grid steps while a body is awake (the step script: 0. wake, alone, the substeps 1.-7. over all awake
    bodies or group by group, 8. sleep), from ``progress`` = (step n, awake bodies, impulses kept, their substep
    length, NEW_STEP / WAKING / IN_SUBSTEPS, substeps, substep, group (-1: one), impulses kept by the group, by the
    groups). It allocates nothing (nor counts references): when the pairs or contacts outgrow their arrays it returns,
    and the kernel grows them and calls again. Returns (progress, status, failing step, DONE / MORE_*)."""
    dt, gravity, max_steps, until_rest, threshold, sleep_speed, sleep_time, slop = read_settings(settings)
    n, n_awake, n_previous, h_previous, phase, n_sub, first_sub, group, n_group, n_kept = progress
    nb, count, smallest_half = pose.shape[0], 0, half.min()
    while n < max_steps and n_awake > 0:
        if phase != IN_SUBSTEPS:
            if n_awake < nb:  # 0. wake the sleeping islands an awake body can reach in this step
                if phase != WAKING:
                    update_geometry(pose, half, awake, trig, bound)
                    body_reach(vel, radius, awake, dt, gravity, tolerance, reach)
                if wake_touched(pose, bound, reach, everyone, awake, island, still_for, rest_time, axis, order, low,
                                pair_keys) < 0:
                    return (n, n_awake, n_previous, h_previous, WAKING, n_sub, 0, -1, 0, 0), layout.STATUS_OK, -1, \
                        MORE_PAIRS
                n_awake = count_awake(awake)
            phase = NEW_STEP
            # alone: whole steps of each awake body against the floor alone while no two boxes can meet
            k = steps_alone(pose, vel, half, radius, awake, params, gravity, tolerance, dt, max_steps - n) \
                if n_awake <= ALONE_LIMIT else 0
            if k > 0:
                n, slept, failed = advance_alone(
                    k, n, pose, vel, params, awake, supported, alone, memory, n_stepped, n_impacts, first_contact,
                    max_penetration, still_for, island, rest_time, work, dt, gravity, until_rest, threshold,
                    sleep_speed, sleep_time, slop, use_penalty, use_friction, record, corners, corner_delassus,
                    corner_ids, trajectory, events)
                n_previous = 0  # the contacts of the substeps before are gone
                if failed >= 0:
                    return (n, n_awake, n_previous, h_previous, phase, n_sub, 0, -1, 0, 0), layout.STATUS_NONFINITE, \
                        n, DONE
                n_awake -= slept
                continue
            # one substep count, or groups (a wake redone after MORE_PAIRS wakes nothing more)
            n_sub, group = step_groups(pose, half, vel, radius, everyone, awake, n_awake, smallest_half, dt, gravity,
                                       tolerance, trig, bound, reach, axis, order, low, pair_keys, group_of,
                                       group_work, parent)
            if n_sub < 0:
                return (n, n_awake, n_previous, h_previous, NEW_STEP, 1, 0, -1, 0, 0), layout.STATUS_OK, -1, \
                    MORE_PAIRS
            first_sub, n_group, n_kept = 0, 0, 0
            supported[:] = False
            alone[:] = False
        grouped = group >= 0
        if grouped:  # 1.-7. group by group, each with its own substeps
            group, n_sub, first_sub, n_group, n_kept, need = advance_groups(
                n, group, n_sub, first_sub, n_group, n_kept, group_of, in_group, pose, half, vel, radius, params,
                settings, inv_mass, inv_inertia, tolerance, axis, trig, bound, reach, floor_reach, pseudo,
                kinetic_before, max_penetration, touched, impacted, supported, first_contact, n_impacts, parent, low,
                order, pair_keys, contacts, ids, (previous_keys, previous_impulses, n_previous, h_previous),
                group_kept, kept, exact, use_penalty, use_friction, record, events)
        else:  # 1.-7. over every awake body
            first_sub, count, n_previous, h_previous, need = advance_substeps(
                n, n_sub, first_sub, n_previous, h_previous, awake, pose, half, vel, radius, params, settings, inv_mass,
                inv_inertia, tolerance, (axis, trig, bound, reach, floor_reach, low, order), (pseudo, kinetic_before,
                max_penetration, touched, impacted, supported, first_contact, n_impacts), pair_keys, contacts, ids,
                previous_keys, previous_impulses, exact, (use_penalty, use_friction, record), events)
        if need != DONE:
            return (n, n_awake, n_previous, h_previous, IN_SUBSTEPS, n_sub, first_sub, group, n_group, n_kept), \
                layout.STATUS_OK, -1, need
        if grouped:  # every group's last impulses, in key order, for the next step's warm start
            h_previous = sort_kept(kept[0], kept[1], n_kept, previous_keys, previous_impulses, dt)
            n_previous, group = n_kept, -1
        phase, n = NEW_STEP, n + 1
        if not end_step(pose, vel, awake, n_stepped, n, record, trajectory):
            return (n, n_awake, n_previous, h_previous, phase, n_sub, 0, -1, 0, 0), layout.STATUS_NONFINITE, n, DONE
        if until_rest:  # 8. sleep
            if not grouped:
                join_islands(ids, count, parent)
            n_awake -= sleep_islands(pose, vel, radius, awake, supported, still_for, sleep_speed, sleep_time, parent,
                                     ready, island, rest_time, n, dt, record, trajectory)
    return (n, n_awake, n_previous, h_previous, phase, n_sub, 0, -1, 0, 0), layout.STATUS_OK, -1, DONE


def make_colliding_robust_kernel(use_penalty: bool, use_friction: bool, record: bool, source_digest: int):
    """Build the robust kernel for scenes whose boxes collide (flags are compile-time, as
    ``robust_solver.make_robust_kernel``'s): ``run(state, params, settings, stats, trajectory, events)``
    advances every body of the scene together, in place."""
    PENALTY, FRICTION_ON, RECORD, DIGEST = use_penalty, use_friction, record, source_digest

    @jit_kernel
    def run(state, params, settings, stats, trajectory, events, warm):
        _ = DIGEST  # the on-disk cache key includes every engine source (see robust_solver)
        dt, gravity, max_steps, until_rest, threshold, sleep_speed, sleep_time, slop = read_settings(settings)
        nb = state.shape[0]
        if until_rest and not RECORD and sleeps_through(warm, state, params, dt, max(8 * nb, MIN_CAPACITY), stats):
            return  # every body kept asleep and untouched: nothing to set up
        pose = state[:, 0:3].copy()
        vel = state[:, 3:6].copy()
        half = params[:, 0:2].copy()
        inv_mass = 1.0 / params[:, layout.MASS]
        inv_inertia = 1.0 / params[:, layout.INERTIA]
        radius = np.sqrt(half[:, 0] ** 2 + half[:, 1] ** 2)
        tolerance = CONTACT_TOLERANCE * (1.0 + radius.max())
        trig, bound, pseudo, work = np.zeros((nb, 2)), np.zeros((nb, 2)), np.zeros((nb, 3)), np.zeros((nb, 6))
        reach, floor_reach, kinetic_before, max_penetration = np.zeros(nb), np.zeros(nb), np.zeros(nb), np.zeros(nb)
        touched, supported, ready = np.zeros(nb, np.bool_), np.zeros(nb, np.bool_), np.zeros(nb, np.bool_)
        impacted, n_impacts, n_stepped = np.zeros(nb, np.int64), np.zeros(nb, np.int64), np.zeros(nb, np.int64)
        first_contact = np.full(nb, math.nan)
        capacity = max(8 * nb, MIN_CAPACITY)  # contact rows, each written before it is read: left unzeroed
        contacts, ids = np.empty((capacity, CONTACT_COLUMNS)), np.empty((capacity, ID_COLUMNS), np.int64)
        previous_keys, previous_impulses = np.empty(capacity, np.int64), np.empty((capacity, 2))
        group_of, in_group, group_work, group_kept, kept = group_arrays(nb, capacity)
        exact = exact_work(nb)
        # broadphase (sort and sweep) and islands (sleeping; island: a sleeping body's root body, -1 while awake)
        everyone, awake, island = np.ones(nb, np.bool_), np.ones(nb, np.bool_), np.full(nb, -1, np.int64)
        still_for = np.zeros(nb)  # [s] how long each awake body has been supported and still
        rest_time, parent = np.full(nb, math.nan), np.zeros(nb, np.int64)  # when each body last fell asleep; work
        low, order, pair_keys = np.zeros(nb), np.empty(nb, np.int64), np.zeros(max(4 * nb, MIN_CAPACITY), np.int64)
        # bodies advanced alone: advance_box's memory rows and work arrays (contact_solver)
        memory = np.zeros((nb, MEMORY_SIZE))
        alone = np.zeros(nb, np.bool_)  # whether a body's memory row holds on (advanced alone since the substeps)
        corners, corner_delassus = np.zeros((CORNER_ROWS, MAX_CORNERS)), np.zeros((MAX_CORNERS, MAX_CORNERS))
        corner_ids = np.zeros(MAX_CORNERS, np.int64)
        n_awake = nb
        n_previous, h_previous = load_warm_start(warm, nb, previous_keys, previous_impulses, dt)  # from the last call
        if RECORD:
            record_states(trajectory, 0, pose, vel)
        if until_rest:  # the islands asleep at the end of the last call sleep again
            n_awake -= restore_sleeping(warm, pose, vel, params, awake, island, still_for, rest_time, ready)
        axis = start_sweep(pose, half, everyone, trig, bound, order) if n_awake > 0 else 0  # all asleep: no sweep
        if until_rest and n_awake > 0:  # and the bodies placed at rest
            slept = -1
            while slept < 0:
                slept = sleep_placed(pose, vel, half, bound, reach, everyone, awake, island, rest_time, ready,
                                     sleep_speed, tolerance, axis, order, low, pair_keys)
                if slept < 0:
                    pair_keys = np.zeros(2 * pair_keys.shape[0], np.int64)
            n_awake -= slept
        progress, need = (0, n_awake, n_previous, h_previous, NEW_STEP, 1, 0, -1, 0, 0), MORE_PAIRS
        while need != DONE:  # the steps, each time their pairs or contacts outgrow their arrays grown
            progress, status, fail_step, need = advance_steps(
                progress, pose, vel, half, params, settings, inv_mass, inv_inertia, radius, tolerance, axis, trig,
                bound, reach, floor_reach, pseudo, work, kinetic_before, max_penetration, touched, supported,
                impacted, n_impacts, n_stepped, first_contact, everyone, awake, island, still_for, rest_time, parent,
                ready, low, order, pair_keys, memory, alone, corners, corner_delassus, corner_ids, contacts, ids,
                previous_keys, previous_impulses, group_of, in_group, group_work, group_kept, kept, exact, PENALTY,
                FRICTION_ON, RECORD, trajectory, events)
            if need == MORE_PAIRS:
                pair_keys = np.zeros(2 * pair_keys.shape[0], np.int64)
            elif need == MORE_CONTACTS:
                contacts, ids, previous_keys, previous_impulses = grown_contacts(contacts, ids, previous_keys,
                                                                                 previous_impulses, progress[2])
                group_kept = grown_rows(group_kept[0], group_kept[1], progress[8])
                kept = grown_rows(kept[0], kept[1], progress[9])
        n, n_previous, h_previous = progress[0], progress[2], progress[3]
        write_back(state, stats, pose, vel, first_contact, n_impacts, n_stepped, max_penetration, rest_time, n, dt,
                   status, fail_step, warm, previous_keys, previous_impulses, n_previous, h_previous, awake, island,
                   still_for, params)

    return run
