"""Threads for large scenes whose boxes collide: the stages of a substep that dominate a scene of hundreds or
thousands of boxes, run over numba's thread pool (its count for the run set by the kernel, ``threads``, from
``Simulator``'s ``threads``), with results that do not depend on the number of threads, bit for bit.

Two kinds of stage, by what they change:

- **The same results as before, on any number of threads.** The broadphase's sweep (``parallel_candidate_pairs``:
  each sweep position's pairs into slots of its own, then put in key order by a counting sort over the smaller body)
  and the narrowphase (``parallel_find_contacts``: each body's contacts into rows of its own, then packed in body
  order) give the very pairs and contacts in the very order of ``broadphase.candidate_pairs`` and
  ``narrowphase.find_contacts``. They run from PARALLEL_BODIES bodies up.
- **Gauss-Seidel by blocks.** A sweep visits the contacts one after another, each against the velocities the ones
  before it left: two that share a body cannot run at once. The bodies are cut into BLOCKS blocks of consecutive
  positions along the broadphase's sweep axis (``partition_contacts``: a pile or a pyramid cut into vertical
  slabs); a contact whose bodies lie in one block (the floor is no body: it moves for none) is that block's, any
  other goes to the boundary. A sweep then visits the blocks' contacts, each block in contact order, the blocks at
  once (no two share a body, so any split of the blocks over threads gives the same velocities), then the boundary's
  contacts in contact order. That order is the same on any number of threads, one included: the velocity sweeps
  (``partitioned_gauss_seidel``), the penalty's (``partitioned_penalty_sweeps``), the restitution polish
  (``partitioned_restitution``) and its hold (``partitioned_hold``) run so from PARALLEL_CONTACTS contacts up, in
  place of the contact-order sweeps (``sweeps.gauss_seidel``, ``relax.penalty_sweeps``,
  ``restitution.apply_restitution``, ``restitution.hold_targets``), which smaller scenes keep.
  Each block adds up its own changes and impulses (a sweep's stop rule), and the sums are added block by block, so
  they too are the same on any number of threads. The passes that write to each contact's bodies go block by block
  the same way: the warm start's impulses (``partitioned_warm_start``: found for runs of contacts at once, applied
  block by block), each body's deepest penetration (``partitioned_penetrations``) and whether it took an impulse
  (``partitioned_touched``); run in contact order on one thread, they held the second waiting. A sweep is one
  parallel region (graph colouring, Box2D v3's way, needs one per colour: a dozen per sweep, each waiting for the
  slowest thread, which costs on a loaded machine), and only the contacts that cross a cut change their place in
  the order.
"""

from typing import NamedTuple

import numba
import numpy as np
from numba import prange

from ..compile.compilation import jit_stage
from ..robust.contact_solver import penalty_correction_share
from ..tunables import EXACT_CONVERGED, HOLD_ROUNDS, RESTITUTION_ITERATIONS, SINGLE_CHANGE
from .broadphase import candidate_pairs, interval_end, pair_overlaps, sort_intervals
from .narrowphase import (
    APPROACH,
    BODY1,
    BODY2,
    FRICTION,
    FRICTION_IMPULSE,
    GAP,
    ID_COLUMNS,
    IMPULSE,
    KEY,
    NORMAL_MASS,
    NX,
    NY,
    PSEUDO_IMPULSE,
    STIFFNESS,
    TARGET,
    box_box_contacts,
    box_geometry,
    first_key_at_least,
    floor_contacts,
    update_geometry,
)
from .prepare import (
    apply_contact_impulses,
    body_kinetic_energy,
    is_impact_contact,
    note_depth,
    prepare_contact,
    relative_velocity,
    restitution_step,
    short_of_target,
    take_kept_impulses,
    touch_bodies,
)
from .substeps import body_reach, travel
from .sweeps import friction_step, mark_moved, normal_step, touches_moved

PARALLEL_BODIES = 256
"""[bodies] from this many up, the broadphase's sweep and the narrowphase run on threads (same results)."""

PARALLEL_CONTACTS = 1024
"""[contacts] from this many up, a substep's sweeps go block by block (``partition_contacts``): on threads, and in
that order on one thread too. Fewer keep the contact order of the sweeps (the exact solves take up to 64)."""


def reaches_threads(n_bodies: int) -> bool:
    """Whether a run of ``n_bodies`` colliding bodies can reach a stage on threads: it has PARALLEL_BODIES bodies
    or more, or it may hold PARALLEL_CONTACTS contacts, of which n bodies have at most n (n - 1) + 4 n (two a pair
    of boxes, four a box on the floor): from 31 bodies up."""
    return n_bodies >= PARALLEL_BODIES or n_bodies * (n_bodies - 1) + 4 * n_bodies >= PARALLEL_CONTACTS


