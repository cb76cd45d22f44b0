"""Many small scenes of colliding boxes in one compiled call: a batch of ``BoxToss-OnBox-v0`` throws.

The colliding kernels (``kernels.make_kernel`` with ``KernelFlags(boxes_collide=True)``) step every body
of a call together, as one scene. A batch of envs is many such scenes side by side: env i's bodies are
rows ``i * group_size`` to ``(i + 1) * group_size - 1`` of the arrays (its thrown box first, then the
boxes it may land on). ``make_grouped_kernel`` compiles a kernel that runs the colliding kernel on each
consecutive group of rows in turn, so a batch costs one call from Python, and each group's result is
bit for bit what the colliding kernel gives that group alone (the single env's call).

    run_groups(state, params, settings, stats, group_size, warm)    # state (n_groups * group_size, 6) ...

``GroupedSimulator`` is ``Simulator``'s counterpart: it splits the groups over threads (whole groups per
thread, so the split never changes a result). A scene whose boxes cannot meet has groups of one body and
no use for any of this: ``make_simulator`` gives it the plain ``Simulator`` and its kernel, unchanged.
"""

from __future__ import annotations

import functools
import types
from typing import NamedTuple

import numba
import numpy as np

from . import layout
from .colliding.parallel import reaches_threads
from .compile import background_compile
from .compile.compilation import ensure_compiled, jit_kernel
from .kernels import KernelFlags, make_kernel, source_digest
from .simulate import Simulator, check_threads, thread_pool, with_threads
from .validation import check_integer

MAX_GROUP_SIZE = 64
"""The most bodies one group (one env's scene) may hold."""

MAX_INTERPRETED_GROUPED_BODIES = 16
"""The bodies of one interpreted call while the grouped kernel compiles (at least one group): a batch runs
interpreted in calls of this many bodies, and between two calls looks whether the compiled kernel is ready
(then its remaining groups run compiled). A colliding throw costs ~30 times a floor-only one, so 8 throws onto
a box already take 0.6-1.1 s in Python (measured beside the compiling worker on 2 cores); a step is never held
up for longer than such a call past the moment the compiled kernel is ready, and never waits on the compile."""


