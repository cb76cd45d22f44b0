"""Any box_toss_env ``Scene`` (several boxes, their material, dt, gravity) as a pymunk space, a Box2D 2.3
world and a Box2D v3 world, stepped for N steps, states back in our layout.

``benchmarks.other_engines`` throws one box; this module builds a whole scene the same way, so the
multi-box comparison (``reports.collisions``) and the pile benchmark (``benchmarks.engine``) run the
same boxes in every engine.

Usage::

    from benchmarks.other_scenes import SCENE_ENGINES, simulate_scene

    run = simulate_scene("pymunk", scene, steps=720)        # record=True by default
    run.states            # (steps + 1, n, 6): x, y, angle, vx, vy, spin per box, as our Trajectory.state
    run.ns_per_body_step  # wall time of the stepping loop / (steps * n)

Conventions and settings
------------------------
Everything ``benchmarks.other_engines`` states holds here (state layout, uniform boxes of mass m and
moment m (L^2 + W^2) / 12, semi-implicit Euler, timing of the stepping loop alone, a fresh world per
call). Each engine runs with its documented defaults except where the scene says otherwise:

- **What the scene sets**: gravity, dt (one engine step per scene step, no substeps), each box's size,
  mass, moment, pose and velocities, the material (restitution e, friction mu), and whether boxes
  collide with one another (``scene.boxes_collide``; when False, boxes touch only the floor, through a
  collision group: pymunk ``ShapeFilter(group=1)``, Box2D ``groupIndex=-1``).
- **What the scene cannot set** (and so differs between engines): our penalty stiffness, restitution
  threshold, sleep settings and penetration slop have no counterpart; each engine uses its own
  (``simulate_scene(..., sleep=False)`` turns Box2D's sleeping off, for runs where no engine may sleep).
  ``simulate_scene(..., dt=DEFAULT_DT[engine])`` steps at the engine's own default instead of the scene's.
- **pymunk**: 10 solver iterations (its default), no sleeping (its default), collision slop 1 mm
  (``PYMUNK_COLLISION_SLOP``: pymunk's default 0.1 is meant for pixels). pymunk multiplies the two
  shapes' elasticities and frictions. With boxes that collide, every shape (the floor included) gets
  ``sqrt(e)`` and ``sqrt(mu)``, so every pair, box-floor and box-box, gets exactly e and mu; this needs
  one material for the whole scene. Without box-box contact, the floor gets 1 and each box its own
  values (as ``other_engines``), so per-box material works.
- **Box2D 2.3** (float32): ``world.Step(dt, 8, 3)`` (the manual's suggested iterations), sleeping
  allowed and warm starting on (its defaults), boxes not bullets (its default: continuous collision
  only against static bodies, so fast boxes can pass through each other, as a user's would). Box2D
  mixes friction as ``sqrt(mu_a mu_b)`` and restitution as ``max(e_a, e_b)``: the floor gets mu and
  e = 0 and the boxes their own, so every pair gets e and mu when all boxes share one material. Skin:
  each polygon is its box shrunk by ``b2_polygonRadius`` = 1 cm and the floor edge lies at y = -1 cm,
  so skins meet where our boxes' surfaces meet (corners rounded to 1 cm); boxes need sides > 2 cm.
  Its compiled-in limits (2 m of travel per step, restitution only above 1 m/s of approach, up to
  ``b2_linearSlop`` = 5 mm of overlap left at each contact, so a stack of n boxes sits up to
  about 5n mm low) are listed in ``other_engines``. ``doSleep=False`` on the world does not keep 2.3's
  bodies awake; ``sleep=False`` also sets every body's ``sleepingAllowed=False``.
- **Box2D v3** (pyb2d3, float32): ``world.step(dt, 4)`` (its default 4 substeps), its defaults otherwise
  (soft contacts of 30 Hz, restitution only above 1 m/s of approach, sleeping on; ``sleep=False`` turns
  sleeping off on the world and on every body). No skin: v3 polygons have radius 0 and contacts are
  speculative, so each box is its plain L x W polygon and the floor a segment on y = 0; a resting 20 cm box
  sits about 0.1 mm low. Friction ``sqrt(mu_a mu_b)``, restitution ``max(e_a, e_b)``, as 2.3 (floor: mu, e = 0).
  Its soft contacts push overlapping boxes apart after restitution is applied, so boxes part up to ~9% faster
  than e says (tests/benchmarks/test_other_scenes.py). Checked with pyb2d3 0.11 at 60 Hz and 4 substeps: a box
  of mu 0.8 on a floor of mu 0.2 slides as mu 0.40 (the sqrt); e 0.5 on e 0 rebounds as e 0 on e 0.5 (the
  max), but a flat 3 m/s landing on the floor rebounds at 1.06 m/s, not 1.5 (e 0.35: restitution is applied
  per contact point, once per step, after the soft solve); mass 2 kg and moment m (L^2 + W^2) / 12 to 1e-6.
- **MuJoCo** is not built here: its soft contacts are the subject of ``other_engines``' single-box
  comparison; the multi-box comparison is between impulse engines.

A scene an engine cannot represent (per-box material where the engine's mixing rule cannot give it,
sides Box2D's skin does not fit) raises ``UnsupportedScene`` with the reason.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from box_toss_env.physics import Scene

from .other_engines import (
    BOX2D_FLOOR_HALF_LENGTH,
    PYMUNK_COLLISION_SLOP,
    PYMUNK_FLOOR_HALF_LENGTH,
    _import,
    _importable,
)

STATE_SIZE = 6  # x, y, angle, vx, vy, spin
BOX2D_ITERATIONS = (8, 3)  # velocity, position: the Box2D manual's suggestion
PYMUNK_ITERATIONS = 10  # pymunk's default


class UnsupportedScene(ValueError):
    """The engine cannot represent this scene as we define it; the message says why."""


@dataclass(frozen=True)
class SceneRun:
    """What one engine did with one scene."""

    engine: str
    final_state: np.ndarray  # (n, 6) after ``steps`` steps
    wall_seconds: float  # wall time of the stepping loop alone [s]
    steps: int
    states: np.ndarray | None = None  # (steps + 1, n, 6) including the initial state, if recorded

    @property
    def n_bodies(self) -> int:
        return self.final_state.shape[0]

    @property
    def ns_per_body_step(self) -> float:
        return 1e9 * self.wall_seconds / (self.steps * self.n_bodies) if self.steps else math.nan


def boxes_collide(scene: Scene) -> bool:
    """Whether the scene's boxes collide with one another (False for a scene built before the flag existed)."""
    return bool(getattr(scene, "boxes_collide", False))


