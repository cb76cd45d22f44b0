"""Box2D v3 (pyb2d3, float32) building the drop as ``benchmarks.other_engines`` builds it for the other engines.

- ``World(gravity=(0, g))`` with the defaults a user gets: contact hertz 30, damping ratio 10, restitution
  threshold 1 m/s (slower impacts are inelastic), sleeping on; ``world.step(dt, 4)`` (v3's recommended 4
  substeps).
- Floor: a static segment from x = -1000 to 1000 m on y = 0. Box: ``b2MakeBox(L/2, W/2)`` with no rounding
  (v3's polygons need no skin: contacts are speculative, with a linear slop of 5 mm), on a dynamic body whose
  mass data are set to mass ``m``, centre 0, moment ``m (L^2 + W^2) / 12``.
- Box2D v3 mixes friction as ``sqrt(mu_a mu_b)`` and restitution as ``max(e_a, e_b)``: both shapes get
  ``mu``, the floor restitution 0, so the pair gets exactly ``mu`` and ``e``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from benchmarks.other_engines import Engine, _import

FLOOR_HALF_LENGTH = 1000.0  # [m]
SUBSTEPS = 4


@dataclass(frozen=True)
class Box2DV3Engine(Engine):
    name: ClassVar[str] = "box2d-v3"
    package: ClassVar[str] = "pyb2d3"
    module: ClassVar[str] = "pyb2d3"

    substeps: int = SUBSTEPS

    def build(self, toss, dt):
        b2 = _import(self.module, self.package)
        world = b2.World(gravity=(0.0, toss.gravity))
        floor = world.create_static_body(position=(0.0, 0.0))
        floor_shape = b2.shape_def()
        floor_shape.material.friction = toss.friction
        floor_shape.material.restitution = 0.0
        floor.create_segment_shape(floor_shape, b2.segment((-FLOOR_HALF_LENGTH, 0.0), (FLOOR_HALF_LENGTH, 0.0)))
        body = world.create_dynamic_body(position=(toss.x, toss.y), rotation=toss.angle)
        box_shape = b2.shape_def(density=1.0)
        box_shape.material.friction = toss.friction
        box_shape.material.restitution = toss.restitution
        body.create_polygon_shape(box_shape, b2.box(toss.length / 2, toss.width / 2))
        mass = body.mass_data
        mass.mass, mass.center, mass.rotational_inertia = toss.mass, (0.0, 0.0), toss.moment
        body.mass_data = mass
        body.linear_velocity = (toss.vx, toss.vy)
        body.angular_velocity = toss.omega
        unwound = [toss.angle]  # Box2D reports the angle in (-pi, pi]: unwrap it as it goes
        alive = (world, floor, body)  # the world is destroyed with its last Python reference: every closure keeps it

        def step():
            world.step(dt, self.substeps)

        def read_state():
            assert alive
            x, y = body.position
            angle = body.angle
            unwound[0] += math.remainder(angle - unwound[0], 2 * math.pi)
            vx, vy = body.linear_velocity
            return (x, y, unwound[0], vx, vy, body.angular_velocity)

        def mass_properties():
            assert alive
            return float(body.mass), float(body.rotational_inertia())

        return step, read_state, mass_properties
