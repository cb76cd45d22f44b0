"""What ``robust_solver.advance_box`` keeps of a box between calls: one row per box, MEMORY_SIZE columns.

A box advanced in pieces goes on as one advanced in one call because everything its stage script carries
from one step to the next (its mode, the corner located to arrive, the corners that carried load, its time and
its counts) is in its row: ``read_memory`` at the start of a call, ``write_memory`` at its end, and
``start_memory`` for a box that starts (in flight) at a given time. The floor-only kernel keeps one row per box
for one call; the colliding kernel keeps the rows of the boxes it hands to ``advance_box`` (those no other box
can reach) across its substeps.
"""

import math

import numpy as np

from .. import layout
from ..compile.compilation import jit_stage

IN_FLIGHT, LOCATED, LOADED, LIFT, STILL_FOR, FIRST_CONTACT, REST_TIME, MAX_PENETRATION, N_IMPACTS, N_STEPS, TIME, \
    STATUS, FAIL_STEP = range(13)
MEMORY_SIZE = 13


@jit_stage
def start_memory(memory, i, time):
    """Box i's row of ``advance_box``'s memory for a box starting (in flight) at ``time``: no corner located or
    loaded, no lift, not still, no contact, rest or penetration yet, no impacts or steps, status OK."""
    write_memory(memory, i, True, -1, 0, 0.0, 0.0, math.nan, math.nan, 0.0, 0, 0, time, layout.STATUS_OK, -1)


@jit_stage(inline="always")
def read_memory(memory, i):
    """Box i's row of ``memory`` as (in flight, located corner, loaded corners, lift, still for, first contact,
    rest time, max penetration, impacts, steps, time)."""
    return (memory[i, IN_FLIGHT] != 0.0, np.int64(memory[i, LOCATED]), np.int64(memory[i, LOADED]), memory[i, LIFT],
            memory[i, STILL_FOR], memory[i, FIRST_CONTACT], memory[i, REST_TIME], memory[i, MAX_PENETRATION],
            np.int64(memory[i, N_IMPACTS]), np.int64(memory[i, N_STEPS]), memory[i, TIME])


@jit_stage(inline="always")
def write_memory(memory, i, in_flight, located, loaded, lift, still_for, first_contact, rest_time, max_penetration,
                 n_impacts, n_steps, t, status, fail_step):
    """``read_memory``'s inverse, with the status and the failed step: every column of box i's row."""
    memory[i, IN_FLIGHT] = 1.0 if in_flight else 0.0
    memory[i, LOCATED] = located
    memory[i, LOADED] = loaded
    memory[i, LIFT] = lift
    memory[i, STILL_FOR] = still_for
    memory[i, FIRST_CONTACT] = first_contact
    memory[i, REST_TIME] = rest_time
    memory[i, MAX_PENETRATION] = max_penetration
    memory[i, N_IMPACTS] = n_impacts
    memory[i, N_STEPS] = n_steps
    memory[i, TIME] = t
    memory[i, STATUS] = status
    memory[i, FAIL_STEP] = fail_step
