"""The BoxToss rigid-body engine: boxes against the floor plane y = 0.

Two solvers share one scene description:

- ``solver="seed"``: the scheme of the reference text (its method restated in docs/engine.md), exactly
  (``reference_solver``);
- ``solver="robust"`` (default): the same ingredients arranged to stay right at any step,
  stiffness, speed, spin, mass and aspect ratio (``robust_solver``).

``simulate(scene, ...)`` runs a scene; ``Simulator`` runs compiled kernels on raw arrays.

``Scene(boxes_collide=True)`` makes the boxes of a scene collide with one another too (``narrowphase``,
``colliding``, ``colliding_reference``; docs/box_collisions.md); by default they meet only the floor
and none of that is compiled.
"""

from . import layout, scenes
from .geometry import face_down
from .kernels import KernelFlags, make_kernel
from .scene import SOLVERS, Box, Scene
from .simulate import (
    NonFiniteStateError,
    SimulationResult,
    Simulator,
    Trajectory,
    check_finite_stats,
    make_settings,
    simulate,
    warm_start_memory,
)

__all__ = [
    "SOLVERS",
    "Box",
    "KernelFlags",
    "NonFiniteStateError",
    "Scene",
    "SimulationResult",
    "Simulator",
    "Trajectory",
    "check_finite_stats",
    "face_down",
    "layout",
    "make_kernel",
    "make_settings",
    "scenes",
    "simulate",
    "warm_start_memory",
]
