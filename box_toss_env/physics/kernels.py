"""Kernel factory: one compiled kernel per combination of the stages a scene uses.

The flags (solver, impulses, penalty, friction, recording, boxes colliding) are compile-time: a branch on a flag
that is off is compiled away, so a scene pays nothing for what it lacks. ``parallel`` is not: it says whether
``Simulator`` runs on threads (the bodies split over them, or a colliding scene's large stages on numba's), and one
body or a batch of them runs the same compiled kernel. Floats never enter the flags (each new value would
recompile); they travel in arrays. Kernels are cached in memory per compile-time flags and on disk by numba
(``compilation``); the on-disk key includes a digest of the engine's sources, so editing any
stage recompiles its callers.

``boxes_collide`` picks a different kernel, not a branch in one: with it False (every scene that does
not ask for box-box contact) ``make_kernel`` returns the very kernel it returned before box-box contact
existed, and nothing of ``colliding`` or ``colliding_reference`` is compiled; with it True the bodies of the scene
are stepped together (``colliding.kernel``, ``colliding_reference``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from .colliding.kernel import make_colliding_robust_kernel
from .colliding.parallel import launch_threads
from .compile.compilation import engine_source_digest
from .reference.colliding_reference import make_colliding_reference_kernel
from .reference.reference_solver import make_reference_kernel
from .robust.robust_solver import make_robust_kernel


@dataclass(frozen=True)
class KernelFlags:
    """What a kernel is built for (every field but ``parallel``), and whether ``Simulator`` runs it on
    threads (``parallel``, a run option: it does not change the compiled kernel nor its results; a kernel whose
    boxes collide runs its bodies together, its large stages on numba's threads, ``colliding.parallel``)."""

    solver: str = "robust"  # "robust" or "seed"
    use_impulses: bool = True
    use_penalty: bool = True
    use_friction: bool = True
    record: bool = False
    parallel: bool = False
    boxes_collide: bool = False  # the bodies of a call are one scene whose boxes collide (stepped together)


def source_digest() -> int:
    """A 56-bit digest of every engine source file (``compilation.engine_source_digest``)."""
    return engine_source_digest()


def make_kernel(flags: KernelFlags):
    """The numba kernel ``run(state, params, settings, stats, trajectory, events)`` for ``flags``
    (the same kernel whatever ``flags.parallel``)."""
    if flags.boxes_collide:
        return _make_colliding_kernel(
            flags.solver, flags.use_impulses, flags.use_penalty, flags.use_friction, flags.record
        )
    return _make_kernel(flags.solver, flags.use_impulses, flags.use_penalty, flags.use_friction, flags.record)


def make_kernel_of(**fields):
    """``make_kernel`` of ``KernelFlags(**fields)`` (how a background compile rebuilds a kernel)."""
    return make_kernel(KernelFlags(**fields))


@functools.cache
def _make_kernel(solver: str, use_impulses: bool, use_penalty: bool, use_friction: bool, record: bool):
    if solver == "seed":
        return make_reference_kernel(use_impulses, use_penalty, use_friction, record, source_digest())
    if solver == "robust":
        if not use_impulses:
            raise ValueError("use_impulses must be True with solver='robust'")
        return make_robust_kernel(use_penalty, use_friction, record, source_digest())
    raise ValueError(f"solver must be 'robust' or 'seed', got {solver!r}")


@functools.cache
def _make_colliding_kernel(solver: str, use_impulses: bool, use_penalty: bool, use_friction: bool, record: bool):
    launch_threads()  # the kernel's parallel stages call into numba's threading layer
    if solver == "seed":
        return make_colliding_reference_kernel(use_impulses, use_penalty, use_friction, record, source_digest())
    if solver == "robust":
        if not use_impulses:
            raise ValueError("use_impulses must be True with solver='robust'")
        return make_colliding_robust_kernel(use_penalty, use_friction, record, source_digest())
    raise ValueError(f"solver must be 'robust' or 'seed', got {solver!r}")
