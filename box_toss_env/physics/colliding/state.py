"""The colliding solver's step state: a few named structures, built once per kernel call (``make_step_state``), so
that each stage takes the two or three it reads (Box2D v3 passes one ``b2StepContext``; numba compiles a named
tuple as its fields, so passing one costs what passing its fields did).

- ``StepContext``: the scene's settings and the kernel's switches, read once;
- ``Bodies``: every body's pose and velocity and its constants;
- ``Sweep``: the broadphase's geometry (bounding boxes, reaches, the sweep order) and its pairs;
- ``Contacts``: the contact rows of a substep;
- ``Impulses``: the impulses kept for warm starts (from substep to substep, group to group, step to step);
- ``Sleep``: the islands and sleep timers;
- ``Stats``: what a run reports per body, and where a recorded run writes;
- ``Scratch``: work arrays of the substeps (``Work``), the exact solves (``ExactWork``), the groups
  (``GroupWork``) and the bodies advanced alone (``AloneWork``), each handed only to the stages that use it.

Every array is sized between grid steps (``grown_sweep``, ``room_for_contacts``): a step's substeps never run out
of room, so they never stop half-way.
"""

import math
from typing import NamedTuple

import numpy as np

from .. import layout
from ..compile.compilation import jit_stage
from ..kernel_support import read_settings
from ..robust.contact_solver import CORNER_ROWS, MAX_CORNERS
from ..robust.memory import MEMORY_SIZE
from ..robust.state import CornerWork
from ..tunables import CONTACT_TOLERANCE, DIRECT_LIMIT, MAX_SUBSTEPS, MIN_CAPACITY
from .narrowphase import CONTACT_COLUMNS, ID_COLUMNS
from .parallel import Partition, Spare, Spread, make_partition, make_spread


class StepContext(NamedTuple):
    """The scene's settings (``layout``) and the kernel's compile-time switches, as every stage reads them."""

    dt: float  # [s] grid step
    gravity: float  # [m/s^2] along y
    max_steps: int
    until_rest: bool  # the run ends once every body sleeps
    sleeping: bool  # islands at rest sleep (``Scene`` sleep settings; always with until_rest)
    threshold: float  # [m/s] restitution threshold
    sleep_speed: float  # [m/s]
    sleep_time: float  # [s]
    slop: float  # [m] penetration slop
    sweep_tolerance: float  # [-] Gauss-Seidel stop (``Scene.solver_tolerance``)
    sweeps: int  # Gauss-Seidel sweeps at most (``Scene.solver_iterations``)
    tolerance: float  # [m] contact tolerance at the scene's size (``tunables.CONTACT_TOLERANCE``)
    smallest_half: float  # [m] the smallest half extent of any box (the substeps' tunnelling bound)
    use_penalty: bool
    use_friction: bool
    record: bool


class Bodies(NamedTuple):
    """Every body: pose (x, y, angle) and velocity (vx, vy, omega) a row, half extents, parameters (``layout``),
    inverse mass and inertia, corner radius."""

    pose: np.ndarray  # (n, 3)
    vel: np.ndarray  # (n, 3)
    half: np.ndarray  # (n, 2) [m]
    params: np.ndarray  # (n, PARAM_SIZE)
    inv_mass: np.ndarray  # (n,) [1/kg]
    inv_inertia: np.ndarray  # (n,) [1/(kg m^2)]
    radius: np.ndarray  # (n,) [m]


class KeptSearch(NamedTuple):
    """The step's last pair search at padded reaches (``groups.step_pairs``): each body's centre then, the half size of
    its padded box (bounding box + reach + PAIR_MARGIN), its padded reach and whether it was awake; its own sweep
    order (the step's, ``Sweep.order``, stays sorted at the step's reaches alone); the pairs it found and how many
    (``found[0]``, -1 until the first search of a run)."""

    centre: np.ndarray  # (n, 2) [m]
    half: np.ndarray  # (n, 2) [m]
    reach: np.ndarray  # (n,) [m]
    awake: np.ndarray  # (n,) bool
    order: np.ndarray  # (n,) int64
    pairs: np.ndarray  # (capacity,) int64
    found: np.ndarray  # (1,) int64


class Sweep(NamedTuple):
    """The broadphase (``broadphase``): each box's cos and sin, the half size of its bounding box, its reach (what it
    can travel) against boxes and against the floor, the sweep's axis, interval starts and order, the step's
    candidate pairs (keys i n + j) and a substep's share of them, and the last search kept (``KeptSearch``)."""

    trig: np.ndarray  # (n, 2)
    bound: np.ndarray  # (n, 2) [m]
    reach: np.ndarray  # (n,) [m]
    floor_reach: np.ndarray  # (n,) [m]
    axis: int  # 0 (x) or 1 (y)
    low: np.ndarray  # (n,) [m]
    order: np.ndarray  # (n,) int64
    pairs: np.ndarray  # (capacity,) int64
    substep_pairs: np.ndarray  # (capacity,) int64
    spread: Spread  # the threads' work (``parallel``)
    kept: KeptSearch


