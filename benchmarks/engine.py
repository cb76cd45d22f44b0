"""Engine benchmark: ns per body-step for each solver on named scenes, wall time per throw, ns per
body-step on piles of boxes in contact beside pymunk and Box2D, and numba compile time cold and cached.
Prints measured figures; asserts nothing.

    python -m benchmarks.engine [--quick]
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from benchmarks.other_scenes import UnsupportedScene, available_scene_engines, simulate_scene
from benchmarks.readme_section import replace_section
from box_toss_env.physics import (
    Box,
    NonFiniteStateError,
    Scene,
    Simulator,
    check_finite_stats,
    layout,
    make_settings,
    scenes,
    simulate,
)


def best_time(function, repeats: int) -> float:
    """Minimum wall time of ``repeats`` calls after one warm-up call [s]."""
    function()
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def runner(scene: Scene, max_steps: int, until_rest: bool, parallel: bool | None = None, threads=None):
    """A closure running ``scene`` on preallocated arrays, and its stats array."""
    simulator = Simulator.for_scene(scene, parallel=parallel, threads=threads)
    initial = scene.initial_state()
    params = scene.body_params()
    settings = make_settings(scene, max_steps, until_rest)
    stats = np.zeros((scene.n_bodies, layout.STATS_SIZE))
    state = initial.copy()

    def run():
        state[:] = initial
        simulator.run(state, params, settings, stats)

    return run, stats


def many(scene: Scene, n: int, spread: float = 1e-3) -> Scene:
    """``n`` copies of a one-box scene, each nudged so no two are identical."""
    box = scene.boxes[0]
    boxes = tuple(Box(length=box.length, width=box.width, mass=box.mass,
                      position=(box.position[0], box.position[1] + spread * k / n), angle=box.angle,
                      velocity=box.velocity, spin=box.spin) for k in range(n))
    return scene.replace(boxes=boxes)


STEP_SCENES = {
    "flight": lambda solver: scenes.free_flight(solver=solver, dt=1 / 256),  # no contact within 1 s
    "resting": lambda solver: scenes.resting(solver=solver, dt=1 / 256, restitution=0.3, friction=0.5,
                                             penalty_stiffness=1e4),
    "toss": lambda solver: scenes.toss(solver=solver, dt=1 / 256, penalty_stiffness=1e4),
}


def step_costs(repeats: int, steps: int) -> list[tuple]:
    """ns per body-step for one box (the fixed cost of a call subtracted; a flight that is not stepped
    costs nothing per step, up to timing noise) and for 1,024 boxes in one parallel call, per solver
    and scene, in runs of the same length (the flight lasts 1 s)."""
    rows = []
    for solver in ("seed", "robust"):
        for name, make in STEP_SCENES.items():
            scene = make(solver)
            n = 256 if name == "flight" else steps
            one, _ = runner(scene, n, until_rest=False)
            call, _ = runner(scene, 1, until_rest=False)
            per_step = (best_time(one, repeats) - best_time(call, repeats)) / (n - 1)
            batch, _ = runner(many(scene, 1024), n, until_rest=False, parallel=True)
            rows.append((solver, name, max(per_step, 0.0) * 1e9, best_time(batch, repeats) / (1024 * n) * 1e9))
    return rows


def throw_costs(repeats: int) -> list[tuple]:
    """Wall time per throw, simulated until rest (at most 10 s), one box at a time."""
    rows = []
    for solver, dt in (("robust", 1 / 256), ("robust", 1 / 1024), ("seed", 1 / 256), ("seed", 1 / 1024)):
        scene = scenes.toss(solver=solver, dt=dt, penalty_stiffness=1e4)
        run, stats = runner(scene, int(10 / dt), until_rest=True)
        seconds = best_time(run, repeats)
        rows.append((solver, dt, seconds * 1e6, int(stats[0, layout.N_STEPS]),
                     stats[0, layout.REST_TIME]))
    return rows


PILE_SIZES = (1, 10, 100)
PILE_DURATION, QUICK_PILE_DURATION = 2.0, 0.5  # [s] simulated from release, every step timed
NEVER_SLEEP = 1e6  # [s] a sleep_time no pile run reaches


def pile(n: int) -> Scene:
    """``scenes.pile(n)``: boxes dropped onto one another into a pile, here never put to sleep (``sleep_time`` =
    NEVER_SLEEP; ``pile_costs`` turns Box2D's sleeping off too), so every step solves every contact."""
    try:
        return scenes.pile(n, sleep_time=NEVER_SLEEP)
    except ValueError:  # TEMPORARY: scenes.pile of aaac18f starts boxes overlapping for n >= 2 (fix under way)
        width = math.ceil(math.sqrt(n))
        boxes = tuple(Box(**scenes.TOSS_BOX, position=(0.42 * (k % width) + 0.21 * ((k // width) % 2),
                                                       0.12 + 0.23 * (k // width)), angle=0.05 * (-1) ** k)
                      for k in range(n))
        return Scene(boxes=boxes, boxes_collide=True, **scenes.TOSS_MATERIAL, dt=1 / 256, sleep_time=NEVER_SLEEP)


def pile_energy(scene: Scene, state: np.ndarray) -> float:
    """Total energy of every box, 0.5 m |v|^2 + 0.5 I w^2 - m g y [J] (floor at y = 0, g < 0)."""
    mass = np.array([box.mass for box in scene.boxes])
    inertia = np.array([box.inertia for box in scene.boxes])
    return float(0.5 * mass @ (state[:, 3:5] ** 2).sum(axis=1) + 0.5 * inertia @ state[:, 5] ** 2
                 - scene.gravity * mass @ state[:, 1])


def pile_costs(sizes=PILE_SIZES, duration: float = PILE_DURATION, repeats: int = 3) -> list[tuple]:
    """(method, boxes, ns per body-step or nan, note) for each pile: our solvers single-thread on raw arrays,
    pymunk and Box2D stepped from Python as their users would (the loop alone, a fresh world per repeat)."""
    rows = []
    for n in sizes:
        scene = pile(n)
        steps = int(round(duration / scene.dt))
        for solver in ("robust", "seed"):
            ours = scene.replace(solver=solver)
            run, stats = runner(ours, steps, until_rest=False, parallel=False)
            seconds = best_time(run, repeats)
            try:
                check_finite_stats(stats, solver)
                end = simulate(ours, steps=steps).final_state
            except NonFiniteStateError as error:
                rows.append((solver, n, math.nan, f"non-finite at step {error.step}"))
                continue
            gain = pile_energy(ours, end) / pile_energy(ours, ours.initial_state())
            if gain > 1.1:  # a pile that blew apart has no contacts left to solve: its cost means nothing
                rows.append((solver, n, math.nan, f"blows up on the piles (energy x{gain:.3g} at the end)"))
                continue
            rows.append((solver, n, seconds / (steps * n) * 1e9, ""))
        for engine in available_scene_engines():
            try:
                runs = [simulate_scene(engine, scene, steps, record=False, sleep=False) for _ in range(repeats + 1)]
            except UnsupportedScene as error:
                rows.append((engine, n, math.nan, str(error)))
                continue
            rows.append((engine, n, min(r.ns_per_body_step for r in runs[1:]), ""))
    return rows


def pile_lines(rows) -> list[str]:
    methods = list(dict.fromkeys(method for method, *_ in rows))
    sizes = list(dict.fromkeys(n for _, n, *_ in rows))
    cost = {(m, n): (ns, note) for m, n, ns, note in rows}
    lines = [f"{'method':8} " + " ".join(f"{boxes_text(n):>11}" for n in sizes)]
    for method in methods:
        lines.append(f"{method:8} " + " ".join(f"{cost[(method, n)][0]:11.1f}" if not math.isnan(cost[(method, n)][0])
                                               else f"{'-':>11}" for n in sizes))
    return lines + [f"  {method}, {boxes_text(n)}: {note}" for method, n, _, note in rows if note]


def boxes_text(n: int) -> str:
    return f"{n} box" if n == 1 else f"{n} boxes"


COMPILE_PROBE = """
import time
start = time.perf_counter()
from box_toss_env.physics import scenes, simulate
imported = time.perf_counter()
simulate(scenes.toss(), duration=3.0, until_rest=True)
first = time.perf_counter()
simulate(scenes.toss(), duration=3.0, until_rest=True)
second = time.perf_counter()
print(imported - start, (first - imported) - (second - first))
"""


def compile_times() -> tuple[float, float, float]:
    """(import s, first-call compile s with an empty cache, the same with the cache warm), each
    in a fresh interpreter with its own numba cache directory."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        figures = []
        for _ in range(2):
            out = subprocess.run([sys.executable, "-c", COMPILE_PROBE], env=env, capture_output=True, text=True,
                                 check=True).stdout.split()
            figures.append((float(out[0]), float(out[1])))
    return figures[1][0], figures[0][1], figures[1][1]


def load_text() -> str:
    """The 1-minute load average against the cores: other jobs share this machine."""
    try:
        return f"{os.getloadavg()[0]:.2f} on {os.cpu_count()} cores"
    except OSError:
        return "unknown"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="fewer repeats and steps")
    parser.add_argument("--readme", action="store_true", help="also write the figures into README.md")
    args = parser.parse_args()
    repeats, steps = (3, 1024) if args.quick else (5, 4096)
    import numba

    lines = [f"numba {numba.__version__}, {numba.get_num_threads()} threads, {os.cpu_count()} cores", ""]
    lines.append("ns per body-step (fixed-length runs, dt = 1/256 s; robust flight is closed form, not stepped)")
    lines.append(f"{'solver':8} {'scene':8} {'1 box':>10} {'1024 boxes':>11}")
    for solver, name, one, batch in step_costs(repeats, steps):
        lines.append(f"{solver:8} {name:8} {one:10.1f} {batch:11.1f}")
    lines += ["", "wall time per throw (typical toss, simulated until at rest, at most 10 s; one box per call)"]
    lines.append(f"{'solver':8} {'dt [s]':>10} {'us/throw':>10} {'steps':>7} {'rest at [s]':>12}")
    for solver, dt, micros, n_steps, rest in throw_costs(repeats):
        lines.append(f"{solver:8} {dt:10.6f} {micros:10.1f} {n_steps:7d} {rest:12.3f}")
    pile_duration = QUICK_PILE_DURATION if args.quick else PILE_DURATION
    lines += ["", f"ns per body-step, piles of boxes in contact (boxes collide, never sleep; {pile_duration:g} s from "
              "release at dt = 1/256 s, every step timed; ours single-thread on raw arrays, pymunk and Box2D stepped "
              "from Python, the loop alone; best of "
              f"{repeats}; a shared machine, load {load_text()})"]
    lines += pile_lines(pile_costs(duration=pile_duration, repeats=repeats))
    imported, cold, warm = compile_times()
    lines += ["", f"import {imported:.2f} s; compile of the robust toss kernel: {cold:.2f} s cold, "
              f"{warm:.2f} s from the on-disk cache"]
    report = "\n".join(lines)
    print(report)
    if args.readme:
        replace_section("engine-benchmark", f"```text\n$ python -m benchmarks.engine\n{report}\n```")


if __name__ == "__main__":
    main()
