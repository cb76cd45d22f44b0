"""Any box_toss_env ``Scene`` (several boxes, their material, dt, gravity) as a pymunk space, a Box2D 2.3
world and a Box2D v3 world, stepped for N steps, states back in our layout.

``benchmarks.other_engines`` throws one box; this module builds a whole scene the same way, so the
multi-box comparison (``reports.collisions``) and the pile benchmark (``benchmarks.engine``) run the
same boxes in every engine.

Usage::

    from benchmarks.other_scenes import SCENE_ENGINES, make_world, simulate_scene

    run = simulate_scene("pymunk", scene, steps=720)        # record=True by default
    run.states            # (steps + 1, n, 6): x, y, angle, vx, vy, spin per box, as our Trajectory.state
    run.ns_per_body_step  # CPU time of the stepping loop / (steps * n)

    world = make_world("box2d3", scene, sleep=True)         # a world to step on: the engine comparison's
    seconds = world.advance(60)                             # thread CPU time of 60 steps, the loop alone
    world.read_states(out); world.asleep(); world.place(body, state_row)

Conventions and settings
------------------------
Everything ``benchmarks.other_engines`` states holds here (state layout, uniform boxes of mass m and
moment m (L^2 + W^2) / 12, semi-implicit Euler, timing of the stepping loop alone, a fresh world per
call; thread CPU time, ``time.thread_time``). Each engine runs with its documented defaults except where the scene
says otherwise:

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
  ``Box2D3Settings`` turns its substeps and its contact tuning (``World.set_contact_tuning``: contact hertz,
  damping ratio, push speed; left alone at Box2D's defaults unless one is given) for ``benchmarks.pile_pareto``.
- **Layout** (``scene_suite.Layout``): a scene may place the bodies elsewhere in the other engines (body i at ours
  plus an offset) on other static ground (segments at given heights; in Box2D v3 a ground box), as Box2D's
  ``many_pyramids`` stacks its levels where ours has one floor; states are read back in our frame.
- **MuJoCo** is not built here: its soft contacts are the subject of ``other_engines``' single-box
  comparison; the multi-box comparison is between impulse engines.

A scene an engine cannot represent (per-box material where the engine's mixing rule cannot give it,
sides Box2D's skin does not fit) raises ``UnsupportedScene`` with the reason.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

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
BOX2D3_SUBSTEPS = 4  # Box2D v3's documented default (b2World_Step(world, 1/60, 4) in its manual and samples)
BOX2D3_DT = 1 / 60  # [s] its documented default step
BOX2D3_FLOOR_HALF_LENGTH = 1.0e3  # [m] float32 engine, as Box2D 2.3
BOX2D3_CONTACT = {"contact_hertz": 30.0, "damping_ratio": 10.0, "push": 3.0}
"""Box2D v3's default contact tuning (``b2DefaultWorldDef``: contactHertz 30, contactDampingRatio 10,
contactPushMaxVelocity 3 m/s), used to fill the values a ``Box2D3Settings`` leaves unset."""


class UnsupportedScene(ValueError):
    """The engine cannot represent this scene as we define it; the message says why."""


@dataclass(frozen=True)
class Layout:
    """Where the other engines put the bodies when not where ours has them: body i at ours + ``offsets[i]``, on the
    static ``floors`` (y, x from, x to) instead of one floor y = 0; in Box2D v3 ``ground_box`` (half width, half
    height, centre y), if set, is the ground instead, as Box2D's large_pyramid builds it."""

    offsets: np.ndarray | None = None  # (n, 2) [m]
    floors: tuple[tuple[float, float, float], ...] | None = None
    ground_box: tuple[float, float, float] | None = None

    def segments(self, half_length: float) -> tuple[tuple[float, float, float], ...]:
        return self.floors if self.floors is not None else ((0.0, -half_length, half_length),)

    def shift(self, n: int) -> np.ndarray:
        return np.zeros((n, 2)) if self.offsets is None else np.asarray(self.offsets, dtype=float)


@dataclass(frozen=True)
class Box2D3Settings:
    """What a Box2D v3 user can turn: substeps per step, and the contact tuning (None: Box2D's default)."""

    substeps: int = BOX2D3_SUBSTEPS
    contact_hertz: float | None = None
    damping_ratio: float | None = None
    push: float | None = None  # [m/s] the most its soft contacts push overlapping bodies apart

    @property
    def tuned(self) -> bool:
        return any(value is not None for value in (self.contact_hertz, self.damping_ratio, self.push))

    def contact(self) -> tuple[float, float, float]:
        given = {"contact_hertz": self.contact_hertz, "damping_ratio": self.damping_ratio, "push": self.push}
        return tuple(BOX2D3_CONTACT[k] if v is None else v for k, v in given.items())  # type: ignore[return-value]