class Contacts(NamedTuple):
    """A substep's contacts (``narrowphase``: ``rows`` of CONTACT_COLUMNS, ``ids`` of ID_COLUMNS), and per-contact
    work of the penalty (``relax``: whether a contact's island is deep, the list of those contacts; before the
    penalty's sweeps list them, and in the velocity solve, ``listed`` orders the islands solved exactly:
    ``solve.order_marked``)."""

    rows: np.ndarray  # (capacity, CONTACT_COLUMNS)
    ids: np.ndarray  # (capacity, ID_COLUMNS) int64
    deep: np.ndarray  # (capacity,) bool
    listed: np.ndarray  # (capacity,) int64
    partition: Partition  # the contacts' blocks, for sweeps on threads (``parallel``)
    spare: Spare  # rows the narrowphase on threads fills before packing them (``parallel``)


class Impulses(NamedTuple):
    """The impulses kept for warm starts: those the next substep starts from (``keys``, ``impulses``: normal and
    friction, by key, in key order), a group's own (``group_keys``, ``group_impulses``) and every group's of a step
    with their substep lengths (``kept_keys``, ``kept_impulses``)."""

    keys: np.ndarray  # (capacity,) int64
    impulses: np.ndarray  # (capacity, 2) [N s]
    group_keys: np.ndarray  # (capacity,) int64
    group_impulses: np.ndarray  # (capacity, 2) [N s]
    kept_keys: np.ndarray  # (capacity,) int64
    kept_impulses: np.ndarray  # (capacity, 3) [N s], [N s], [s]


class Sleep(NamedTuple):
    """Islands and sleeping (``islands``): all True (``everyone``), who is awake, each sleeping body's island (its
    root body, -1 awake), each awake body's sleep timer [s], when each fell asleep [s] (nan: awake), the union-find
    forest of the islands and a per-body work mask."""

    everyone: np.ndarray  # (n,) bool
    awake: np.ndarray  # (n,) bool
    island: np.ndarray  # (n,) int64
    still_for: np.ndarray  # (n,) [s]
    rest_time: np.ndarray  # (n,) [s]
    parent: np.ndarray  # (n,) int64
    ready: np.ndarray  # (n,) bool


class Stats(NamedTuple):
    """What a run reports per body (``layout``'s stats), whether each took a contact impulse in the step
    (``supported``: the sleep test's), and where a recorded run writes."""

    first_contact: np.ndarray  # (n,) [s] (nan: none)
    n_impacts: np.ndarray  # (n,) int64
    n_stepped: np.ndarray  # (n,) int64
    max_penetration: np.ndarray  # (n,) [m]
    supported: np.ndarray  # (n,) bool
    trajectory: np.ndarray  # (max_steps + 1, n, STATE_SIZE) or empty
    events: np.ndarray  # (n, MAX_EVENTS, EVENT_SIZE) or empty


class ExactWork(NamedTuple):
    """The exact solves' work arrays (``normal_lcp``, ``joint_contact_solve``): W, its factor, the free velocities,
    the solution, the active set, an index, the forward solve's y, the contacts' states; the sweeps'
    ``moved`` (``sweeps.gauss_seidel``); and the islands solved exactly among many contacts (``solve``)."""

    w: np.ndarray  # (DIRECT_LIMIT, DIRECT_LIMIT)
    factor: np.ndarray  # (DIRECT_LIMIT, DIRECT_LIMIT)
    free: np.ndarray  # (DIRECT_LIMIT,)
    x: np.ndarray  # (DIRECT_LIMIT,)
    active: np.ndarray  # (DIRECT_LIMIT,) bool
    index: np.ndarray  # type: ignore[assignment]  # (DIRECT_LIMIT,) int64; a field, over tuple.index
    y: np.ndarray  # (DIRECT_LIMIT,)
    state: np.ndarray  # (DIRECT_LIMIT,) int64
    moved: np.ndarray  # (2, n) bool
    root: np.ndarray  # (n,) int64: the islands' union-find forest (``solve.solve_unlike_islands``)
    tally: np.ndarray  # (n,) int64: per island root, minus its contact count if it is to be solved exactly
    rows: np.ndarray  # (DIRECT_LIMIT, CONTACT_COLUMNS): one island's contacts, gathered
    ids: np.ndarray  # (DIRECT_LIMIT, ID_COLUMNS) int64
    listed: np.ndarray  # (DIRECT_LIMIT,) int64: where each gathered contact came from
    start: np.ndarray  # (n,) int64: per marked island root, where its contacts end in ``Contacts.listed``