def materials(scene: Scene) -> list[tuple[float, float]]:
    """(restitution, friction) of each box: its own where given, else the scene's."""
    return [
        (
            scene.restitution if box.restitution is None else box.restitution,
            scene.friction if box.friction is None else box.friction,
        )
        for box in scene.boxes
    ]


def one_material(scene: Scene, engine: str, why: str) -> tuple[float, float]:
    """The scene's single (e, mu), or UnsupportedScene naming the engine and ``why`` it needs one."""
    pairs = set(materials(scene))
    if len(pairs) != 1:
        raise UnsupportedScene(f"{engine} needs one material for every box {why}; this scene has {sorted(pairs)}")
    return pairs.pop()


def build_pymunk(
    scene: Scene,
    sleep: bool = True,
    state: np.ndarray | None = None,
    dt: float | None = None,
    iterations: int = PYMUNK_ITERATIONS,
) -> tuple[Callable[[], object], Callable[[np.ndarray], None]]:
    """A pymunk space of ``scene``: (step, read_states into an (n, 6) array). pymunk does not sleep by default
    (``sleep_time_threshold`` infinite), so ``sleep`` changes nothing; ``dt`` replaces the scene's step."""
    pymunk = _import("pymunk", "pymunk")
    space = pymunk.Space()
    space.gravity = (0.0, scene.gravity)
    space.iterations = iterations
    space.collision_slop = PYMUNK_COLLISION_SLOP
    collide = boxes_collide(scene)
    if collide:  # every pair multiplies two sqrt's back to the scene's value
        e, mu = one_material(scene, "pymunk", "that collide (it multiplies the two shapes' values)")
        floor_e, floor_mu = math.sqrt(e), math.sqrt(mu)
        box_material = [(floor_e, floor_mu)] * scene.n_bodies
    else:
        floor_e, floor_mu = 1.0, 1.0
        box_material = materials(scene)

    half = PYMUNK_FLOOR_HALF_LENGTH
    floor = pymunk.Segment(space.static_body, (-half, 0.0), (half, 0.0), 0.0)
    floor.elasticity, floor.friction = floor_e, floor_mu
    space.add(floor)
    bodies = []
    start = scene.initial_state() if state is None else np.asarray(state, dtype=float)
    for box, (e, mu), (x, y, angle, vx, vy, spin) in zip(scene.boxes, box_material, start, strict=True):
        body = pymunk.Body(box.mass, box.inertia)
        body.position = (x, y)
        body.angle = angle
        body.velocity = (vx, vy)
        body.angular_velocity = spin
        shape = pymunk.Poly.create_box(body, (box.length, box.width), 0.0)
        shape.elasticity, shape.friction = e, mu
        if not collide:
            shape.filter = pymunk.ShapeFilter(group=1)  # shapes of one non-zero group never collide
        space.add(body, shape)
        bodies.append(body)

    def read_states(out: np.ndarray) -> None:
        for row, body in zip(out, bodies, strict=True):
            p, v = body.position, body.velocity
            row[:] = (p.x, p.y, body.angle, v.x, v.y, body.angular_velocity)

    dt = scene.dt if dt is None else dt
    return lambda: space.step(dt), read_states