@dataclass
class World:
    """One engine's world of a scene, stepped on: ``advance`` times its stepping loop alone."""

    engine: str
    dt: float
    step: Callable[[], object]
    read_states: Callable[[np.ndarray], None]  # into an (n, 6) array, our frame
    asleep: Callable[[], np.ndarray]  # (n,) bool
    place: Callable[[int, Sequence[float]], None]  # one body's state (x, y, angle, vx, vy, spin), woken
    keep: list = field(default_factory=list, repr=False)  # what must outlive the step closure

    def advance(self, steps: int) -> float:
        """Thread CPU seconds of ``steps`` steps (the loop alone, no state read)."""
        step = self.step
        began = time.thread_time()
        for _ in range(steps):
            step()
        return time.thread_time() - began


@dataclass(frozen=True)
class SceneRun:
    """What one engine did with one scene."""

    engine: str
    final_state: np.ndarray  # (n, 6) after ``steps`` steps
    wall_seconds: float  # thread CPU time of the stepping loop alone [s]
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


def one_friction(scene: Scene, engine: str) -> float:
    """The friction every box shares (Box2D mixes sqrt(mu_a mu_b)), checking restitution mixes for colliding boxes."""
    mixed = set(materials(scene))
    if len({mu for _, mu in mixed}) > 1:
        raise UnsupportedScene(
            f"{engine} needs one friction for every box (it mixes sqrt(mu_a mu_b), so no floor "
            f"friction gives each box its own); this scene has {sorted(mixed)}"
        )
    if boxes_collide(scene) and len(mixed) > 1:
        one_material(scene, engine, "that collide (it mixes restitution as max(e_a, e_b))")
    return next(iter(mixed))[1]


def starts(scene: Scene, state: np.ndarray | None, layout: Layout) -> np.ndarray:
    """(n, 6) start of every body in the engine's frame."""
    start = (scene.initial_state() if state is None else np.array(state, dtype=float)).copy()
    start[:, :2] += layout.shift(scene.n_bodies)
    return start


def reader(bodies: list, pose: Callable, shift: np.ndarray) -> Callable[[np.ndarray], None]:
    """read_states over ``bodies``: ``pose(body)`` gives (x, y, angle, vx, vy, spin) in the engine's frame."""

    def read_states(out: np.ndarray) -> None:
        for row, body in zip(out, bodies, strict=True):
            row[:] = pose(body)
        out[:, :2] -= shift

    return read_states


def world_pymunk(
    scene: Scene,
    sleep: bool = True,
    state: np.ndarray | None = None,
    dt: float | None = None,
    iterations: int = PYMUNK_ITERATIONS,
    layout: Layout = Layout(),  # noqa: B008 (frozen)
) -> World:
    """A pymunk space of ``scene``. pymunk does not sleep by default (``sleep_time_threshold`` infinite), so
    ``sleep`` changes nothing; ``dt`` replaces the scene's step."""
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
    for y, x0, x1 in layout.segments(PYMUNK_FLOOR_HALF_LENGTH):
        floor = pymunk.Segment(space.static_body, (x0, y), (x1, y), 0.0)
        floor.elasticity, floor.friction = floor_e, floor_mu
        space.add(floor)
    bodies = []
    for box, (e, mu), (x, y, angle, vx, vy, spin) in zip(
        scene.boxes, box_material, starts(scene, state, layout), strict=True
    ):
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

    def pose(body):
        p, v = body.position, body.velocity
        return p.x, p.y, body.angle, v.x, v.y, body.angular_velocity

    shift = layout.shift(scene.n_bodies)

    def place(i: int, row: Sequence[float]) -> None:
        body = bodies[i]
        body.position = (row[0] + shift[i, 0], row[1] + shift[i, 1])
        body.angle, body.velocity, body.angular_velocity = row[2], (row[3], row[4]), row[5]
        space.reindex_shapes_for_body(body)

    dt = scene.dt if dt is None else dt
    return World(
        "pymunk",
        dt,
        lambda: space.step(dt),
        reader(bodies, pose, shift),
        lambda: np.array([body.is_sleeping for body in bodies]),
        place,
        [space],
    )


