"""Throwing at once on a cold cache: the kernel compiles in another process while this one runs
the kernel's interpreted copy, which gives the same results bit for bit.

A cold compile of the robust kernel takes several seconds (measured by ``benchmarks.cold_start``),
while one throw of its plain-Python source takes a few milliseconds. So an env's first throws need
not wait: ``Simulator(..., start_interpreted=True)`` (what the envs use) asks a worker process
(``python -m box_toss_env.physics.compile.background_compile``) to compile the kernel into numba's on-disk
cache, runs ``interpreted_copy(kernel)`` meanwhile, and switches to the compiled kernel (loaded from
the cache) at the first run after the worker is done. The worker takes the engine's compile lock
(``compilation.compile_locked``), so processes starting together (``SubprocVecEnv``) compile once.

The interpreted copy is the kernel's own Python source with every compiled stage it calls replaced
by that stage's Python source: the same IEEE double operations in the same order, so the results
are identical, which ``tests/physics/test_background_compile.py`` checks throw by throw. Nothing is
interpreted where it would cost more than waiting: batches larger than ``MAX_INTERPRETED_BODIES``
bodies, scenes run through ``simulate`` (the default ``start_interpreted=False``), and a machine
without a writable cache directory (the worker's result could not reach this process) compile here.
Setting ``BOX_TOSS_ENV_START_INTERPRETED=0`` turns the interpreted start off everywhere. The worker
outlives a process that exits before it is done, so the compiled kernel is in the cache for the next.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import types
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

import numpy as np
from numba.core import config
from numba.core.dispatcher import Dispatcher

from .compilation import argument_types, cache_location, cached_on_disk, compile_locked, compiled_in_process

MAX_INTERPRETED_BODIES = 64  # a larger batch waits for the compiled kernel (the interpreted one is ~100x slower)
SWITCH = "BOX_TOSS_ENV_START_INTERPRETED"  # "0" turns the interpreted start off


def interpreted_start_enabled() -> bool:
    """Whether envs may start interpreted: not with ``BOX_TOSS_ENV_START_INTERPRETED=0``, nor when
    numba's JIT is disabled (everything is interpreted anyway)."""
    return os.environ.get(SWITCH, "1") != "0" and not config.DISABLE_JIT


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


class Compilation:
    """A worker process compiling one kernel (named by ``recipe``: the module, the factory and its
    keyword arguments that rebuild it) for one set of argument types into numba's on-disk cache."""

    def __init__(self, recipe: tuple[str, str, dict], signature: tuple):
        package_root = str(Path(__file__).resolve().parents[2])  # the directory holding box_toss_env
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (package_root, env.get("PYTHONPATH")) if p)
        self.process = subprocess.Popen(
            [sys.executable, "-m", "box_toss_env.physics.compile.background_compile"],
            stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            env=env,
            start_new_session=True,
        )
        try:
            self.process.stdin.write(pickle.dumps((recipe, signature)))
            self.process.stdin.close()
        except OSError:  # the worker died at once: ``succeeded`` says so and this process compiles
            pass

    def done(self) -> bool:
        return self.process.poll() is not None

    def succeeded(self) -> bool:
        return self.done() and self.process.returncode == 0

    def wait(self) -> None:
        self.process.wait()


_running: dict[tuple, Compilation] = {}


def start(kernel, recipe: tuple[str, str, dict], args: tuple) -> Compilation | None:
    """The worker compiling ``kernel`` (rebuilt in the worker from ``recipe``) for ``args``'s types:
    started now, or the one already running in this process; None where the worker's result could not
    be used here (no on-disk cache) or there is nothing to compile (already loaded or cached)."""
    if cache_location(kernel) is None or compiled_in_process(kernel, args) or cached_on_disk(kernel, args):
        return None
    signature = argument_types(kernel, args)
    key = (recipe[0], recipe[1], tuple(sorted(recipe[2].items())), signature)
    compilation = _running.get(key)
    if compilation is None or (compilation.done() and not compilation.succeeded()):
        compilation = _running[key] = Compilation(recipe, signature)
    return compilation


def wait_for_workers() -> None:
    """Wait until every worker this process started is done (benchmarks call it before timing; the
    next run of each simulator then loads its compiled kernel)."""
    for compilation in list(_running.values()):
        compilation.wait()


def kernel_recipe(flags) -> tuple[str, str, dict]:
    """How a worker rebuilds the kernel of ``flags`` (a ``KernelFlags``)."""
    return ("box_toss_env.physics.kernels", "make_kernel_of", asdict(flags))


class InterpretedStart:
    """Runs of ``kernel`` (a compiled kernel whose first argument is the (n, ...) body array) that use
    its interpreted copy while a worker compiles it, then the compiled kernel. ``recipe`` says how the
    worker rebuilds the kernel (``Compilation``); a run of more than ``max_bodies`` bodies waits for
    the compiled kernel."""

    def __init__(self, kernel, recipe: tuple[str, str, dict], max_bodies: int = MAX_INTERPRETED_BODIES):
        self.kernel = kernel
        self.recipe = recipe
        self.max_bodies = max_bodies
        self.compilation: Compilation | None = None
        self.compiled = False  # once True, every run is compiled

    def run(self, args: tuple, outputs: tuple) -> bool:
        """Run the interpreted copy on ``args`` if the compiled kernel is not ready and ``args`` is a small
        batch, starting the worker at the first such run; returns whether it ran. ``outputs`` are the
        arrays the kernel writes: if the copy raises (on a state the compiled kernel would carry on with,
        such as NaN, or on code only numba runs), they are put back and False is returned, as when the
        copy does not run: the caller then runs the compiled kernel, which compiles or loads it here."""
        if self.compiled or args[0].shape[0] > self.max_bodies or not interpreted_start_enabled():
            self.compiled = True
            return False
        if self.compilation is None:
            self.compilation = start(self.kernel, self.recipe, args)
        if self.compilation is None or self.compilation.done():
            self.compiled = True
            return False
        saved = [array.copy() for array in outputs]
        try:
            with np.errstate(over="ignore"):  # integer kernels wrap around as compiled code does
                interpreted_copy(self.kernel)(*args)
            return True
        except Exception:  # noqa: BLE001  (whatever the interpreter refuses, the compiled kernel decides)
            for array, copy in zip(outputs, saved, strict=True):
                array[...] = copy
            self.compiled = True
            return False


def main() -> int:
    """The worker: read (recipe, argument types) from stdin, rebuild the kernel, compile it into the
    cache (or find it there) under the engine's compile lock."""
    import importlib

    recipe, signature = pickle.loads(sys.stdin.buffer.read())
    module, factory, kwargs = recipe
    kernel = getattr(importlib.import_module(module), factory)(**kwargs)
    compile_locked(kernel, signature)
    return 0


if __name__ == "__main__":
    sys.exit(main())
