"""Throwing at once on a cold cache: the kernel compiles in another process while this one runs
the kernel's interpreted copy, which gives the same results bit for bit.

A cold compile of a kernel takes seconds to a minute of CPU (measured by ``benchmarks.cold_start``),
while one throw of its plain-Python source takes milliseconds. So an env's first throws need not
wait: ``Simulator(..., start_interpreted=True)`` (what the envs use) asks a worker process
(``main`` here, in a fresh interpreter) to compile the kernel into numba's
on-disk cache, runs ``interpreted_copy(kernel)`` meanwhile, and switches to the compiled kernel (loaded
from the cache) at its first run after the cache holds it. It says so on the ``box_toss_env.compile``
logger (a warning when it starts interpreted, naming the worker and its log file, which the worker
appends to when it starts and ends), so the slow first throws are never a silent mystery.

One compilation of a kernel at a time, whoever asks: the worker holds the kernel's compile lock
(``compilation.compile_lock``) while it compiles, and a process that finds the lock held (another
process's worker, or a process compiling it in the foreground) starts no worker of its own: it runs
interpreted and looks in the cache every ``CHECK_INTERVAL`` seconds, and starts its own worker only if
the lock comes free with the kernel still missing (its holder died). So the vector-env workers of
``SubprocVecEnv`` or Ray, starting together, start one compiling process between them. The worker runs
in a session of its own and outlives the process that started it: a short process (a test, a CLI call,
a worker that is closed) still leaves the compiled kernel in the cache for the next.

The interpreted copy is the kernel's own Python source with every compiled stage it calls replaced
by that stage's Python source: the same IEEE double operations in the same order, so the results
are identical, which ``tests/physics/test_background_compile.py`` checks throw by throw. Nothing is
interpreted where it would cost more than waiting: batches larger than ``MAX_INTERPRETED_BODIES``
bodies (a batch of scenes of colliding boxes runs interpreted in calls of a few scenes instead, looking for
the compiled kernel between two calls: ``grouped.GroupedSimulator``), scenes run through ``simulate`` (the
default ``start_interpreted=False``), and a machine without a writable cache directory (the worker's result
could not reach this process) compile here.
Setting ``BOX_TOSS_ENV_START_INTERPRETED=0`` turns the interpreted start off everywhere.
"""

from __future__ import annotations

import datetime
import logging
import os
import pickle
import subprocess
import sys
import time
import types
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

import numpy as np
from numba.core import config
from numba.core.dispatcher import Dispatcher

from .compilation import (
    argument_types,
    cache_location,
    cached_for,
    cached_on_disk,
    compile_locked,
    compiled_in_process,
    compiling_elsewhere,
)

MAX_INTERPRETED_BODIES = 64  # a larger batch waits for the compiled kernel (the interpreted one is ~100x slower)
SWITCH = "BOX_TOSS_ENV_START_INTERPRETED"  # "0" turns the interpreted start off
CHECK_INTERVAL = 0.1  # [s] how often an interpreted run looks in numba's cache for the compiled kernel
LOG_NAME = "box_toss_env-compile.log"  # the workers' log, appended, in the kernel's cache directory
PACKAGE = Path(__file__).resolve().parents[2]  # the box_toss_env package this process runs
LOG = logging.getLogger("box_toss_env.compile")
WORKER = "import sys; from box_toss_env.physics.compile.background_compile import main; sys.exit(main())"


def interpreted_start_enabled() -> bool:
    """Whether envs may start interpreted: not with ``BOX_TOSS_ENV_START_INTERPRETED=0``, nor when
    numba's JIT is disabled (everything is interpreted anyway)."""
    return os.environ.get(SWITCH, "1") != "0" and not config.DISABLE_JIT  # type: ignore[attr-defined]  # numba sets its config at import


_copies: dict[int, Callable] = {}


def interpreted_copy(function: Callable) -> Callable:
    """The plain-Python form of a compiled engine function: its source, run by the interpreter, with
    every compiled function it reaches (through its globals or its closure) replaced by that
    function's interpreted copy. Stages compiled without Python wrappers cannot be called from
    Python; their copies can."""
    source = function.py_func if isinstance(function, Dispatcher) else function
    known = _copies.get(id(source))
    if known is not None:
        return known
    scope = dict(source.__globals__)
    cells = None
    if source.__closure__:
        cells = tuple(types.CellType(_interpreted(cell.cell_contents)) for cell in source.__closure__)
    copy = types.FunctionType(source.__code__, scope, source.__name__, source.__defaults__, cells)
    copy.__kwdefaults__ = source.__kwdefaults__
    _copies[id(source)] = copy  # before the globals: a function may reach itself
    for name in source.__code__.co_names:
        if isinstance(scope.get(name), Dispatcher):
            scope[name] = interpreted_copy(scope[name])
    return copy


