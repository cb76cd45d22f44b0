"""Islands and sleeping for scenes whose boxes collide: a box that rests costs nothing until touched.

Bodies joined by box-box contacts form an island (union-find over the contacts of the last substep; the
floor joins nothing, as in Box2D). With sleeping on (``simulate``'s ``sleep``, the default; always with
``until_rest``) each awake body keeps a sleep timer: the time it
has been supported (it took a contact impulse) with every point slower than ``sleep_speed``
(|v| + |omega| R <= sleep_speed); an island falls asleep when every one of its bodies has been so for
``sleep_time``. A sleeping body's velocity is set to zero and it is left out of everything: no contact is
looked for, no velocity or position integrated, no impulse solved. It keeps the island it fell asleep in
(the island's root body, ``island``), so that a touch wakes the whole island at once: at the start of
every grid step, every sleeping body that an awake body can reach within the step (the broadphase's
test, ``broadphase.candidate_pairs``) wakes with its island, and the test is repeated for the bodies just
woken. A body woken keeps the still time it slept through (its timer is infinite until it moves faster than
``sleep_speed`` or goes unsupported): an island woken because a box came within reach, and left untouched, sleeps
again at the end of the step, not ``sleep_time`` later. With sleeping off nothing sleeps; with ``until_rest`` the
run ends once every body sleeps. A body placed at rest (zero velocity, lying on a face on the floor, touching no
other box, ``sleep_placed``) sleeps from the start, as the resting base of ``BoxToss-OnBox-v0``: stepping it would
only find it at rest ``sleep_time`` later.

Sleep carries from run to run in the caller's warm start (``simulate.warm_start_memory``, rows in
``layout``): at the end of a run each body's island label (-1 awake), sleep timer, pose and parameters are kept
(``keep_sleeping``); at the start of the next, every island that was asleep sleeps again, unless the
caller moved, pushed or changed one of its bodies since (``restore_sleeping``), and the awake bodies' timers go on.
A pile that fell asleep costs nothing in the next run until something reaches it, as in one long run; a run in
which every body is kept asleep and untouched skips even the run's set-up (``sleeps_through``), whether it ends
once every body sleeps (``until_rest``) or goes on to its last step (sleeping, ``simulate``'s default).
"""

import math

import numpy as np

from .. import layout
from ..compile.compilation import jit_stage
from ..kernel_support import is_lying_still, write_stats
from .broadphase import candidate_pairs, interval_end, pair_overlaps, sort_intervals
from .narrowphase import BODY1, BODY2, GAP, separation


@jit_stage
def find_root(parent, b):
    """The root of body b's island in the union-find forest ``parent`` (with path halving)."""
    while parent[b] != b:
        parent[b] = parent[parent[b]]
        b = parent[b]
    return b


@jit_stage
def join_islands(ids, count, parent):
    """``parent``: a union-find forest in which two bodies share a root when a chain of box-box contacts (of
    the first ``count`` rows of ``ids``) joins them; a body's root is the island's smallest body."""
    for b in range(parent.shape[0]):
        parent[b] = b
    join_contacts(ids, count, parent)


@jit_stage
def join_contacts(ids, count, parent):
    """Join in the union-find forest ``parent`` the two bodies of each box-box contact of the first ``count``
    rows of ``ids`` (a root stays its island's smallest body)."""
    for c in range(count):
        b2 = ids[c, BODY2]
        if b2 < 0:
            continue
        r1 = find_root(parent, ids[c, BODY1])
        r2 = find_root(parent, b2)
        if r1 != r2:
            parent[max(r1, r2)] = min(r1, r2)


@jit_stage
def fall_asleep(sleep, sleep_time, vel):
    """Put to sleep every island (``sleep.parent``, joined by ``join_islands``) whose awake bodies have all been still
    for ``sleep_time`` (``sleep.still_for``): velocities zero, ``awake`` False, ``island`` the island's root. Returns
    how many bodies fell asleep."""
    awake, still_for, parent, ready, island = sleep.awake, sleep.still_for, sleep.parent, sleep.ready, sleep.island
    n = awake.shape[0]
    for b in range(n):
        ready[b] = True
    for b in range(n):
        if awake[b] and still_for[b] < sleep_time:
            ready[find_root(parent, b)] = False
    slept = 0
    for b in range(n):
        if awake[b]:
            root = find_root(parent, b)
            if ready[root]:
                awake[b] = False
                island[b] = root
                vel[b, 0] = 0.0
                vel[b, 1] = 0.0
                vel[b, 2] = 0.0
                slept += 1
    return slept


