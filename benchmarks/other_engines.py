"""The same 2D box toss in pymunk, Box2D and MuJoCo: the engines a user would pick instead of ours.

The throughput benchmarks and the precision reports compare box_toss_env's engine against these three.
Each adapter builds one scene (a box thrown onto the floor y = 0), steps it with the engine's own
Python API in a plain Python loop, as a user of that engine would, and returns the trajectory and the
wall time of the stepping loop alone (scene construction excluded). Scenes of several boxes (stacks,
piles, boxes that collide) are built in pymunk and Box2D by ``benchmarks.other_scenes``, with the same
conventions.

Usage::

    from benchmarks.other_engines import ENGINES, Toss, missing_engines

    result = ENGINES["pymunk"].simulate_toss(Toss(), dt=1 / 240, n_steps=720, record=True)
    result.states        # (721, 6): x [m], y [m], angle [rad], vx [m/s], vy [m/s], omega [rad/s]
    result.ns_per_step   # wall time of the stepping loop / steps
    missing_engines()    # e.g. ["mujoco"] when `import mujoco` fails

    python -m benchmarks.other_engines      # ns per step and final state of the default toss

Common conventions
------------------
- State ``[x, y, angle, vx, vy, omega]``: centre of mass, angle counter-clockwise in the x-y plane
  (y up), not wrapped; the same layout and signs as box_toss_env.
- The box is uniform: mass ``m``, moment about its centre ``m (L^2 + W^2) / 12``; ``L`` is its full
  size along its own x axis (horizontal at angle 0), ``W`` along its own y axis.
- Gravity ``g`` (negative) along y. Every engine integrates with a symplectic (semi-implicit) Euler
  step, so in free flight velocities and the angle are exact and y is off the parabola by
  ``|g| t dt / 2``: below it for Box2D and MuJoCo (velocity first, then position), above it for
  pymunk (Chipmunk moves positions with the previous velocity, then updates velocities).
- Timing: ``wall_seconds`` covers the loop of ``n_steps`` step calls only (``time.perf_counter``).
  With ``record=True`` the loop also reads the state after every step (2 to 5 us per step through
  the engines' Python bindings, more than the step itself), so take throughput from
  ``record=False``. The per-step cost of calling the engine from Python is part of what a user of
  these engines pays, and is included on purpose (MuJoCo: ``mujoco.mj_step(model, data)`` once per
  step, not ``nstep=``).
- Each call builds a fresh scene, so results are deterministic and independent of earlier calls.

pymunk (Chipmunk2D, float64)
----------------------------
- ``Space`` with gravity ``(0, g)``, the default 10 solver iterations, no damping, no sleeping.
- Floor: a static ``Segment`` from x = -1e4 to 1e4 m on y = 0, radius 0.
- Box: ``Body(m, m (L^2 + W^2) / 12)`` with ``Poly.create_box(body, (L, W), radius=0)``; the shape has
  no density of its own, so the body keeps exactly the given mass and moment.
- pymunk multiplies the two shapes' elasticities and frictions: the floor has 1.0 for both and the box
  has ``e`` and ``mu``, so the pair gets exactly ``e`` and ``mu``. No restitution velocity threshold.
- ``space.collision_slop`` (allowed overlap) defaults to 0.1, a value meant for pixel units; in metres
  that is 10 cm, so we set it to ``PYMUNK_COLLISION_SLOP`` = 1 mm. A resting box sinks up to that far.

Box2D 2.3 (pybox2d, float32)
----------------------------
- ``b2World(gravity=(0, g))`` with sleeping allowed (the default: a box at rest for 0.5 s sleeps and
  its steps get cheaper, as a user's would), continuous collision against static bodies on (the
  default), ``world.Step(dt, 8, 3)`` (velocity and position iterations).
- Skin: Box2D 2.3 gives every polygon and edge a collision skin of ``b2_polygonRadius`` = 1 cm and
  keeps bodies apart by the skins, so a plain ``L x W`` box rests 1.5 to 2 cm above a plain edge. To
  collide as the same box on the same floor, the polygon is the box shrunk by the skin (half sizes
  ``L/2 - r, W/2 - r``, so core plus skin is the ``L x W`` box with corners rounded to r = 1 cm) and
  the edge lies at y = -r (its skin's top at y = 0), from x = -1000 to 1000 m (float32: keep
  coordinates moderate). Boxes need ``L, W > 2 cm``.
- Mass: the shrunk polygon would weigh less, so ``body.massData`` is set to mass ``m``, centre 0 and
  moment ``m (L^2 + W^2) / 12`` (``body.mass`` and ``body.inertia``, about the centre, are checked in
  the tests to float32 rounding).
- Box2D mixes friction as ``sqrt(mu_a mu_b)`` and restitution as ``max(e_a, e_b)``: both fixtures get
  ``mu`` and the floor gets restitution 0, so the pair gets exactly ``mu`` and ``e``.
- Compiled-in limits (b2Settings.h, not changeable from Python) that matter for comparisons:
  * ``b2_maxTranslation`` = 2 m per step: speeds above 2 / dt are clamped, velocity included
    (480 m/s at dt = 1/240, 120 m/s at 1/60).
  * ``b2_maxRotation`` = pi/2 per step: spins above pi / (2 dt) are clamped (377 rad/s at 1/240).
  * ``b2_velocityThreshold`` = 1 m/s: impacts with a normal approach speed below it are perfectly
    inelastic whatever ``e`` is (so small bounces die out sooner than in the other engines).
  * ``b2_linearSlop`` = 5 mm: the position solver leaves up to that much overlap, so a resting box
    sits up to 5 mm low and may rest tilted by up to ~0.01 rad.

MuJoCo (float64, soft contacts)
-------------------------------
- Axes: MJCF built in ``mujoco_xml``; our x-y plane is MuJoCo's x-z plane (our y is MuJoCo's z,
  gravity ``(0, 0, g)``). The box body sits at the world origin with three joints in this order:
  slide along x, slide along z, hinge about **-y**. A positive rotation about -y turns +x toward +z,
  which is our counter-clockwise; so ``qpos = [x, y, angle]`` and ``qvel = [vx, vy, omega]`` are our
  state as is, no sign flips (with a hinge about +y the angle would be minus ours). Tested with the
  box's rotation matrix, a free spin, and which corner a tilted box tips over.
- Box geom ``size = (L/2, D/2, W/2)`` with out-of-plane depth ``D = min(L, W)`` (irrelevant to the
  planar motion: the joints forbid y motion and tilt); an explicit ``<inertial>`` with mass ``m`` and
  ``diaginertia`` of a uniform L x D x W box, whose moment about the hinge is ``m (L^2 + W^2) / 12``.
- Floor: a ``plane`` geom at z = 0. ``integrator="Euler"`` (semi-implicit Euler, like the others),
  ``cone="elliptic"`` (the exact Coulomb cone), the default Newton solver and ``solimp``,
  ``condim=3``, friction ``mu`` on both geoms (MuJoCo takes the max of the two, and averages
  ``solref``, which is the same on both).
- Restitution: MuJoCo contacts are soft (a spring-damper on the penetration, solved as a constraint)
  and have no restitution coefficient. We use the direct form ``solref = (-k, -b)``, which makes the
  penetration obey about ``r'' + b r' + k r = 0`` (per unit effective mass, whatever the box's mass or
  the contact point) while in contact. With natural frequency ``w0`` and damping ratio ``z``: ``k = w0^2``,
  ``b = 2 z w0``; a linear oscillator rebounds with ``e = exp(-pi z / sqrt(1 - z^2))``, hence
  ``z = -ln(e) / sqrt(pi^2 + ln(e)^2)`` (``z = 1`` for ``e = 0``). Stiffness: ``w0 = MUJOCO_OMEGA_DT / dt``
  with ``MUJOCO_OMEGA_DT`` = 0.5, the stiffest MuJoCo's own safety rule (``timeconst >= 2 dt`` for a
  critically damped contact) allows; stiffer makes the explicit damping unstable for small e, softer
  lets a fast corner impact last so long that the first bounce differs from the rigid engines'. (The
  (timeconst, dampratio) form suits bouncy contacts badly: its stiffness grows as 1 / z^2, so at
  dt = 1/240 and MuJoCo's default timeconst 0.02 s, e = 0.6 rebounds with 0.96 and e = 0.9 blows up.)
- The effective e is only approximate: the contact lasts only a few steps, it releases when the force
  would pull, and the impedance is below 1. Flat drops at 3 m/s and dt = 1/240 rebound with 0.10 for
  e = 0, 0.15 for e = 0.1 and within 0.03 of e for 0.3 <= e <= 1; at dt = 1e-3 the first contact's
  phase within a step matters more: 0.22 for e = 0, 0.40 for e = 0.3, within 0.05 of e above 0.6.
- Soft contacts penetrate: at dt = 1/240 a box landing flat at 3 m/s sinks about 3 mm (e = 0),
  1.2 cm (e = 0.3) to 2.5 cm (e = 1) during the impact (proportional to impact speed times dt). At rest
  it sinks < 0.2 mm, but for e >= 0.3 contacts switching on and off keep a small vibration going
  (|vy| up to 0.03 m/s at e = 0.3 and 0.6, 0.26 m/s and +-3 mm at e = 0.9, where the rigid engines
  come to rest).
"""

