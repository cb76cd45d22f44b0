"""What the reports measure: cases with exact answers, the seeded BoxToss throws, the report-only
scenes of the stability matrix, and the quantities measured on states (energy, pose errors).

States are the engine's rows ``(x, y, angle, vx, vy, spin)`` (``box_toss_env.physics.layout``).
Every scene is built from a named scene of ``box_toss_env.physics.scenes`` where one fits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from benchmarks.other_engines import Toss
from box_toss_env.envs import arguments, task, task_columns, task_config
from box_toss_env.envs.functional import BoxTossFunctional
from box_toss_env.physics import Box, Scene, layout, scenes

ENV_DEFAULTS = arguments.ENV_DEFAULTS
"""BoxToss-v0's keyword defaults, read from their declaration (``solver``, ``dt``, ``penalty_stiffness``, ...)."""

STIFFNESS = float(ENV_DEFAULTS["penalty_stiffness"])
"""Penalty stiffness of every report scene that does not vary it: the env's default [N/m]."""


def dt_of(exponent: int) -> float:
    """The grid's time step 2^-exponent [s]."""
    return 2.0**-exponent


# -- quantities measured on states -----------------------------------------------------------------
def energy(box: Box, gravity: float, states: np.ndarray) -> np.ndarray:
    """Total energy 0.5 m |v|^2 + 0.5 I omega^2 - m g y of states (..., 6) [J] (g < 0, floor at y = 0)."""
    return kinetic_energy(box, states) - box.mass * gravity * states[..., layout.Y]


def kinetic_energy(box: Box, states: np.ndarray) -> np.ndarray:
    """0.5 m |v|^2 + 0.5 I omega^2 [J]."""
    speed_squared = states[..., layout.VX] ** 2 + states[..., layout.VY] ** 2
    return 0.5 * box.mass * speed_squared + 0.5 * box.inertia * states[..., layout.SPIN] ** 2


def lowest_corner(box: Box, states: np.ndarray) -> np.ndarray:
    """Height of the lowest corner [m]: y - (L/2 |sin a| + W/2 |cos a|)."""
    angle = states[..., layout.ANGLE]
    reach = 0.5 * box.length * np.abs(np.sin(angle)) + 0.5 * box.width * np.abs(np.cos(angle))
    return states[..., layout.Y] - reach


def corner_radius(box: Box) -> float:
    """Distance from the centre to a corner [m]."""
    return 0.5 * math.hypot(box.length, box.width)


def wrap(angle):
    """Angles wrapped to [-pi, pi)."""
    return (np.asarray(angle) + math.pi) % (2.0 * math.pi) - math.pi


def pose_error(state: np.ndarray, exact: np.ndarray, radius: float) -> float:
    """|position error| + radius |angle error| [m]: a bound on how far any point of the box is off."""
    return float(math.hypot(state[0] - exact[0], state[1] - exact[1]) + radius * abs(float(wrap(state[2] - exact[2]))))


def velocity_error(state: np.ndarray, exact: np.ndarray, radius: float) -> float:
    """|velocity error| + radius |spin error| [m/s]: a bound on how wrong any point's velocity is."""
    return float(math.hypot(state[3] - exact[3], state[4] - exact[4]) + radius * abs(state[5] - exact[5]))


def toss_of(scene: Scene) -> Toss:
    """The one-box ``scene`` as the other engines' ``Toss`` (same box, pose, velocity, material)."""
    box = scene.boxes[0]
    return Toss(
        length=box.length,
        width=box.width,
        mass=box.mass,
        x=box.position[0],
        y=box.position[1],
        angle=box.angle,
        vx=box.velocity[0],
        vy=box.velocity[1],
        omega=box.spin,
        gravity=scene.gravity,
        restitution=scene.restitution if box.restitution is None else box.restitution,
        friction=scene.friction if box.friction is None else box.friction,
    )


def with_box(scene: Scene, **changes) -> Scene:
    """``scene`` with its one box changed (``position``, ``mass``, ...)."""
    return scene.replace(boxes=(replace(scene.boxes[0], **changes),))


