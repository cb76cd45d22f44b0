"""Quiet steps: a scene whose awake bodies are all nearly still takes QUIET_STRIDE grid steps as one.

A resting pile kept awake, a structure standing, the last tenth of a second before a pile sleeps: every contact's
impulse is then the warm start's to within the solver's stop, and each grid step costs what finding the contacts
costs. Stepping such a scene at dt costs about QUIET_STRIDE times what stepping it at QUIET_STRIDE dt does, for the
same result: from the suite's settled scenes (``benchmarks.scene_suite``), kept awake 2 s at dt and at 4 dt, the tower
of 20, the pyramid of 210, the stacks of 5 (100:1 and 1000:1), thin plates and the pile of 16 moved and went as deep
as at dt, to the last digit or within 1e-13 m, at 0.25-0.5 of the cost. A quiet step may sweep QUIET_STRIDE times
the scene's ``solver_iterations`` (the grid steps it stands for had as many): with 16 a settling pile of 100 crept for
seconds. A scene whose heaviest box is more than QUIET_MASS_RATIO times its lightest does not step quietly (a stack
of 5 at 1000:1 stepped at 4 dt from its start slipped 2e-7 m/s at every step).

A step of k = QUIET_STRIDE grid steps is taken at grid step n when

- every awake body is slower than the scene's ``sleep_speed`` at every point (|v| + |omega| R, the sleep test's
  speed);
- one substep of k dt keeps the no-tunnelling bound (``substeps.substep_count``: |g| k dt counts in the point speed,
  so boxes of a millimetre never take it);
- no trajectory is recorded (it has a row a grid step), and the k steps end within the run;
- n is a multiple of k, so a run in chunks of a multiple of k steps is the run at once, bit for bit (a quiet step
  never spans two runs);
- the scene's heaviest box is at most QUIET_MASS_RATIO times its lightest (``masses_alike``), and its
  ``quiet_steps`` is on (``Scene``, the default).

Otherwise it takes one grid step. Everything that scales with the step reads the quiet step's length: the substeps,
the pairs' reach, the warm start (impulses scale with the substep length, ``warm_start``), the sleep timers.
"""

import math

from .. import layout
from ..compile.compilation import jit_stage
from ..tunables import QUIET_MASS_RATIO, QUIET_STRIDE
from .state import StepContext
from .substeps import substeps


@jit_stage(inline="always")
def quiet_context(context):
    """The step context of a quiet step: the grid step and the Gauss-Seidel sweeps at most times QUIET_STRIDE (the
    sweeps of the grid steps it stands for: at 16 a quiet step, the settling pile of 100 kept awake crept for
    seconds, 1.3 mm in its fourth second, still 17 um in its ninth; at 1/256 s it lay still to rounding, and at 64
    sweeps a quiet step it moves 0.1-0.2 um a second), every other setting as it is. Built where the steps use it
    (``kernel.advance_steps``): built once a call by the kernel and passed in with the steps' other arguments, it made
    a throw of ``BoxToss-OnBox-v0`` cost the engine 95 us instead of 68, the same results."""
    return StepContext(
        context.dt * QUIET_STRIDE,
        context.gravity,
        context.max_steps,
        context.until_rest,
        context.sleeping,
        context.threshold,
        context.sleep_speed,
        context.sleep_time,
        context.slop,
        context.sweep_tolerance,
        context.sweeps * QUIET_STRIDE,
        context.tolerance,
        context.smallest_half,
        context.use_penalty,
        context.use_friction,
        context.record,
    )


@jit_stage
def masses_alike(params):
    """Whether the scene may step quietly: its heaviest box at most QUIET_MASS_RATIO times its lightest."""
    lightest = params[0, layout.MASS]
    heaviest = lightest
    for b in range(params.shape[0]):
        lightest = min(lightest, params[b, layout.MASS])
        heaviest = max(heaviest, params[b, layout.MASS])
    return heaviest <= QUIET_MASS_RATIO * lightest


@jit_stage
def quiet_stride(context, bodies, awake, n, allowed):
    """How many grid steps the step from grid step n takes: QUIET_STRIDE where the scene is quiet (module doc;
    ``allowed``: the scene's ``quiet_steps`` and ``masses_alike``), else 1."""
    if QUIET_STRIDE <= 1 or not allowed or context.record or n + QUIET_STRIDE > context.max_steps:
        return 1
    if n % QUIET_STRIDE != 0:
        return 1
    vel, radius = bodies.vel, bodies.radius
    for b in range(vel.shape[0]):
        if awake[b]:
            speed = math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(vel[b, 2]) * radius[b]
            if speed > context.sleep_speed:
                return 1
    dt = context.dt * QUIET_STRIDE
    if substeps(vel, radius, awake, context.smallest_half, dt, context.gravity) > 1:
        return 1
    return QUIET_STRIDE