from __future__ import annotations

import argparse
import functools
import importlib
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import ClassVar

import numpy as np

STATE_FIELDS = ("x", "y", "angle", "vx", "vy", "omega")
"""Column names of every state array: [m, m, rad, m/s, m/s, rad/s]."""

INSTALL_HINT = "pip install 'box_toss_env[benchmark]'"

PYMUNK_FLOOR_HALF_LENGTH = 1.0e4
"""pymunk floor segment spans x in [-this, this] [m]."""

PYMUNK_COLLISION_SLOP = 1.0e-3
"""pymunk allowed overlap [m]; pymunk's default 0.1 assumes pixel units."""

BOX2D_FLOOR_HALF_LENGTH = 1.0e3
"""Box2D floor edge spans x in [-this, this] [m] (float32 engine: keep it moderate)."""

MUJOCO_OMEGA_DT = 0.5
"""MuJoCo contact natural frequency times the time step (w0 dt), see the module docstring."""


@dataclass(frozen=True)
class Toss:
    """One throw of a uniform box onto the floor y = 0; the defaults are the benchmark's default toss."""

    length: float = 0.3  # L: full size along the box's own x axis [m]
    width: float = 0.15  # W: full size along the box's own y axis [m]
    mass: float = 1.0  # [kg]
    x: float = 0.0  # initial centre [m]
    y: float = 1.2  # [m]
    angle: float = 0.3  # initial angle, counter-clockwise [rad]
    vx: float = 3.0  # initial centre velocity [m/s]
    vy: float = 2.0  # [m/s]
    omega: float = 5.0  # initial spin, counter-clockwise [rad/s]
    gravity: float = -9.81  # acceleration along y [m/s^2], negative
    restitution: float = 0.3  # e in [0, 1]
    friction: float = 0.5  # Coulomb mu >= 0

    def __post_init__(self) -> None:
        if not (self.length > 0 and self.width > 0 and self.mass > 0):
            raise ValueError(f"length, width and mass must be positive, got {self}")
        if not 0.0 <= self.restitution <= 1.0:
            raise ValueError(f"restitution must be in [0, 1], got {self.restitution}")
        if not self.friction >= 0.0:
            raise ValueError(f"friction must be >= 0, got {self.friction}")
        values = (self.x, self.y, self.angle, self.vx, self.vy, self.omega, self.gravity)
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"initial state and gravity must be finite, got {self}")

    @property
    def moment(self) -> float:
        """Moment of inertia about the centre, m (L^2 + W^2) / 12 [kg m^2]."""
        return self.mass * (self.length**2 + self.width**2) / 12.0

    def initial_state(self) -> np.ndarray:
        """[x, y, angle, vx, vy, omega] at t = 0."""
        return np.array([self.x, self.y, self.angle, self.vx, self.vy, self.omega], dtype=np.float64)