def build_box2d(
    scene: Scene, sleep: bool = True, state: np.ndarray | None = None, dt: float | None = None
) -> tuple[Callable[[], object], Callable[[np.ndarray], None]]:
    """A Box2D 2.3 world of ``scene``: (step, read_states into an (n, 6) array). ``sleep=False`` keeps every
    body awake: ``doSleep=False`` on the world alone does not (bodies still fall asleep), so each body also
    gets ``sleepingAllowed=False``. ``dt`` replaces the scene's step."""
    Box2D = _import("Box2D", "box2d")
    world = Box2D.b2World(gravity=(0.0, scene.gravity), doSleep=sleep)
    skin = Box2D.b2_polygonRadius
    mixed = set(materials(scene))
    if len({mu for _, mu in mixed}) > 1:
        raise UnsupportedScene(
            f"box2d needs one friction for every box (it mixes sqrt(mu_a mu_b), so no floor "
            f"friction gives each box its own); this scene has {sorted(mixed)}"
        )
    if boxes_collide(scene) and len(mixed) > 1:
        one_material(scene, "box2d", "that collide (it mixes restitution as max(e_a, e_b))")
    floor_mu = next(iter(mixed))[1]
    for k, box in enumerate(scene.boxes):
        if min(box.length, box.width) <= 2.0 * skin:
            raise UnsupportedScene(
                f"box2d needs sides above 2 b2_polygonRadius = {2 * skin:.3g} m; box {k} is "
                f"{box.length:g} x {box.width:g} m"
            )
    group = 0 if boxes_collide(scene) else -1  # a shared negative group never collides with itself
    half = BOX2D_FLOOR_HALF_LENGTH
    ground = world.CreateStaticBody(position=(0.0, 0.0))
    ground.CreateEdgeFixture(vertices=[(-half, -skin), (half, -skin)], friction=floor_mu, restitution=0.0)
    bodies = []
    start = scene.initial_state() if state is None else np.asarray(state, dtype=float)
    for box, (e, mu), (x, y, angle, vx, vy, spin) in zip(scene.boxes, materials(scene), start, strict=True):
        body = world.CreateDynamicBody(position=(x, y), angle=angle)
        body.CreatePolygonFixture(
            box=(box.length / 2 - skin, box.width / 2 - skin),
            density=box.mass / (box.length * box.width),
            friction=mu,
            restitution=e,
            groupIndex=group,
        )
        body.massData = Box2D.b2MassData(mass=box.mass, center=(0.0, 0.0), I=box.inertia)
        body.linearVelocity = (vx, vy)
        body.angularVelocity = spin
        if not sleep:
            body.sleepingAllowed = False
            body.awake = True
        bodies.append(body)

    def read_states(out: np.ndarray) -> None:
        for row, body in zip(out, bodies, strict=True):
            p, v = body.position, body.linearVelocity
            row[:] = (p.x, p.y, body.angle, v.x, v.y, body.angularVelocity)

    dt = scene.dt if dt is None else dt
    velocity_iterations, position_iterations = BOX2D_ITERATIONS
    return lambda: world.Step(dt, velocity_iterations, position_iterations), read_states


