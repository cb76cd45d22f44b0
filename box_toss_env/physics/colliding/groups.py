"""Groups of the awake bodies for the substeps of a grid step: bodies that cannot touch one another within
the step and need fewer substeps than the fastest take them apart, so a box thrown fast far from a pile does not
make the pile pay its substeps.

Two awake bodies cannot be apart within the step when a chain of the step's candidate pairs joins them
(``step_pairs``: the broadphase's test, each body reaching what it travels in the step dt (``body_reach``) plus what
the fastest body travels: a struck body moves further than its own speed says, as for the floor's contacts; the same
pairs bound every substep's search); bodies in contact are so joined too (a contact's gap is within the reach of a
substep). Each such set needs the substep count of its fastest point and turn (``substep_count``); the sets that
need the same count make one group, named by its smallest body, and the groups are taken in that order
(``plan_substeps``). A split must pay (``group_by_substeps``): it saves each body the substeps its group takes fewer
than the fastest group, and costs each group's substeps a pass over every body (their loops run over the scene's
arrays); where it saves fewer than SPLIT_SAVING body-substeps, or fewer than 1 / SOLVE_SHARE of the passes it adds,
there is one group, and the step is what it was without groups, bit for bit (as it is wherever every body needs one
count, a resting pile's usual case: then no grouping is looked for, ``one_count``).

Each group's first substep is warm-started from the impulses the last step kept (all groups' contacts, by
key), its later substeps from its own; at its end a group's last impulses are kept with its substep length
h (``keep_group``), and at the step's end all groups' are put in key order, each scaled to one substep length
(``sort_kept``: p h_ref / h with h_ref the first group's, the warm start scales them again by h' / h_ref), for
the next step's warm start and, through it, the next run's.
"""

import math

from ..compile.compilation import jit_stage
from ..tunables import PAIR_MARGIN, ROUNDING, SOLVE_SHARE, SPLIT_SAVING
from .broadphase import candidate_pairs, kept_pairs, sort_intervals
from .islands import find_root
from .parallel import PARALLEL_BODIES, geometry_and_reach, parallel_candidate_pairs
from .substeps import contact_speeds, substep_count, substeps


@jit_stage
def step_pairs(context, bodies, sweep, sleep, n_sub):
    """The step's candidate pairs among the awake bodies, into ``sweep.pairs``. A step of one substep: the substep's own
    search (its find contacts stage's geometry, reaches over dt and pairs, ``step.contact_reach``), which it then uses
    as they are. A step of n_sub > 1 substeps: each body reaching what it travels in the step dt plus one and a half
    times what the fastest body travels (``geometry_and_reach``; a struck body moves further than its own speed
    says): every pair a substep of the step can find (``broadphase.substep_pairs``), and the chains that join bodies
    into sets (``plan_substeps``). Returns how many, or -1 if ``sweep.pairs`` is too short (the caller grows it and
    calls again).

    The pairs are those of the last search kept (``sweep.kept``) that pass the exact test at this step's bounds and
    reaches (``broadphase.kept_pairs``), while that search still holds them all (``search_holds``): it was made with
    every reach padded by PAIR_MARGIN of the smallest half extent, and every awake body has stayed within its padded box
    since (no body woke); else a new padded search is kept first (``search_padded``). The same pairs as a search at this
    step's reaches, in the same order: two boxes whose boxes at this step's reaches overlap lie within their padded
    boxes, which overlapped at the search. A resting pile searches once, not at every step. The step's sweep order is
    sorted at this step's reaches, as a search at them leaves it (it places the contacts in blocks, ``parallel``); the
    padded search sorts its own copy (sorted by the padded reaches, boxes whose order is a rounding apart moved the
    blocks and the large pyramid's last digits)."""
    pose, reach, awake = bodies.pose, sweep.reach, sleep.awake
    fastest = geometry_and_reach(bodies, awake, context.dt, context, sweep)  # on threads for many bodies
    for b in range(pose.shape[0]):
        if n_sub == 1:
            sweep.floor_reach[b] = reach[b] + fastest
        else:
            reach[b] += fastest
    kept = sweep.kept
    if not search_holds(pose, sweep.bound, reach, awake, kept):
        if search_padded(pose, sweep, awake, PAIR_MARGIN * context.smallest_half) < 0:
            return -1
    sort_intervals(pose, sweep.bound, reach, sweep.axis, sweep.order, sweep.low)  # the sweep order at these reaches
    return kept_pairs(pose, sweep.bound, reach, awake, kept.pairs, kept.found[0], sweep.pairs)


