"""How the engine is compiled: the two numba decorators every compiled function uses, where the
compiled code is cached on disk and loaded from there, and one compilation of a kernel across processes.

Compile cost is per compiled function, so the decorators keep the number of compilations down:

- ``jit_stage``: a function called only from compiled code (a stage of a solver). It is compiled
  for the plain types of its arguments (a constant argument such as ``True`` or a corner index
  ``0`` does not compile its own copy), without the wrappers that make a function callable from
  Python (building them was about a quarter of a cold compile), and cached on disk.
- ``jit_kernel``: an entry point called from Python (a solver's kernel). It releases the GIL, so
  ``Simulator`` runs one compiled kernel over a batch on several threads: the single env, the
  batched env and subprocess workers all load the same compiled code.

Where compiled code is cached (numba's own search order, ``numba.core.caching``): the directory
in ``NUMBA_CACHE_DIR`` if set; otherwise ``__pycache__`` next to the engine's sources if writable;
otherwise numba's user-wide cache directory (``~/.cache/numba`` on Linux). If none is writable,
the engine compiles in memory in every process and warns once (``CacheWarning``) instead of
failing to import, which is what numba alone does. ``kernel_support.engine_cache_location()`` says which applies.
A cached function is found again only under the digest of every engine source (``EngineCache``): numba
alone checks a function's own file, and served stages of unedited files with their edited callees' old code.

A cached kernel loads without numba refreshing its compiler's context first (``EngineCache.load_overload``):
loading needs none of it, and it was most of a warm process's first throw.

``ensure_compiled`` makes a kernel's first compilation for a set of argument types hold that kernel's lock
file in the cache directory (``compile_lock``): processes started together (``SubprocVecEnv``,
``AsyncVectorEnv``) wait for the first one's compilation and then load its result from the cache, instead of
each compiling (and racing to write the same cache files, numba issue #4807); different kernels compile at once.
"""

from __future__ import annotations

import functools
import hashlib
import logging
import os
import warnings
from collections.abc import Callable
from pathlib import Path

import filelock
from numba.core import config, types
from numba.core.caching import FunctionCache, IndexDataCacheFile
from numba.core.dispatcher import Dispatcher
from numba.core.registry import CPUDispatcher
from numba.core.runtime import rtsys

LOCK_PREFIX = "box_toss_env-compile-"  # + a digest of the kernel and its signature + ".lock"
LOCK_TIMEOUT = 600.0  # [s] a compilation elsewhere holding the lock longer than this is not waited for


LOG = logging.getLogger("box_toss_env.compile")


class CacheWarning(UserWarning):
    """The engine's compiled code cannot be cached on disk: it is compiled in every process."""


@functools.lru_cache(maxsize=1)
def engine_source_digest() -> int:
    """A 56-bit digest of every engine source file (the ``physics`` package)."""
    sha = hashlib.sha256()
    for path in sorted(Path(__file__).parent.parent.rglob("*.py")):
        sha.update(path.read_bytes())
    return int.from_bytes(sha.digest()[:7], "little")


class EngineCacheFile(IndexDataCacheFile):
    """numba's index and data files of one cached function, read as a miss where they cannot be unpickled. numba
    unpickles a function's whole index to look up one entry, so an index written while a signature named a class
    that a later version of the engine deleted (or one cut short by a full disk) made every call of that function
    raise (``ModuleNotFoundError``, ``AttributeError``, ``EOFError``) instead of compiling it again; here such a
    file reads as empty, the function compiles, and the index is written anew."""

    def _load_index(self):
        try:
            return super()._load_index()
        except Exception as error:  # noqa: BLE001  (whatever unpickling an outdated or damaged file raises)
            LOG.warning("numba's cache index %s is unreadable (%r): compiling anew", self._index_path, error)
            return {}

    def _load_data(self, name):
        try:
            return super()._load_data(name)
        except OSError:
            raise
        except Exception as error:  # noqa: BLE001  (numba's ``load`` takes an OSError for a missing entry)
            raise OSError(f"numba's cache file {name} is unreadable: {error!r}") from error


