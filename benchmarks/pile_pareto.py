"""Error against run time for piles: penetration and drift against cost as each engine's accuracy knob
turns (our dt at the scene's default Gauss-Seidel stop, and our ``solver_tolerance`` and ``penetration_slop`` at a
fixed dt; Box2D v3's substeps; pymunk's iterations), on the 210-box pyramid and a 100-box pile.
Prints one table and writes one Pareto plot; asserts nothing.

    python -m benchmarks.pile_pareto [--quick] [--write-docs]

Each variant runs ``WINDOW`` s of simulated time, awake (nobody sleeps), from the same start (the pyramid
as built; the pile settled 2 s by our engine, as ``benchmarks.engine_scale``), one thread, the stepping
loop alone after ``engine_scale.LEAD_IN["awake"]`` s untimed in the same world (contacts warm), best of up to
3 runs. Cost: us per body per simulated second = wall / (n T), which counts a
smaller step as the extra steps it takes. Error, at the end of the window: the deepest penetration (m)
and how far the top box moved (m) (``engine_scale.quality``).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from benchmarks import engine_scale
from benchmarks.other_scenes import BOX2D3_DT, available_scene_engines, build_box2d3, build_pymunk
from box_toss_env.files import save_figure
from box_toss_env.physics import Scene, scenes

OUR_DTS = (1 / 64, 1 / 128, 1 / 256, 1 / 512)  # [s], at the scene's default solver_tolerance (1e-9, 16 sweeps)
OUR_TOLERANCES = (1e-3, 1e-4, 1e-5, 1e-6)  # solver_tolerance with 32 sweeps at most, at OUR_TOLERANCE_DT
OUR_TOLERANCE_DT = 1 / 120  # [s]
OURS_BY_TOLERANCE = "ours, solver_tolerance"
OUR_SLOPS = (1e-5, 3e-5, 5e-5, 1e-4, 3e-4)  # [m] penetration_slop at OUR_TOLERANCE_DT, tolerance 1e-4, 32 sweeps
OURS_BY_SLOP = "ours, penetration_slop"
BOX2D3_SUBSTEPS = (1, 2, 4, 8)  # at its default 60 Hz
PYMUNK_ITERATIONS = (5, 10, 20, 40)  # at 60 Hz
PYMUNK_DT = 1 / 60
WINDOW, QUICK_WINDOW = 1.0, 0.25  # [s]
PILE = 100
REPEAT_BUDGET = 5.0  # [s] a variant is run again (best of up to 3) while its runs stay within this; its window is fixed
FIGURE = engine_scale.DOCS / "figures" / "pile_pareto.png"
MARKER = "pile-pareto"


def time_loop(step, read_states, steps: int, n: int, dt: float) -> tuple[float, np.ndarray]:
    """(wall s, final states) of ``steps`` steps, after engine_scale.LEAD_IN["awake"] s untimed (as our runs)."""
    for _ in range(round(engine_scale.LEAD_IN["awake"] / dt)):
        step()
    start = time.perf_counter()
    for _ in range(steps):
        step()
    wall = time.perf_counter() - start
    out = np.empty((n, 6))
    read_states(out)
    return wall, out


def ours_at(defaults: dict, **settings):
    """run(scene, start, steps) of our engine at OUR_TOLERANCE_DT, 32 sweeps at most, ``defaults`` with ``settings``."""
    changed = {**defaults, "solver_iterations": 32, **settings}
    return lambda scene, start, steps: engine_scale.run_ours(
        scene.replace(**changed, dt=OUR_TOLERANCE_DT), start, steps, "awake"
    )[:2]


def variants(engines: list[str]):
    """(engine, knob text, dt, run(scene, start, steps) -> (wall, final state))."""
    # our settings at the scene defaults (tolerance 1e-9, 16 sweeps, no slop), whatever engine_scale.OUR_SOLVER says
    defaults = {name: getattr(Scene(), name) for name in engine_scale.OUR_SOLVER}
    for dt in OUR_DTS:
        yield (
            engine_scale.OURS,
            f"dt 1/{round(1 / dt)}",
            dt,
            lambda scene, start, steps, dt=dt: engine_scale.run_ours(
                scene.replace(dt=dt, **defaults), start, steps, "awake"
            )[:2],
        )
    for tolerance in OUR_TOLERANCES:
        yield OURS_BY_TOLERANCE, f"{tolerance:g}", OUR_TOLERANCE_DT, ours_at(defaults, solver_tolerance=tolerance)
    for slop in OUR_SLOPS:
        yield (
            OURS_BY_SLOP,
            f"{slop:g} m",
            OUR_TOLERANCE_DT,
            ours_at(defaults, solver_tolerance=1e-4, penetration_slop=slop),
        )
    if "box2d3" in engines:
        for sub in BOX2D3_SUBSTEPS:
            yield (
                "box2d3",
                f"{sub} substeps",
                BOX2D3_DT,
                lambda scene, start, steps, sub=sub: time_loop(
                    *build_box2d3(scene, False, start, BOX2D3_DT, sub), steps, scene.n_bodies, BOX2D3_DT
                ),
            )
    if "pymunk" in engines:
        for it in PYMUNK_ITERATIONS:
            yield (
                "pymunk",
                f"{it} iterations",
                PYMUNK_DT,
                lambda scene, start, steps, it=it: time_loop(
                    *build_pymunk(scene, False, start, PYMUNK_DT, it), steps, scene.n_bodies, PYMUNK_DT
                ),
            )


def pareto_rows(window: float = WINDOW, pile: int = PILE, log=lambda _: None) -> list[tuple]:
    """(case, engine, knob, us per body per simulated second, max penetration [m], top drift [m])."""
    engines = available_scene_engines()
    pile_scene = scenes.pile(pile).replace(dt=engine_scale.OUR_DT["pile"])
    cases: list[tuple[str, Scene, np.ndarray]] = [
        ("pyramid", engine_scale.pyramid_case(), engine_scale.pyramid_case().initial_state()),
        (f"pile {pile}", pile_scene, engine_scale.settle(pile_scene, [], our_max=pile)[0]),
    ]
    rows = []
    for name, scene, start in cases:
        for engine, knob, dt, run in variants(engines):
            log(f"{name}: {engine}, {knob}")
            steps = max(1, round(window / dt))
            wall, state = engine_scale.best_of(
                lambda run=run, scene=scene, start=start, steps=steps: run(scene, start, steps), REPEAT_BUDGET
            )
            penetration, drift = engine_scale.quality(scene, start, state)
            rows.append((name, engine, knob, 1e6 * wall / (scene.n_bodies * steps * dt), penetration, drift))
    return rows


def table(rows) -> list[str]:
    lines = [
        "| case | engine | knob | us/body/sim-s | max penetration [m] | top drift [m] |",
        "|---|---|---|---:|---:|---:|",
    ]
    return lines + [
        f"| {case} | {engine} | {knob} | {cost:,.1f} | {pen:.2e} | {drift:.2e} |"
        for case, engine, knob, cost, pen, drift in rows
    ]


def plot(rows, path: Path = FIGURE) -> None:
    """Two panels per case, error (log) against cost (log), a line per engine through its knob values."""
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = list(dict.fromkeys(r[0] for r in rows))
    fig, axes = plt.subplots(len(cases), 2, figsize=(10, 4 * len(cases)), squeeze=False)
    for i, case in enumerate(cases):
        for j, (column, label) in enumerate(((4, "max penetration [m]"), (5, "top box drift [m]"))):
            ax = axes[i, j]
            for k, engine in enumerate(dict.fromkeys(r[1] for r in rows)):
                points = [(r[3], max(r[column], 1e-12), r[2]) for r in rows if r[0] == case and r[1] == engine]
                ax.loglog([p[0] for p in points], [p[1] for p in points], "-o", color=f"C{k}", label=engine)
                for x, y, knob in points:
                    ax.annotate(knob, (x, y), fontsize=6, xytext=(3, 3), textcoords="offset points")
            ax.set_title(f"{case}: {label.split(' [')[0]}", fontsize=10)
            ax.set_xlabel("wall time per body per simulated second [us]")
            ax.set_ylabel(label)
            ax.grid(True, which="both", alpha=0.3)
            ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help=f"{QUICK_WINDOW:g} s window instead of {WINDOW:g} s")
    parser.add_argument("--write-docs", action="store_true", help="write the table and the figure into docs/")
    args = parser.parse_args(argv)
    window = QUICK_WINDOW if args.quick else WINDOW
    began = time.perf_counter()
    rows = pareto_rows(window, log=lambda line: print(f"[{time.perf_counter() - began:6.1f} s] {line}", flush=True))
    if args.write_docs:  # the figure is the docs' (a tracked file): written only when asked
        plot(rows)
    lines = [
        f"`python -m benchmarks.pile_pareto{' --quick' if args.quick else ''}`: {window:g} s of simulated time "
        f"per variant, awake; {engine_scale.load_text()}.",
        "",
        *table(rows),
    ]
    if args.quick:
        lines += ["", "(quick run: shorter window)"]
    text = "\n".join(lines)
    print(text)
    if args.write_docs:
        engine_scale.write_docs(text, marker=MARKER)
    if any(not math.isfinite(r[3]) for r in rows):
        raise SystemExit("a variant has no cost figure")


if __name__ == "__main__":
    main()