@jit_stage
def search_padded(pose, sweep, awake, margin):
    """A pair search among the awake bodies with each reach padded by ``margin`` (on threads from PARALLEL_BODIES
    bodies up: ``parallel.parallel_candidate_pairs``, the same pairs), kept in ``sweep.kept`` with each body's centre,
    padded box and whether it is awake; returns how many pairs (kept in ``sweep.kept.found``), or -1 if they do not
    fit."""
    kept, bound, reach = sweep.kept, sweep.bound, sweep.reach
    for b in range(pose.shape[0]):
        kept.reach[b] = reach[b] + margin
        kept.centre[b, 0] = pose[b, 0]
        kept.centre[b, 1] = pose[b, 1]
        kept.half[b, 0] = bound[b, 0] + kept.reach[b]
        kept.half[b, 1] = bound[b, 1] + kept.reach[b]
        kept.awake[b] = awake[b]
        kept.order[b] = sweep.order[b]  # nearly sorted already; the step's order is left as it was
    if pose.shape[0] >= PARALLEL_BODIES:
        count = parallel_candidate_pairs(
            pose, bound, kept.reach, awake, awake, sweep.axis, kept.order, sweep.low, kept.pairs, sweep.spread
        )
    else:
        count = candidate_pairs(pose, bound, kept.reach, awake, awake, sweep.axis, kept.order, sweep.low, kept.pairs)
    kept.found[0] = count
    return count


@jit_stage
def search_holds(pose, bound, reach, awake, kept):
    """Whether the kept search holds every pair a search at these reaches finds: there is one, no body awake now was
    asleep at it, and every awake body's box at its reach lies within its padded box (less a rounding margin)."""
    if kept.found[0] < 0:
        return False
    for b in range(pose.shape[0]):
        if not awake[b]:
            continue
        if not kept.awake[b]:
            return False
        for axis in range(2):
            pad = ROUNDING * (1.0 + abs(pose[b, axis]))
            if abs(pose[b, axis] - kept.centre[b, axis]) + bound[b, axis] + reach[b] + pad > kept.half[b, axis]:
                return False
    return True


@jit_stage
def step_substeps(context, bodies, sleep):
    """The substep count every awake body's step needs (``substeps``: the fastest point's and turn's)."""
    return substeps(bodies.vel, bodies.radius, sleep.everyone, context.smallest_half, context.dt, context.gravity)


@jit_stage(inline="always")
def may_split(n_sub, n_awake):
    """Whether a step of n_sub substeps over n_awake bodies could save SPLIT_SAVING body-substeps by groups: at most
    n_sub - 1 for each body but one (two boxes never)."""
    return (n_awake - 1) * (n_sub - 1) >= SPLIT_SAVING


@jit_stage
def plan_substeps(context, bodies, sweep, sleep, groups, n_pairs, n_awake):
    """How a step of more than one substep by ``step_substeps``'s bound takes them, (n_sub, group), once its
    ``n_pairs`` candidate pairs are known (``step_pairs``): each awake body's speed against what it can touch and
    turn rate (``substeps.contact_speeds``, into ``groups.speed_turn``) set the counts. All awake bodies one count
    (group -1, n_sub that of the fastest), or group by group from the first (n_sub 0: each group counts its own,
    ``group_count``, and ``sleep.parent`` is reset for the groups to join their islands in): the sets of bodies
    joined by chains of the pairs that need the same count make a group (``group_by_substeps``), where that pays."""
    vel, awake, speed_turn, dt, smallest_half = (
        bodies.vel,
        sleep.awake,
        groups.speed_turn,
        context.dt,
        context.smallest_half,
    )
    fastest, turn = contact_speeds(bodies, sweep, awake, n_pairs, dt, context.gravity, speed_turn)
    n_sub = substep_count(fastest, turn, smallest_half, dt)
    if not may_split(n_sub, n_awake):
        return n_sub, -1
    if one_count(speed_turn, awake, smallest_half, dt):
        return n_sub, -1  # no group can need fewer substeps than another
    group_of, keys, n = groups.group_of, sweep.pairs, vel.shape[0]
    for b in range(n):
        group_of[b] = b
    for p in range(n_pairs):
        i = keys[p] // n
        r1 = find_root(group_of, i)
        r2 = find_root(group_of, keys[p] - i * n)
        if r1 != r2:
            group_of[max(r1, r2)] = min(r1, r2)
    if group_by_substeps(awake, context, groups) == 1:
        return n_sub, -1
    for b in range(n):
        sleep.parent[b] = b
    return 0, next_group(group_of, -1)


@jit_stage
def one_count(speed_turn, awake, smallest_half, dt):
    """Whether every awake body alone needs the same substep count, so every group would: the slowest speed and turn
    rate (``speed_turn``, ``contact_speeds``) need the count the fastest need (``substep_count`` grows with both)."""
    low_speed, low_turn, high_speed, high_turn = math.inf, math.inf, 0.0, 0.0
    for b in range(awake.shape[0]):
        if awake[b]:
            speed, turn = speed_turn[b, 0], speed_turn[b, 1]
            low_speed, low_turn = min(low_speed, speed), min(low_turn, turn)
            high_speed, high_turn = max(high_speed, speed), max(high_turn, turn)
    return substep_count(low_speed, low_turn, smallest_half, dt) == substep_count(
        high_speed, high_turn, smallest_half, dt
    )


