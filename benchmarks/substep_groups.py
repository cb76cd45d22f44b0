"""What a box thrown fast far from an awake pile costs the pile: the colliding solver's step time for the
100-box pile alone and with one box thrown 10 m beside it. Prints one table; asserts nothing.

    python -m benchmarks.substep_groups [--steps N]

Method. ``engine_scale``'s 100-box pile (``pile_case(100)``, its dt and solver settings) is settled for
``SETTLE`` s by our engine (untimed), then stepped awake (``sleep_time`` 1e6 s): ``LEAD_IN`` steps untimed with a
warm start (``warm_start_memory``), then ``--steps`` steps timed in the same warm start, best of ``REPEATS``, in
thread CPU time, each case's runs interleaved with the other's. The thrown box (40 x 20 cm, 18 m/s up and away
from the pile, spinning at 10 rad/s) needs about 12 substeps a step, the pile 1 or 2: with one substep count for
every awake body the pile pays the box's; with substeps per group (``colliding.groups``) it keeps its own.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from box_toss_env.physics import Box, Simulator, layout, make_settings, warm_start_memory

from .engine_scale import NEVER_SLEEP, pile_case

SETTLE = 2.0  # [s]
LEAD_IN = 6  # steps
STEPS = 60
REPEATS = 3


def settled_pile():
    """(scene, state) of the 100-box pile after SETTLE s, awake from here on."""
    _, scene = pile_case(100)
    state = scene.initial_state()
    steps = round(SETTLE / scene.dt)
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    settings = make_settings(scene, steps, until_rest=True)
    Simulator.for_scene(scene, parallel=False).run(state, scene.body_params(), settings, stats)
    return scene.replace(sleep_time=NEVER_SLEEP), state


def with_thrown_box(scene, state):
    """The pile and one box thrown up and away from it, 10 m beyond its right end."""
    right = float(state[:, 0].max())
    box = Box(length=0.4, width=0.2, mass=2.0, position=(right + 10.0, 2.0), velocity=(15.0, 10.0), spin=10.0)
    return scene.replace(boxes=(*scene.boxes, box)), np.concatenate([state, box_state(box)])


def box_state(box: Box) -> np.ndarray:
    return np.array([[box.position[0], box.position[1], box.angle, box.velocity[0], box.velocity[1], box.spin]])


def timed_run(scene, start, steps: int) -> float:
    """Thread CPU seconds of ``steps`` awake steps after LEAD_IN untimed ones, one warm start through both."""
    simulator = Simulator.for_scene(scene, parallel=False)
    params, state, warm = scene.body_params(), start.copy(), warm_start_memory(scene.n_bodies)
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    simulator.run(state, params, make_settings(scene, LEAD_IN, until_rest=False, sleep=False), stats, warm_start=warm)
    began = time.thread_time()
    simulator.run(state, params, make_settings(scene, steps, until_rest=False, sleep=False), stats, warm_start=warm)
    return time.thread_time() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=STEPS)
    args = parser.parse_args()
    scene, state = settled_pile()
    cases = {"pile alone": (scene, state), "pile + thrown box": with_thrown_box(scene, state)}
    for case_scene, case_start in cases.values():  # compile
        timed_run(case_scene, case_start, 1)
    best = dict.fromkeys(cases, np.inf)
    for _ in range(REPEATS):
        for name, (case_scene, case_start) in cases.items():
            best[name] = min(best[name], timed_run(case_scene, case_start, args.steps))
    print(f"{'case':<20} {'us per step':>12} {'x pile alone':>13}")
    for name in cases:
        per_step = 1e6 * best[name] / args.steps
        print(f"{name:<20} {per_step:12.0f} {best[name] / best['pile alone']:13.2f}")


if __name__ == "__main__":
    main()
