"""What a simulation contains: boxes, the floor plane y = 0, gravity, the contact material
and the time step. Everything is validated when it is built, so kernels never see bad input:
a wrong type is a TypeError, a value outside its range (``ranges``, docs/ranges.md) a ValueError.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from . import layout
from .colliding.narrowphase import overlapping_boxes
from .ranges import ENGINE_RANGES
from .validation import check_bool, check_choice, check_finite, check_integer, check_vector

SOLVERS = ("robust", "seed")


@dataclass(frozen=True)
class Box:
    """A rigid rectangle. ``length`` runs along the body's local x axis, ``width`` along local y.

    Inertia about the centre of mass is ``m (L^2 + W^2) / 12``. ``restitution`` and ``friction``
    override the scene's material for this box when given (domain randomisation, batches).
    """

    length: float = 2.0  # [m]
    width: float = 1.0  # [m]
    mass: float = 1.0  # [kg]
    position: tuple[float, float] = (0.0, 0.0)  # centre of mass [m]
    angle: float = 0.0  # [rad], counter-clockwise
    velocity: tuple[float, float] = (0.0, 0.0)  # [m/s]
    spin: float = 0.0  # [rad/s], counter-clockwise
    restitution: float | None = None  # [-] in [0, 1]
    friction: float | None = None  # [-] >= 0

    def __post_init__(self):
        set_ = object.__setattr__
        for name in ("length", "width", "mass"):
            set_(self, name, ENGINE_RANGES[name].check(name, getattr(self, name)))
        set_(self, "position", check_vector("position", self.position, 2))
        set_(self, "angle", check_finite("angle", self.angle))
        set_(self, "velocity", check_vector("velocity", self.velocity, 2))
        set_(self, "spin", check_finite("spin", self.spin))
        for name in ("restitution", "friction"):
            if getattr(self, name) is not None:
                set_(self, name, ENGINE_RANGES[name].check(name, getattr(self, name)))

    @property
    def inertia(self) -> float:
        """Moment of inertia about the centre of mass [kg m^2]: m (L^2 + W^2) / 12."""
        return self.mass * (self.length**2 + self.width**2) / 12.0


@dataclass(frozen=True)
class Scene:
    """Boxes above the floor y = 0, with the contact material and the solver settings.

    Defaults are the seed demo's panel (dt 0.005 s, g -9.81 m/s^2, penalty stiffness 100 N/m,
    restitution 0.5, friction 0.02, impulses and penalty force on); ``solver`` picks the
    robust default or the seed's explicit scheme (see ``box_toss_env.physics`` docs).
    The next four settings belong to the robust solver: impacts slower than
    ``restitution_threshold`` are inelastic, a box lying on a face slower than ``sleep_speed``
    for ``sleep_time`` is put to sleep, and ``penetration_slop`` is left uncorrected (the penalty starts once a
    corner is twice that deep, island by island, then removes what lies beyond it). The last two
    belong to its colliding scenes' contacts that it does not solve exactly (``colliding.solve``: a pile of
    like boxes): their projected Gauss-Seidel sweeps stop once a sweep changes the
    impulses by less than ``solver_tolerance`` of their sum (and none by more than 100 times that share of
    their mean), after ``solver_iterations`` sweeps at most
    (the penalty's after at most 16); the exact solves take 8 contacts or fewer, and up to 64 where a contact joins
    boxes of unlike masses or there is no friction (``colliding.solve.exact_pays``), at any tolerance. The
    defaults, 1e-9 and 16, run the 16 sweeps nearly always: a settled pile of 100 moves 0.1 um in 10 s. A
    looser tolerance costs less and creeps more: at 1e-4 with 32 sweeps, awake piles cost about 0.6x and the
    pyramid's top box drifts less in 2 s, but a settled pile of 100 creeps 4.7 mm in 10 s awake (asleep, as
    ``simulate`` lets it by default, it does not move); docs/engine_scale.md measures both. ``quiet_steps`` (colliding
    scenes): where every awake box is slower than ``sleep_speed`` at every point, the scene takes 4 grid steps as one
    (``colliding.quiet``: a resting pile kept awake costs about a quarter, as still); False steps every grid step.

    ``boxes_collide``: False (default), every box meets only the floor and the boxes are independent
    (a batch of them runs on threads); True, the boxes of the scene also collide with one another and
    are stepped together (``colliding``, ``colliding_reference``). A colliding scene must start with no
    two boxes overlapping by more than 1% of the thinner one's smaller half extent (a ValueError names
    them); smaller overlaps, and those that arise during a run, are resolved by the penalty.
    """

    boxes: tuple[Box, ...] = field(default_factory=lambda: (Box(position=(0.0, 5.0)),))
    dt: float = 0.005  # [s]
    gravity: float = -9.81  # [m/s^2] along y
    restitution: float = 0.5  # [-]
    friction: float = 0.02  # [-] Coulomb coefficient
    penalty_stiffness: float = 100.0  # [N/m]
    use_impulses: bool = True
    use_penalty: bool = True
    solver: str = "robust"
    restitution_threshold: float = 0.02  # [m/s]
    sleep_speed: float = 0.01  # [m/s]
    sleep_time: float = 0.1  # [s]
    penetration_slop: float = 0.0  # [m]
    solver_tolerance: float = 1e-9  # [-] share of the impulses' sum
    solver_iterations: int = 16
    quiet_steps: bool = True
    boxes_collide: bool = False

    def __post_init__(self):
        set_ = object.__setattr__
        boxes = tuple(self.boxes) if not isinstance(self.boxes, Box) else (self.boxes,)
        if not boxes:
            raise ValueError("boxes must hold at least one Box, got none")
        for k, box in enumerate(boxes):
            if not isinstance(box, Box):
                raise TypeError(f"boxes[{k}] must be a Box, got {type(box).__name__}")
        set_(self, "boxes", boxes)
        for name in (
            "dt",
            "gravity",
            "restitution",
            "friction",
            "penalty_stiffness",
            "restitution_threshold",
            "sleep_speed",
            "sleep_time",
            "penetration_slop",
            "solver_tolerance",
        ):
            set_(self, name, ENGINE_RANGES[name].check(name, getattr(self, name)))
        iterations = ENGINE_RANGES["solver_iterations"]
        set_(
            self,
            "solver_iterations",
            check_integer("solver_iterations", self.solver_iterations, int(iterations.low), int(iterations.high)),
        )
        for name in ("use_impulses", "use_penalty", "quiet_steps", "boxes_collide"):
            set_(self, name, check_bool(name, getattr(self, name)))
        check_choice("solver", self.solver, SOLVERS)
        if self.solver == "robust" and not self.use_impulses:
            raise ValueError(
                "use_impulses must be True with solver='robust' (its contacts are impulses); "
                "a penalty-only run is available with solver='seed'"
            )
        if self.boxes_collide:
            overlap = overlapping_boxes(boxes)
            if overlap is not None:
                i, j, depth = overlap
                raise ValueError(
                    f"boxes[{i}] and boxes[{j}] overlap by {depth:.3g} m at the start; with "
                    "boxes_collide=True the boxes must start apart or touching (an overlap of at most "
                    "1% of the thinner box's half width is resolved by the penalty)"
                )

    # -- what the scene has: these decide which kernel stages are compiled in -------------------
    @property
    def n_bodies(self) -> int:
        return len(self.boxes)

    @property
    def has_friction(self) -> bool:
        return bool(np.any(self.body_params()[:, layout.FRICTION] > 0.0))

    @property
    def has_penalty(self) -> bool:
        return self.use_penalty and self.penalty_stiffness > 0.0

    def replace(self, **changes) -> Scene:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)

    # -- arrays for the kernels ---------------------------------------------------------------
    def initial_state(self) -> np.ndarray:
        """(n_bodies, 6) float64: x, y, angle, vx, vy, spin (see ``layout``)."""
        state = np.empty((self.n_bodies, layout.STATE_SIZE))
        for i, box in enumerate(self.boxes):
            state[i] = (*box.position, box.angle, *box.velocity, box.spin)
        return state

    def body_params(self) -> np.ndarray:
        """(n_bodies, 7) float64: half extents, mass, inertia, restitution, friction, stiffness."""
        params = np.empty((self.n_bodies, layout.PARAM_SIZE))
        for i, box in enumerate(self.boxes):
            params[i] = (
                0.5 * box.length,
                0.5 * box.width,
                box.mass,
                box.inertia,
                self.restitution if box.restitution is None else box.restitution,
                self.friction if box.friction is None else box.friction,
                self.penalty_stiffness,
            )
        return params