@dataclass(frozen=True)
class TossResult:
    """What one engine did with one toss."""

    engine: str
    final_state: np.ndarray  # (6,) [x, y, angle, vx, vy, omega] after `steps` steps
    wall_seconds: float  # wall time of the stepping loop alone [s]
    steps: int
    states: np.ndarray | None = None  # (steps + 1, 6) including the initial state, if recorded

    @property
    def ns_per_step(self) -> float:
        return 1e9 * self.wall_seconds / self.steps if self.steps else math.nan


def steps_for_duration(duration: float, dt: float) -> int:
    """Number of steps of size dt that cover `duration` seconds (rounded to the nearest)."""
    return int(round(duration / dt))


@functools.cache
def _importable(module: str) -> bool:
    try:
        importlib.import_module(module)
    except (ImportError, OSError):  # OSError: a binary wheel whose shared library fails to load
        return False
    return True


def _import(module: str, package: str) -> ModuleType:
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise ImportError(f"`import {module}` failed: install {package!r} ({INSTALL_HINT})") from err


def _run(
    name: str,
    step: Callable[[], object],
    read_state: Callable[[], Sequence[float]],
    n_steps: int,
    record: bool,
) -> TossResult:
    """Call `step` n_steps times under a wall clock; read the state after each step if `record`."""
    if n_steps < 0:
        raise ValueError(f"n_steps must be >= 0, got {n_steps}")
    states = None
    if record:
        states = np.empty((n_steps + 1, len(STATE_FIELDS)), dtype=np.float64)
        states[0] = read_state()
        start = time.perf_counter()
        for i in range(1, n_steps + 1):
            step()
            states[i] = read_state()
        wall_seconds = time.perf_counter() - start
    else:
        start = time.perf_counter()
        for _ in range(n_steps):
            step()
        wall_seconds = time.perf_counter() - start
    final_state = np.array(read_state(), dtype=np.float64)
    return TossResult(name, final_state, wall_seconds, n_steps, states)