class GroupWork(NamedTuple):
    """The groups of a step (``groups``): each body's group (-1 asleep), the mask of the group stepped, and the
    grouping's work (per body its speed against what it can touch and turn rate, then per set the fastest of both,
    its label and count, per substep count a label)."""

    group_of: np.ndarray  # (n,) int64
    in_group: np.ndarray  # (n,) bool
    speed_turn: np.ndarray  # (n, 2)
    label: np.ndarray  # (n, 2) int64
    label_of_count: np.ndarray  # (MAX_SUBSTEPS + 1,) int64


class AloneWork(NamedTuple):
    """The bodies advanced alone against the floor (``alone``): ``robust_solver.advance_box``'s memory rows,
    whether a body's row holds on, a body's state (n, 6) as advance_box reads it, and its corner work."""

    memory: np.ndarray  # (n, MEMORY_SIZE)
    alone: np.ndarray  # (n,) bool
    state: np.ndarray  # (n, 6)
    corners: CornerWork


class Work(NamedTuple):
    """Scratch of the substeps: the penalty's pseudo-velocities, each body's kinetic energy before the substep,
    which bodies took an impulse and at how many impacts, and the penalty's islands (a union-find forest, a mark
    per root)."""

    pseudo: np.ndarray  # (n, 3)
    kinetic_before: np.ndarray  # (n,) [J]
    touched: np.ndarray  # (n,) bool
    impacted: np.ndarray  # (n,) int64
    root: np.ndarray  # (n,) int64
    marked: np.ndarray  # (n,) bool


class Scratch(NamedTuple):
    """Every work structure, for the step-level stages to hand out (a call costs what its arguments weigh: a
    substep's stages take the one they use)."""

    work: Work
    exact: ExactWork
    groups: GroupWork
    alone: AloneWork


@jit_stage(inline="always")  # into the kernel (array reductions need numba's runtime)
def step_context(settings, half, radius, use_penalty, use_friction, record):
    """``StepContext`` from the settings array and the scene's boxes."""
    dt, gravity, max_steps, until_rest, threshold, sleep_speed, sleep_time, slop = read_settings(settings)
    return StepContext(
        dt,
        gravity,
        max_steps,
        until_rest,
        until_rest or settings[layout.SLEEP] != 0.0,
        threshold,
        sleep_speed,
        sleep_time,
        slop,
        settings[layout.SOLVER_TOLERANCE],
        np.int64(settings[layout.SOLVER_ITERATIONS]),
        CONTACT_TOLERANCE * (1.0 + radius.max()),
        half.min(),
        use_penalty,
        use_friction,
        record,
    )


