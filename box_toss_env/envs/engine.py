"""The engine a task runs on, set up once from what the task asks of it: ``make_engine(config)``.

Both cores take their engine from here: the one-throw core (``functional.BoxTossFunctional``: ``BoxToss-v0``,
its variants, the oracle) and the multi-throw core (``multi_throw.MultiThrowFunctional``: ``BoxToss-Stack-v0``,
``BoxToss-HiddenPhysics-v0``). A task states the largest box it throws, its material and its solver settings
(``EngineConfig``); the engine's ``Scene`` validates them (naming what is wrong) and ``make_engine`` returns the
solver, the time step, the step budget of a throw, the compile-time switches of the kernel and the settings
array the kernel reads.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from box_toss_env.physics import Box, KernelFlags, Scene, make_settings
from box_toss_env.physics.ranges import check_step_count


@dataclass(frozen=True)
class EngineConfig:
    """What a task asks of the engine (SI units).

    Attributes:
        box_size: (length, width) of the largest box thrown [m].
        mass: the largest mass thrown [kg].
        release: (x, y) of a release point [m].
        gravity: gravitational acceleration, pointing down [m/s^2].
        restitution, friction: the largest restitution and friction coefficient of any body.
        penalty_stiffness: stiffness of the penetration correction [N/m].
        solver: "robust" or "seed" (``physics.SOLVERS``).
        dt: the solver's time step [s].
        max_sim_time: simulated time after which a throw ends anyway [s].
        boxes_collide: whether the bodies of a scene meet one another (box-box contact compiled in).
    """

    box_size: tuple[float, float]
    mass: float
    release: tuple[float, float]
    gravity: float
    restitution: float
    friction: float
    penalty_stiffness: float
    solver: str
    dt: float
    max_sim_time: float
    boxes_collide: bool


@dataclass(frozen=True)
class Engine:
    """The engine of a task's throws (``make_engine``).

    Attributes:
        solver, dt: the engine's solver and time step [s].
        max_steps: the most time steps of a throw (``max_sim_time`` in whole steps, at least 1).
        flags: the compile-time switches of the engine kernel (``physics.KernelFlags``), serial, no recording.
        settings: the engine's settings array (dt, gravity, sleep, ...; ``physics.layout``), runs until rest.
    """

    solver: str
    dt: float
    max_steps: int
    flags: KernelFlags
    settings: np.ndarray


def make_engine(config: EngineConfig) -> Engine:
    """The engine of ``config``; the engine's ``Scene`` checks each setting (a TypeError or ValueError naming it)."""
    length, width = config.box_size
    scene = Scene(
        boxes=(Box(length=length, width=width, mass=config.mass, position=config.release),),
        dt=config.dt,
        gravity=-config.gravity,
        restitution=config.restitution,
        friction=config.friction,
        penalty_stiffness=config.penalty_stiffness,
        solver=config.solver,
        boxes_collide=config.boxes_collide,
    )
    max_steps = max(1, check_step_count("max_sim_time", config.max_sim_time, scene.dt))
    # without box-box contact, the floor-only kernel, which compiles no box-box contact at all
    flags = KernelFlags(
        solver=scene.solver,
        use_impulses=True,
        use_penalty=scene.has_penalty,
        use_friction=config.friction > 0.0,
        record=False,
        parallel=False,
        boxes_collide=config.boxes_collide,
    )
    return Engine(scene.solver, scene.dt, max_steps, flags, make_settings(scene, max_steps, until_rest=True))