@jit_stage
def wake_island(label, sleep):
    """Wake every sleeping body of island ``label``; returns how many woke. Each keeps the still time it slept
    through: its timer is infinite (the step's sleep test sets it to zero once the body moves faster than
    ``sleep_speed`` or goes unsupported), so an island woken and left untouched sleeps again at the step's end. With
    the timer at zero instead, the resting base of ``BoxToss-OnBox-v0`` woken by a throw that missed it stayed awake
    ``sleep_time`` (26 steps at the defaults) after the thrown box had passed."""
    awake, island, still_for, rest_time = sleep.awake, sleep.island, sleep.still_for, sleep.rest_time
    woken = 0
    for b in range(awake.shape[0]):
        if not awake[b] and island[b] == label:
            awake[b] = True
            island[b] = -1
            still_for[b] = math.inf
            rest_time[b] = math.nan
            woken += 1
    return woken


@jit_stage
def wake_touched(pose, half, sweep, sleep, struck):
    """Wake the sleeping islands that an awake body can reach (the broadphase's test, ``broadphase``, with the
    bodies' ``sweep.reach``, then the boxes' own separation within the two reaches and ``struck``, what the fastest
    body travels, as a struck box moves further than its own speed says: ``narrowphase.separation``), again for
    the bodies just woken, until none wakes: the smallest set of islands closed under "an awake body reaches it",
    whatever the order they are found in. The pairs are tested as the sweep meets them, none stored (so the search
    never runs out of room). Returns the number of bodies woken. With the bounding boxes alone, a tilted box whose
    bounds overlapped a sleeping neighbour 26 mm away woke it at every step it was awake: two islands side by side
    in a pile of 5,000 woke each other in turn and never slept.

    Fewer than half the bodies awake (a box thrown into a sleeping pile), the sweep looks from the awake bodies
    alone: forward to every box whose interval starts within the awake one's, and back to every box whose interval
    starts within the longest interval W before it (an interval that reaches the awake one's start begins at most W
    before it). Those are all the pairs of an awake and a sleeping box that the sweep from every box meets, so the
    same islands wake; the sleeping boxes cost the sort's pass, not a sweep of their own neighbours."""
    awake, bound, reach, axis, order, low = (
        sleep.awake,
        sweep.bound,
        sweep.reach,
        sweep.axis,
        sweep.order,
        sweep.low,
    )
    n = pose.shape[0]
    sort_intervals(pose, bound, reach, axis, order, low)
    n_awake, width = 0, 0.0
    for b in range(n):
        n_awake += awake[b]
        width = max(width, interval_end(pose, bound, reach, axis, b) - low[b])
    total = 0
    while True:
        woken = 0
        few = 2 * n_awake < n  # few awake: the awake bodies look both ways
        for p in range(n):
            i = order[p]
            if few and not awake[i]:
                continue
            high = interval_end(pose, bound, reach, axis, i)
            for q in range(p + 1, n):
                j = order[q]
                if low[j] > high:
                    break
                if awake[i] != awake[j]:
                    woken += wake_reached(i, j, pose, half, sweep, sleep, struck)
            if few:
                for q in range(p - 1, -1, -1):
                    j = order[q]
                    if low[j] < low[i] - width:
                        break
                    if not awake[j]:
                        woken += wake_reached(i, j, pose, half, sweep, sleep, struck)
        if woken == 0:
            return total
        total += woken
        n_awake += woken


@jit_stage(inline="always")
def wake_reached(i, j, pose, half, sweep, sleep, struck):
    """Wake the island of whichever of bodies i and j sleeps if the other, awake, reaches it (``wake_touched``'s
    test); returns how many woke."""
    a, b = min(i, j), max(i, j)
    reach = sweep.reach
    if pair_overlaps(pose, sweep.bound, reach, a, b) and separation(a, b, pose, sweep.trig, half) <= (
        reach[a] + reach[b] + struck
    ):
        return wake_island(sleep.island[j] if sleep.awake[i] else sleep.island[i], sleep)
    return 0