def _interpreted(value):
    return interpreted_copy(value) if isinstance(value, Dispatcher) else value


def describe(recipe: tuple[str, str, dict]) -> str:
    """``recipe`` as the call that builds its kernel, e.g. ``make_kernel_of(solver='robust', ...)``."""
    module, factory, kwargs = recipe
    return f"{factory}({', '.join(f'{name}={value!r}' for name, value in kwargs.items())})"


class Worker:
    """A process of its own session compiling one kernel (named by ``recipe``: the module, the factory
    and its keyword arguments that rebuild it) for one set of argument types into numba's on-disk cache."""

    def __init__(self, recipe: tuple[str, str, dict], signature: tuple, log_path: str):
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(PACKAGE.parent), env.get("PYTHONPATH")) if p)
        try:
            errors = open(log_path, "ab")  # what the worker prints if it fails goes to its log  # noqa: SIM115
        except OSError:
            errors = None
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-c", WORKER],
                stdin=subprocess.PIPE,
                stdout=subprocess.DEVNULL,
                stderr=errors or subprocess.DEVNULL,
                env=env,
                start_new_session=True,
            )
        finally:
            if errors is not None:
                errors.close()
        assert self.process.stdin is not None  # opened with stdin=subprocess.PIPE
        try:
            self.process.stdin.write(pickle.dumps({"package": str(PACKAGE), "recipe": recipe, "signature": signature}))
            self.process.stdin.close()
        except OSError:  # the worker died at once: ``done`` says so and this process compiles
            pass

    @property
    def pid(self) -> int:
        return self.process.pid

    def done(self) -> bool:
        return self.process.poll() is not None

    def succeeded(self) -> bool:
        return self.done() and self.process.returncode == 0

    def wait(self) -> None:
        self.process.wait()


_workers: list[Worker] = []  # every worker this process started


class BackgroundCompile:
    """``kernel`` compiled for ``args``'s types by a worker process, watched from this process: by this
    process's own worker, or by whichever process holds the kernel's compile lock (then no worker is
    started here unless the lock comes free with the kernel still missing)."""

    def __init__(self, kernel, recipe: tuple[str, str, dict], args: tuple):
        self.kernel = kernel
        self.recipe = recipe
        self.signature = argument_types(kernel, args)
        self.worker: Worker | None = None
        self.found = False  # the compiled kernel seen in the cache (it stays there)
        self.started = time.monotonic()
        self._next_check = self.started + CHECK_INTERVAL
        if not compiling_elsewhere(kernel, self.signature):
            self._start_worker()
        where = f"worker pid {self.worker.pid}" if self.worker else "another process holds its compile lock"
        LOG.warning(
            "box_toss_env: the engine kernel %s is not in numba's cache yet: it compiles in the background "
            "(%s; progress in %s), seconds to a minute of CPU once, and meanwhile runs of up to a few dozen "
            "bodies use its interpreted copy (the same results, about 100x slower)",
            describe(recipe),
            where,
            self.log_path(),
        )

    def log_path(self) -> str:
        return os.path.join(cache_location(self.kernel) or "", LOG_NAME)

    def _start_worker(self) -> None:
        self.worker = Worker(self.recipe, self.signature, self.log_path())
        _workers.append(self.worker)

    def failed(self) -> bool:
        """Whether this process's own worker ended without success (a new one may be started)."""
        return self.worker is not None and self.worker.done() and not self.worker.succeeded()

    def ready(self) -> bool:
        """Whether the interpreted runs may stop: this process's worker is done (if it failed, the caller
        compiles here), or the compiled kernel is in the cache (looked for at most every ``CHECK_INTERVAL``; once
        seen there, ready for every caller: the single and the batched env, or a batch's scene sizes, share one)."""
        if self.found or (self.worker is not None and self.worker.done()):
            return True
        now = time.monotonic()
        if now < self._next_check:
            return False
        self._next_check = now + CHECK_INTERVAL
        if cached_for(self.kernel, self.signature):
            self.found = True
            return True
        if self.worker is None and not compiling_elsewhere(self.kernel, self.signature):
            self._start_worker()  # the process that held the lock stopped without the kernel
        return False


_watched: dict[tuple, BackgroundCompile] = {}


