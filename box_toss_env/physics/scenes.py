"""Named scenes, shared by the tests, the benchmarks, the reports and the viewer.

Each is a function returning a ``Scene``; keyword arguments change the parts that are varied.
``SCENES`` maps a name to its function.
"""

from __future__ import annotations

import math

import numpy as np

from .scene import Box, Scene

# the typical BoxToss throw: a 40 x 20 cm, 2 kg box released at 1.5 m, thrown forward and up
TOSS_BOX = dict(length=0.4, width=0.2, mass=2.0)
TOSS_MATERIAL = dict(restitution=0.3, friction=0.5, penalty_stiffness=1e5)


def seed_demo(seed: int = 0, **scene) -> Scene:
    """The seed demo: five 2 x 1 m boxes of 1 kg at x = 3j - 5, y = 5, at rest, each at a random
    angle in [0, pi); the panel's defaults (dt 0.005 s, g -9.81, k 100, e 0.5, mu 0.02), solved with
    the seed scheme unless ``solver`` says otherwise."""
    angles = np.random.default_rng(seed).uniform(0.0, math.pi, size=5)
    boxes = tuple(Box(length=2.0, width=1.0, mass=1.0, position=(3.0 * j - 5.0, 5.0), angle=float(angles[j]))
                  for j in range(5))
    return Scene(boxes=boxes, **{"solver": "seed", **scene})


def free_flight(**scene) -> Scene:
    """A box thrown high, spinning, that does not reach the floor within 1 s."""
    box = Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 20.0), angle=0.3, velocity=(3.0, 4.0), spin=7.0)
    return Scene(boxes=(box,), **{"dt": 1 / 256, **scene})


def flat_drop(height: float = 1.0, restitution: float = 0.5, **scene) -> Scene:
    """A 2 x 1 m box dropped level from rest, its bottom face ``height`` above the floor."""
    box = Box(length=2.0, width=1.0, mass=1.0, position=(0.0, height + 0.5))
    return Scene(boxes=(box,), restitution=restitution, **{"friction": 0.0, **scene})


def corner_impact(angle: float = 0.4, velocity=(0.0, -3.0), spin: float = 0.0, restitution: float = 0.5,
                  **scene) -> Scene:
    """A tilted 2 x 1 m box whose lowest corner is 1 mm above the floor, moving down: a single
    corner impact (frictionless by default)."""
    box = Box(length=2.0, width=1.0, mass=1.0, angle=angle, velocity=velocity, spin=spin)
    half = 0.5 * np.array([box.length, box.width])
    lowest = min(math.sin(angle) * sx * half[0] + math.cos(angle) * sy * half[1]
                 for sx in (-1, 1) for sy in (-1, 1))
    box = Box(length=2.0, width=1.0, mass=1.0, position=(0.0, 1e-3 - lowest), angle=angle, velocity=velocity,
              spin=spin)
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
}