@jit_stage
def sleep_placed(bodies, sweep, sleep, context):
    """Put to sleep, each in an island of its own, the bodies placed at rest: zero velocity, lying on a face
    on the floor (``kernel_support.is_lying_still``) and in no candidate pair with another box within the
    contact tolerance (the broadphase's test, pairs with a body that is otherwise ready; none ready, no search, the
    sweep order sorted as a search sorts it). Returns how many, or -1 if ``sweep.pairs`` is too short (the caller
    grows it and calls again)."""
    pose, vel, half, reach, keys = bodies.pose, bodies.vel, bodies.half, sweep.reach, sweep.pairs
    awake, island, rest_time, ready, everyone = sleep.awake, sleep.island, sleep.rest_time, sleep.ready, sleep.everyone
    n = pose.shape[0]
    n_ready = 0
    for b in range(n):
        reach[b] = context.tolerance
        ready[b] = (
            awake[b]
            and vel[b, 0] == 0.0
            and vel[b, 1] == 0.0
            and vel[b, 2] == 0.0
            and is_lying_still(pose[b, 1], pose[b, 2], 0.0, 0.0, 0.0, half[b, 0], half[b, 1], context.sleep_speed)
        )
        n_ready += ready[b]
    if n_ready == 0:
        sort_intervals(pose, sweep.bound, reach, sweep.axis, sweep.order, sweep.low)
        return 0
    n_pairs = candidate_pairs(pose, sweep.bound, reach, everyone, ready, sweep.axis, sweep.order, sweep.low, keys)
    if n_pairs < 0:
        return -1
    for p in range(n_pairs):
        i = keys[p] // n
        ready[i] = False
        ready[keys[p] - i * n] = False
    slept = 0
    for b in range(n):
        if ready[b]:
            awake[b] = False
            island[b] = b
            rest_time[b] = 0.0
            slept += 1
    return slept