BOX2D3_SUBSTEPS = 4  # Box2D v3's documented default (b2World_Step(world, 1/60, 4) in its manual and samples)
BOX2D3_DT = 1 / 60  # [s] its documented default step
BOX2D3_FLOOR_HALF_LENGTH = 1.0e3  # [m] float32 engine, as Box2D 2.3


def build_box2d3(
    scene: Scene,
    sleep: bool = True,
    state: np.ndarray | None = None,
    dt: float | None = None,
    substeps: int = BOX2D3_SUBSTEPS,
) -> tuple[Callable[[], object], Callable[[np.ndarray], None]]:
    """A Box2D v3 world (pyb2d3, float32) of ``scene``: (step, read_states into an (n, 6) array).

    Box2D v3 at its defaults but for gravity: soft-step solver with ``substeps`` substeps per step
    (``world.step(dt, 4)``), contact hertz 30, restitution only above 1 m/s of approach, sleeping on.
    ``dt`` replaces the scene's step (None: the scene's). ``sleep=False`` turns sleeping off on the world and
    on every body (``enable_sleep=False``). Skin: v3 polygons have radius 0 (``b2MakeBox``) and its contacts
    are speculative, with no skin, so each box is the plain L x W polygon and the floor a segment on y = 0:
    surfaces meet where ours do. Mixing as 2.3 (and as documented for v3's default callbacks): friction
    ``sqrt(mu_a mu_b)``, restitution ``max(e_a, e_b)``, so the floor gets mu and e = 0. Mass and moment come
    from the density m / (L W) on the full box: m and m (L^2 + W^2) / 12, to float32 rounding.
    """
    b2 = _import("pyb2d3", "pyb2d3")
    mixed = set(materials(scene))
    if len({mu for _, mu in mixed}) > 1:
        raise UnsupportedScene(
            f"box2d3 needs one friction for every box (it mixes sqrt(mu_a mu_b), so no floor "
            f"friction gives each box its own); this scene has {sorted(mixed)}"
        )
    if boxes_collide(scene) and len(mixed) > 1:
        one_material(scene, "box2d3", "that collide (it mixes restitution as max(e_a, e_b))")
    floor_mu = next(iter(mixed))[1]
    world = b2.World(gravity=(0.0, scene.gravity))
    world.sleeping_enabled = sleep
    ground = world.create_static_body(position=(0.0, 0.0))
    half = BOX2D3_FLOOR_HALF_LENGTH
    ground.create_segment_shape(
        b2.shape_def(material=b2.surface_material(friction=floor_mu, restitution=0.0)),
        b2.segment((-half, 0.0), (half, 0.0)),
    )
    group = 0 if boxes_collide(scene) else -1  # a shared negative group never collides with itself
    bodies = []
    start = scene.initial_state() if state is None else np.asarray(state, dtype=float)
    for box, (e, mu), (x, y, angle, vx, vy, spin) in zip(scene.boxes, materials(scene), start, strict=True):
        body = world.create_dynamic_body(
            position=(float(x), float(y)),
            rotation=float(angle),
            linear_velocity=(float(vx), float(vy)),
            angular_velocity=float(spin),
            enable_sleep=sleep,
        )
        shape = b2.shape_def(
            density=box.mass / (box.length * box.width), material=b2.surface_material(friction=mu, restitution=e)
        )
        if group:
            shape.filter = b2.make_filter(group_index=group)
        body.create_polygon_shape(shape, b2.box(box.length / 2, box.width / 2))
        bodies.append(body)

    def read_states(out: np.ndarray) -> None:
        for row, body in zip(out, bodies, strict=True):
            p, v = body.position, body.linear_velocity
            row[:] = (p.x, p.y, body.angle, v.x, v.y, body.angular_velocity)

    dt = scene.dt if dt is None else dt
    return lambda: world.step(dt, substeps), read_states


