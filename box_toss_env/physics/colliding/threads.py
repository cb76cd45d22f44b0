"""The run's thread count, set by the colliding kernel itself (``layout.THREADS``): numba's count for this thread
(``numba.set_num_threads``) at the run's own for the run, and back after it.

Set from Python around the kernel (``numba.get_num_threads`` and ``set_num_threads``, through ctypes), it cost
1.5-2 us a call on warm caches and 15-22 us on cold ones: more than 100 thin plates at rest cost Box2D v3 over 120 steps
(49-50 us), and paid even where every body sleeps through the run. Here it is two calls into numba's threading layer
from compiled code, by the symbols numba registers for them (``types.ExternalFunction``: a compiled function that
holds ctypes pointers cannot be cached on disk), and none where the run has no body to step. In Python (the kernel's
interpreted copy) the same functions call numba's.
"""

import numba
from numba import types
from numba.core.extending import overload

from .. import layout
from ..compile.compilation import jit_stage

# the threading layer's functions by the names numba gives them once it starts the layer (``parallel.launch_threads``,
# before a colliding kernel is built): resolved when a compiled function that calls them is loaded
_GET_NUM_THREADS = types.ExternalFunction("get_num_threads", types.intc())
_SET_NUM_THREADS = types.ExternalFunction("set_num_threads", types.void(types.intc))


def threads_now() -> int:
    """numba's thread count for this thread."""
    return numba.get_num_threads()


def set_threads(count: int) -> None:
    """numba's thread count for this thread at ``count`` (in [1, NUMBA_NUM_THREADS], checked by the caller)."""
    numba.set_num_threads(count)


@overload(threads_now)
def _threads_now_compiled():
    return lambda: _GET_NUM_THREADS()


@overload(set_threads)
def _set_threads_compiled(count):
    def impl(count):
        _SET_NUM_THREADS(count)

    return impl


@jit_stage
def use_threads(settings):
    """numba's thread count at ``settings[THREADS]`` for the run (0: as it is); returns the count before."""
    before = threads_now()
    wanted = int(settings[layout.THREADS])
    if wanted > 0 and wanted != before:
        set_threads(wanted)
    return before


@jit_stage
def restore_threads(settings, before):
    """numba's thread count back at ``before`` (``use_threads``'s) after the run."""
    wanted = int(settings[layout.THREADS])
    if wanted > 0 and wanted != before:
        set_threads(before)