def start(kernel, recipe: tuple[str, str, dict], args: tuple) -> BackgroundCompile | None:
    """The background compile of ``kernel`` (rebuilt in a worker from ``recipe``) for ``args``'s types:
    started now, or the one this process watches already (the single and the batched env share a kernel);
    None where a worker's result could not be used here (no on-disk cache) or there is nothing to compile
    (already loaded or cached)."""
    for worker in _workers:
        worker.done()  # reaps a finished worker (no zombie left while this process runs)
    if cache_location(kernel) is None or compiled_in_process(kernel, args) or cached_on_disk(kernel, args):
        return None
    key = (kernel.py_func.__module__, kernel.py_func.__qualname__, argument_types(kernel, args))  # not the recipe
    compilation = _watched.get(key)
    if compilation is None or compilation.failed():
        compilation = _watched[key] = BackgroundCompile(kernel, recipe, args)
    return compilation


def wait_for_workers() -> None:
    """Wait until every worker this process started is done (benchmarks call it before timing; the
    next run of each simulator then loads its compiled kernel)."""
    for worker in list(_workers):
        worker.wait()


def kernel_recipe(flags) -> tuple[str, str, dict]:
    """How a worker rebuilds the kernel of ``flags`` (a ``KernelFlags``)."""
    return ("box_toss_env.physics.kernels", "make_kernel_of", asdict(flags))


class InterpretedStart:
    """Runs of ``kernel`` (a compiled kernel whose first argument is the (n, ...) body array) that use
    its interpreted copy while a worker compiles it, then the compiled kernel. ``recipe`` says how the
    worker rebuilds the kernel (``Worker``); a run of more than ``max_bodies`` bodies waits for
    the compiled kernel."""

    def __init__(self, kernel, recipe: tuple[str, str, dict], max_bodies: int = MAX_INTERPRETED_BODIES):
        self.kernel = kernel
        self.recipe = recipe
        self.max_bodies = max_bodies
        self.compilation: BackgroundCompile | None = None
        self.compiled = False  # once True, every run is compiled
        self.interpreted_runs = 0

    def run(self, args: tuple, outputs: tuple) -> bool:
        """Run the interpreted copy on ``args`` if the compiled kernel is not ready and ``args`` is a small
        batch, starting the background compile at the first such run; returns whether it ran. ``outputs`` are
        the arrays the kernel writes: if the copy raises (on a state the compiled kernel would carry on with,
        such as NaN, or on code only numba runs), they are put back and False is returned, as when the
        copy does not run: the caller then runs the compiled kernel, which compiles or loads it here."""
        if self.compiled or args[0].shape[0] > self.max_bodies or not interpreted_start_enabled():
            self.compiled = True
            return False
        if self.compilation is None:
            self.compilation = start(self.kernel, self.recipe, args)
        if self.compilation is None or self.compilation.ready():
            if self.compilation is not None:
                LOG.info(
                    "box_toss_env: %s runs compiled from now on, %.1f s and %d interpreted runs after it was "
                    "first needed",
                    describe(self.recipe),
                    time.monotonic() - self.compilation.started,
                    self.interpreted_runs,
                )
            self.compiled = True
            return False
        saved = [array.copy() for array in outputs]
        try:
            with np.errstate(over="ignore"):  # integer kernels wrap around as compiled code does
                interpreted_copy(self.kernel)(*args)
            self.interpreted_runs += 1
            return True
        except Exception:  # noqa: BLE001  (whatever the interpreter refuses, the compiled kernel decides)
            for array, copy in zip(outputs, saved, strict=True):
                array[...] = copy
            self.compiled = True
            return False


def append_log(directory: str | None, line: str) -> None:
    """Append a time-stamped ``line`` to the workers' log in ``directory`` (nothing if it cannot be written)."""
    if directory is None:
        return
    stamp = datetime.datetime.now().isoformat(timespec="seconds")
    try:
        with open(os.path.join(directory, LOG_NAME), "a", encoding="utf-8") as log:
            log.write(f"{stamp} pid {os.getpid()}: {line}\n")
    except OSError:
        pass


def main() -> int:
    """The worker: read the package, the recipe and the argument types from stdin, rebuild the kernel in
    that package, compile it into the cache (or find it there) under its compile lock, and log both ends."""
    import importlib

    request = pickle.loads(sys.stdin.buffer.read())
    if Path(request["package"]) != PACKAGE:  # another copy of the package first on the path: its kernel is not wanted
        return 2
    module, factory, kwargs = request["recipe"]
    kernel = getattr(importlib.import_module(module), factory)(**kwargs)
    directory, name = cache_location(kernel), describe(request["recipe"])
    append_log(directory, f"compiling {name} for {request['signature']}")
    wall, cpu = time.perf_counter(), time.process_time()
    compiled = compile_locked(kernel, request["signature"])
    verb = "compiled" if compiled else "found in the cache (another process compiled it)"
    seconds, cpu = time.perf_counter() - wall, time.process_time() - cpu
    append_log(directory, f"{verb} {name} in {seconds:.1f} s ({cpu:.1f} s of CPU)")
    return 0
