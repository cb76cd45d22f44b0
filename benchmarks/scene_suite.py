"""The named scenes of the engine comparison (``benchmarks.engine_scale``): what each case holds, built from our
``scenes``, ``Scene`` and ``Box`` so that our engine runs exactly as ``scenes.*`` builds a scene (its step, solver
and sleep settings at their defaults: a case sets only what exists, boxes and material), and what every engine is
asked to do with it (``plans``).

    from benchmarks.scene_suite import suite
    for case in suite():
        case.name, case.scene.n_bodies, case.plans

Cases (``SUITE``, in table order):

- piles of 16 and 100 (``scenes.pile``), of 1,000 and 5,000 laid out ``WIDE_LAYERS`` rows high (``wide_pile``; the
  square layout of ``scenes.pile`` would be a 10 m and a 21 m column), dropped, settled and kept awake;
- 100 thin boxes (0.5 x 0.01 m) in a pile, and the pile of 16 scaled to 1 x 0.5 mm boxes (tiny) and to 100 x 50 m
  (huge), mass with the area (the pile's 25 kg/m^2), positions and length limits with the length, speed limits with
  its square root (the same motion at the same Froude number); the huge pile's windows last sqrt(250) times as long
  (it takes that much longer to fall and settle), the tiny pile's keep their length (so that sleeping, whose times
  are every engine's absolute settings, can happen in them);
- the 210-box pyramid (``scenes.pyramid(rows=20)``), a tower of 20 (``scenes.stack(20)``), and 4 light boxes of
  1 kg under one 100 and 1,000 times heavier (``scenes.stack(5, masses=...)``), built at rest;
- a box (the pile's 40 x 20 cm, 2 kg) thrown level into the settled pile of 100 at 10, 30 and 100 m/s, from
  ``THROW_STANDOFF`` m left of the pile at half the height of its rows lying flat (it waits at rest on the floor
  ``PARKED_AT`` m away while the pile settles);
- Box2D's own benchmark scenes ``large_pyramid`` (5,050 unit squares, sleeping off, 500 steps at 60 Hz) and
  ``many_pyramids`` (400 pyramids of 55 unit squares on 20 ground levels 11 m apart, 200 steps), built as Box2D's
  ``shared/benchmarks.c`` builds them (Box2D's defaults: friction 0.6, restitution 0, density 1 kg/m^2, gravity
  -10 m/s^2; the benchmark times every step but the first). Ours has one floor, so ``many_pyramids`` lays its 20
  levels end to end on it (each level's pyramids reach 10 m, 1 m short of the next level: no two levels touch);
  the other engines build the published levels (``Layout``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property, partial

import numpy as np

from benchmarks.other_scenes import Layout
from box_toss_env.physics import Box, Scene, scenes

PILE_BOX = dict(length=0.4, width=0.2, mass=2.0)  # scenes.pile's box
AREA_DENSITY = PILE_BOX["mass"] / (PILE_BOX["length"] * PILE_BOX["width"])  # [kg/m^2]
WIDE_LAYERS = 8
THIN_BOX = dict(length=0.5, width=0.01)
TINY, HUGE = 1 / 400, 250.0  # length scales of the tiny and huge piles (a 40 cm box: 1 mm, 100 m)
LIGHT, HEAVY = 1.0, (100.0, 1000.0)  # [kg] heavy-on-light stacks: 4 light boxes under one heavy
THROW_SPEEDS = (10.0, 30.0, 100.0)  # [m/s]
THROW_PILE = 100
THROW_STANDOFF = 1.5  # [m] launch point: this far left of the pile's leftmost box, at half its rows' height
PARKED_AT = -50.0  # [m] x where the thrown box rests until it is thrown

PILE_MODES = ("drop", "rest", "awake")
STRUCTURE_MODES = ("stand", "awake")
SETTLE = 3.0  # [s] untimed before the rest, awake and throw windows
WINDOW = 2.0  # [s] simulated time of every timed window but the published scenes'
AWAKE_LEAD_IN = 0.5  # [s] untimed before a built structure's awake window (warm contacts in every engine)

BOX2D_HZ = 60  # the published benchmarks' step rate
LARGE_PYRAMID_BASE, LARGE_PYRAMID_STEPS = 100, 500
MANY_PYRAMIDS_BASE, MANY_PYRAMIDS_GRID, MANY_PYRAMIDS_STEPS = 10, 20, 200
BOX2D_DEFAULT_MATERIAL = dict(friction=0.6, restitution=0.0, gravity=-10.0)  # b2DefaultShapeDef, b2DefaultWorldDef


@dataclass(frozen=True)
class Segment:
    """A stretch of a run: ``seconds`` of simulated time, timed and measured if ``label`` is set (the label is the
    table's mode), untimed otherwise; ``throw``, if set, is (body, state row) placed before the stretch begins."""

    seconds: float
    label: str | None = None
    throw: tuple[int, tuple[float, ...]] | None = None


@dataclass(frozen=True)
class Plan:
    """One world per engine: sleeping at the engine's default (``sleep`` True) or off, and its segments in order."""

    sleep: bool
    segments: tuple[Segment, ...]

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(s.label for s in self.segments if s.label)


@dataclass(frozen=True)
class Case:
    """A named scene and what each engine does with it. The scene is built when first asked for (``build``: a
    colliding scene's validation compares every pair of boxes, which takes seconds for many_pyramids)."""

    name: str
    kind: str  # "pile", "structure", "throw" or "published"
    build: Callable[[], Scene | tuple[Scene, Layout]] = field(repr=False)
    plans: tuple[Plan, ...]
    scale: float = 1.0  # length scale against the 40 x 20 cm box (penetration limits and speeds scale with it)
    note: str = ""

    @cached_property
    def built(self) -> tuple[Scene, Layout]:
        made = self.build()
        return made if isinstance(made, tuple) else (made, Layout())

    @property
    def scene(self) -> Scene:
        return self.built[0]

    @property
    def layout(self) -> Layout:
        return self.built[1]

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(label for plan in self.plans for label in plan.labels)


# -- scenes --------------------------------------------------------------------------------------
def grid_boxes(n: int, columns: int, pitch: tuple[float, float], size: dict, seed: int = 0, scale: float = 1.0):
    """``n`` boxes in ``columns`` columns ``pitch`` (x, y) apart from y = 0.15 up, centred on x = 0, each shifted by
    up to 8 cm and tilted by up to 0.2 rad at random (``seed``), as ``scenes.pile`` lays them out; every length
    times ``scale``, mass with the area."""
    rng = np.random.default_rng(seed)
    boxes = []
    for k in range(n):
        row, column = divmod(k, columns)
        x = pitch[0] * (column - 0.5 * (columns - 1)) + float(rng.uniform(-0.08, 0.08))
        angle = float(rng.uniform(-0.2, 0.2))
        boxes.append(
            Box(
                length=size["length"] * scale,
                width=size["width"] * scale,
                mass=size.get("mass", AREA_DENSITY * size["length"] * size["width"]) * scale**2,
                position=(x * scale, (0.15 + pitch[1] * row) * scale),
                angle=angle,
            )
        )
    return tuple(boxes)


def template() -> Scene:
    """A colliding scene as ``scenes`` builds one (its material and every engine setting at its defaults)."""
    return scenes.pile(1)


def wide_pile(n: int, layers: int = WIDE_LAYERS, seed: int = 0) -> Scene:
    """``scenes.pile(n)``'s boxes laid out ``layers`` rows high and ceil(n / layers) columns wide."""
    return template().replace(boxes=grid_boxes(n, math.ceil(n / layers), (0.6, 0.3), PILE_BOX, seed))


def scaled_pile(n: int, scale: float) -> Scene:
    """``scenes.pile(n)``'s layout with every length times ``scale`` and mass with the area."""
    return template().replace(boxes=grid_boxes(n, math.ceil(math.sqrt(n)), (0.6, 0.3), PILE_BOX, scale=scale))


def thin_pile(n: int) -> Scene:
    """``n`` boxes of 0.5 x 0.01 m (0.125 kg: the pile's area density) in ``scenes.pile``'s layout, 0.7 m and
    0.15 m apart."""
    return template().replace(boxes=grid_boxes(n, math.ceil(math.sqrt(n)), (0.7, 0.15), THIN_BOX))


def throw_scene(pile: int = THROW_PILE) -> tuple[Scene, tuple[float, float]]:
    """(``scenes.pile(pile)`` and one more box parked on the floor at PARKED_AT, the launch point: THROW_STANDOFF left
    of the pile's leftmost box, at half the height of its rows lying flat, 1 m for the pile of 100)."""
    base = scenes.pile(pile)
    parked = Box(**PILE_BOX, position=(PARKED_AT, 0.5 * PILE_BOX["width"]))
    left = min(b.position[0] for b in base.boxes) - 0.5 * PILE_BOX["length"]
    rows = math.ceil(pile / math.ceil(math.sqrt(pile)))
    return base.replace(boxes=(*base.boxes, parked)), (left - THROW_STANDOFF, 0.5 * rows * PILE_BOX["width"])


def pyramid_boxes(base: int, extent: float, center_x: float, base_y: float, mass: float) -> list[Box]:
    """Box2D's pyramid of ``base`` squares of half side ``extent`` (``CreateLargePyramid``, ``CreateSmallPyramid``):
    row i (from 0) at y = (2i + 1) extent + base_y, its squares 2 extent apart, touching, from x = (i + 1) extent +
    center_x."""
    boxes = []
    for i in range(base):
        for j in range(i, base):
            x = (i + 1) * extent + 2 * (j - i) * extent + center_x
            y = (2 * i + 1) * extent + base_y
            boxes.append(Box(length=2 * extent, width=2 * extent, mass=mass, position=(x, y)))
    return boxes


def large_pyramid(base: int = LARGE_PYRAMID_BASE) -> tuple[Scene, Layout]:
    """Box2D's ``large_pyramid``: ``base`` (100) unit squares of 1 kg at the bottom, 5,050 in all, on a ground box
    200 x 2 m whose top is y = 0."""
    boxes = pyramid_boxes(base, 0.5, -0.5 * base, 0.0, 1.0)
    ground = Layout(floors=((0.0, -100.0, 100.0),), ground_box=(100.0, 1.0, -1.0))
    return template().replace(boxes=tuple(boxes), **BOX2D_DEFAULT_MATERIAL), ground


def many_pyramids(grid: int = MANY_PYRAMIDS_GRID, base: int = MANY_PYRAMIDS_BASE) -> tuple[Scene, Layout]:
    """Box2D's ``many_pyramids``: ``grid`` levels of ``grid`` pyramids of ``base`` unit squares (55 for 10), a
    segment ground under each level, levels 2 (base + 1) extent apart. Ours: the levels end to end on one floor,
    centred (level k moved by (k - (grid - 1) / 2) times the level's width along x and down to y = 0)."""
    extent = 0.5
    level_height = 2 * extent * (base + 1)
    level_width = 2 * extent * grid * (base + 1)
    boxes, offsets = [], []
    for level in range(grid):
        shift = (level - 0.5 * (grid - 1)) * level_width
        for column in range(grid):
            center_x = -0.5 * level_width + column * (2 * extent * base + 2 * extent) + 2 * extent
            pyramid = pyramid_boxes(base, extent, center_x - 0.5, 0.0, 1.0)
            boxes += [Box(**{**vars(b), "position": (b.position[0] + shift, b.position[1])}) for b in pyramid]
            offsets += [(-shift, level * level_height)] * len(pyramid)
    floors = tuple((k * level_height, -0.5 * level_width, 0.5 * level_width) for k in range(grid))
    scene = template().replace(boxes=tuple(boxes), **BOX2D_DEFAULT_MATERIAL)
    return scene, Layout(offsets=np.array(offsets), floors=floors)


# -- what each engine does -----------------------------------------------------------------------
def pile_plans(window: float, settle: float) -> tuple[Plan, ...]:
    """Dropped (timed from the start, each engine's default sleeping), then at rest in the same world; and kept awake
    (sleeping off) after the same settling."""
    return (
        Plan(True, (Segment(window, "drop"), Segment(settle - window), Segment(window, "rest"))),
        Plan(False, (Segment(settle), Segment(window, "awake"))),
    )


def structure_plans(window: float) -> tuple[Plan, ...]:
    """Standing from the built state (each engine's default sleeping); kept awake after AWAKE_LEAD_IN."""
    return (Plan(True, (Segment(window, "stand"),)), Plan(False, (Segment(AWAKE_LEAD_IN), Segment(window, "awake"))))


def throw_plan(speed: float, body: int, launch: tuple[float, float], window: float, settle: float) -> tuple[Plan]:
    state = (launch[0], launch[1], 0.0, speed, 0.0, 0.0)
    return (Plan(True, (Segment(settle), Segment(window, "throw", throw=(body, state)))),)


def published_plan(steps: int) -> tuple[Plan]:
    """Sleeping off; of ``steps`` steps at 60 Hz the first untimed, the rest timed (each engine at its own step over
    the same simulated time)."""
    return (Plan(False, (Segment(1 / BOX2D_HZ), Segment((steps - 1) / BOX2D_HZ, "published"))),)


def suite(quick: bool = False, window: float = WINDOW, settle: float = SETTLE) -> list[Case]:
    """Every case, in table order (``quick``: the small ones, for tests and CI: the pile of 16, the tower, the
    1000:1 stack, a throw at 30 m/s into a pile of 16 and Box2D's large pyramid of base 10 for 20 steps)."""
    piles = pile_plans(window, settle)
    slow = pile_plans(window * math.sqrt(HUGE), settle * math.sqrt(HUGE))  # the huge pile falls sqrt(250) x as long
    structures = structure_plans(window)
    cases = [Case("pile 16", "pile", partial(scenes.pile, 16), piles)]
    if not quick:
        wide = f"{WIDE_LAYERS} layers wide"
        cases += [
            Case("pile 100", "pile", partial(scenes.pile, 100), piles),
            Case("pile 1000", "pile", partial(wide_pile, 1000), piles, note=wide),
            Case("pile 5000", "pile", partial(wide_pile, 5000), piles, note=wide),
            Case("thin 100", "pile", partial(thin_pile, 100), piles, note="0.5 x 0.01 m boxes"),
            Case("tiny 16", "pile", partial(scaled_pile, 16, TINY), piles, scale=TINY, note="1 x 0.5 mm boxes"),
            Case("huge 16", "pile", partial(scaled_pile, 16, HUGE), slow, scale=HUGE, note="100 x 50 m boxes"),
            Case("pyramid 210", "structure", partial(scenes.pyramid, rows=20), structures),
        ]
    cases.append(Case("tower 20", "structure", partial(scenes.stack, 20), structures))
    for ratio in HEAVY[1:] if quick else HEAVY:
        masses = (LIGHT,) * 4 + (LIGHT * ratio,)
        cases.append(Case(f"heavy {ratio:g}:1", "structure", partial(scenes.stack, 5, masses=masses), structures))
    pile = 16 if quick else THROW_PILE
    thrown, launch = throw_scene(pile)
    for speed in THROW_SPEEDS[1:2] if quick else THROW_SPEEDS:
        plans = throw_plan(speed, thrown.n_bodies - 1, launch, window, settle)
        cases.append(Case(f"throw {speed:g} m/s", "throw", lambda: thrown, plans, note=f"into a pile of {pile}"))
    if quick:
        return [*cases, Case("large_pyramid 55", "published", partial(large_pyramid, 10), published_plan(20))]
    return [
        *cases,
        Case(
            "large_pyramid",
            "published",
            large_pyramid,
            published_plan(LARGE_PYRAMID_STEPS),
            note=f"{LARGE_PYRAMID_STEPS} steps at {BOX2D_HZ} Hz, Box2D v3 on its 200 x 2 m ground box",
        ),
        Case(
            "many_pyramids",
            "published",
            many_pyramids,
            published_plan(MANY_PYRAMIDS_STEPS),
            note=f"{MANY_PYRAMIDS_STEPS} steps at {BOX2D_HZ} Hz, the other engines on Box2D's {MANY_PYRAMIDS_GRID} "
            "ground levels, ours with the levels end to end on its one floor",
        ),
    ]


def case_names(quick: bool = False) -> list[str]:
    return [case.name for case in suite(quick)]
