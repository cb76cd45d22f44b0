"""Engine benchmark: ns per body-step for each solver on named scenes, wall time per throw, ns per
body-step of piles of boxes that collide (``pile_cost``) and the same piles in pymunk and Box2D
(``pile_comparison``), and numba compile time cold and cached.
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

from agents.doc_sections import replace_section
from benchmarks.other_scenes import available_scene_engines
from box_toss_env.physics import (
    Box,
    Scene,
    Simulator,
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
    boxes = tuple(
        Box(
            length=box.length,
            width=box.width,
            mass=box.mass,
            position=(box.position[0], box.position[1] + spread * k / n),
            angle=box.angle,
            velocity=box.velocity,
            spin=box.spin,
        )
        for k in range(n)
    )
    return scene.replace(boxes=boxes)


STEP_SCENES = {
    "flight": lambda solver: scenes.free_flight(solver=solver, dt=1 / 256),  # no contact within 1 s
    "resting": lambda solver: scenes.resting(
        solver=solver, dt=1 / 256, restitution=0.3, friction=0.5, penalty_stiffness=1e4
    ),
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
        rows.append((solver, dt, seconds * 1e6, int(stats[0, layout.N_STEPS]), stats[0, layout.REST_TIME]))
    return rows


PILE_SIZES = (1, 10, 100)


def pile_cost(n: int, solver: str = "robust", settle: float = 2.0, steps: int = 256, repeats: int = 3) -> dict:
    """ns per body-step of ``scenes.pile(n)`` (boxes that collide) once it has settled into contact: the
    pile is simulated for ``settle`` seconds, then ``steps`` steps from that state are timed (best of
    ``repeats``). Returns the figure with what it was measured on: n, solver, dt, steps, how many boxes
    still move faster than 1 cm/s at the end of the timed run, and the settled state (n, 6) (for other
    engines to start from the same pile)."""
    scene = scenes.pile(n, solver=solver)
    settled = simulate(scene, duration=settle).final_state
    simulator = Simulator.for_scene(scene)
    params = scene.body_params()
    settings = make_settings(scene, steps, until_rest=False, sleep=False)  # awake: the steps are what is timed
    stats = np.zeros((n, layout.STATS_SIZE))
    state = settled.copy()

    def run():
        state[:] = settled
        simulator.run(state, params, settings, stats)

    seconds = best_time(run, repeats)
    return {
        "n": n,
        "solver": solver,
        "dt": scene.dt,
        "steps": steps,
        "ns_per_body_step": seconds / (n * steps) * 1e9,
        "settled_state": settled,
        "moving_at_end": int(np.sum(np.abs(state[:, 3:]).max(axis=1) > 1e-2)),
    }


PILE_SETTLE = 2.0  # [s] as ``pile_cost``
PILE_STEPS, QUICK_PILE_STEPS = 256, 64  # at 1/256 s: the window each method steps at its own dt
PILE_BUDGET = 10.0  # [s] of CPU per method and pile
PILE_METHODS = ("robust", "seed", "robust, sleeping")
BLOWN = 0.1  # a method whose energy rose above 1.1 times the dropped pile's, settling or in the window, blew it apart


def our_pile_builders() -> dict:
    """Our methods on a pile: the robust solver (the scene's defaults, sleeping off), the seed scheme, and the robust
    solver letting the pile sleep (``until_rest``)."""
    from benchmarks.suite_runs import OurWorld

    return {
        "robust": lambda case, sleep: OurWorld(case.scene, sleep),
        "seed": lambda case, sleep: OurWorld(case.scene, sleep, solver="seed"),
        "robust, sleeping": lambda case, sleep: OurWorld(case.scene, True, until_rest=True),
    }


def pile_comparison(
    sizes=PILE_SIZES, steps: int = PILE_STEPS, settle: float = PILE_SETTLE, repeats: int = 3
) -> list[tuple]:
    """(method, boxes, ns per body-step or nan, note) of ``scenes.pile(n)`` in every method, each settling its own pile
    for ``settle`` s (untimed, sleeping off), then timed for ``steps`` steps of 1/256 s of simulated time at its own
    step (``benchmarks.suite_runs``: thread CPU time, the stepping loop alone, repeats interleaved across methods,
    the median). A method whose energy rose above 1 + BLOWN times the pile's as it was dropped (it can only lose
    energy), by the window's start or in it (``scene_quality``), has no figure: it blows the pile apart. The
    comparison across scenes and windows is ``benchmarks.engine_scale``."""
    from benchmarks.scene_quality import box_arrays, energy
    from benchmarks.scene_suite import Case, Plan, Segment
    from benchmarks.suite_runs import run_case

    builders = our_pile_builders()
    methods = [*PILE_METHODS, *available_scene_engines()]
    window = steps / 256
    rows = []
    for n in sizes:
        plan = Plan(False, (Segment(settle), Segment(window, "awake")))
        case = Case(f"pile {n}", "pile", lambda n=n: scenes.pile(n), (plan,))
        windows, _ = run_case(case, methods, repeats, PILE_BUDGET, builders=builders)
        dropped = energy(case.scene.initial_state(), *box_arrays(case.scene)[1:], case.scene.gravity)
        for w in windows:
            ns = 1e9 * w.cpu / (w.steps * n) if w.steps and w.seconds else math.nan
            note = w.note
            highest = w.quality.energy_start + w.quality.energy_gain
            if highest > (1 + BLOWN) * dropped:
                ns, note = math.nan, f"blows the pile apart (energy x{highest / dropped:.3g} its drop's)"
            elif w.engine == "robust, sleeping":
                note = f"{w.quality.asleep_end} of {n} boxes asleep at the end"
            rows.append((w.engine, n, ns, note))
    return rows


def pile_lines(rows) -> list[str]:
    methods = list(dict.fromkeys(method for method, *_ in rows))
    sizes = list(dict.fromkeys(n for _, n, *_ in rows))
    cost = {(m, n): (ns, note) for m, n, ns, note in rows}
    lines = [f"{'method':17} " + " ".join(f"{boxes_text(n):>11}" for n in sizes)]
    for method in methods:
        lines.append(
            f"{method:17} "
            + " ".join(
                f"{cost[(method, n)][0]:11.1f}" if not math.isnan(cost[(method, n)][0]) else f"{'-':>11}" for n in sizes
            )
        )
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
            out = subprocess.run(
                [sys.executable, "-c", COMPILE_PROBE], env=env, capture_output=True, text=True, check=True
            ).stdout.split()
            figures.append((float(out[0]), float(out[1])))
    return figures[1][0], figures[0][1], figures[1][1]


def load_text() -> str:
    """The 1-minute load average: other jobs share this machine, and its figures move with them."""
    try:
        return f"load {os.getloadavg()[0]:.2f} at the start, shared with other jobs"
    except OSError:  # no load average on this platform
        return "load unknown, shared with other jobs"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="fewer repeats and steps")
    parser.add_argument("--readme", action="store_true", help="also write the methodology page")
    args = parser.parse_args()
    repeats, steps = (3, 1024) if args.quick else (5, 4096)
    import numba

    lines = [f"numba {numba.__version__}, {numba.get_num_threads()} threads, {os.cpu_count()} cores; {load_text()}", ""]
    lines.append("ns per body-step (fixed-length runs, dt = 1/256 s; robust flight is closed form, not stepped)")
    lines.append(f"{'solver':8} {'scene':8} {'1 box':>10} {'1024 boxes':>11}")
    for solver, name, one, batch in step_costs(repeats, steps):
        lines.append(f"{solver:8} {name:8} {one:10.1f} {batch:11.1f}")
    lines += ["", "wall time per throw (typical toss, simulated until at rest, at most 10 s; one box per call)"]
    lines.append(f"{'solver':8} {'dt [s]':>10} {'us/throw':>10} {'steps':>7} {'rest at [s]':>12}")
    for solver, dt, micros, n_steps, rest in throw_costs(repeats):
        lines.append(f"{solver:8} {dt:10.6f} {micros:10.1f} {n_steps:7d} {rest:12.3f}")
    pile_steps = QUICK_PILE_STEPS if args.quick else PILE_STEPS
    lines += [
        "",
        f"boxes that collide: ns per body-step of a pile (scenes.pile) each method settled itself for {PILE_SETTLE:g} "
        f"s, then {pile_steps / 256:g} s timed at the method's own step (ours 1/256 s, the others 60 Hz), nobody "
        "sleeping but in 'robust, sleeping'; one thread, thread CPU time, the stepping loop alone, pymunk and Box2D "
        f"stepped from Python; median of {repeats} repeats interleaved across methods)",
    ]
    lines += pile_lines(pile_comparison(steps=pile_steps, repeats=repeats))
    imported, cold, warm = compile_times()
    lines += [
        "",
        f"import {imported:.2f} s; compile of the robust toss kernel: {cold:.2f} s cold, "
        f"{warm:.2f} s from the on-disk cache",
    ]
    report = "\n".join(lines)
    print(report)
    if args.readme:
        replace_section("engine-benchmark", f"```text\n$ python -m benchmarks.engine\n{report}\n```")


if __name__ == "__main__":
    main()