# -- cases with exact answers ----------------------------------------------------------------------
@dataclass(frozen=True)
class ExactCase:
    """A one-box scene whose answer is known in closed form, and the error of a state against it.

    ``scene(solver, dt)`` is what is simulated for ``steps(dt)`` steps; ``error(state, dt)`` is
    measured on the state reached; ``toss`` is the same scene for the other engines.
    """

    name: str
    title: str
    answer: str  # the closed form, in words
    error_name: str  # what error(state) is, with its unit
    base: Scene
    duration: float  # [s]

    def scene(self, solver: str, dt: float) -> Scene:
        return self.base.replace(solver=solver, dt=dt)

    @property
    def box(self) -> Box:
        return self.base.boxes[0]

    @property
    def toss(self) -> Toss:
        return toss_of(self.base)

    def steps(self, dt: float) -> int:
        return int(round(self.duration / dt))

    def error(self, state: np.ndarray, dt: float) -> float:
        raise NotImplementedError

    def initial_energy(self) -> float:
        return float(energy(self.box, self.base.gravity, self.base.initial_state()[0]))


class FreeFlight(ExactCase):
    """Closed-form parabola and constant spin: x = x0 + v t + g t^2 / 2, a = a0 + w t."""

    def exact(self, time: float) -> np.ndarray:
        box, g = self.box, self.base.gravity
        return np.array(
            [
                box.position[0] + box.velocity[0] * time,
                box.position[1] + box.velocity[1] * time + 0.5 * g * time**2,
                box.angle + box.spin * time,
                box.velocity[0],
                box.velocity[1] + g * time,
                box.spin,
            ]
        )

    def error(self, state, dt):
        return pose_error(state, self.exact(self.steps(dt) * dt), corner_radius(self.box))


class CornerImpact(ExactCase):
    """Zero gravity, no friction: the box flies straight to the floor, its lowest corner hits it,
    and Newton's impact law gives the impulse lam = -(1 + e) u_n / (1/m + rx^2 / I) at that corner,
    so v+ = v- + lam n / m and w+ = w- + rx lam / I; then it flies off without touching again."""

    def corner_height(self, time: float) -> tuple[float, float]:
        """(height, rx) of the lowest corner at ``time`` before the impact."""
        box = self.box
        angle = box.angle + box.spin * time
        c, s = math.cos(angle), math.sin(angle)
        offsets = [
            (c * sx * box.length / 2 - s * sy * box.width / 2, s * sx * box.length / 2 + c * sy * box.width / 2)
            for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))
        ]
        rx, ry = min(offsets, key=lambda r: r[1])
        return box.position[1] + box.velocity[1] * time + ry, rx

    @cached_property
    def contact_time(self) -> float:
        """First root of the lowest corner's height, bracketed on a fine scan, then bisected."""
        times = np.linspace(0.0, self.duration, 20001)
        heights = np.array([self.corner_height(t)[0] for t in times])
        below = np.flatnonzero(heights <= 0.0)
        if below.size == 0:
            raise ValueError(f"{self.name}: the box does not reach the floor within {self.duration} s")
        low, high = times[below[0] - 1], times[below[0]]
        for _ in range(200):
            middle = 0.5 * (low + high)
            if self.corner_height(middle)[0] > 0.0:
                low = middle
            else:
                high = middle
        return 0.5 * (low + high)

    @cached_property
    def after_impact(self) -> np.ndarray:
        """Velocities (vx, vy, w) just after the impact."""
        box, e = self.box, self.base.restitution
        _, rx = self.corner_height(self.contact_time)
        u_n = box.velocity[1] + box.spin * rx
        impulse = -(1.0 + e) * u_n / (1.0 / box.mass + rx * rx / box.inertia)
        return np.array([box.velocity[0], box.velocity[1] + impulse / box.mass, box.spin + rx * impulse / box.inertia])

    def exact(self, time: float) -> np.ndarray:
        box, t_c = self.box, self.contact_time
        vx, vy, spin = self.after_impact
        x_c = box.position[0] + box.velocity[0] * t_c
        y_c = box.position[1] + box.velocity[1] * t_c
        a_c = box.angle + box.spin * t_c
        return np.array([x_c + vx * (time - t_c), y_c + vy * (time - t_c), a_c + spin * (time - t_c), vx, vy, spin])

    def touches_again(self) -> bool:
        """True if after the impact any corner comes back below the floor within the duration."""
        box = self.box
        for time in np.linspace(self.contact_time + 1e-6, self.duration, 4001):
            state = self.exact(time)
            if lowest_corner(box, state) < 0.0:
                return True
        return False

    def error(self, state, dt):
        return velocity_error(state, self.exact(self.steps(dt) * dt), corner_radius(self.box))