class Engine:
    """Adapter interface: an engine `name`, the pip `package` and the `module` it imports."""

    name: ClassVar[str]
    package: ClassVar[str]
    module: ClassVar[str]

    def available(self) -> bool:
        """True if the engine's package imports."""
        return _importable(self.module)

    def simulate_toss(self, toss: Toss, dt: float, n_steps: int, record: bool = False) -> TossResult:
        """Simulate `n_steps` steps of size `dt` [s]; see TossResult."""
        if not dt > 0:
            raise ValueError(f"dt must be positive, got {dt}")
        step, read_state, _ = self.build(toss, dt)
        return _run(self.name, step, read_state, n_steps, record)

    def mass_properties(self, toss: Toss) -> tuple[float, float]:
        """(mass [kg], moment about the centre [kg m^2]) as the engine reports them for this toss."""
        return self.build(toss, 1.0 / 240.0)[2]()

    def build(
        self, toss: Toss, dt: float
    ) -> tuple[Callable[[], object], Callable[[], Sequence[float]], Callable[[], tuple[float, float]]]:
        """Make the scene; return (step, read_state, mass_properties) closures over it."""
        raise NotImplementedError


@dataclass(frozen=True)
class PymunkEngine(Engine):
    name: ClassVar[str] = "pymunk"
    package: ClassVar[str] = "pymunk"
    module: ClassVar[str] = "pymunk"

    iterations: int = 10  # pymunk's default
    collision_slop: float = PYMUNK_COLLISION_SLOP  # [m]

    def build(self, toss, dt):
        pymunk = _import(self.module, self.package)
        space = pymunk.Space()
        space.gravity = (0.0, toss.gravity)
        space.iterations = self.iterations
        space.collision_slop = self.collision_slop

        half = PYMUNK_FLOOR_HALF_LENGTH
        floor = pymunk.Segment(space.static_body, (-half, 0.0), (half, 0.0), 0.0)
        floor.elasticity = 1.0  # pymunk multiplies elasticities and frictions of the pair
        floor.friction = 1.0

        body = pymunk.Body(toss.mass, toss.moment)
        body.position = (toss.x, toss.y)
        body.angle = toss.angle
        body.velocity = (toss.vx, toss.vy)
        body.angular_velocity = toss.omega
        box = pymunk.Poly.create_box(body, (toss.length, toss.width), 0.0)
        box.elasticity = toss.restitution
        box.friction = toss.friction
        space.add(floor, body, box)

        def read_state():
            p, v = body.position, body.velocity
            return (p.x, p.y, body.angle, v.x, v.y, body.angular_velocity)

        return functools.partial(space.step, dt), read_state, lambda: (body.mass, body.moment)