def world_box2d(
    scene: Scene,
    sleep: bool = True,
    state: np.ndarray | None = None,
    dt: float | None = None,
    iterations: tuple[int, int] = BOX2D_ITERATIONS,
    layout: Layout = Layout(),  # noqa: B008 (frozen)
) -> World:
    """A Box2D 2.3 world of ``scene``. ``sleep=False`` keeps every body awake: ``doSleep=False`` on the world alone
    does not (bodies still fall asleep), so each body also gets ``sleepingAllowed=False``. ``dt`` replaces the
    scene's step; ``iterations`` (velocity, position) the manual's 8 and 3."""
    Box2D = _import("Box2D", "box2d")
    world = Box2D.b2World(gravity=(0.0, scene.gravity), doSleep=sleep)
    skin = Box2D.b2_polygonRadius
    floor_mu = one_friction(scene, "box2d")
    for k, box in enumerate(scene.boxes):
        if min(box.length, box.width) <= 2.0 * skin:
            raise UnsupportedScene(
                f"box2d needs sides above 2 b2_polygonRadius = {2 * skin:.3g} m; box {k} is "
                f"{box.length:g} x {box.width:g} m"
            )
    group = 0 if boxes_collide(scene) else -1  # a shared negative group never collides with itself
    ground = world.CreateStaticBody(position=(0.0, 0.0))
    for y, x0, x1 in layout.segments(BOX2D_FLOOR_HALF_LENGTH):
        ground.CreateEdgeFixture(vertices=[(x0, y - skin), (x1, y - skin)], friction=floor_mu, restitution=0.0)
    bodies = []
    for box, (e, mu), (x, y, angle, vx, vy, spin) in zip(
        scene.boxes, materials(scene), starts(scene, state, layout), strict=True
    ):
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

    def pose(body):
        p, v = body.position, body.linearVelocity
        return p.x, p.y, body.angle, v.x, v.y, body.angularVelocity

    shift = layout.shift(scene.n_bodies)

    def place(i: int, row: Sequence[float]) -> None:
        body = bodies[i]
        body.transform = ((row[0] + shift[i, 0], row[1] + shift[i, 1]), row[2])
        body.linearVelocity, body.angularVelocity = (row[3], row[4]), row[5]
        body.awake = True

    dt = scene.dt if dt is None else dt
    velocity_iterations, position_iterations = iterations
    return World(
        "box2d",
        dt,
        lambda: world.Step(dt, velocity_iterations, position_iterations),
        reader(bodies, pose, shift),
        lambda: np.array([not body.awake for body in bodies]),
        place,
        [world],
    )