class EngineCache(FunctionCache):
    """numba's on-disk cache of one engine function, its entries keyed also by ``engine_source_digest``. numba
    keys an entry by the function's own bytecode and checks its own file's time stamp, so a stage in a file
    left as it was, calling or inlining a stage of an edited file, was loaded with the old callee compiled in
    (an edit of ``alone`` ran the old ``steps_alone`` inside ``step.advance_steps``); with the digest any edit
    of the engine compiles every stage again, as a fresh install does."""

    def __init__(self, py_func):
        super().__init__(py_func)
        self._cache_file = EngineCacheFile(
            cache_path=self._cache_path,
            filename_base=self._impl.filename_base,
            source_stamp=self._impl.locator.get_source_stamp(),
        )

    def _index_key(self, sig, codegen):
        return super()._index_key(sig, codegen), engine_source_digest()

    def load_overload(self, sig, target_context):
        """numba's load without its ``target_context.refresh()`` first: the refresh installs every typing and
        lowering registry (and imports ``scipy.linalg`` where SciPy is installed), 0.28-0.31 s of CPU, three
        quarters of a warm process's first throw, while rebuilding a cached function needs none of it (the
        kernel loads in 0.01-0.07 s). What a loaded function needs at run time is numba's runtime (NRT: the arrays
        a kernel allocates), initialized here as the refresh would. A miss compiles, and numba's compiler
        refreshes the context itself."""
        try:
            rtsys.initialize(target_context)
            guard = self._guard_against_spurious_io_errors()
        except AttributeError:  # numba's internals changed: its own load, refresh included
            return super().load_overload(sig, target_context)
        with guard:
            return self._load_overload(sig, target_context)


class EngineDispatcher(CPUDispatcher):
    """numba's CPU dispatcher, compiling for the plain (non-literal) types of its arguments, and
    running without a disk cache (with a ``CacheWarning``) where numba would refuse to import."""

    def get_call_template(self, args, kws):
        # a call from compiled code with a constant argument would compile a copy for that constant
        # (Literal[int](0), Literal[bool](True), ...): compile once for the plain types instead
        return super().get_call_template(
            [types.unliteral(a) for a in args], {name: types.unliteral(a) for name, a in kws.items()}
        )

    def enable_caching(self):
        try:
            self._cache = EngineCache(self.py_func)
        except RuntimeError as error:  # numba: "cannot cache function ...: no locator available"
            warn_uncached(str(error))


_warned_uncached = False


def warn_uncached(reason: str) -> None:
    global _warned_uncached
    if not _warned_uncached:
        _warned_uncached = True
        warnings.warn(
            f"box_toss_env: no writable directory for numba's cache ({reason}). The engine is compiled "
            "again in every process (seconds each time). Set NUMBA_CACHE_DIR to a writable directory to "
            "keep the compiled code.",
            CacheWarning,
            stacklevel=2,
        )


def name_variant(function: Callable) -> Callable:
    """Give a function built by a factory (one per set of flags, the flags in its closure) a
    qualified name of its own per set, ``<name>_v<digest of the closure's values>``, the same in every
    process. numba names a compiled function's symbol after its qualified name and a counter of the
    compiling process; two variants compiled in different processes can get the same symbol, and a
    process that loads both from the cache links a caller of one (the grouped kernel calling a
    colliding kernel) to the other's body (numba issue #10486). Closures of anything but bools,
    ints, floats and strings (whose repr could differ between processes) keep their name."""
    cells = function.__closure__ or ()
    values = tuple(cell.cell_contents for cell in cells)
    if values and all(type(value) in (bool, int, float, str) for value in values):
        digest = hashlib.sha256(repr(values).encode()).hexdigest()[:12]
        function.__qualname__ = f"{function.__qualname__}_v{digest}"
    return function


def _make_dispatcher(function: Callable, **options) -> Callable:
    if config.DISABLE_JIT:  # type: ignore[attr-defined]  # NUMBA_DISABLE_JIT=1: plain Python, as numba.njit gives
        return function
    name_variant(function)
    dispatcher = EngineDispatcher(py_func=function, locals={}, targetoptions={"nopython": True, **options})
    dispatcher.enable_caching()
    return dispatcher


def jit_stage(function: Callable | None = None, *, inline: str = "never", nrt: bool = False, parallel: bool = False):
    """Decorator for a function called only from compiled code: one compilation per set of plain
    argument types, no Python wrappers, cached on disk. ``inline="always"`` inlines it into its
    callers at numba's level (its callers then type it again at each call site).

    A stage is compiled without numba's reference counting (``_nrt=False``): it allocates no array,
    so the counts it would keep are of arrays its caller owns for the whole call. With the counting
    on, every call of a stage that takes arrays increments and decrements each array's count (and
    inlined stages did the same at every call site), several times the arithmetic of the solver's
    sweeps: without it an awake pile of 100 boxes and the 210-box pyramid stepped 2.6-2.8 times
    faster, bit for bit the same (docs/changelog.md). A stage that allocated would
    fail to compile, not run unsafely; one that must allocate (numba's sort keeps a stack array)
    says ``nrt=True``. With ``parallel=True`` its ``prange`` loops run on numba's threads (``colliding.parallel``)."""

    def decorate(function):
        options = {"parallel": True} if parallel else {}
        return _make_dispatcher(
            function, no_cpython_wrapper=True, no_cfunc_wrapper=True, inline=inline, _nrt=nrt, **options
        )

    return decorate if function is None else decorate(function)