@dataclass(frozen=True)
class Box2DEngine(Engine):
    name: ClassVar[str] = "box2d"
    package: ClassVar[str] = "box2d"
    module: ClassVar[str] = "Box2D"

    velocity_iterations: int = 8
    position_iterations: int = 3

    def build(self, toss, dt):
        Box2D = _import(self.module, self.package)
        world = Box2D.b2World(gravity=(0.0, toss.gravity), doSleep=True)

        skin = Box2D.b2_polygonRadius  # [m] collision skin of polygons and edges, see the module docstring
        if min(toss.length, toss.width) <= 2.0 * skin:
            raise ValueError(f"Box2D needs box sizes above 2 b2_polygonRadius = {2 * skin:.3g} m, got {toss}")
        half = BOX2D_FLOOR_HALF_LENGTH
        ground = world.CreateStaticBody(position=(0.0, 0.0))
        # the edge's skin surface is y = 0; friction mixes as sqrt(mu_a mu_b), restitution as max(e_a, e_b)
        ground.CreateEdgeFixture(vertices=[(-half, -skin), (half, -skin)], friction=toss.friction, restitution=0.0)

        body = world.CreateDynamicBody(position=(toss.x, toss.y), angle=toss.angle)
        body.CreatePolygonFixture(
            box=(toss.length / 2 - skin, toss.width / 2 - skin),  # core + skin = the L x W box
            density=toss.mass / (toss.length * toss.width),
            friction=toss.friction,
            restitution=toss.restitution,
        )
        # the core polygon is smaller than the box: set the box's mass and moment about the centre
        body.massData = Box2D.b2MassData(mass=toss.mass, center=(0.0, 0.0), I=toss.moment)
        body.linearVelocity = (toss.vx, toss.vy)
        body.angularVelocity = toss.omega

        def read_state():
            p, v = body.position, body.linearVelocity
            return (p.x, p.y, body.angle, v.x, v.y, body.angularVelocity)

        step = functools.partial(world.Step, dt, self.velocity_iterations, self.position_iterations)
        return step, read_state, lambda: (body.mass, body.inertia)  # inertia about the body origin = centre


def restitution_damping_ratio(restitution: float) -> float:
    """Damping ratio z of a linear oscillator rebounding with e = exp(-pi z / sqrt(1 - z^2)); 1 if e = 0."""
    if restitution <= 0.0:
        return 1.0
    log_e = math.log(restitution)
    return -log_e / math.sqrt(math.pi**2 + log_e**2)