SCENE_ENGINES: dict[str, Callable] = {"pymunk": build_pymunk, "box2d": build_box2d, "box2d3": build_box2d3}
"""Builders by engine name: ``build(scene, sleep, state, dt) -> (step, read_states)``."""

SCENE_ENGINE_MODULES = {"pymunk": "pymunk", "box2d": "Box2D", "box2d3": "pyb2d3"}
"""The module each engine of SCENE_ENGINES imports (for ``pytest.importorskip`` and availability)."""

DEFAULT_DT = {"pymunk": 1 / 60, "box2d": 1 / 60, "box2d3": BOX2D3_DT}
"""[s] each engine's own default step, as its manual and samples use it (pymunk's and Box2D 2.3's
examples step at 60 Hz as well)."""


def available_scene_engines() -> list[str]:
    """Names in SCENE_ENGINES whose package imports."""
    return [name for name in SCENE_ENGINES if _importable(SCENE_ENGINE_MODULES[name])]


def simulate_scene(
    engine: str,
    scene: Scene,
    steps: int,
    record: bool = True,
    sleep: bool = True,
    state: np.ndarray | None = None,
    dt: float | None = None,
    untimed: int = 0,
) -> SceneRun:
    """Build ``scene`` in ``engine`` and step it ``steps`` times of ``scene.dt``, timing the loop alone
    (with ``record``, reading every box's state after each step is inside the loop: time without it).
    ``sleep=False`` keeps every body awake (Box2D's ``doSleep``; pymunk never sleeps by default);
    ``state`` (n, 6) starts the boxes there instead of at the scene's initial state (e.g. a pile settled
    by another engine, which may overlap a little: no check is made); ``dt`` steps at that instead of
    ``scene.dt`` (e.g. ``DEFAULT_DT[engine]``); ``untimed`` steps are taken first, outside the timing and the
    record (e.g. for Box2D's islands to fall asleep)."""
    if steps < 0 or untimed < 0:
        raise ValueError(f"steps and untimed must be >= 0, got {steps} and {untimed}")
    step, read_states = SCENE_ENGINES[engine](scene, sleep, state, dt)
    for _ in range(untimed):
        step()
    n = scene.n_bodies
    states = None
    if record:
        states = np.empty((steps + 1, n, STATE_SIZE))
        read_states(states[0])
        start = time.perf_counter()
        for i in range(1, steps + 1):
            step()
            read_states(states[i])
        wall = time.perf_counter() - start
    else:
        start = time.perf_counter()
        for _ in range(steps):
            step()
        wall = time.perf_counter() - start
    final = np.empty((n, STATE_SIZE))
    read_states(final)
    return SceneRun(engine, final, wall, steps, states)
