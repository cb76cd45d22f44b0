"""What ``robust_solver.advance_box`` keeps of a box between calls: one row per box, MEMORY_SIZE columns.

A box advanced in pieces goes on as one advanced in one call because everything its stage script carries
from one step to the next (its mode, the corner located to arrive, the corners that carried load, its time and
its counts) is in its row: ``read_memory`` at the start of a call, ``write_memory`` at its end, and
``start_memory`` for a box that starts (in flight) at a given time. The floor-only kernel keeps one row per box
for one call; the colliding kernel keeps the rows of the boxes it hands to ``advance_box`` (those no other box
can reach) across its substeps.
"""

import math
from typing import NamedTuple

import numpy as np

from .. import layout
from ..compile.compilation import jit_stage

(
    IN_FLIGHT,
    LOCATED,
    LOADED,
    LIFT,
    STILL_FOR,
    FIRST_CONTACT,
    REST_TIME,
    MAX_PENETRATION,
    N_IMPACTS,
    N_STEPS,
    TIME,
    STATUS,
    FAIL_STEP,
) = range(13)
MEMORY_SIZE = 13


class Corners(NamedTuple):
    """What one contact step leaves the next: the corner located to arrive (-1 none), the corners that carried
    load (bit c for corner c) and how far a rotating step lifts a held corner [m]."""

    located: int
    loaded: int
    lift: float


class Tally(NamedTuple):
    """A box's counts for its stats: first contact [s] (nan: none yet), impacts, deepest penetration [m], steps."""

    first_contact: float
    n_impacts: int
    max_penetration: float
    n_steps: int


class Progress(NamedTuple):
    """Where a box is: in flight or in contact, its time [s], its sleep timer [s] and rest time [s] (nan: awake),
    and whether it is still finite (``layout.STATUS_*``, the failed grid step or -1)."""

    in_flight: bool
    t: float
    still_for: float
    rest_time: float
    status: int
    fail_step: int


@jit_stage
def start_memory(memory, i, time):
    """Box i's row of ``advance_box``'s memory for a box starting (in flight) at ``time``: no corner located or
    loaded, no lift, not still, no contact, rest or penetration yet, no impacts or steps, status OK."""
    write_memory(
        memory,
        i,
        Progress(True, time, 0.0, math.nan, layout.STATUS_OK, -1),
        Corners(-1, 0, 0.0),
        Tally(math.nan, 0, 0.0, 0),
    )


@jit_stage(inline="always")
def read_memory(memory, i):
    """Box i's row of ``memory`` as (``Progress``, ``Corners``, ``Tally``)."""
    progress = Progress(
        memory[i, IN_FLIGHT] != 0.0,
        memory[i, TIME],
        memory[i, STILL_FOR],
        memory[i, REST_TIME],
        np.int64(memory[i, STATUS]),
        np.int64(memory[i, FAIL_STEP]),
    )
    corners = Corners(np.int64(memory[i, LOCATED]), np.int64(memory[i, LOADED]), memory[i, LIFT])
    tally = Tally(
        memory[i, FIRST_CONTACT],
        np.int64(memory[i, N_IMPACTS]),
        memory[i, MAX_PENETRATION],
        np.int64(memory[i, N_STEPS]),
    )
    return progress, corners, tally


@jit_stage(inline="always")
def write_memory(memory, i, progress, corners, tally):
    """``read_memory``'s inverse: every column of box i's row."""
    memory[i, IN_FLIGHT] = 1.0 if progress.in_flight else 0.0
    memory[i, TIME] = progress.t
    memory[i, STILL_FOR] = progress.still_for
    memory[i, REST_TIME] = progress.rest_time
    memory[i, STATUS] = progress.status
    memory[i, FAIL_STEP] = progress.fail_step
    memory[i, LOCATED] = corners.located
    memory[i, LOADED] = corners.loaded
    memory[i, LIFT] = corners.lift
    memory[i, FIRST_CONTACT] = tally.first_contact
    memory[i, N_IMPACTS] = tally.n_impacts
    memory[i, MAX_PENETRATION] = tally.max_penetration
    memory[i, N_STEPS] = tally.n_steps