BLOCKS = 4
"""[-] blocks of bodies along the sweep axis, whatever the number of threads (it sets the sweeps' order): more
blocks spread over more threads, and put more contacts on the boundary, swept one after another."""

PAIR_SLOTS = 16
"""[pairs] slots per sweep position in the parallel broadphase; a position with more (a box overlapping more than
this many boxes after it along the sweep axis) sends the search to ``broadphase.candidate_pairs``."""


class Partition(NamedTuple):
    """The blocks of a substep's contacts (``partition_contacts``) and the sweeps' work."""

    block: np.ndarray  # (capacity,) int64: each contact's block (BLOCKS: the boundary)
    order: np.ndarray  # (capacity,) int64: the contacts block by block, the boundary's last
    start: np.ndarray  # (BLOCKS + 2,) int64: where each block starts in ``order``
    filled: np.ndarray  # (BLOCKS + 1,) int64: work
    partial: np.ndarray  # (BLOCKS + 1, 3): each block's sums in a sweep (change, impulses, largest change)


class Spare(NamedTuple):
    """Contact rows as ``state.Contacts``' (the ``narrowphase`` columns it writes, NX to GAP), each box's at its own
    place, before packing."""

    rows: np.ndarray  # (capacity, GAP + 1)
    ids: np.ndarray  # (capacity, ID_COLUMNS) int64


