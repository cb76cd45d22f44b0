"""Kernels loaded or compiled off the drawing thread, so the viewer's window draws while numba works.

The first call of a numba kernel loads it from numba's on-disk cache (a fraction of a second) or, the
first time a combination of solver and switches is used, compiles it (seconds). ``KernelLoader``
makes that first call, with zero steps on copies of the arrays, on a background thread; until it
returns, the viewer holds the scene still and draws a notice over it (``KernelJob.notice``). The
window starts the loader only after its first frame is on screen, so the first frame never waits for
numba. Numba holds the GIL for stretches of a compilation: the window draws more slowly meanwhile, but
it draws.

Without a loader (``loader=None`` everywhere) the kernel is compiled by its first real call, on the
calling thread, as before.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from box_toss_env.physics import layout, warm_start_memory
from box_toss_env.physics.compile.compilation import cached_on_disk, compiled_in_process, ensure_compiled

COMPILING_NOTICE = "compiling the {name} kernel... (first use only)"
LOADING_NOTICE = "loading the {name} kernel from numba's cache..."


def load_kernel(kernel: Callable[..., Any], args: tuple) -> None:
    """The call that loads or compiles ``kernel`` for ``args``'s types (and runs it on them); a
    compilation holds the engine's compile lock (``compilation.ensure_compiled``)."""
    ensure_compiled(kernel, args)
    kernel(*args)


def zero_step_args(
    state: np.ndarray, params: np.ndarray, settings: np.ndarray, stats: np.ndarray, warm_start: bool = False
) -> tuple:
    """Arguments for a kernel call that compiles it for these arrays' types and simulates nothing:
    copies, with ``MAX_STEPS`` = 0 and a one-row trajectory and events (the types of the real ones), and a
    warm start for a kernel that carries one (``Simulator.carries_warm_start``)."""
    settings = np.array(settings, dtype=np.float64)
    settings[layout.MAX_STEPS] = 0.0
    n = state.shape[0]
    return (
        np.array(state, dtype=np.float64),
        np.array(params, dtype=np.float64),
        settings,
        np.array(stats, dtype=np.float64),
        np.zeros((1, n, layout.STATE_SIZE)),
        np.zeros((n, layout.MAX_EVENTS, layout.EVENT_SIZE)),
        *((warm_start_memory(n),) if warm_start else ()),
    )


@dataclass(eq=False)
class KernelJob:
    """One kernel's first call: queued, then running on the loader's thread, then ``ready``."""

    kernel: Any
    args: tuple
    name: str  # the solver, for the notice
    cached: bool  # numba's disk cache has it: loading, not compiling
    clock: Callable[[], float] = time.perf_counter
    started: float | None = None
    error: BaseException | None = None
    done: threading.Event = field(default_factory=threading.Event)

    @property
    def ready(self) -> bool:
        """The first call has returned (if it failed, the real call raises the error again)."""
        return self.done.is_set()

    @property
    def notice(self) -> str:
        return (LOADING_NOTICE if self.cached else COMPILING_NOTICE).format(name=self.name)

    def elapsed(self) -> float:
        """Seconds since the loader began this kernel (0 while queued)."""
        return 0.0 if self.started is None else self.clock() - self.started


class KernelLoader:
    """Loads or compiles kernels one at a time on a background thread.

    ``prepare`` queues a kernel's first call and returns its ``KernelJob`` (None if the kernel is
    compiled in this process already); the thread starts at ``start`` (the window calls it once its
    first frame is shown) and runs the jobs in order. Each kernel is loaded once per loader.
    """

    def __init__(self, clock: Callable[[], float] = time.perf_counter):
        self.clock = clock
        self._jobs: dict[int, KernelJob] = {}
        self._queue: queue.SimpleQueue[KernelJob] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None

    def prepare(self, kernel, args: tuple, name: str) -> KernelJob | None:
        with self._lock:
            job = self._jobs.get(id(kernel))
            if job is not None:
                return job
            if compiled_in_process(kernel, args):
                return None
            job = KernelJob(kernel, args, name, cached_on_disk(kernel, args), self.clock)
            self._jobs[id(kernel)] = job
            self._queue.put(job)
            return job

    @property
    def started(self) -> bool:
        return self._thread is not None

    def start(self) -> None:
        """Start the background thread (once; later calls do nothing)."""
        with self._lock:
            if self._thread is None:
                self._thread = threading.Thread(target=self._work, name="box-toss-kernel-loader", daemon=True)
                self._thread.start()

    def _work(self) -> None:
        while True:
            job = self._queue.get()
            job.started = self.clock()
            try:
                load_kernel(job.kernel, job.args)
            except BaseException as error:  # noqa: BLE001  (the real call on the main thread raises it)
                job.error = error
            finally:
                job.done.set()

    def pending(self) -> list[KernelJob]:
        """The jobs not ready yet, in the order they were queued."""
        with self._lock:
            return [job for job in self._jobs.values() if not job.ready]

    def wait(self, timeout: float | None = None) -> bool:
        """Start the thread and wait until every queued kernel is ready; False on timeout."""
        self.start()
        deadline = None if timeout is None else time.monotonic() + timeout
        for job in self.pending():
            remaining = None if deadline is None else max(0.0, deadline - time.monotonic())
            if not job.done.wait(remaining):
                return False
        return True