def mujoco_xml(toss: Toss, dt: float, omega_dt: float = MUJOCO_OMEGA_DT) -> str:
    """MJCF of the planar toss scene; our (x, y) plane is MuJoCo's (x, z) plane, see the module docstring."""
    depth = min(toss.length, toss.width)
    L, W, D, m = toss.length, toss.width, depth, toss.mass
    inertia = (m * (W**2 + D**2) / 12, m * (L**2 + W**2) / 12, m * (L**2 + D**2) / 12)
    omega0 = omega_dt / dt  # contact natural frequency [rad/s]
    stiffness = omega0**2  # per unit effective mass [1/s^2]
    damping = 2.0 * restitution_damping_ratio(toss.restitution) * omega0  # [1/s]
    return f"""<mujoco model="box_toss">
  <option timestep="{dt!r}" gravity="0 0 {toss.gravity!r}" integrator="Euler" cone="elliptic"/>
  <default>
    <geom condim="3" friction="{toss.friction!r} 0 0" solref="{-stiffness!r} {-damping!r}"/>
  </default>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1"/>
    <body name="box" pos="0 0 0">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="y" type="slide" axis="0 0 1"/>
      <joint name="angle" type="hinge" axis="0 -1 0"/>
      <inertial pos="0 0 0" mass="{m!r}" diaginertia="{inertia[0]!r} {inertia[1]!r} {inertia[2]!r}"/>
      <geom name="box" type="box" size="{L / 2!r} {D / 2!r} {W / 2!r}"/>
    </body>
  </worldbody>
</mujoco>
"""


@dataclass(frozen=True)
class MujocoEngine(Engine):
    name: ClassVar[str] = "mujoco"
    package: ClassVar[str] = "mujoco"
    module: ClassVar[str] = "mujoco"

    omega_dt: float = MUJOCO_OMEGA_DT

    def build(self, toss, dt):
        mujoco = _import(self.module, self.package)
        model = mujoco.MjModel.from_xml_string(mujoco_xml(toss, dt, self.omega_dt))
        data = mujoco.MjData(model)
        data.qpos[:] = (toss.x, toss.y, toss.angle)  # hinge about -y: qpos[2] is our angle as is
        data.qvel[:] = (toss.vx, toss.vy, toss.omega)
        qpos, qvel = data.qpos, data.qvel

        def read_state():
            return (*qpos, *qvel)

        def mass_properties():
            body = model.body("box")
            rotation = np.empty(9)
            mujoco.mju_quat2Mat(rotation, body.iquat)
            rotation = rotation.reshape(3, 3)  # principal inertia frame -> body frame
            axis = model.jnt_axis[model.joint("angle").id]
            moment = axis @ rotation @ np.diag(body.inertia) @ rotation.T @ axis
            return float(body.mass[0]), float(moment)

        return functools.partial(mujoco.mj_step, model, data), read_state, mass_properties


ENGINES: dict[str, Engine] = {
    "pymunk": PymunkEngine(),
    "box2d": Box2DEngine(),
    "mujoco": MujocoEngine(),
}
"""The other engines by name, each with its default settings."""


def missing_engines() -> list[str]:
    """Names in ENGINES whose package does not import."""
    return [name for name, engine in ENGINES.items() if not engine.available()]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.other_engines",
        description="Time the default box toss in pymunk, Box2D and MuJoCo and print the final states.",
    )
    parser.add_argument("--dt", type=float, default=1.0 / 240.0, help="time step [s] (default 1/240)")
    parser.add_argument("--duration", type=float, default=3.0, help="simulated time [s] (default 3)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per engine; the fastest is shown")
    args = parser.parse_args(argv)

    toss = Toss()
    n_steps = steps_for_duration(args.duration, args.dt)
    print(f"toss: {toss}")
    print(f"dt = {args.dt:.6g} s, {n_steps} steps ({args.duration:g} s), best of {args.repeat}")
    header = f"{'engine':<8} {'ns/step':>9}  " + " ".join(f"{f:>9}" for f in STATE_FIELDS)
    print(header)
    for name, engine in ENGINES.items():
        if not engine.available():
            continue
        results = [engine.simulate_toss(toss, args.dt, n_steps) for _ in range(max(1, args.repeat))]
        best = min(results, key=lambda r: r.wall_seconds)
        state = " ".join(f"{v:9.4f}" for v in best.final_state)
        print(f"{name:<8} {best.ns_per_step:9.0f}  {state}")
    missing = missing_engines()
    print(f"missing: {', '.join(missing)} ({INSTALL_HINT})" if missing else "missing: none")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