@jit_stage
def group_by_substeps(awake, context, groups):
    """Join the sets of ``groups.group_of`` (a union-find forest over the awake bodies) that need the same substep
    count (``substep_count`` of each set's fastest speed and turn, from each body's in ``groups.speed_turn``, the
    set's kept in its root's row) into one group, named by its smallest body (its count: ``group_count``), into
    ``group_of`` (-1 asleep); returns how many groups, or 1 where they would not pay: if they save fewer than
    SPLIT_SAVING body-substeps in the step (each body's substeps fewer than the fastest group's, summed), or fewer
    than 1 / SOLVE_SHARE of the passes over every body that their substeps add (each group's substeps pass over
    every body, as the one count's do)."""
    dt, smallest_half = context.dt, context.smallest_half
    group_of, speed_turn, label, label_of_count = (
        groups.group_of,
        groups.speed_turn,
        groups.label,
        groups.label_of_count,
    )
    n = group_of.shape[0]
    for b in range(n):  # a root is its set's smallest body: its row is its own when its other bodies come to it
        if awake[b]:
            group_of[b] = find_root(group_of, b)
            r = group_of[b]
            speed_turn[r, 0] = max(speed_turn[r, 0], speed_turn[b, 0])
            speed_turn[r, 1] = max(speed_turn[r, 1], speed_turn[b, 1])
    label_of_count[:] = -1
    groups_count, most, passes = 0, 0, 0
    for b in range(n):
        if awake[b] and group_of[b] == b:
            count = substep_count(speed_turn[b, 0], speed_turn[b, 1], smallest_half, dt)
            if label_of_count[count] < 0:
                label_of_count[count] = b
                groups_count += 1
                passes += count
            label[b, 0], label[b, 1], most = label_of_count[count], count, max(most, count)
    saved = 0
    for b in range(n):
        if awake[b]:
            saved += most - label[group_of[b], 1]
            group_of[b] = label[group_of[b], 0]
        else:
            group_of[b] = -1
    added = (passes - most) * n
    return groups_count if saved >= SPLIT_SAVING and SOLVE_SHARE * saved >= added else 1


@jit_stage
def next_group(group_of, after):
    """The group after group ``after`` in the order of their smallest bodies (that body), or the number of
    bodies if there is none."""
    for b in range(after + 1, group_of.shape[0]):
        if group_of[b] == b:
            return b
    return group_of.shape[0]


@jit_stage
def group_count(groups, group):
    """The substep count of ``group`` (its smallest body), as ``group_by_substeps`` named it."""
    return groups.label[group, 1]


@jit_stage
def keep_group(impulses, n_group, h, n_kept):
    """Append a group's last impulses (``impulses.group_keys``, ``group_impulses``: key, normal and friction impulse)
    with its substep length h to the step's kept rows (``impulses.kept_keys``, ``kept_impulses``) after the first
    ``n_kept``; returns how many rows are kept then (the rows hold every contact a step can find)."""
    group_keys, group_impulses = impulses.group_keys, impulses.group_impulses
    kept_keys, kept_impulses = impulses.kept_keys, impulses.kept_impulses
    for c in range(n_group):
        kept_keys[n_kept + c] = group_keys[c]
        kept_impulses[n_kept + c, 0] = group_impulses[c, 0]
        kept_impulses[n_kept + c, 1] = group_impulses[c, 1]
        kept_impulses[n_kept + c, 2] = h
    return n_kept + n_group


@jit_stage
def sort_kept(impulses, n_kept, dt):
    """The ``n_kept`` kept impulses in increasing key order into ``impulses.keys`` / ``impulses.impulses`` (the
    warm start's order), each scaled from its substep length h to h_ref, the first group's (p h_ref / h); returns
    h_ref (dt if none is kept). Heapsort in place on the kept rows (the keys are distinct)."""
    kept_keys, kept_impulses, previous_keys, previous_impulses = (
        impulses.kept_keys,
        impulses.kept_impulses,
        impulses.keys,
        impulses.impulses,
    )
    h_ref = kept_impulses[0, 2] if n_kept > 0 else dt
    for start in range(n_kept // 2 - 1, -1, -1):
        sift_row(kept_keys, kept_impulses, start, n_kept)
    for end in range(n_kept - 1, 0, -1):
        swap_rows(kept_keys, kept_impulses, 0, end)
        sift_row(kept_keys, kept_impulses, 0, end)
    for c in range(n_kept):
        scale = h_ref / kept_impulses[c, 2]
        previous_keys[c] = kept_keys[c]
        previous_impulses[c, 0] = scale * kept_impulses[c, 0]
        previous_impulses[c, 1] = scale * kept_impulses[c, 1]
    return h_ref


@jit_stage(inline="always")
def swap_rows(keys, rows, a, b):
    """Swap entries a and b of ``keys`` and of the three columns of ``rows``."""
    keys[a], keys[b] = keys[b], keys[a]
    for k in range(3):
        rows[a, k], rows[b, k] = rows[b, k], rows[a, k]


@jit_stage(inline="always")
def sift_row(keys, rows, root, end):
    """Heapsort's step on rows by key: move row ``root`` down the max-heap of the first ``end`` to its place."""
    while True:
        child = 2 * root + 1
        if child >= end:
            return
        if child + 1 < end and keys[child + 1] > keys[child]:
            child += 1
        if keys[root] >= keys[child]:
            return
        swap_rows(keys, rows, root, child)
        root = child