def _grouped_kernel_source(SOLVER, IMPULSES, PENALTY, FRICTION, DIGEST):
    """The grouped kernel's Python function for one set of flags (compiled by ``make_grouped_kernel``).
    It calls ``colliding_kernel``, a global that ``make_grouped_kernel`` binds to the colliding kernel of
    these flags; the flags themselves are closure constants, so numba's on-disk cache (keyed by the code
    and the closure's values) keeps one entry per set of flags and finds it again in the next process."""

    def run_groups(state, params, settings, stats, group_size, warm):
        _ = (SOLVER, IMPULSES, PENALTY, FRICTION, DIGEST)  # part of the on-disk cache key
        trajectory = np.zeros((0, 0, layout.STATE_SIZE))  # nothing recorded
        events = np.zeros((0, 0, layout.EVENT_SIZE))
        cold = np.zeros((0, layout.WARM_START_SIZE))  # without warm starts each group starts cold
        for group in range(state.shape[0] // group_size):
            first = group * group_size
            last = first + group_size
            colliding_kernel(  # noqa: F821
                state[first:last],
                params[first:last],
                settings,
                stats[first:last],
                trajectory,
                events,
                warm[group] if warm.shape[0] > 0 else cold,
            )

    return run_groups


@functools.cache
def make_grouped_kernel(solver: str, use_impulses: bool, use_penalty: bool, use_friction: bool):
    """``run_groups(state, params, settings, stats, group_size, warm)``: the colliding kernel of these flags
    (no recording) run on each consecutive group of ``group_size`` rows of the body arrays, group g with the
    warm start ``warm[g]`` (``warm`` (n_groups, rows, WARM_START_SIZE), or (0, 0, WARM_START_SIZE): none)."""
    kernel = make_kernel(
        KernelFlags(
            solver=solver,
            use_impulses=use_impulses,
            use_penalty=use_penalty,
            use_friction=use_friction,
            record=False,
            boxes_collide=True,
        )
    )
    function = _grouped_kernel_source(solver, use_impulses, use_penalty, use_friction, source_digest())
    # the same code and closure with the colliding kernel as a global (a dispatcher in the closure would
    # enter numba's cache key as its pickle, which differs in every process: a new cache entry each time)
    bound = types.FunctionType(
        function.__code__,
        {**globals(), "colliding_kernel": kernel},
        function.__name__,
        function.__defaults__,
        function.__closure__,
    )
    bound.__qualname__ = function.__qualname__
    return jit_kernel(bound)


class GroupedSimulator:
    """``Simulator`` for a batch of scenes of ``group_size`` colliding bodies each (module docstring).

    ``run(state, params, settings, stats)`` advances every group in place: the groups are split into
    ``threads`` contiguous shares of whole groups run at once (``threads`` in [1,
    numba.config.NUMBA_NUM_THREADS], default all of them; with ``flags.parallel`` False, one). No
    recording: a recorded scene (rendering) is one group, which the plain ``Simulator`` runs. With
    ``start_interpreted`` (the batched env), a kernel not in the cache yet is compiled by a worker process while
    runs use its interpreted copy (``background_compile``), in calls of whole groups of up to
    ``MAX_INTERPRETED_GROUPED_BODIES`` bodies; once the compiled kernel is ready (between two such calls) the
    remaining groups, and every later run, use it. A run of any size therefore never waits for the compile (a
    scene of four boxes in each of 8 envs is 32 bodies: waiting made a cold ``BoxToss-Stack-v0`` batch's third
    step take the whole compile, 175 s at load 5), and each group's result is the same either way.
    """

    def __init__(
        self, flags: KernelFlags, group_size: int, threads: int | None = None, start_interpreted: bool = False
    ):
        if not flags.boxes_collide:
            raise ValueError(
                "GroupedSimulator runs scenes whose boxes collide (flags.boxes_collide=True); "
                "independent boxes run on Simulator"
            )
        if flags.record:
            raise ValueError(
                "GroupedSimulator does not record trajectories (flags.record must be False); "
                "run one recorded scene on Simulator"
            )
        self.flags = flags
        self.group_size = check_integer("group_size", group_size, 1, MAX_GROUP_SIZE)
        self.threads = None if threads is None else check_threads(threads)
        recipe = {
            "solver": flags.solver,
            "use_impulses": flags.use_impulses,
            "use_penalty": flags.use_penalty,
            "use_friction": flags.use_friction,
        }
        self.kernel = make_grouped_kernel(**recipe)
        self._no_warm_start = np.zeros((0, 0, layout.WARM_START_SIZE))
        self._ready = False
        recipe_call = (__name__, "make_grouped_kernel", recipe)
        # a call of the copy is one chunk of whole groups (``_run_interpreted``): any one group may run interpreted
        self._start = (
            background_compile.InterpretedStart(self.kernel, recipe_call, MAX_GROUP_SIZE) if start_interpreted else None
        )
        self.interpreted = False  # whether the last run used the kernel's interpreted copy (for some groups)

    @property
    def shares(self) -> int:
        if not self.flags.parallel:
            return 1
        return self.threads if self.threads is not None else numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # numba sets its config at import

    def run(
        self,
        state: np.ndarray,
        params: np.ndarray,
        settings: np.ndarray,
        stats: np.ndarray,
        trajectory: np.ndarray | None = None,
        events: np.ndarray | None = None,
        warm_start: np.ndarray | None = None,
    ) -> None:
        """Advance ``state`` (n_groups * group_size, 6) in place and fill ``stats``; ``trajectory``
        and ``events`` must be None (kept for ``Simulator``'s signature). ``warm_start``: one
        ``warm_start_memory`` a group, stacked (n_groups, rows, WARM_START_SIZE) (``Simulator.run``'s, group by
        group), or None: each group starts cold."""
        if trajectory is not None or events is not None:
            raise ValueError("GroupedSimulator does not record: trajectory and events must be None")
        size = self.group_size
        if state.shape[0] % size:
            raise ValueError(f"state must hold whole groups of group_size={size} bodies, got {state.shape[0]} rows")
        groups = state.shape[0] // size
        warm = self._no_warm_start if warm_start is None else check_group_warm_starts(warm_start, groups)
        if reaches_threads(size):  # a group can reach a stage on threads: one thread each, the shares are the threads
            settings = with_threads(settings, 1)
        arrays = GroupArrays(state, params, settings, stats, size, warm)
        first = 0  # the first group the compiled kernel runs
        self.interpreted = False
        if not self._ready:
            first = self._run_interpreted(arrays, groups)
            self.interpreted = first > 0
            if first == groups:
                return
            ensure_compiled(self.kernel, arrays.share(first, groups))
            self._ready = True
        shares = min(self.shares, groups - first)
        if shares <= 1:
            self.kernel(*arrays.share(first, groups))
            return
        edges = [first + (groups - first) * k // shares for k in range(shares + 1)]
        pool = thread_pool(shares - 1)
        futures = [pool.submit(self.kernel, *arrays.share(a, b)) for a, b in zip(edges[:-2], edges[1:-1], strict=True)]
        try:
            self.kernel(*arrays.share(edges[-2], groups))
        finally:
            for future in futures:
                future.result()

    def _run_interpreted(self, arrays: GroupArrays, groups: int) -> int:
        """Run groups 0, 1, ... with the kernel's interpreted copy, in calls of whole groups of up to
        ``MAX_INTERPRETED_GROUPED_BODIES`` bodies (at least one group), until every group has run or the
        compiled kernel is ready (or the copy refused a call: ``InterpretedStart.run``); returns how many
        groups ran. Nothing here waits for the compile."""
        if self._start is None:
            return 0
        chunk = max(1, MAX_INTERPRETED_GROUPED_BODIES // arrays.size)
        done = 0
        while done < groups:
            end = min(groups, done + chunk)
            args = arrays.share(done, end)
            if not self._start.run(args, (args[0], args[3], args[5])):  # it writes the state, stats, warm starts
                break
            done = end
        return done


class GroupArrays(NamedTuple):
    """One run's arrays (``GroupedSimulator.run``): the bodies of ``state.shape[0] // size`` groups."""

    state: np.ndarray
    params: np.ndarray
    settings: np.ndarray
    stats: np.ndarray
    size: int
    warm: np.ndarray

    def share(self, a: int, b: int) -> tuple:
        """The grouped kernel's arguments for groups ``a`` to ``b - 1`` (views: the kernel writes in place)."""
        rows = slice(self.size * a, self.size * b)
        warm = self.warm[a:b] if self.warm.shape[0] else self.warm
        return self.state[rows], self.params[rows], self.settings, self.stats[rows], self.size, warm


def check_group_warm_starts(warm_start, groups: int) -> np.ndarray:
    """``warm_start`` if it is a C-contiguous float64 array (groups, rows >= 1, WARM_START_SIZE) (a
    ``warm_start_memory`` a group), else a ValueError naming it."""
    if (
        not isinstance(warm_start, np.ndarray)
        or warm_start.dtype != np.float64
        or warm_start.ndim != 3
        or warm_start.shape[0] != groups
        or warm_start.shape[1] < 1
        or warm_start.shape[2] != layout.WARM_START_SIZE
        or not warm_start.flags.c_contiguous
    ):
        shape = getattr(warm_start, "shape", None)
        raise ValueError(
            f"warm_start must be a C-contiguous float64 array of shape ({groups} groups, rows >= 1, "
            f"{layout.WARM_START_SIZE}), a warm_start_memory a group, got {type(warm_start).__name__} "
            f"{shape}"
        )
    return warm_start


def make_simulator(
    flags: KernelFlags, group_size: int = 1, threads: int | None = None, start_interpreted: bool = False
):
    """The simulator for a batch of scenes of ``group_size`` bodies each: ``Simulator`` (the plain
    kernel, its bodies independent, unchanged; ``start_interpreted`` as there) when the boxes cannot
    meet, ``GroupedSimulator`` when they can (with ``flags.record``, the plain ``Simulator`` on one scene)."""
    if not flags.boxes_collide or flags.record:
        return Simulator(flags, threads=threads, start_interpreted=start_interpreted)
    return GroupedSimulator(flags, group_size, threads, start_interpreted)