class FlatDrop(ExactCase):
    """A level box dropped from rest lands flat at sqrt(2 g h) and rebounds level to the apex e^2 h."""

    @property
    def height(self) -> float:
        """Drop height of the bottom face [m]."""
        return self.box.position[1] - 0.5 * self.box.width

    @staticmethod
    def apex_time(height: float, restitution: float, gravity: float) -> float:
        """Time of the apex after the first bounce: the fall takes sqrt(2 h / g), the rebound e times that."""
        return (1.0 + restitution) * math.sqrt(2.0 * height / -gravity)

    def error(self, state, dt):
        """|apex - e^2 h|, the apex read off the state as lowest corner + vy^2 / (2 g) (exact in flight,
        wherever on the rebound the grid point falls)."""
        g = -self.base.gravity
        apex = float(lowest_corner(self.box, state)) + state[layout.VY] ** 2 / (2.0 * g)
        return abs(apex - self.base.restitution**2 * self.height)


class Slide(ExactCase):
    """A box lying on the floor sliding at v0 stops after v0^2 / (2 mu g)."""

    def error(self, state, dt):
        box, g = self.box, -self.base.gravity
        distance = box.velocity[0] ** 2 / (2.0 * self.base.friction * g)
        return abs(state[layout.X] - box.position[0] - distance)


class Resting(ExactCase):
    """A box lying still on the floor stays where it is (no drift, no energy gain)."""

    def error(self, state, dt):
        return pose_error(state, self.base.initial_state()[0], corner_radius(self.box))


def exact_cases() -> tuple[ExactCase, ...]:
    """The five cases of the precision report, each at the env's penalty stiffness."""
    k = dict(penalty_stiffness=STIFFNESS)
    drop = scenes.flat_drop(height=1.0, restitution=0.5, **k)
    corner = CornerImpact(
        "corner_impact",
        "Frictionless corner impact",
        "Newton's impact law at the lowest corner (zero gravity, e = 0.5, no friction), then free flight",
        "velocity error |dv| + R |dw| at t = 0.25 s [m/s]",
        scenes.corner_impact(angle=0.9, velocity=(0.3, -3.0), spin=1.0, restitution=0.5, **k),
        0.25,
    )
    return (
        FreeFlight(
            "free_flight",
            "Free flight",
            "parabola x0 + v t + g t^2 / 2, angle a0 + w t",
            "pose error |dx| + R |da| at t = 1 s [m]",
            scenes.free_flight(**k),
            1.0,
        ),
        corner,
        FlatDrop(
            "flat_drop",
            "Flat drop",
            "a level drop from h = 1 m rebounds to the apex e^2 h (e = 0.5), no spin",
            "apex error |apex - e^2 h| [m], read at the apex time",
            drop,
            FlatDrop.apex_time(1.0, 0.5, drop.gravity),
        ),
        Slide(
            "slide",
            "Sliding to rest",
            "a box sliding at 2 m/s with mu = 0.3 stops after v0^2 / (2 mu g)",
            "stopping distance error [m] at t = 1.5 s",
            scenes.slide(speed=2.0, friction=0.3, **k),
            1.5,
        ),
        Resting(
            "resting",
            "Resting 10 s",
            "a box lying on the floor does not move (e = 0.5, mu = 0.02)",
            "pose drift |dx| + R |da| at t = 10 s [m]",
            scenes.resting(restitution=0.5, friction=0.02, **k),
            10.0,
        ),
    )