@jit_stage(inline="always")  # a few comparisons, per body
def as_kept(warm, row, pose, params, b):
    """Whether body b's pose (the first three columns of ``pose``) and parameters are those ``keep_sleeping`` kept
    in ``warm``'s body rows from ``row``. Every comparison is made (``|``, not ``or``), over the PARAM_SIZE columns
    (a constant: the row and column of each are folded, no division left per body)."""
    differs = (pose[b, 0] != warm[row + 1, 0]) | (pose[b, 1] != warm[row + 1, 1]) | (pose[b, 2] != warm[row + 1, 2])
    for k in range(layout.PARAM_SIZE):
        differs |= params[b, k] != warm[row + 2 + k // layout.WARM_START_SIZE, k % layout.WARM_START_SIZE]
    return not differs


@jit_stage
def restore_sleeping(warm, bodies, sleep):
    """The sleep ``keep_sleeping`` kept in ``warm`` at the end of the last run: the awake bodies' sleep timers
    (where the pose and parameters are as kept), and the islands asleep then asleep again, each whole island
    only if none of its bodies was moved, set moving or changed since (pose and parameters as kept, velocity
    zero: else the caller changed it, and the island wakes). Bodies past the ones kept are awake. Returns how
    many bodies sleep so."""
    pose, vel, params = bodies.pose, bodies.vel, bodies.params
    awake, island, still_for, rest_time, intact = (
        sleep.awake,
        sleep.island,
        sleep.still_for,
        sleep.rest_time,
        sleep.ready,
    )
    n = pose.shape[0]
    kept = min(np.int64(warm[0, 2]), n, (warm.shape[0] - 1) // layout.WARM_BODY_ROWS) if warm.shape[0] > 0 else 0
    for b in range(n):
        intact[b] = True
    for b in range(kept):
        row = 1 + layout.WARM_BODY_ROWS * b
        label = np.int64(warm[row, 0])
        same = as_kept(warm, row, pose, params, b)
        if label < 0 and same:
            still_for[b] = warm[row, 1]
        elif 0 <= label < kept and not (same and vel[b, 0] == 0.0 and vel[b, 1] == 0.0 and vel[b, 2] == 0.0):
            intact[label] = False
    slept = 0
    for b in range(kept):
        label = np.int64(warm[1 + layout.WARM_BODY_ROWS * b, 0])
        if 0 <= label < kept and intact[label]:
            awake[b] = False
            island[b] = label
            rest_time[b] = 0.0
            slept += 1
    return slept


@jit_stage
def sleeps_through(warm, state, params, dt, capacity, stats, end_step):
    """Whether every body sleeps through this run: ``warm`` kept all of them asleep and none was moved, set
    moving or changed since (``restore_sleeping`` would put every island to sleep again, and nothing is awake to
    step). If so, what the run would leave is written at once, without its set-up: each body's stats (no step,
    at rest from the start, the run ended at ``end_step``: 0 with until_rest, else its last step), ``warm`` as
    ``keep_sleeping`` and the contact rows would leave it (sleep timers 0, at most ``capacity`` contacts, the
    kernel's room for them), ``state`` untouched. Each body's stats are written as it is checked (a run that does
    not sleep through writes every body's at its end), each body's checks made at once (no branch a comparison, no
    division: ``as_kept``): a sleeping pile of 1,000 took 8.0 us instead of 15.8 warm, 23 instead of 28 after a 64 MB
    sum; of 5,000, 45 instead of 79 and 66 instead of 92."""
    n = state.shape[0]
    if warm.shape[0] == 0 or np.int64(warm[0, 2]) != n or (warm.shape[0] - 1) // layout.WARM_BODY_ROWS < n:
        return False
    for b in range(n):
        row = 1 + layout.WARM_BODY_ROWS * b
        asleep = (warm[row, 0] >= 0.0) & (warm[row, 0] < n)  # kept asleep (False for NaN)
        still = (state[b, 3] == 0.0) & (state[b, 4] == 0.0) & (state[b, 5] == 0.0)
        if not (asleep & still & as_kept(warm, row, state, params, b)):
            return False
        write_stats(stats, b, math.nan, 0, 0, 0.0, 0.0, end_step * dt, layout.STATUS_OK, -1, end_step + 1)
    for b in range(n):
        row = 1 + layout.WARM_BODY_ROWS * b
        warm[row, 1] = 0.0
        warm[row, 2] = 0.0
    first = 1 + layout.WARM_BODY_ROWS * n
    count = min(np.int64(warm[0, 0]), warm.shape[0] - first, capacity)
    warm[0, 0] = count
    if count == 0:
        warm[0, 1] = dt
    return True


@jit_stage
def keep_sleeping(warm, bodies, sleep):
    """Each body's island label (its island's root while it sleeps, -1 awake), sleep timer, pose and parameters into
    ``warm``'s body rows for the next run (``restore_sleeping``), as many bodies as there are rows for (a
    prefix: an island's label is its smallest body, so a kept sleeping body's label is kept too); returns how
    many bodies were kept (0 if ``warm`` is empty)."""
    if warm.shape[0] == 0:
        return 0
    pose, params, awake, island, still_for = bodies.pose, bodies.params, sleep.awake, sleep.island, sleep.still_for
    kept = min(pose.shape[0], (warm.shape[0] - 1) // layout.WARM_BODY_ROWS)
    warm[0, 2] = kept
    for b in range(kept):
        row = 1 + layout.WARM_BODY_ROWS * b
        warm[row, 0] = -1.0 if awake[b] else island[b]
        warm[row, 1] = still_for[b]
        warm[row, 2] = 0.0
        warm[row + 1, 0], warm[row + 1, 1], warm[row + 1, 2] = pose[b, 0], pose[b, 1], pose[b, 2]
        for k in range(layout.PARAM_SIZE):
            warm[row + 2 + k // layout.WARM_START_SIZE, k % layout.WARM_START_SIZE] = params[b, k]
    return kept


@jit_stage
def islands_deeper_than(contacts, ids, count, depth, parent, marked, deep_island):
    """``deep_island[c]``: whether contact c's island (bodies joined by the box-box contacts among the first
    ``count``, a union-find in ``parent``) holds a contact deeper than ``depth`` (-gap > depth); ``marked``
    per root body, work."""
    join_islands(ids, count, parent)
    for b in range(parent.shape[0]):
        marked[b] = False
    for c in range(count):
        if -contacts[c, GAP] > depth:
            marked[find_root(parent, ids[c, BODY1])] = True
    for c in range(count):
        deep_island[c] = marked[find_root(parent, ids[c, BODY1])]
