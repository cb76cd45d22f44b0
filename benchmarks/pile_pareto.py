"""Error against cost, every point a setting a user can pick: our engine's public ``Scene`` settings (the step, the
Gauss-Seidel stop and sweeps, the penetration slop) one at a time from the defaults, Box2D v3's substeps and contact
stiffness (contact hertz) together and its damping ratio and push speed, Box2D 2.3's and pymunk's iterations, on the
100-box pile dropped and the 210-box pyramid kept awake. Prints one table; writes nothing unless asked.

    python -m benchmarks.pile_pareto [--quick] [--budget S] [--repeats N] [--write-docs]

Each setting builds its own world and settles its own pile (``scene_suite`` cases, ``suite_runs``: an observed run
measures, interleaved timed repeats in thread CPU time give the cost, us per body per simulated second). Sleeping is
off in every engine, so the figures compare the solvers' work. Error: the deepest penetration over the window (the
pile's impacts; the pyramid under its own weight) and at its end, and how far any box moved (drift: the pyramid
should not move at all). A setting is on the Pareto front of its case when no other setting, of any engine, is both
cheaper and has less penetration over the window (depths under a nanometre count as equal).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from benchmarks import engine_scale
from benchmarks.engine import load_text
from benchmarks.other_scenes import (
    BOX2D3_CONTACT,
    BOX2D3_DT,
    BOX2D3_SUBSTEPS,
    BOX2D_ITERATIONS,
    PYMUNK_ITERATIONS,
    Box2D3Settings,
    available_scene_engines,
    make_world,
)
from benchmarks.scale_report import ENGINE_NAMES, fmt
from benchmarks.scene_suite import AWAKE_LEAD_IN, Case, Plan, Segment
from benchmarks.suite_runs import OUR_TUNED, OURS, QUICK_REPEATS, REPEATS, Builder, OurWorld, Window, run_case
from box_toss_env.files import save_figure
from box_toss_env.physics import Scene, scenes

OUR_KNOBS = {
    "dt": (1 / 60, 1 / 120, 1 / 256, 1 / 512),
    "solver_tolerance": (1e-3, 1e-4, 1e-6, 1e-9),
    "solver_iterations": (4, 8, 16, 32),
    "penetration_slop": (0.0, 1e-5, 5e-5, 2e-4),
}
"""Our settings, each turned alone from the scene's defaults (a value equal to the default is the defaults' point)."""
BOX2D3_SUBSTEP_COUNTS = (1, 2, 4, 8, 16)
BOX2D3_HERTZ = (7.5, 15.0, 30.0, 60.0, 120.0)  # with every substep count
BOX2D3_HERTZ_CAP = 1 / 8
"""Box2D 3.1 (pyb2d3 0.11) stiffens its contacts up to this share of the substep rate and no further: a setting above
acts as the cap (7.5 Hz at 1 substep of 60 Hz, 30 Hz at its default 4; measured: a 200 kg box on another sinks the
same for every setting from the cap up, and less for each setting below it; tests/benchmarks/test_pile_pareto.py)."""
BOX2D3_DAMPING = (2.0, 5.0, 20.0)  # at 4 substeps and 30 Hz
BOX2D3_PUSH = (1.0, 10.0)  # [m/s] at 4 substeps and 30 Hz
PYMUNK_ITERATION_COUNTS = (5, 10, 20, 40)
BOX2D_VELOCITY_ITERATIONS = (4, 8, 16, 32)  # position iterations 3
WINDOW, QUICK_WINDOW = 2.0, 0.25  # [s] the pile's drop; the pyramid's window is half of it
BUDGET, QUICK_BUDGET = 10.0, 1.0  # [s] CPU per window
PILE = 100
PYRAMID_ROWS = 20  # 210 boxes
FIGURE = engine_scale.DOCS / "figures" / "pile_pareto.png"
MARKER = "pile-pareto"
ERROR_FLOOR = 1e-9  # [m] depths below this are rounding (a pyramid at rest: 1e-12), equal on the front


@dataclass(frozen=True)
class Variant:
    name: str  # unique: engine and setting
    engine: str  # of ENGINE_NAMES
    setting: str
    build: Builder
    default: bool = False


def our_variants(defaults: Scene, quick: bool) -> list[Variant]:
    """Ours at the scene defaults, each knob of OUR_KNOBS turned alone, and OUR_TUNED."""
    out = [Variant("ours: defaults", OURS, "defaults", lambda case, sleep: OurWorld(case.scene, sleep), True)]
    for knob, values in OUR_KNOBS.items():
        for value in values[::3] if quick else values:
            if value == getattr(defaults, knob):
                continue
            text = setting_text(knob, value)
            build = partial(
                lambda case, sleep, knob, value: OurWorld(case.scene, sleep, **{knob: value}), knob=knob, value=value
            )
            out.append(Variant(f"ours: {text}", OURS, text, build))
    tuned = ", ".join(setting_text(k, v) for k, v in OUR_TUNED.items())
    build = partial(lambda case, sleep: OurWorld(case.scene, sleep, **OUR_TUNED))
    return [*out, Variant("ours: tuned", OURS, f"tuned: {tuned}", build)]


def setting_text(knob: str, value: float) -> str:
    return f"{knob} 1/{round(1 / value)}" if knob == "dt" else f"{knob} {value:g}"


def box2d3_variants(quick: bool) -> list[Variant]:
    """Box2D v3: substeps with contact hertz, then damping ratio and push at the defaults."""
    settings = [Box2D3Settings(s, h) for s in BOX2D3_SUBSTEP_COUNTS for h in BOX2D3_HERTZ]
    settings += [Box2D3Settings(BOX2D3_SUBSTEPS, damping_ratio=d) for d in BOX2D3_DAMPING]
    settings += [Box2D3Settings(BOX2D3_SUBSTEPS, push=p) for p in BOX2D3_PUSH]
    if quick:  # the defaults and two more
        settings = [Box2D3Settings(), Box2D3Settings(1, 7.5), Box2D3Settings(8, 60.0)]
    out = []
    for setting in settings:
        hertz, damping, push = setting.contact()
        cap = BOX2D3_HERTZ_CAP * setting.substeps / BOX2D3_DT
        acts = f" (acts as {cap:g})" if hertz > cap else ""
        text = f"{setting.substeps} substeps, {hertz:g} Hz{acts}, damping {damping:g}, push {push:g} m/s"
        default = setting.substeps == BOX2D3_SUBSTEPS and (hertz, damping, push) == tuple(BOX2D3_CONTACT.values())
        build = partial(lambda case, sleep, s: make_world("box2d3", case.scene, sleep, settings=s), s=setting)
        out.append(Variant(f"box2d3: {text}", "box2d3", text, build, default))
    return out


def iteration_variants(engine: str, counts, default: int, option) -> list[Variant]:
    out = []
    for count in counts:
        build = partial(lambda case, sleep, c: make_world(engine, case.scene, sleep, **option(c)), c=count)
        out.append(Variant(f"{engine}: {count}", engine, f"{count} iterations", build, count == default))
    return out


def variants(quick: bool, engines: list[str]) -> list[Variant]:
    out = our_variants(scenes.pile(1), quick)
    if "box2d3" in engines:
        out += box2d3_variants(quick)
    if "box2d" in engines:
        counts = BOX2D_VELOCITY_ITERATIONS[1:3] if quick else BOX2D_VELOCITY_ITERATIONS
        out += iteration_variants("box2d", counts, BOX2D_ITERATIONS[0], lambda c: {"iterations": (c, 3)})
    if "pymunk" in engines:
        counts = PYMUNK_ITERATION_COUNTS[1:3] if quick else PYMUNK_ITERATION_COUNTS
        out += iteration_variants("pymunk", counts, PYMUNK_ITERATIONS, lambda c: {"iterations": c})
    return out


def cases(window: float, pile: int = PILE, rows: int = PYRAMID_ROWS) -> list[Case]:
    """The pile dropped (sleeping off) for ``window`` s; the pyramid kept awake for half of it after the lead-in."""
    drop = (Plan(False, (Segment(window, "drop"),)),)
    awake = (Plan(False, (Segment(AWAKE_LEAD_IN), Segment(0.5 * window, "awake"))),)
    return [
        Case(f"pile {pile}", "pile", partial(scenes.pile, pile), drop),
        Case(f"pyramid {rows * (rows + 1) // 2}", "structure", partial(scenes.pyramid, rows=rows), awake),
    ]


def pareto_rows(
    quick: bool = False,
    budget: float | None = None,
    repeats: int | None = None,
    log=lambda _: None,
    pile: int = PILE,
    rows: int = PYRAMID_ROWS,
) -> list[tuple[Variant, Window, bool]]:
    """(variant, its window, on the front) for every variant in every case."""
    engines = available_scene_engines()
    chosen = variants(quick, engines)
    builders = {v.name: v.build for v in chosen}
    budget = budget if budget is not None else (QUICK_BUDGET if quick else BUDGET)
    repeats = repeats if repeats is not None else (QUICK_REPEATS if quick else REPEATS)
    found_rows = []
    for case in cases(QUICK_WINDOW if quick else WINDOW, pile, rows):
        windows, _ = run_case(case, [v.name for v in chosen], repeats, budget, log, builders)
        found = {w.engine: w for w in windows}
        pairs = [(v, found[v.name]) for v in chosen if found[v.name].steps]
        found_rows += [(v, w, on_front(w, [x for _, x in pairs])) for v, w in pairs]
    return found_rows


def on_front(window: Window, others: list[Window]) -> bool:
    """No other window is both cheaper and less deep (and at least as good in both); depths under ERROR_FLOOR are
    equal."""
    cost, error = window.us_per_body_second, max(window.quality.penetration, ERROR_FLOOR)
    return not any(
        o.us_per_body_second <= cost
        and max(o.quality.penetration, ERROR_FLOOR) <= error
        and (o.us_per_body_second < cost or max(o.quality.penetration, ERROR_FLOOR) < error)
        for o in others
    )


def table(rows) -> list[str]:
    lines = [
        "| case | engine | setting | us/body/sim-s | max penetration [m] | at the end [m] | drift [m] | front |",
        "|---|---|---|---:|---:|---:|---:|---|",
    ]
    for variant, w, front in rows:
        setting = f"**{variant.setting}** (default)" if variant.default else variant.setting
        lines.append(
            f"| {w.case} | {ENGINE_NAMES[variant.engine]} | {setting} | {engine_scale.scale_report.cost_cell(w)} | "
            f"{fmt(w.quality.penetration, '.1e')} | {fmt(w.quality.penetration_end, '.1e')} | "
            f"{fmt(w.quality.drift, '.1e')} | {'yes' if front else ''} |"
        )
    return lines


def plot(rows, path: Path = FIGURE) -> None:
    """Per case: penetration over the window, and at its end, against cost (log-log), a colour per engine, the
    defaults as stars, the Pareto front as a line."""
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(w.case for _, w, _ in rows))
    fig, axes = plt.subplots(len(names), 2, figsize=(12, 4.5 * len(names)), squeeze=False)
    engines = list(dict.fromkeys(v.engine for v, _, _ in rows))
    for i, case in enumerate(names):
        mine = [(v, w, f) for v, w, f in rows if w.case == case]
        for j, (label, value) in enumerate(
            (
                ("max penetration [m]", lambda w: w.quality.penetration),
                ("penetration at the end [m]", lambda w: w.quality.penetration_end),
            )
        ):
            ax = axes[i, j]
            for k, engine in enumerate(engines):
                points = [
                    (w.us_per_body_second, max(value(w), 1e-13), v.default) for v, w, _ in mine if v.engine == engine
                ]
                if points:
                    ax.scatter(
                        [p[0] for p in points], [p[1] for p in points], color=f"C{k}", s=18, label=ENGINE_NAMES[engine]
                    )
                    ax.scatter(
                        [p[0] for p in points if p[2]],
                        [p[1] for p in points if p[2]],
                        color=f"C{k}",
                        marker="*",
                        s=160,
                        edgecolors="k",
                    )
            front = sorted((w.us_per_body_second, max(value(w), 1e-13)) for _, w, f in mine if f)
            if front and j == 0:
                ax.step(
                    *zip(*front, strict=True),
                    where="post",
                    color="k",
                    lw=0.8,
                    alpha=0.6,
                    marker="s",
                    markerfacecolor="none",
                    markersize=9,
                    label="front",
                )
            ax.set(
                xscale="log",
                yscale="log",
                title=f"{case}: {label.split(' [')[0]}",
                ylabel=label,
                xlabel="CPU per body per simulated second [us]",
            )
            ax.grid(True, which="both", alpha=0.3)
            ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            ax.legend(fontsize=7)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=100)
    plt.close(fig)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help=f"{QUICK_WINDOW:g} s windows, fewer settings")
    parser.add_argument("--budget", type=engine_scale.positive(0.01, 3600), help="CPU s per window, [0.01, 3600]")
    parser.add_argument("--repeats", type=engine_scale.positive(1, 100, int), help="timed repeats, in [1, 100]")
    parser.add_argument(
        "--write-docs", action="store_true", help="write the table into docs/engine_scale.md and the plot"
    )
    args = parser.parse_args(argv)
    import numba

    numba.set_num_threads(1)
    began = time.perf_counter()
    rows = pareto_rows(
        args.quick,
        args.budget,
        args.repeats,
        log=lambda line: print(f"[{time.perf_counter() - began:7.1f} s] {line}", flush=True),
    )
    window = QUICK_WINDOW if args.quick else WINDOW
    lines = [
        f"`python -m benchmarks.pile_pareto{' --quick' if args.quick else ''}`: the pile dropped for {window:g} s, the "
        f"pyramid kept awake {0.5 * window:g} s after {AWAKE_LEAD_IN:g} s, sleeping off, one thread; {load_text()}.",
        "",
        *table(rows),
    ]
    text = "\n".join(lines)
    print(text)
    if args.write_docs:
        engine_scale.write_docs(text, marker=MARKER)
        plot(rows)
    if any(not math.isfinite(w.us_per_body_second) for _, w, _ in rows):
        raise SystemExit("a setting has no cost figure")


if __name__ == "__main__":
    main()