@jit_stage(inline="always")
def initial_capacity(n):
    """Contact rows a kernel of n bodies starts with: 8 a body, at least MIN_CAPACITY."""
    return max(8 * n, MIN_CAPACITY)


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_bodies(state, params):
    """``Bodies`` of the state and parameters (copies: the kernel writes the state back at its end)."""
    half = params[:, 0:2].copy()
    radius = np.sqrt(half[:, 0] ** 2 + half[:, 1] ** 2)
    return Bodies(
        state[:, 0:3].copy(),
        state[:, 3:6].copy(),
        half,
        params,
        1.0 / params[:, layout.MASS],
        1.0 / params[:, layout.INERTIA],
        radius,
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_sweep(n):
    """An empty ``Sweep`` for n bodies (its axis 0 until ``broadphase``'s first search picks one)."""
    pairs = max(4 * n, MIN_CAPACITY)
    return Sweep(
        np.zeros((n, 2)),
        np.zeros((n, 2)),
        np.zeros(n),
        np.zeros(n),
        0,
        np.zeros(n),
        np.empty(n, np.int64),
        np.zeros(pairs, np.int64),
        np.zeros(pairs, np.int64),
        make_spread(n),
        make_kept_search(n, pairs),
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_kept_search(n, pairs):
    """A ``KeptSearch`` for n bodies and room for ``pairs`` pairs, holding no search."""
    return KeptSearch(
        np.zeros((n, 2)),
        np.zeros((n, 2)),
        np.zeros(n),
        np.zeros(n, np.bool_),
        np.zeros(n, np.int64),
        np.zeros(pairs, np.int64),
        np.full(1, -1, np.int64),
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def with_axis(sweep, axis):
    """The sweep with its axis set."""
    return Sweep(
        sweep.trig,
        sweep.bound,
        sweep.reach,
        sweep.floor_reach,
        axis,
        sweep.low,
        sweep.order,
        sweep.pairs,
        sweep.substep_pairs,
        sweep.spread,
        sweep.kept,
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def grown_sweep(sweep):
    """The sweep with room for twice the pairs (none kept: a search that ran out of room is repeated)."""
    pairs = 2 * sweep.pairs.shape[0]
    return Sweep(
        sweep.trig,
        sweep.bound,
        sweep.reach,
        sweep.floor_reach,
        sweep.axis,
        sweep.low,
        sweep.order,
        np.zeros(pairs, np.int64),
        np.zeros(pairs, np.int64),
        sweep.spread,
        make_kept_search(sweep.reach.shape[0], pairs),
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_contacts(capacity):
    """``Contacts`` and ``Impulses`` with room for ``capacity`` rows (each written before it is read: left
    unzeroed)."""
    partition, spare = make_partition(capacity)
    return (
        Contacts(
            np.empty((capacity, CONTACT_COLUMNS)),
            np.empty((capacity, ID_COLUMNS), np.int64),
            np.empty(capacity, np.bool_),
            np.empty(capacity, np.int64),
            partition,
            spare,
        ),
        Impulses(
            np.empty(capacity, np.int64),
            np.empty((capacity, 2)),
            np.empty(capacity, np.int64),
            np.empty((capacity, 2)),
            np.empty(capacity, np.int64),
            np.empty((capacity, 3)),
        ),
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def room_for_contacts(contacts, impulses, needed, n_kept):
    """``contacts`` and ``impulses`` with room for ``needed`` rows: new ones at twice their rows (or ``needed``, if
    more) that keep the first ``n_kept`` warm-start impulses, or the same if they have room."""
    capacity = contacts.rows.shape[0]
    if needed <= capacity:
        return contacts, impulses
    grown_contacts, grown = make_contacts(max(2 * capacity, needed))
    grown.keys[:n_kept] = impulses.keys[:n_kept]
    grown.impulses[:n_kept] = impulses.impulses[:n_kept]
    return grown_contacts, grown


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_sleep(n):
    """``Sleep`` with every body awake, no timer run, never asleep."""
    return Sleep(
        np.ones(n, np.bool_),
        np.ones(n, np.bool_),
        np.full(n, -1, np.int64),
        np.zeros(n),
        np.full(n, math.nan),
        np.zeros(n, np.int64),
        np.zeros(n, np.bool_),
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_stats(n, trajectory, events):
    """``Stats`` before the run: no contact, impact, step or penetration yet."""
    return Stats(
        np.full(n, math.nan),
        np.zeros(n, np.int64),
        np.zeros(n, np.int64),
        np.zeros(n),
        np.zeros(n, np.bool_),
        trajectory,
        events,
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_exact_work(n):
    """``ExactWork`` for n bodies."""
    return ExactWork(
        np.zeros((DIRECT_LIMIT, DIRECT_LIMIT)),
        np.zeros((DIRECT_LIMIT, DIRECT_LIMIT)),
        np.zeros(DIRECT_LIMIT),
        np.zeros(DIRECT_LIMIT),
        np.zeros(DIRECT_LIMIT, np.bool_),
        np.zeros(DIRECT_LIMIT, np.int64),
        np.zeros(DIRECT_LIMIT),
        np.zeros(DIRECT_LIMIT, np.int64),
        np.zeros((2, n), np.bool_),
        np.zeros(n, np.int64),
        np.zeros(n, np.int64),
        np.zeros((DIRECT_LIMIT, CONTACT_COLUMNS)),
        np.zeros((DIRECT_LIMIT, ID_COLUMNS), np.int64),
        np.zeros(DIRECT_LIMIT, np.int64),
        np.zeros(n, np.int64),
    )


@jit_stage(inline="always")  # into its callers, which run with numba's runtime
def make_scratch(n):
    """``Scratch`` for n bodies."""
    exact = make_exact_work(n)
    groups = GroupWork(
        np.full(n, -1, np.int64),
        np.zeros(n, np.bool_),
        np.zeros((n, 2)),
        np.zeros((n, 2), np.int64),
        np.zeros(MAX_SUBSTEPS + 1, np.int64),
    )
    corners = CornerWork(
        np.zeros((CORNER_ROWS, MAX_CORNERS)), np.zeros((MAX_CORNERS, MAX_CORNERS)), np.zeros(MAX_CORNERS, np.int64)
    )
    alone = AloneWork(np.zeros((n, MEMORY_SIZE)), np.zeros(n, np.bool_), np.zeros((n, 6)), corners)
    work = Work(
        np.zeros((n, 3)),
        np.zeros(n),
        np.zeros(n, np.bool_),
        np.zeros(n, np.int64),
        np.zeros(n, np.int64),
        np.zeros(n, np.bool_),
    )
    return Scratch(work, exact, groups, alone)
