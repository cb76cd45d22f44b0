"""The per-body stages that run block by block from PARALLEL_CONTACTS contacts up (``colliding.parallel``): on a
random set of contacts between many bodies and the floor, each gives what the contact-order stage gives (the
deepest penetrations, the touched and impacted bodies: the same values; the warm start: the same impulses, the
velocities a rounding apart), and the same bit for bit on one thread and on two."""

import numba
import numpy as np
import pytest

from box_toss_env.physics.colliding.narrowphase import (
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
    R1X,
    R1Y,
    R2X,
    R2Y,
)
from box_toss_env.physics.colliding.parallel import (
    PARALLEL_CONTACTS,
    partition_contacts,
    partitioned_penetrations,
    partitioned_touched,
    partitioned_warm_start,
)
from box_toss_env.physics.colliding.prepare import apply_contact_impulses, note_depth, touch_bodies
from box_toss_env.physics.colliding.state import Bodies, Contacts, make_partition

BODIES = 400
COUNT = 3 * PARALLEL_CONTACTS
THRESHOLD = 0.5  # [m/s] the restitution threshold of ``touch_bodies``


def random_contacts(seed):
    """COUNT contacts in key order between BODIES bodies near one another in a random sweep order (most within a
    block, some across a cut) or with the floor (one in five); random geometry, gaps, impulses and approach speeds.
    Returns (rows, ids, the sweep order)."""
    rng = np.random.default_rng(seed)
    rows, ids = np.zeros((COUNT, CONTACT_COLUMNS)), np.zeros((COUNT, ID_COLUMNS), np.int64)
    sweep_order = rng.permutation(BODIES)
    first = rng.integers(0, BODIES - 4, COUNT)  # a pair: bodies near one another in the sweep order
    ids[:, BODY1] = sweep_order[first]
    ids[:, BODY2] = np.where(rng.random(COUNT) < 0.2, -1, sweep_order[first + rng.integers(1, 4, COUNT)])
    ids[:, KEY] = np.sort(rng.choice(50 * COUNT, COUNT, replace=False))
    angle = rng.uniform(0.0, 2.0 * np.pi, COUNT)
    rows[:, NX], rows[:, NY] = np.cos(angle), np.sin(angle)
    for column in (R1X, R1Y, R2X, R2Y):
        rows[:, column] = rng.uniform(-0.5, 0.5, COUNT)
    rows[:, GAP] = rng.uniform(-1e-3, 1e-3, COUNT)
    rows[:, IMPULSE] = np.where(rng.random(COUNT) < 0.7, rng.uniform(0.0, 2.0, COUNT), 0.0)
    rows[:, APPROACH] = rng.uniform(-2.0, 1.0, COUNT)
    return rows, ids, sweep_order


@numba.njit(cache=False)
def contacts_in_blocks(rows, ids, sweep_order):
    """``Contacts`` of the rows and ids, their blocks found (``partition_contacts``)."""
    n = rows.shape[0]
    partition, spare = make_partition(n)
    contacts = Contacts(rows, ids, np.zeros(n, np.bool_), np.zeros(n, np.int64), partition, spare)
    partition_contacts(ids, n, sweep_order, np.zeros(sweep_order.shape[0], np.int64), partition)
    return contacts


@numba.njit(cache=False)
def depths(rows, ids, sweep_order, blocks):
    """(each body's deepest penetration, the deepest) in contact order, or block by block."""
    max_penetration = np.zeros(BODIES)
    if blocks:
        return max_penetration, partitioned_penetrations(contacts_in_blocks(rows, ids, sweep_order), max_penetration)
    deepest = 0.0
    for c in range(rows.shape[0]):
        deepest = max(deepest, note_depth(c, rows, ids, max_penetration))
    return max_penetration, deepest


@numba.njit(cache=False)
def touches(rows, ids, sweep_order, impacts, blocks):
    """(touched, impacted) in contact order, or block by block (from bodies marked beforehand: both clear them)."""
    touched, impacted = np.ones(BODIES, np.bool_), np.full(BODIES, 7, np.int64)
    if blocks:
        contacts = contacts_in_blocks(rows, ids, sweep_order)
        partitioned_touched(rows, ids, contacts.partition, impacts, THRESHOLD, touched, impacted)
        return touched, impacted
    touched[:], impacted[:] = False, 0
    for c in range(rows.shape[0]):
        touch_bodies(c, rows, ids, impacts, THRESHOLD, touched, impacted)
    return touched, impacted