# -- the seeded BoxToss throws -----------------------------------------------------------------------
@dataclass
class Throws:
    """``n`` BoxToss-v0 throws: release poses, targets and dynamics drawn by the env's own sampling
    (``BoxTossFunctional.initial``, as ``task.sample_episodes``) and one fixed action each, uniform in
    [-1, 1]^3, from one seeded generator. ``run`` simulates them as the env does: until each box rests (at most
    ``max_sim_time``), one row per throw in one engine call."""

    config: task_config.TaskConfig
    initial: np.ndarray  # (n, 6) thrown states
    params: np.ndarray  # (n, 7)
    seed: int

    @property
    def n(self) -> int:
        return self.initial.shape[0]

    def core(self, solver: str, dt: float) -> BoxTossFunctional:
        """BoxToss-v0's throw (its default arguments) with ``solver`` and ``dt``: the env's engine settings
        (thresholds, sleep), kernel flags and step count."""
        return BoxTossFunctional(solver=solver, dt=dt)

    def max_steps(self, dt: float) -> int:
        return max(1, math.ceil(self.config.max_sim_time / dt - 1e-9))

    def runner(self, solver: str, dt: float, parallel: bool = False):
        """A closure simulating every throw from its initial state, and the (state, stats) it fills."""
        core = self.core(solver, dt)
        simulator = core.make_simulator(parallel=parallel)
        state = self.initial.copy()
        stats = np.zeros((self.n, layout.STATS_SIZE))

        def run():
            state[:] = self.initial
            simulator.run(state, self.params, core.settings, stats)

        return run, state, stats

    def run(self, solver: str, dt: float, parallel: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(final states (n, 6), stats (n, STATS_SIZE)) of every throw."""
        run, state, stats = self.runner(solver, dt, parallel)
        run()
        return state.copy(), stats.copy()

    @cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) of (x, y) that no throw can leave: the env's observation bounds, which follow
        from the throw's energy; a landing outside them is a blow-up."""
        low, high = task.observation_bounds(self.config, self.config.max_sim_time)
        return low[task_columns.OBS_X : task_columns.OBS_Y + 1].astype(float), high[
            task_columns.OBS_X : task_columns.OBS_Y + 1
        ].astype(float)

    def blown_up(self, states: np.ndarray, stats: np.ndarray) -> np.ndarray:
        """(n,) True where a throw went non-finite or landed where its energy cannot take it."""
        low, high = self.bounds
        finite = (stats[:, layout.STATUS] == layout.STATUS_OK) & np.isfinite(states).all(axis=1)
        inside = ((states[:, :2] >= low) & (states[:, :2] <= high)).all(axis=1)
        return ~(finite & inside)


def seeded_throws(n: int = 256, seed: int = 2024) -> Throws:
    """``n`` throws of BoxToss-v0 with its default arguments (see ``Throws``): the env's own throw
    (``BoxTossFunctional``) draws the episodes and launches the boxes."""
    core = BoxTossFunctional()
    rng = np.random.default_rng(seed)
    batch = core.initial(rng, core.empty(n))
    actions = rng.uniform(-1.0, 1.0, size=(n, task_columns.ACTION_SIZE))
    core.launch(batch, core.check_actions(actions, (n, task_columns.ACTION_SIZE)))
    return Throws(config=core.config, initial=batch.state.copy(), params=batch.params.copy(), seed=seed)


# -- report-only scenes of the stability matrix ---------------------------------------------------------
def fast_impact(speed: float, **scene) -> Scene:
    """The toss box falling corner first (angle 0.3) at ``speed`` from 3 m, e = 0, mu = 0.5."""
    base = scenes.toss(restitution=0.0, friction=0.5, penalty_stiffness=STIFFNESS, **scene)
    return with_box(base, position=(0.0, 3.0), angle=0.3, velocity=(0.0, -speed), spin=0.0)


def spinning_landing(spin: float, **scene) -> Scene:
    """The toss box released 0.5 m up, moving (1, -2) m/s and spinning at ``spin`` [rad/s]."""
    base = scenes.toss(penalty_stiffness=STIFFNESS, **scene)
    return with_box(base, position=(0.0, 0.5), angle=0.3, velocity=(1.0, -2.0), spin=spin)


def thin_toss(ratio: float, **scene) -> Scene:
    """The typical toss with a 1 m long, 2 kg box of width 1/ratio m."""
    return with_box(scenes.toss(penalty_stiffness=STIFFNESS, **scene), length=1.0, width=1.0 / ratio)


def mass_toss(mass: float, **scene) -> Scene:
    """The typical toss with the box's mass changed and the material (e, mu, k) unchanged."""
    return with_box(scenes.toss(penalty_stiffness=STIFFNESS, **scene), mass=mass)


def far_toss(x: float, **scene) -> Scene:
    """The typical toss released at horizontal position ``x`` [m]."""
    base = scenes.toss(penalty_stiffness=STIFFNESS, **scene)
    return with_box(base, position=(x, base.boxes[0].position[1]))


def embedded(share: float = 0.25, **scene) -> Scene:
    """The 2 x 1 m resting box started with ``share`` of its height inside the floor, at rest."""
    base = scenes.resting(**{"penalty_stiffness": STIFFNESS, **scene})
    box = base.boxes[0]
    return with_box(base, position=(0.0, 0.5 * box.width - share * box.width))


def friction_corner_hit(
    friction: float, restitution: float, angle: float = 0.4, velocity=(2.0, -3.0), spin: float = 1.0, **scene
) -> Scene:
    """An angled corner hit with friction in zero gravity (``scenes.corner_impact``), so its kinetic
    energy can only fall."""
    return scenes.corner_impact(
        angle=angle,
        velocity=velocity,
        spin=spin,
        restitution=restitution,
        **{"friction": friction, "penalty_stiffness": STIFFNESS, **scene},
    )


def tipping_box(restitution: float, friction: float, **scene) -> Scene:
    """The toss box standing still on one corner (angle 0.3) and sliding at 1 m/s: it tips over, and its other
    corner slams down while the first one is held, an impact that happens in the robust solver's contact mode."""
    base = scenes.toss(restitution=restitution, friction=friction, penalty_stiffness=STIFFNESS, **scene)
    box = base.boxes[0]
    angle = 0.3
    reach = 0.5 * box.length * math.sin(angle) + 0.5 * box.width * math.cos(angle)  # centre above the lowest corner
    return with_box(base, position=(0.0, reach), angle=angle, velocity=(1.0, 0.0), spin=0.0)


# -- scenes of several boxes that collide ---------------------------------------------------------------------
def scene_energy(scene: Scene, states: np.ndarray) -> np.ndarray:
    """(T,) total energy of every box of ``scene`` in states (T, n, 6) [J]."""
    return sum(energy(box, scene.gravity, states[:, i]) for i, box in enumerate(scene.boxes))


def scene_kinetic_energy(scene: Scene, states: np.ndarray) -> np.ndarray:
    """(T,) kinetic energy of every box of ``scene`` in states (T, n, 6) [J]."""
    return sum(kinetic_energy(box, states[:, i]) for i, box in enumerate(scene.boxes))


def box_overlap(a: Box, b: Box, state_a: np.ndarray, state_b: np.ndarray) -> np.ndarray:
    """(...,) how deep two boxes overlap [m]: the smallest overlap of their projections on the four face
    normals (separating axes), 0 where one of them separates the boxes."""
    half = {id(a): (0.5 * a.length, 0.5 * a.width), id(b): (0.5 * b.length, 0.5 * b.width)}
    axes_of = {}
    for box, state in ((a, state_a), (b, state_b)):
        c, s = np.cos(state[..., layout.ANGLE]), np.sin(state[..., layout.ANGLE])
        axes_of[id(box)] = ((c, s), (-s, c))
    d = (state_b[..., layout.X] - state_a[..., layout.X], state_b[..., layout.Y] - state_a[..., layout.Y])
    depth = np.full(np.shape(d[0]), np.inf)
    for axis in (*axes_of[id(a)], *axes_of[id(b)]):
        reach = sum(
            h * np.abs(axis[0] * u[0] + axis[1] * u[1])
            for box in (a, b)
            for h, u in zip(half[id(box)], axes_of[id(box)], strict=True)
        )
        depth = np.minimum(depth, reach - np.abs(axis[0] * d[0] + axis[1] * d[1]))
    return np.maximum(depth, 0.0)


def deepest_overlaps(scene: Scene, states: np.ndarray) -> tuple[float, float]:
    """(the deepest any two boxes of ``scene`` overlap, the deepest any box goes below the floor) over the
    states (T, n, 6) [m]."""
    boxes = scene.boxes
    floor = max(float(-lowest_corner(box, states[:, i]).min()) for i, box in enumerate(boxes))
    between = 0.0
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            between = max(between, float(box_overlap(boxes[i], boxes[j], states[:, i], states[:, j]).max()))
    return between, max(floor, 0.0)


def stack(n: int, **scene) -> Scene:
    """``scenes.stack`` of ``n`` boxes at the env's penalty stiffness."""
    return scenes.stack(n=n, **{"penalty_stiffness": STIFFNESS, **scene})


MASS_ORDERS = {"heavy on top": (0, 1), "heavy below": (1, 0), "light between heavy": (1, 0, 1)}
"""A mass-ratio stack's boxes from the bottom: 1 the heavy box, 0 the light one."""


def mass_ratio_stack(ratio: float, order: str, **scene) -> Scene:
    """A stack of ``scenes.stack`` whose boxes weigh the stack's mass (light) or ``ratio`` times it (heavy) in the
    ``order`` of MASS_ORDERS, material unchanged."""
    light = scenes.stack(n=1).boxes[0].mass
    pattern = MASS_ORDERS[order]
    return stack(len(pattern), masses=tuple(light * ratio if heavy else light for heavy in pattern), **scene)


def body_impact(speed: float, onto_floor: bool, **scene) -> Scene:
    """The toss box (corner first, angle 0.3) hitting a level toss box at ``speed``, e = 0, mu = 0.5. In flight
    (zero gravity): it flies along x into the other box at rest 0.5 m away. Onto the floor: it falls on the other
    box lying on the floor, its lowest corner 0.5 m above it."""
    material = {**scenes.TOSS_MATERIAL, "restitution": 0.0, "friction": 0.5, "penalty_stiffness": STIFFNESS}
    size = scenes.TOSS_BOX
    angle = 0.3
    reach_x = 0.5 * size["length"] * math.cos(angle) + 0.5 * size["width"] * math.sin(angle)
    reach_y = 0.5 * size["length"] * math.sin(angle) + 0.5 * size["width"] * math.cos(angle)
    if onto_floor:
        boxes = (
            Box(**size, position=(0.0, 0.5 * size["width"])),
            Box(**size, position=(0.05, size["width"] + 0.5 + reach_y), angle=angle, velocity=(0.0, -speed)),
        )
        return Scene(boxes=boxes, boxes_collide=True, **{**material, "dt": 1 / 256, **scene})
    boxes = (
        Box(**size, position=(-0.5 - reach_x - 0.5 * size["length"], 10.0), angle=angle, velocity=(speed, 0.0)),
        Box(**size, position=(0.0, 10.05)),
    )
    return Scene(boxes=boxes, boxes_collide=True, **{**material, "gravity": 0.0, "dt": 1 / 256, **scene})
