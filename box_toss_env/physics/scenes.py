"""Named scenes, shared by the tests, the benchmarks, the reports and the viewer.

Each is a function returning a ``Scene``; keyword arguments change the parts that are varied.
``SCENES`` maps a name to its function.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .scene import Box, Scene
from .validation import check_integer

# the typical BoxToss throw: a 40 x 20 cm, 2 kg box released at 1.5 m, thrown forward and up
TOSS_BOX = dict(length=0.4, width=0.2, mass=2.0)
TOSS_MATERIAL = dict(restitution=0.3, friction=0.5, penalty_stiffness=1e5)


def seed_demo(seed: int = 0, boxes_collide: bool = False, **scene) -> Scene:
    """The seed demo: five 2 x 1 m boxes of 1 kg at x = 3j - 5, y = 5, at rest, each at a random
    angle in [0, pi); the panel's defaults (dt 0.005 s, g -9.81, k 100, e 0.5, mu 0.02), solved with
    the seed scheme unless ``solver`` says otherwise. ``boxes_collide=True`` lets the boxes collide with
    one another too (the demo's boxes meet only the floor)."""
    angles = np.random.default_rng(seed).uniform(0.0, math.pi, size=5)
    boxes = tuple(
        Box(length=2.0, width=1.0, mass=1.0, position=(3.0 * j - 5.0, 5.0), angle=float(angles[j])) for j in range(5)
    )
    return Scene(boxes=boxes, boxes_collide=boxes_collide, **{"solver": "seed", **scene})


def free_flight(**scene) -> Scene:
    """A box thrown high, spinning, that does not reach the floor within 1 s."""
    box = Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 20.0), angle=0.3, velocity=(3.0, 4.0), spin=7.0)
    return Scene(boxes=(box,), **{"dt": 1 / 256, **scene})


def flat_drop(height: float = 1.0, restitution: float = 0.5, **scene) -> Scene:
    """A 2 x 1 m box dropped level from rest, its bottom face ``height`` above the floor."""
    box = Box(length=2.0, width=1.0, mass=1.0, position=(0.0, height + 0.5))
    return Scene(boxes=(box,), restitution=restitution, **{"friction": 0.0, **scene})


def corner_impact(
    angle: float = 0.4, velocity=(0.0, -3.0), spin: float = 0.0, restitution: float = 0.5, **scene
) -> Scene:
    """A tilted 2 x 1 m box whose lowest corner is 1 mm above the floor, moving down: a single
    corner impact (frictionless by default)."""
    box = Box(length=2.0, width=1.0, mass=1.0, angle=angle, velocity=velocity, spin=spin)
    half = 0.5 * np.array([box.length, box.width])
    lowest = min(math.sin(angle) * sx * half[0] + math.cos(angle) * sy * half[1] for sx in (-1, 1) for sy in (-1, 1))
    box = Box(length=2.0, width=1.0, mass=1.0, position=(0.0, 1e-3 - lowest), angle=angle, velocity=velocity, spin=spin)
    return Scene(boxes=(box,), restitution=restitution, **{"friction": 0.0, "gravity": 0.0, **scene})


def slide(speed: float = 2.0, friction: float = 0.3, **scene) -> Scene:
    """A 40 x 20 cm box lying on the floor, sliding at ``speed``: it stops after v^2 / (2 mu g)."""
    box = Box(**TOSS_BOX, position=(0.0, 0.1), velocity=(speed, 0.0))
    return Scene(boxes=(box,), friction=friction, **{"restitution": 0.5, "dt": 1 / 1024, **scene})


def resting(**scene) -> Scene:
    """A 2 x 1 m box lying still on the floor (with friction, the case where the seed scheme creeps)."""
    box = Box(length=2.0, width=1.0, mass=1.0, position=(0.0, 0.5))
    return Scene(boxes=(box,), **scene)


def bouncing(restitution: float = 1.0, height: float = 1.0, **scene) -> Scene:
    """A box dropped level, for energy conservation with e = 1."""
    return flat_drop(height=height, restitution=restitution, **scene)


def toss(**scene) -> Scene:
    """A typical BoxToss throw: released at 1.5 m, 3 m/s forward and 2 m/s up, spinning 5 rad/s."""
    box = Box(**TOSS_BOX, position=(0.0, 1.5), angle=0.3, velocity=(3.0, 2.0), spin=5.0)
    return Scene(boxes=(box,), **{**TOSS_MATERIAL, "dt": 1 / 256, **scene})


def stiff(**scene) -> Scene:
    """The seed demo's box resting with penalty stiffness 1e5 N/m at dt 0.005 s: omega dt = 2.2 > 2, so the
    seed scheme's explicit penalty spring gains energy at every step in contact and throws the box up."""
    box = Box(length=2.0, width=1.0, mass=1.0, position=(0.0, 0.49))
    return Scene(boxes=(box,), **{"penalty_stiffness": 1e5, **scene})


# -- scenes whose boxes collide with one another (boxes_collide=True) ------------------------------
STACK_BOX: dict[str, Any] = dict(length=0.4, width=0.2)  # the BoxToss box's size, 2 kg unless ``masses`` says otherwise
STACK_MATERIAL = dict(restitution=0.3, friction=0.5, penalty_stiffness=1e5, dt=1 / 256)


def stack(n: int = 10, masses=None, length: float = 0.4, width: float = 0.2, **scene) -> Scene:
    """``n`` boxes lying level in a vertical stack on the floor, each touching the one below, at rest;
    ``masses`` (one per box, bottom first) defaults to 2 kg each."""
    n = check_integer("n", n, 1)
    masses = (2.0,) * n if masses is None else tuple(masses)
    if len(masses) != n:
        raise ValueError(f"masses must hold one mass per box (n = {n}), got {len(masses)}")
    boxes = tuple(Box(length=length, width=width, mass=masses[k], position=(0.0, (k + 0.5) * width)) for k in range(n))
    return Scene(boxes=boxes, boxes_collide=True, **{**STACK_MATERIAL, **scene})