@numba.njit(cache=False)
def warm_started(rows, ids, sweep_order, keys, impulses, ratio, blocks):
    """The velocities of bodies at rest after the warm start from ``keys``, ``impulses``: block by block, or in
    contact order (``warm_start.warm_start``'s pairing of the two key lists, each found impulse applied)."""
    vel, inv_mass, inv_inertia = np.zeros((BODIES, 3)), np.full(BODIES, 0.5), np.full(BODIES, 2.0)
    if blocks:
        bodies = Bodies(vel, vel, vel[:, :2], vel, inv_mass, inv_inertia, inv_mass)
        contacts = contacts_in_blocks(rows, ids, sweep_order)
        partitioned_warm_start(contacts, rows.shape[0], (keys, impulses, keys.shape[0]), bodies, ratio)
        return vel
    at = 0
    for c in range(rows.shape[0]):
        rows[c, IMPULSE], rows[c, FRICTION_IMPULSE] = 0.0, 0.0
        while at < keys.shape[0] and keys[at] < ids[c, KEY]:
            at += 1
        if at < keys.shape[0] and keys[at] == ids[c, KEY]:
            rows[c, IMPULSE], rows[c, FRICTION_IMPULSE] = ratio * impulses[at, 0], ratio * impulses[at, 1]
            apply_contact_impulses(c, rows, ids, vel, inv_mass, inv_inertia)
    return vel


def on_threads(count, function, *args):
    before = numba.get_num_threads()
    numba.set_num_threads(min(count, numba.config.NUMBA_NUM_THREADS))
    try:
        return function(*args)
    finally:
        numba.set_num_threads(before)


@pytest.mark.parametrize("seed", [0, 1])
def test_deepest_penetrations_block_by_block_are_the_contact_orders(seed):
    rows, ids, order = random_contacts(seed)
    contacts = contacts_in_blocks(rows, ids, order)
    in_blocks = np.diff(contacts.partition.start)
    assert in_blocks[:-1].min() > 0 and 0 < in_blocks[-1] < COUNT / 4  # every block and the boundary hold some
    serial, deepest = depths(rows, ids, order, False)
    for threads in (1, 2):
        blocked, blocked_deepest = on_threads(threads, depths, rows, ids, order, True)
        assert np.array_equal(blocked, serial)
        assert blocked_deepest == deepest == max(0.0, -rows[:, GAP].min())
    assert serial[ids[:, BODY1]].min() >= -rows[:, GAP].max()


@pytest.mark.parametrize("impacts", [0, 5])
def test_touched_and_impacted_bodies_block_by_block_are_the_contact_orders(impacts):
    rows, ids, order = random_contacts(2)
    rows[np.isin(ids[:, BODY1], order[::3]) | np.isin(ids[:, BODY2], order[::3]), IMPULSE] = 0.0  # a third untouched
    touched, impacted = touches(rows, ids, order, impacts, False)
    assert touched.any() and not touched.all()
    assert (impacted.sum() > 0) == (impacts > 0)
    for threads in (1, 2):
        blocked_touched, blocked_impacted = on_threads(threads, touches, rows, ids, order, impacts, True)
        assert np.array_equal(blocked_touched, touched)
        assert np.array_equal(blocked_impacted, impacted)


def test_the_warm_start_block_by_block_finds_the_same_impulses_and_velocities():
    rows, ids, order = random_contacts(3)
    rng = np.random.default_rng(4)
    kept = np.sort(np.concatenate([rng.choice(ids[:, KEY], COUNT // 2, replace=False), rng.choice(10**6, 300) + 1]))
    keys = np.unique(kept)  # half the contacts' keys and some of contacts gone
    impulses = rng.uniform(-1.0, 1.0, (keys.shape[0], 2))
    serial_rows = rows.copy()
    serial = warm_started(serial_rows, ids, order, keys, impulses, 0.5, False)
    found = np.isin(ids[:, KEY], keys)
    assert 0 < found.sum() < COUNT
    results = []
    for threads in (1, 2):
        blocked_rows = rows.copy()
        results.append(on_threads(threads, warm_started, blocked_rows, ids, order, keys, impulses, 0.5, True))
        assert np.array_equal(blocked_rows[:, [IMPULSE, FRICTION_IMPULSE]], serial_rows[:, [IMPULSE, FRICTION_IMPULSE]])
        assert not blocked_rows[~found, IMPULSE].any()
    assert np.array_equal(results[0], results[1])  # any number of threads: the blocks' order
    np.testing.assert_allclose(results[0], serial, rtol=0.0, atol=1e-12)  # a rounding from the contacts' order
    assert np.abs(serial).max() > 1.0