def jit_kernel(function: Callable) -> Callable:
    """Decorator for a kernel called from Python: it releases the GIL (so threads can run it
    together) and is cached on disk."""
    return _make_dispatcher(function, nogil=True, no_cfunc_wrapper=True)


def cache_location(function: Callable) -> str | None:
    """The directory numba caches ``function`` (a function compiled with these decorators) in, or
    None if nothing is cached (no writable directory); the engine's: ``kernel_support.engine_cache_location``."""
    return getattr(getattr(function, "_cache", None), "cache_path", None)


def argument_types(kernel, args: tuple) -> tuple:
    """The numba types ``kernel`` would be compiled for when called with ``args``."""
    return tuple(kernel.typeof_pyval(a) for a in args)


def compiled_in_process(kernel, args: tuple) -> bool:
    """Whether ``kernel`` (a numba dispatcher) is compiled or loaded for ``args``'s types in this
    process already; False for anything else."""
    try:
        return argument_types(kernel, args) in kernel.overloads
    except Exception:  # noqa: BLE001  (not a numba dispatcher)
        return False


def cached_on_disk(kernel, args: tuple) -> bool:
    """Whether numba's on-disk cache holds ``kernel`` compiled for ``args``'s types. Best effort,
    through numba's cache index (the key its loader looks up); False if it cannot tell."""
    try:
        return cached_for(kernel, argument_types(kernel, args))
    except Exception:  # noqa: BLE001  (not a numba dispatcher)
        return False


def cached_for(kernel, signature: tuple) -> bool:
    """Whether numba's on-disk cache holds ``kernel`` compiled for the numba types ``signature`` (its index,
    read as numba's loader reads it); False if it cannot tell."""
    try:
        cache = kernel._cache
        key = cache._index_key(signature, kernel.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001  (no disk cache, or numba's internals changed)
        return False


def ensure_compiled(kernel, args: tuple) -> None:
    """Compile ``kernel`` for ``args``'s types, or load it from the disk cache, before its first
    call (``compile_locked``)."""
    if not isinstance(kernel, Dispatcher) or compiled_in_process(kernel, args):
        return
    compile_locked(kernel, argument_types(kernel, args))


def compile_lock(kernel, signature: tuple) -> filelock.FileLock | None:
    """The lock file a compilation of ``kernel`` for the numba types ``signature`` holds, in its cache
    directory (one lock a kernel and signature: different kernels compile at once, one kernel once); None
    where nothing is cached."""
    directory = cache_location(kernel)
    if directory is None:
        return None
    name = f"{kernel.py_func.__module__}.{kernel.py_func.__qualname__}{signature!r}"
    digest = hashlib.sha256(name.encode()).hexdigest()[:16]
    return filelock.FileLock(os.path.join(directory, f"{LOCK_PREFIX}{digest}.lock"), timeout=LOCK_TIMEOUT)


def compiling_elsewhere(kernel, signature: tuple) -> bool:
    """Whether another process (or thread) holds ``kernel``'s compile lock for ``signature`` now."""
    lock = compile_lock(kernel, signature)
    if lock is None:
        return False
    try:
        lock.acquire(timeout=0)
    except filelock.Timeout:
        return True
    except OSError:  # the directory went away: nobody can be compiling into it
        return False
    lock.release()
    return False


def compile_locked(kernel, signature: tuple) -> bool:
    """Compile ``kernel`` for the numba types ``signature``, or load it from the disk cache; returns
    whether it was compiled here. A compilation holds the kernel's lock file (``compile_lock``), so
    that of several processes needing the same kernel at once one compiles and the others load its
    result (numba's cache files are written whole, but two processes compiling one function race to
    write its index, numba issue #4807)."""
    misses = sum(kernel.stats.cache_misses.values())
    lock = None if cached_for(kernel, signature) else compile_lock(kernel, signature)
    if lock is not None:
        if compiling_elsewhere(kernel, signature):
            LOG.info(
                "waiting for another process compiling %s into %s", kernel.py_func.__qualname__, cache_location(kernel)
            )
        else:
            LOG.info(
                "compiling %s in this process (not in numba's cache %s yet)",
                kernel.py_func.__qualname__,
                cache_location(kernel),
            )
        try:
            with lock:
                kernel.compile(signature)  # numba looks in the cache first: another process may have compiled it
            return sum(kernel.stats.cache_misses.values()) > misses
        except (filelock.Timeout, OSError):  # held too long elsewhere, or the directory went away: compile anyway
            pass
    kernel.compile(signature)
    return sum(kernel.stats.cache_misses.values()) > misses