def world_box2d3(
    scene: Scene,
    sleep: bool = True,
    state: np.ndarray | None = None,
    dt: float | None = None,
    settings: Box2D3Settings = Box2D3Settings(),  # noqa: B008 (frozen)
    layout: Layout = Layout(),  # noqa: B008 (frozen)
) -> World:
    """A Box2D v3 world (pyb2d3, float32) of ``scene``.

    Box2D v3 at its defaults but for gravity: soft-step solver with ``settings.substeps`` substeps per step
    (``world.step(dt, 4)``), contact hertz 30, restitution only above 1 m/s of approach, sleeping on, continuous
    collision against static bodies; ``settings`` may turn the contact tuning. ``dt`` replaces the scene's step
    (None: the scene's). ``sleep=False`` turns sleeping off on the world and on every body (``enable_sleep=False``).
    Skin: v3 polygons have radius 0 (``b2MakeBox``) and its contacts are speculative, with no skin, so each box is
    the plain L x W polygon and the floor a segment on y = 0: surfaces meet where ours do. Mixing as 2.3 (and as
    documented for v3's default callbacks): friction ``sqrt(mu_a mu_b)``, restitution ``max(e_a, e_b)``, so the
    floor gets mu and e = 0. Mass and moment come from the density m / (L W) on the full box: m and
    m (L^2 + W^2) / 12, to float32 rounding. States are read in one call per quantity (``Bodies``), the angle from
    the rotation's cosine and sine.
    """
    b2 = _import("pyb2d3", "pyb2d3")
    floor_mu = one_friction(scene, "box2d3")
    world = b2.World(gravity=(0.0, scene.gravity))
    world.sleeping_enabled = sleep
    if settings.tuned:
        world.set_contact_tuning(*settings.contact())
    ground = box2d3_ground(b2, world, layout, floor_mu)
    group = 0 if boxes_collide(scene) else -1  # a shared negative group never collides with itself
    bodies, batch = [], b2.Bodies()
    for box, (e, mu), (x, y, angle, vx, vy, spin) in zip(
        scene.boxes, materials(scene), starts(scene, state, layout), strict=True
    ):
        body = world.create_dynamic_body(
            position=(float(x), float(y)),
            rotation=b2.Rot(float(angle)),
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
        batch.append(body)
    shift = layout.shift(scene.n_bodies)

    def read_states(out: np.ndarray) -> None:
        rotation = batch.get_rotations()
        out[:, :2] = batch.get_positions() - shift
        out[:, 2] = np.arctan2(rotation[:, 1], rotation[:, 0])
        out[:, 3:5] = batch.get_linear_velocities()
        out[:, 5] = batch.get_angular_velocities()

    def place(i: int, row: Sequence[float]) -> None:
        body = bodies[i]
        body.set_transform((float(row[0] + shift[i, 0]), float(row[1] + shift[i, 1])), b2.Rot(float(row[2])))
        body.linear_velocity, body.angular_velocity = (float(row[3]), float(row[4])), float(row[5])
        body.awake = True

    dt = scene.dt if dt is None else dt
    substeps = settings.substeps
    return World(
        "box2d3",
        dt,
        lambda: world.step(dt, substeps),
        read_states,
        lambda: np.array([not body.awake for body in bodies]),
        place,
        [world, ground, batch],
    )


def box2d3_ground(b2, world, layout: Layout, friction: float):
    """The static ground of a Box2D v3 world: the layout's ground box, else its floor segments (e = 0)."""
    material = b2.shape_def(material=b2.surface_material(friction=friction, restitution=0.0))
    if layout.ground_box is not None:
        half_width, half_height, centre_y = layout.ground_box
        ground = world.create_static_body(position=(0.0, centre_y))
        ground.create_polygon_shape(material, b2.box(half_width, half_height))
        return ground
    ground = world.create_static_body(position=(0.0, 0.0))
    for y, x0, x1 in layout.segments(BOX2D3_FLOOR_HALF_LENGTH):
        ground.create_segment_shape(material, b2.segment((x0, y), (x1, y)))
    return ground


def build_pymunk(scene, sleep=True, state=None, dt=None, iterations: int = PYMUNK_ITERATIONS):
    """(step, read_states) of ``world_pymunk``."""
    world = world_pymunk(scene, sleep, state, dt, iterations)
    return world.step, world.read_states


def build_box2d(scene, sleep=True, state=None, dt=None):
    """(step, read_states) of ``world_box2d``."""
    world = world_box2d(scene, sleep, state, dt)
    return world.step, world.read_states


def build_box2d3(scene, sleep=True, state=None, dt=None, substeps: int = BOX2D3_SUBSTEPS):
    """(step, read_states) of ``world_box2d3`` at ``substeps`` substeps."""
    world = world_box2d3(scene, sleep, state, dt, Box2D3Settings(substeps=substeps))
    return world.step, world.read_states


WORLDS: dict[str, Callable[..., World]] = {"pymunk": world_pymunk, "box2d": world_box2d, "box2d3": world_box2d3}
"""World builders by engine name: ``make(scene, sleep, state, dt, ..., layout=...) -> World``."""

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


def make_world(engine: str, scene: Scene, sleep: bool = True, layout: Layout | None = None, **options) -> World:
    """``engine``'s world of ``scene`` at its own default step (``DEFAULT_DT``) unless ``options`` give ``dt``;
    ``options`` also pass ``state``, ``iterations`` (pymunk) or ``settings`` (Box2D v3)."""
    options.setdefault("dt", DEFAULT_DT[engine])
    return WORLDS[engine](scene, sleep, layout=layout or Layout(), **options)


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
    ``state`` (n, 6) starts the boxes there instead of at the scene's initial state (no check is made for
    overlaps); ``dt`` steps at that instead of ``scene.dt`` (e.g. ``DEFAULT_DT[engine]``); ``untimed`` steps are
    taken first, outside the timing and the record (e.g. for Box2D's islands to fall asleep)."""
    if steps < 0 or untimed < 0:
        raise ValueError(f"steps and untimed must be >= 0, got {steps} and {untimed}")
    world = WORLDS[engine](scene, sleep, state, dt)
    world.advance(untimed)
    n = scene.n_bodies
    states = None
    if record:
        states = np.empty((steps + 1, n, STATE_SIZE))
        world.read_states(states[0])
        began = time.thread_time()
        for i in range(1, steps + 1):
            world.step()
            world.read_states(states[i])
        wall = time.thread_time() - began
    else:
        wall = world.advance(steps)
    final = np.empty((n, STATE_SIZE))
    world.read_states(final)
    return SceneRun(engine, final, wall, steps, states)