class Spread(NamedTuple):
    """Per sweep position or box: the parallel broadphase's pair slots and counts, where each box's pairs or
    contacts start, and each body's block (``partition_contacts``)."""

    slots: np.ndarray  # (n * PAIR_SLOTS,) int64
    found: np.ndarray  # (n,) int64
    first: np.ndarray  # (n + 1,) int64
    filled: np.ndarray  # (n,) int64
    block: np.ndarray  # (n,) int64


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_partition(capacity):
    """``Partition`` and ``Spare`` for ``capacity`` contact rows (each entry written before it is read)."""
    return (
        Partition(
            np.empty(capacity, np.int64),
            np.empty(capacity, np.int64),
            np.zeros(BLOCKS + 2, np.int64),
            np.zeros(BLOCKS + 1, np.int64),
            np.zeros((BLOCKS + 1, 3)),
        ),
        Spare(np.empty((capacity, GAP + 1)), np.empty((capacity, ID_COLUMNS), np.int64)),
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_spread(n):
    """``Spread`` for n bodies."""
    return Spread(
        np.zeros(n * PAIR_SLOTS, np.int64),
        np.zeros(n, np.int64),
        np.zeros(n + 1, np.int64),
        np.zeros(n, np.int64),
        np.zeros(n, np.int64),
    )


def launch_threads() -> None:
    """Start numba's threading layer (``numba.get_num_threads`` starts it), before a kernel holding these stages
    runs: a kernel loaded from numba's cache does not start it, and its parallel stages then called a null pointer
    (a segmentation fault, even where no stage ran on threads)."""
    numba.get_num_threads()


# -- blocks ------------------------------------------------------------------------------------------
@jit_stage
def partition_contacts(ids, count, sweep_order, body_block, partition):
    """The blocks of the first ``count`` contacts (module docstring) into ``partition``: body at position p of the
    sweep order ``sweep_order`` (of n) in block p BLOCKS // n (into ``body_block``), each contact in its bodies'
    block or the boundary (BLOCKS), the contacts block by block in contact order, and where each block starts."""
    block, order, start, filled = partition.block, partition.order, partition.start, partition.filled
    n = body_block.shape[0]
    for p in range(n):
        body_block[sweep_order[p]] = p * BLOCKS // n
    start[:] = 0
    for c in range(count):
        b2 = ids[c, BODY2]
        k = body_block[ids[c, BODY1]]
        if b2 >= 0 and body_block[b2] != k:
            k = BLOCKS
        block[c] = k
        start[k + 1] += 1
    for k in range(BLOCKS + 1):
        start[k + 1] += start[k]
        filled[k] = start[k]
    for c in range(count):
        order[filled[block[c]]] = c
        filled[block[c]] += 1


@jit_stage
def add_blocks(partial):
    """The sums of every block and the boundary (``Partition.partial``), added in block order: (change, impulses,
    largest change)."""
    change, total, largest = 0.0, 0.0, 0.0
    for k in range(BLOCKS + 1):
        change += partial[k, 0]
        total += partial[k, 1]
        largest = max(largest, partial[k, 2])
    return change, total, largest


# -- per-body stages, block by block -----------------------------------------------------------------
@jit_stage(inline="always")
def depth_block(k, rows, ids, order, start, max_penetration):
    """``prepare.note_depth`` over block k's contacts; returns the deepest penetration among them (0 if none)."""
    deepest = 0.0
    for position in range(start[k], start[k + 1]):
        deepest = max(deepest, note_depth(order[position], rows, ids, max_penetration))
    return deepest


@jit_stage(parallel=True)
def depth_blocks(rows, ids, order, start, max_penetration, partial):
    """``depth_block`` over the blocks at once, then over the boundary; each one's deepest into ``partial[:, 2]``."""
    for k in prange(BLOCKS):
        partial[k, 2] = depth_block(k, rows, ids, order, start, max_penetration)
    partial[BLOCKS, 2] = depth_block(BLOCKS, rows, ids, order, start, max_penetration)


@jit_stage
def partitioned_penetrations(contacts, max_penetration):
    """``step.note_penetration`` block by block (the same values: a maximum in any order): each body's deepest
    penetration so far; returns the deepest of the substep's contacts (0 if none)."""
    partition = contacts.partition
    depth_blocks(contacts.rows, contacts.ids, partition.order, partition.start, max_penetration, partition.partial)
    deepest = 0.0
    for k in range(BLOCKS + 1):
        deepest = max(deepest, partition.partial[k, 2])
    return deepest


@jit_stage(inline="always")
def touched_block(k, rows, ids, order, start, impacts, threshold, touched, impacted):
    """``prepare.touch_bodies`` over block k's contacts."""
    for position in range(start[k], start[k + 1]):
        touch_bodies(order[position], rows, ids, impacts, threshold, touched, impacted)


@jit_stage(parallel=True)
def partitioned_touched(rows, ids, partition, impacts, threshold, touched, impacted):
    """``step.mark_touched`` block by block (the same values): every body cleared at once, then ``touched_block`` over
    the blocks at once, then over the boundary."""
    order, start = partition.order, partition.start
    for b in prange(touched.shape[0]):
        touched[b] = False
        impacted[b] = 0
    for k in prange(BLOCKS):
        touched_block(k, rows, ids, order, start, impacts, threshold, touched, impacted)
    touched_block(BLOCKS, rows, ids, order, start, impacts, threshold, touched, impacted)


@jit_stage(parallel=True)
def warm_impulses_on_threads(rows, ids, count, keys, impulses, n_previous, ratio):
    """``warm_start.warm_start``'s impulses (not yet applied), BLOCKS runs of consecutive contacts at once: each
    run finds where its first key lies among the last substep's (``first_key_at_least``), then pairs the two
    increasing lists of keys in one pass (``prepare.take_kept_impulses``), as the serial warm start does."""
    for k in prange(BLOCKS):
        begin, end = k * count // BLOCKS, (k + 1) * count // BLOCKS
        at = first_key_at_least(keys, n_previous, ids[begin, KEY]) if begin < end else 0
        for c in range(begin, end):
            at, _ = take_kept_impulses(c, rows, ids, (keys, impulses, n_previous), at, ratio)


@jit_stage(inline="always")
def warm_block(k, rows, ids, order, start, vel, inv_mass, inv_inertia):
    """``prepare.apply_contact_impulses`` over block k's contacts that start from an impulse."""
    for position in range(start[k], start[k + 1]):
        c = order[position]
        if rows[c, IMPULSE] != 0.0 or rows[c, FRICTION_IMPULSE] != 0.0:
            apply_contact_impulses(c, rows, ids, vel, inv_mass, inv_inertia)


@jit_stage(parallel=True)
def warm_blocks(rows, ids, order, start, vel, inv_mass, inv_inertia):
    """``warm_block`` over the blocks at once, then over the boundary."""
    for k in prange(BLOCKS):
        warm_block(k, rows, ids, order, start, vel, inv_mass, inv_inertia)
    warm_block(BLOCKS, rows, ids, order, start, vel, inv_mass, inv_inertia)


@jit_stage
def partitioned_warm_start(contacts, count, warm_from, bodies, ratio):
    """``warm_start.warm_start`` (warm: ``warm_from``, the last substep's keys, impulses and their count; the
    impulses scaled by ``ratio``) with the impulses found for runs of contacts at once
    (``warm_impulses_on_threads``) and applied block by block (``warm_blocks``): the same impulses, added to each
    body's velocity in the blocks' order rather than the contacts' (a rounding apart)."""
    keys, impulses, n_previous = warm_from
    rows, ids, partition = contacts.rows, contacts.ids, contacts.partition
    warm_impulses_on_threads(rows, ids, count, keys, impulses, n_previous, ratio)
    vel, inv_mass, inv_inertia = bodies.vel, bodies.inv_mass, bodies.inv_inertia
    warm_blocks(rows, ids, partition.order, partition.start, vel, inv_mass, inv_inertia)


# -- Gauss-Seidel of the velocities ------------------------------------------------------------------
@jit_stage(inline="always")
def velocity_step(c, rows, ids, vel, inv_mass, inv_inertia, use_friction, sweep, before, now, quiet):
    """``sweeps.gauss_seidel``'s step on contact c in sweep ``sweep`` (its friction, then its normal impulse; after
    the first sweep only if a body of it moved: in ``before``, the sweep before, or in ``now``, this one so far,
    ``sweeps.touches_moved``). Returns (its change, its largest change)."""
    b1 = ids[c, BODY1]
    b2 = ids[c, BODY2]
    change, largest = 0.0, 0.0
    if sweep == 0 or touches_moved(before, now, b1, b2):
        if use_friction and rows[c, FRICTION] > 0.0:
            dq = abs(friction_step(c, rows, ids, vel, inv_mass, inv_inertia))
            change, largest = dq, dq
            if dq > quiet:
                mark_moved(now, b1, b2)
        dp = abs(normal_step(c, IMPULSE, rows, ids, vel, inv_mass, inv_inertia))
        change, largest = change + dp, max(largest, dp)
        if dp > quiet:
            mark_moved(now, b1, b2)
    return change, largest


@jit_stage(inline="always")
def velocity_block(k, rows, ids, order, start, vel, inv_mass, inv_inertia, use_friction, sweep, moved, quiet):
    """``velocity_step`` over block k's contacts in order (``moved[sweep % 2]`` the sweep before's bodies,
    ``moved[(sweep + 1) % 2]`` this one's); returns its sums (change, impulses, largest change)."""
    before, now = moved[sweep % 2], moved[(sweep + 1) % 2]
    change, total, largest = 0.0, 0.0, 0.0
    for position in range(start[k], start[k + 1]):
        c = order[position]
        dc, dl = velocity_step(c, rows, ids, vel, inv_mass, inv_inertia, use_friction, sweep, before, now, quiet)
        change, total, largest = change + dc, total + rows[c, IMPULSE], max(largest, dl)
    return change, total, largest


@jit_stage(parallel=True)
def velocity_blocks(rows, ids, order, start, vel, inv_mass, inv_inertia, use_friction, sweep, moved, quiet, partial):
    """One sweep: ``velocity_block`` over the blocks at once (no two share a body), then over the boundary; each
    one's sums into ``partial``."""
    for k in prange(BLOCKS):
        partial[k, 0], partial[k, 1], partial[k, 2] = velocity_block(
            k, rows, ids, order, start, vel, inv_mass, inv_inertia, use_friction, sweep, moved, quiet
        )
    partial[BLOCKS, 0], partial[BLOCKS, 1], partial[BLOCKS, 2] = velocity_block(
        BLOCKS, rows, ids, order, start, vel, inv_mass, inv_inertia, use_friction, sweep, moved, quiet
    )


@jit_stage
def partitioned_gauss_seidel(contacts, count, bodies, use_friction, iterations, tolerance, moved, seeded):
    """``sweeps.gauss_seidel`` (its stop rule, its sweeps after the first over the contacts of bodies that moved;
    with ``seeded`` the first too, from the bodies set in ``moved[0]``) block by block (module docstring): at most
    ``iterations`` sweeps; ``moved``: (2, bodies) work. A seeded solve counts its sweeps from 1, so that its first
    reads the seed as the sweep before's (``velocity_step``)."""
    rows, ids, partition = contacts.rows, contacts.ids, contacts.partition
    order, start, partial = partition.order, partition.start, partition.partial
    vel, inv_mass, inv_inertia = bodies.vel, bodies.inv_mass, bodies.inv_inertia
    total = 0.0
    for c in range(count):
        total += rows[c, IMPULSE]
    first = 0
    if seeded:
        for b in range(moved.shape[1]):
            moved[1, b] = moved[0, b]
        first = 1
    for sweep in range(first, first + iterations):
        quiet = tolerance * total / count
        moved[(sweep + 1) % 2, :] = False
        velocity_blocks(rows, ids, order, start, vel, inv_mass, inv_inertia, use_friction, sweep, moved, quiet, partial)
        change, total, largest = add_blocks(partial)
        if change <= tolerance * total and largest * count <= SINGLE_CHANGE * tolerance * total:
            break


# -- the penalty's sweeps ----------------------------------------------------------------------------
@jit_stage(inline="always")
def penalty_block(k, rows, ids, order, start, pseudo, inv_mass, inv_inertia, deep):
    """``relax.penalty_sweeps``' step over block k's contacts of deep islands, in order; returns its sums (change,
    impulses)."""
    change, total = 0.0, 0.0
    for position in range(start[k], start[k + 1]):
        c = order[position]
        if deep[c]:
            change += abs(normal_step(c, PSEUDO_IMPULSE, rows, ids, pseudo, inv_mass, inv_inertia))
            total += rows[c, PSEUDO_IMPULSE]
    return change, total


@jit_stage(parallel=True)
def penalty_blocks(rows, ids, order, start, pseudo, inv_mass, inv_inertia, deep, partial):
    """One penalty sweep: ``penalty_block`` over the blocks at once, then over the boundary; sums into ``partial``."""
    for k in prange(BLOCKS):
        partial[k, 0], partial[k, 1] = penalty_block(k, rows, ids, order, start, pseudo, inv_mass, inv_inertia, deep)
    partial[BLOCKS, 0], partial[BLOCKS, 1] = penalty_block(
        BLOCKS, rows, ids, order, start, pseudo, inv_mass, inv_inertia, deep
    )


@jit_stage
def partitioned_penalty_sweeps(contacts, pseudo, bodies, iterations, tolerance):
    """``relax.penalty_sweeps`` over the contacts of the deep islands (``contacts.deep``) block by block."""
    rows, ids, partition, deep = contacts.rows, contacts.ids, contacts.partition, contacts.deep
    order, start, partial = partition.order, partition.start, partition.partial
    partial[:, 2] = 0.0
    for _ in range(iterations):
        penalty_blocks(rows, ids, order, start, pseudo, bodies.inv_mass, bodies.inv_inertia, deep, partial)
        change, total, _ = add_blocks(partial)
        if change <= tolerance * total:
            break


# -- the restitution polish --------------------------------------------------------------------------
@jit_stage(inline="always")
def restitution_block(k, rows, ids, order, start, vel, inv_mass, inv_inertia, threshold):
    """``restitution.apply_restitution``'s step over block k's contacts in order (an impact, or a floor contact
    whose impulse may only grow); returns its sums (change, impulses)."""
    change, total = 0.0, 0.0
    for position in range(start[k], start[k + 1]):
        moved, after = restitution_step(order[position], rows, ids, vel, inv_mass, inv_inertia, threshold)
        change += moved
        total += after
    return change, total


@jit_stage(parallel=True)
def restitution_blocks(rows, ids, order, start, vel, inv_mass, inv_inertia, threshold, partial):
    """One polish sweep: ``restitution_block`` over the blocks at once, then the boundary; sums into ``partial``."""
    for k in prange(BLOCKS):
        partial[k, 0], partial[k, 1] = restitution_block(
            k, rows, ids, order, start, vel, inv_mass, inv_inertia, threshold
        )
    partial[BLOCKS, 0], partial[BLOCKS, 1] = restitution_block(
        BLOCKS, rows, ids, order, start, vel, inv_mass, inv_inertia, threshold
    )


@jit_stage
def partitioned_restitution(contacts, count, bodies, threshold):
    """``restitution.apply_restitution`` block by block (its impacts counted first: none, nothing done); returns
    how many contacts are impacts."""
    rows, ids, partition = contacts.rows, contacts.ids, contacts.partition
    order, start, partial = partition.order, partition.start, partition.partial
    impacts = 0
    for c in range(count):
        if is_impact_contact(c, rows, threshold):
            impacts += 1
    if impacts == 0:
        return 0
    partial[:, 2] = 0.0
    for _ in range(RESTITUTION_ITERATIONS):
        restitution_blocks(rows, ids, order, start, bodies.vel, bodies.inv_mass, bodies.inv_inertia, threshold, partial)
        change, total, _ = add_blocks(partial)
        if change <= EXACT_CONVERGED * total:
            break
    return impacts


@jit_stage(inline="always")
def hold_block(k, rows, ids, order, start, vel, inv_mass, inv_inertia, threshold, hold_round, moved):
    """``restitution.hold_targets``' round ``hold_round`` over block k's contacts in order, after the first only those
    of a body stepped since it was last tried (``moved``, as ``velocity_block``'s: any other has the relative velocity
    it was found not short with); returns how many it stepped."""
    before, now = moved[hold_round % 2], moved[(hold_round + 1) % 2]
    held = 0
    for position in range(start[k], start[k + 1]):
        c = order[position]
        b1 = ids[c, BODY1]
        b2 = ids[c, BODY2]
        if hold_round > 0 and not touches_moved(before, now, b1, b2):
            continue
        if short_of_target(c, rows, ids, vel, threshold):
            restitution_step(c, rows, ids, vel, inv_mass, inv_inertia, threshold)
            mark_moved(now, b1, b2)
            held += 1
    return held


@jit_stage(parallel=True)
def hold_blocks(rows, ids, order, start, vel, inv_mass, inv_inertia, threshold, moved, partial):
    """The hold's first round: ``hold_block`` over the blocks at once, then the boundary; counts into ``partial``."""
    for k in prange(BLOCKS):
        partial[k, 0] = hold_block(k, rows, ids, order, start, vel, inv_mass, inv_inertia, threshold, 0, moved)
    partial[BLOCKS, 0] = hold_block(BLOCKS, rows, ids, order, start, vel, inv_mass, inv_inertia, threshold, 0, moved)


@jit_stage
def partitioned_hold(contacts, bodies, threshold, moved):
    """``restitution.hold_targets`` block by block: a first round over every contact on threads (``hold_blocks``),
    then rounds over the contacts of the bodies the round before stepped, on this thread in the same order (a few
    contacts each: a parallel region per round cost more than it saved), until one steps none (at most HOLD_ROUNDS).
    ``moved``: (2, bodies) work."""
    rows, ids, partition = contacts.rows, contacts.ids, contacts.partition
    order, start, partial = partition.order, partition.start, partition.partial
    vel, inv_mass, inv_inertia = bodies.vel, bodies.inv_mass, bodies.inv_inertia
    moved[1, :] = False
    partial[:, 1:] = 0.0
    hold_blocks(rows, ids, order, start, vel, inv_mass, inv_inertia, threshold, moved, partial)
    held = int(add_blocks(partial)[0])
    for hold_round in range(1, HOLD_ROUNDS):
        if held == 0:
            return
        moved[(hold_round + 1) % 2, :] = False
        held = 0
        for k in range(BLOCKS + 1):
            held += hold_block(k, rows, ids, order, start, vel, inv_mass, inv_inertia, threshold, hold_round, moved)


# -- broadphase --------------------------------------------------------------------------------------
@jit_stage(parallel=True)
def sweep_slots(pose, bound, reach, include, moving, axis, order, low, slots, found):
    """``broadphase.candidate_pairs``' sweep, each position p of the sweep order at once: its pairs (keys) into
    ``slots[p * PAIR_SLOTS:]``, how many into ``found[p]`` (more than PAIR_SLOTS: not all kept)."""
    n = pose.shape[0]
    for p in prange(n):
        i = order[p]
        k = 0
        if include[i]:
            high = interval_end(pose, bound, reach, axis, i)
            for q in range(p + 1, n):
                j = order[q]
                if low[j] > high:
                    break
                if include[j] and (moving[i] or moving[j]):
                    a, b = min(i, j), max(i, j)
                    if pair_overlaps(pose, bound, reach, a, b):
                        if k < PAIR_SLOTS:
                            slots[p * PAIR_SLOTS + k] = a * n + b
                        k += 1
        found[p] = k


@jit_stage(parallel=True)
def sort_buckets(keys, first):
    """Each body's keys ``keys[first[a]:first[a + 1]]`` (its pairs with larger bodies) sorted, by insertion."""
    for a in prange(first.shape[0] - 1):
        for p in range(first[a] + 1, first[a + 1]):
            item = keys[p]
            q = p - 1
            while q >= first[a] and keys[q] > item:
                keys[q + 1] = keys[q]
                q -= 1
            keys[q + 1] = item


@jit_stage
def parallel_candidate_pairs(pose, bound, reach, include, moving, axis, order, low, keys, spread):
    """``broadphase.candidate_pairs`` (same arguments, same pairs in the same order; ``spread``: ``state.Spread``)
    with its sweep on threads (``sweep_slots``) and its sort a counting sort by the smaller body, each body's keys
    then sorted (``sort_buckets``). A position with more than PAIR_SLOTS pairs: ``candidate_pairs`` itself."""
    n = pose.shape[0]
    sort_intervals(pose, bound, reach, axis, order, low)
    found, first, filled, slots = spread.found, spread.first, spread.filled, spread.slots
    sweep_slots(pose, bound, reach, include, moving, axis, order, low, slots, found)
    count = 0
    for p in range(n):
        if found[p] > PAIR_SLOTS:
            return candidate_pairs(pose, bound, reach, include, moving, axis, order, low, keys)
        count += found[p]
    if count > keys.shape[0]:
        return -1
    first[:] = 0
    for p in range(n):
        for k in range(found[p]):
            first[slots[p * PAIR_SLOTS + k] // n + 1] += 1
    for a in range(n):
        first[a + 1] += first[a]
        filled[a] = first[a]
    for p in range(n):
        for k in range(found[p]):
            key = slots[p * PAIR_SLOTS + k]
            keys[filled[key // n]] = key
            filled[key // n] += 1
    sort_buckets(keys, first)
    return count


# -- narrowphase -------------------------------------------------------------------------------------
@jit_stage(parallel=True)
def contacts_by_body(pose, half, trig, reach, floor_reach, pair_keys, include, spare, first, found, previous):
    """``narrowphase.find_contacts``' contacts of each box i at once (against the floor, then its pairs with larger
    boxes, ``first[i]:first[i + 1]`` of ``pair_keys``) into rows of its own of ``spare`` (rows, ids; from 4 i + 2
    first[i]: four a box, two a pair), how many into ``found[i]`` (negative: no room)."""
    rows, ids = spare
    n = pose.shape[0]
    for i in prange(n):
        slot = 4 * i + 2 * first[i]
        count = slot
        if include[i]:
            count = floor_contacts(i, pose, trig, half, floor_reach[i], i * (n + 1), rows, ids, count)
        for p in range(first[i], first[i + 1]):
            j = pair_keys[p] - i * n
            code = i * (n + 1) + j + 1
            count = box_box_contacts(i, j, pose, trig, half, reach[i] + reach[j], code, rows, ids, count, previous)
        found[i] = count - slot if count >= 0 else -1


@jit_stage(parallel=True)
def first_pairs(pair_keys, n_pairs, first):
    """``first[i]``: where box i's pairs (keys i n + j) start in the increasing ``pair_keys[:n_pairs]`` (binary
    search, each box at once); ``first[n]`` = n_pairs."""
    n = first.shape[0] - 1
    for i in prange(n + 1):
        low, high = 0, n_pairs
        while low < high:
            middle = (low + high) // 2
            if pair_keys[middle] < i * n:
                low = middle + 1
            else:
                high = middle
        first[i] = low


@jit_stage(parallel=True)
def pack_contacts(spare_rows, spare_ids, rows, ids, first, found, filled):
    """Each box's rows of the spare rows (``contacts_by_body``) into ``rows``, ``ids`` from ``filled[i]`` on, at
    once."""
    for i in prange(found.shape[0]):
        slot = 4 * i + 2 * first[i]
        for r in range(found[i]):
            for column in range(GAP + 1):  # the columns the narrowphase writes
                rows[filled[i] + r, column] = spare_rows[slot + r, column]
            for column in range(ID_COLUMNS):
                ids[filled[i] + r, column] = spare_ids[slot + r, column]


@jit_stage
def parallel_find_contacts(bodies, sweep, pair_keys, n_pairs, include, contacts, previous):
    """``narrowphase.find_contacts`` (same arguments, the same contacts in the same order) with each box's contacts
    found at once (``contacts_by_body``) and packed in box order (``pack_contacts``); returns how many."""
    spare, first, found, filled = contacts.spare, sweep.spread.first, sweep.spread.found, sweep.spread.filled
    first_pairs(pair_keys, n_pairs, first)
    trig, reach, floor_reach = sweep.trig, sweep.reach, sweep.floor_reach
    spare_arrays = (spare.rows, spare.ids)
    contacts_by_body(
        bodies.pose, bodies.half, trig, reach, floor_reach, pair_keys, include, spare_arrays, first, found, previous
    )
    count = 0
    for i in range(found.shape[0]):
        if found[i] < 0:
            return -1
        filled[i] = count
        count += found[i]
    pack_contacts(spare.rows, spare.ids, contacts.rows, contacts.ids, first, found, filled)
    return count


# -- each body, each contact at once -----------------------------------------------------------------
@jit_stage(parallel=True)
def geometry_on_threads(pose, half, include, trig, bound, vel, radius, h, gravity, tolerance, reach):
    """``narrowphase.update_geometry`` and ``substeps.body_reach`` (without its largest), each body at once."""
    for b in prange(pose.shape[0]):
        if include[b]:
            box_geometry(b, pose, half, trig, bound)
        reach[b] = tolerance
        if include[b]:
            reach[b] += travel(vel, radius, b, h, gravity)


@jit_stage
def geometry_and_reach(bodies, include, h, context, sweep):
    """Each included body's geometry (``narrowphase.update_geometry``) and reach over h: what it travels
    (``substeps.body_reach``) plus half what the fastest body travels, which is returned. A struck box moves further
    than its own speed says: two boxes are searched for contacts within what both travel plus what the fastest does
    (before, a box lying 4 mm from another and struck within the substep turned into it unseen, 8 mm deep in a
    dropped pile of 100). On threads from PARALLEL_BODIES bodies up (the same values)."""
    pose, vel, radius, trig, bound, reach = bodies.pose, bodies.vel, bodies.radius, sweep.trig, sweep.bound, sweep.reach
    if pose.shape[0] < PARALLEL_BODIES:
        update_geometry(pose, bodies.half, include, trig, bound)
        fastest = body_reach(vel, radius, include, h, context.gravity, context.tolerance, reach)
    else:
        gravity, tolerance = context.gravity, context.tolerance
        geometry_on_threads(pose, bodies.half, include, trig, bound, vel, radius, h, gravity, tolerance, reach)
        fastest = 0.0
        for b in range(pose.shape[0]):
            if include[b]:
                fastest = max(fastest, reach[b])
    for b in range(pose.shape[0]):
        if include[b]:
            reach[b] += 0.5 * fastest  # a pair: the fastest's travel beyond their own
    return fastest


@jit_stage(parallel=True)
def prepare_on_threads(rows, ids, count, params, inv_mass, inv_inertia):
    """``prepare.prepare_contacts``, each contact at once."""
    for c in prange(count):
        prepare_contact(c, rows, ids, params, inv_mass, inv_inertia)


@jit_stage(parallel=True)
def approach_on_threads(rows, ids, count, vel, params, kinetic_before):
    """``step.approach_speeds``, each body and each contact at once."""
    for b in prange(vel.shape[0]):
        kinetic_before[b] = body_kinetic_energy(vel, b, params)
    for c in prange(count):
        ux, uy = relative_velocity(c, rows, ids, vel)
        rows[c, APPROACH] = ux * rows[c, NX] + uy * rows[c, NY]


@jit_stage(parallel=True)
def gravity_on_threads(vel, include, h, gravity):
    """``step.integrate_velocities``, each body at once."""
    for b in prange(vel.shape[0]):
        if include[b]:
            vel[b, 1] += h * gravity


@jit_stage(parallel=True)
def targets_on_threads(rows, count, h):
    """``step.speculative_targets``, each contact at once."""
    for c in prange(count):
        rows[c, TARGET] = -max(rows[c, GAP], 0.0) / h


@jit_stage(parallel=True)
def store_on_threads(rows, ids, count, keys, impulses):
    """``step.store_impulses``, each contact at once."""
    for c in prange(count):
        keys[c] = ids[c, KEY]
        impulses[c, 0] = rows[c, IMPULSE]
        impulses[c, 1] = rows[c, FRICTION_IMPULSE]


@jit_stage(parallel=True)
def positions_on_threads(pose, vel, include, touched, h, gravity):
    """``step.integrate_positions``, each body at once."""
    for b in prange(pose.shape[0]):
        if include[b]:
            pose[b, 0] += h * vel[b, 0]
            pose[b, 1] += h * vel[b, 1]
            if not touched[b]:
                pose[b, 1] -= 0.5 * h * h * gravity
            pose[b, 2] += h * vel[b, 2]


@jit_stage(inline="always")
def penalty_target(c, rows, deep, slop, tolerance, h):
    """Contact c's target for the penalty's pseudo-velocities (``relax.correct_penetrations``): the penalty's share
    of its depth beyond the slop over h in a deep island, else its gap may close but not pass; its pseudo-impulse 0."""
    depth = -rows[c, GAP] - slop
    rows[c, PSEUDO_IMPULSE] = 0.0
    if depth > tolerance and deep[c]:
        share = penalty_correction_share(rows[c, STIFFNESS], 1.0 / rows[c, NORMAL_MASS], h)
        rows[c, TARGET] = share * depth / h
    else:
        rows[c, TARGET] = -max(rows[c, GAP], 0.0) / h


@jit_stage(parallel=True)
def penalty_targets_on_threads(rows, count, deep, slop, tolerance, h):
    """``penalty_target``, each contact at once."""
    for c in prange(count):
        penalty_target(c, rows, deep, slop, tolerance, h)


@jit_stage(inline="always")
def pseudo_gap(c, rows, ids, pseudo, h):
    """Contact c's gap after the positions move by h times the pseudo-velocities (to first order)."""
    ux, uy = relative_velocity(c, rows, ids, pseudo)
    rows[c, GAP] += h * (ux * rows[c, NX] + uy * rows[c, NY])


@jit_stage(parallel=True)
def pseudo_gaps_on_threads(rows, ids, count, pseudo, h):
    """``pseudo_gap``, each contact at once."""
    for c in prange(count):
        pseudo_gap(c, rows, ids, pseudo, h)