def pyramid(rows: int = 5, length: float = 0.4, width: float = 0.2, spacing: float = 0.04, **scene) -> Scene:
    """A pyramid of rows (rows, rows - 1, ..., 1 boxes from the bottom: 15 for 5 rows), each box lying level
    across two of the row below; boxes of a row ``spacing`` apart, at rest."""
    rows = check_integer("rows", rows, 1)
    boxes = []
    pitch = length + spacing
    for row in range(rows):
        count = rows - row
        for k in range(count):
            boxes.append(
                Box(
                    length=length,
                    width=width,
                    mass=2.0,
                    position=((k - 0.5 * (count - 1)) * pitch, (row + 0.5) * width),
                )
            )
    return Scene(boxes=tuple(boxes), boxes_collide=True, **{**STACK_MATERIAL, **scene})


def drop_on_box(height: float = 0.5, offset: float = 0.05, angle: float = 0.1, **scene) -> Scene:
    """A 40 x 20 cm box dropped from rest, its centre ``height`` above the top of an equal box lying on the
    floor, ``offset`` to the side and tilted by ``angle``: it lands on the lower box and comes to rest on it."""
    lower = Box(**STACK_BOX, mass=2.0, position=(0.0, 0.1))
    upper = Box(**STACK_BOX, mass=2.0, position=(offset, 0.2 + height), angle=angle)
    return Scene(boxes=(lower, upper), boxes_collide=True, **{**STACK_MATERIAL, **scene})


def flight_collision(
    speed: float = 2.0,
    angle: float = 0.4,
    offset: float = 0.0,
    gap: float = 0.2,
    spin: float = 0.0,
    masses=(1.0, 3.0),
    restitution: float = 0.5,
    **scene,
) -> Scene:
    """Two boxes colliding in flight without gravity, 10 m above the floor: a 1 x 0.5 m box tilted by
    ``angle`` moving at ``speed`` along +x (spinning at ``spin``) hits with its right-most corner, ``gap``
    away at the start, the left face of a 2 x 1 m box at rest, ``offset`` above that face's middle
    (frictionless by default: a corner-on-face impact with a closed form)."""
    half_length, half_width = 0.5, 0.25
    corners = [
        (
            math.cos(angle) * sx * half_length - math.sin(angle) * sy * half_width,
            math.sin(angle) * sx * half_length + math.cos(angle) * sy * half_width,
        )
        for sx in (-1, 1)
        for sy in (-1, 1)
    ]
    rx, ry = max(corners)
    moving = Box(
        length=1.0,
        width=0.5,
        mass=masses[0],
        position=(-1.0 - gap - rx, 10.0 + offset - ry),
        angle=angle,
        velocity=(speed, 0.0),
        spin=spin,
    )
    still = Box(length=2.0, width=1.0, mass=masses[1], position=(0.0, 10.0))
    return Scene(
        boxes=(moving, still),
        boxes_collide=True,
        restitution=restitution,
        **{"gravity": 0.0, "friction": 0.0, "dt": 1 / 256, **scene},
    )


def newton_row(n: int = 5, speed: float = 1.0, spacing: float = 0.1, **scene) -> Scene:
    """``n`` equal 40 x 20 cm boxes lying in a row on a frictionless floor, ``spacing`` apart, with e = 1
    and mu = 0; the first slides into the second at ``speed``: momentum passes along the row."""
    n = check_integer("n", n, 1)
    boxes = tuple(
        Box(**STACK_BOX, mass=2.0, position=(k * (0.4 + spacing), 0.1), velocity=(speed if k == 0 else 0.0, 0.0))
        for k in range(n)
    )
    return Scene(
        boxes=boxes,
        boxes_collide=True,
        **{"restitution": 1.0, "friction": 0.0, "penalty_stiffness": 1e5, "dt": 1 / 256, **scene},
    )


def pile(n: int = 10, seed: int = 0, **scene) -> Scene:
    """``n`` 40 x 20 cm boxes dropped onto one another: a loose grid (ceil(sqrt(n)) columns) a little
    above the floor, each box shifted and tilted at random (``seed``), falling into a pile (the
    engine benchmark's pile; one box is a box dropped on the floor)."""
    n = check_integer("n", n, 1)
    rng = np.random.default_rng(seed)
    columns = math.ceil(math.sqrt(n))
    boxes = []
    for k in range(n):
        row, column = divmod(k, columns)
        boxes.append(
            Box(
                **STACK_BOX,
                mass=2.0,
                position=(0.6 * (column - 0.5 * (columns - 1)) + float(rng.uniform(-0.08, 0.08)), 0.15 + 0.3 * row),
                angle=float(rng.uniform(-0.2, 0.2)),
            )
        )
    return Scene(boxes=tuple(boxes), boxes_collide=True, **{**STACK_MATERIAL, **scene})


SCENES = {
    "seed_demo": seed_demo,
    "free_flight": free_flight,
    "flat_drop": flat_drop,
    "corner_impact": corner_impact,
    "slide": slide,
    "resting": resting,
    "bouncing": bouncing,
    "toss": toss,
    "stiff": stiff,
    "stack": stack,
    "pyramid": pyramid,
    "drop_on_box": drop_on_box,
    "flight_collision": flight_collision,
    "newton_row": newton_row,
    "pile": pile,
}
