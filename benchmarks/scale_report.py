"""The engine comparison's tables, goals, plot and README summary, from the windows ``suite_runs`` measured
(``benchmarks.engine_scale`` runs them and writes what this module makes)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from benchmarks.scene_suite import Case
from benchmarks.suite_runs import OURS, OURS_TUNED, Window
from box_toss_env.files import save_figure

ENGINE_NAMES = {OURS: "ours", OURS_TUNED: "ours, tuned", "box2d3": "Box2D v3", "box2d": "Box2D 2.3", "pymunk": "pymunk"}
OTHERS = ("box2d3", "box2d", "pymunk")
RIVAL = "box2d3"  # the engine the goals compare ours with
PENETRATION_LIMIT, REST_PENETRATION_LIMIT = 1e-3, 1e-4  # [m at the 40 x 20 cm box's scale] the engine goals' bounds
SPREAD_FROM = 0.01  # [s] of CPU: shorter windows' spread is the clock's and the cache's, not the engine's
AT_REST = ("rest", "awake", "stand", "published")  # windows in which the scene should lie still at the end
SLEEPING = ("rest", "stand", "throw")  # windows with each engine's default sleeping, after or at rest
WINDOW_TEXT = {
    "drop": "dropped",
    "rest": "at rest",
    "awake": "kept awake",
    "stand": "standing",
    "throw": "thrown in",
    "published": "as published",
}
README_ROWS = (("pile 1000", "drop"), ("throw 30 m/s", "throw"), ("large_pyramid", "published"))
"""The README's rows (it holds at most 160 lines): a pile in motion, the throw into a pile that sequential tasks make,
Box2D's own benchmark."""


def fmt(value: float, spec: str) -> str:
    return "-" if value is None or not math.isfinite(value) else format(value, spec)


def keyed(windows: Sequence[Window]) -> dict[tuple[str, str, str], Window]:
    return {(w.case, w.label, w.engine): w for w in windows}


def window_keys(windows: Sequence[Window]) -> list[tuple[str, str]]:
    return list(dict.fromkeys((w.case, w.label) for w in windows))


def cost_cell(window: Window | None) -> str:
    """us per body per simulated second, with the steps run where the budget cut the window."""
    if window is None:
        return ""
    if not window.steps or not window.seconds:
        return "n/a"
    text = f"{window.us_per_body_second:,.1f}"
    return f"{text} ({window.steps}/{window.wanted} steps)" if window.cut else text


def ratio(ours: Window | None, rival: Window | None) -> float:
    if ours is None or rival is None:
        return math.nan
    return ours.us_per_body_second / rival.us_per_body_second


def verdict(value: float) -> str:
    """ours / Box2D v3 in words: where ours loses, the table says so."""
    if not math.isfinite(value):
        return "-"
    return f"ours loses, {value:,.1f}x" if value > 1.0 else f"ours wins, {value:.2f}x"


def cost_table(windows: Sequence[Window]) -> list[str]:
    """us per body per simulated second, a row per case and window, an engine a column."""
    by = keyed(windows)
    engines = [e for e in (OURS, *OTHERS) if any(w.engine == e for w in windows)]
    tuned = any(w.engine == OURS_TUNED for w in windows)
    head = ["case", "window", "boxes", *(ENGINE_NAMES[e] for e in engines), "ours / Box2D v3"]
    head += ["ours, tuned (beside, not instead)"] if tuned else []
    align = ["---", "---", "---:", *["---:"] * len(engines), "---", *(["---:"] if tuned else [])]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join(align) + "|"]
    for case, label in window_keys(windows):
        row = [case, WINDOW_TEXT.get(label, label), f"{next(w.n for w in windows if w.case == case):,}"]
        row += [cost_cell(by.get((case, label, engine))) for engine in engines]
        row.append(verdict(ratio(by.get((case, label, OURS)), by.get((case, label, RIVAL)))))
        row += [cost_cell(by.get((case, label, OURS_TUNED)))] if tuned else []
        lines.append("| " + " | ".join(row) + " |")
    return lines


def quality_table(windows: Sequence[Window], cases: dict[str, Case]) -> list[str]:
    """What each engine did in each window."""
    lines = [
        "| case | window | engine | dt [s] | steps | max penetration [m] | at the end [m] | energy gain [J] | "
        "max rise [m] | tunnelled | all asleep at [s] | asleep at the end | moving at the end | drift [m] |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for w in windows:
        if not w.steps:
            continue
        q = w.quality
        gain = fmt(q.energy_gain, ".1e") + (" (gained)" if q.gains_energy else "")
        tunnel = f"{q.tunnelled}" + (", crossed the pile" if q.crossed else "")
        drift = fmt(q.drift, ".1e")
        if cases[w.case].kind in ("structure", "published"):
            drift += " (holds)" if w.stands else " (moved)"
        lines.append(
            f"| {w.case} | {WINDOW_TEXT.get(w.label, w.label)} | {ENGINE_NAMES[w.engine]} | {dt_text(w.dt)} | "
            f"{w.steps}/{w.wanted} | {fmt(q.penetration, '.1e')} | {fmt(q.penetration_end, '.1e')} | {gain} | "
            f"{fmt(q.rise, '.2g')} | {tunnel} | {fmt(q.asleep_at, '.2f')} | {q.asleep_end:,} | {q.moving_end:,} | "
            f"{drift} |"
        )
    return lines


def goals(window: Window, rival: Window | None, case: Case) -> dict[str, str]:
    """The engine goals for one window of ours: 'yes', 'no (the figure)' or '-' where a goal does not apply."""
    q, scale = window.quality, case.scale

    def check(ok: bool, figure: str) -> str:
        return "yes" if ok else f"no ({figure})"

    value = ratio(window, rival)
    out = {
        "cost <= Box2D v3": "-" if not math.isfinite(value) else check(value <= 1.0, f"{value:,.1f}x"),
        "penetration <= 1 mm": check(q.penetration <= PENETRATION_LIMIT * scale, f"{q.penetration:.1e} m"),
        "<= 0.1 mm at rest": "-",
        "stands": "-",
        "no tunnelling": check(
            q.tunnelled == 0 and not q.crossed, f"{q.tunnelled}" + (", crossed" if q.crossed else "")
        ),
        "no energy gain": check(not q.gains_energy, f"{q.energy_gain:.1e} J"),
        "no jitter": "-",
        "asleep at the end": "-",
    }
    if window.label in AT_REST:
        limit = REST_PENETRATION_LIMIT * scale
        out["<= 0.1 mm at rest"] = check(q.penetration_end <= limit, f"{q.penetration_end:.1e} m")
        out["no jitter"] = check(q.moving_end == 0, f"{q.moving_end} moving")
    if case.kind in ("structure", "published"):
        out["stands"] = check(window.stands, f"drift {q.drift:.1e} m")
    if window.label in SLEEPING:
        out["asleep at the end"] = check(q.asleep_end == window.n, f"{q.asleep_end:,} of {window.n:,}")
    return out


def goals_table(windows: Sequence[Window], cases: dict[str, Case]) -> list[str]:
    """Ours at its defaults against the engine goals, a row per window."""
    by = keyed(windows)
    rows = [(w, goals(w, by.get((w.case, w.label, RIVAL)), cases[w.case])) for w in windows if w.engine == OURS]
    rows = [(w, g) for w, g in rows if w.steps]
    if not rows:
        return []
    names = list(rows[0][1])
    lines = ["| case | window | " + " | ".join(names) + " |", "|---|---|" + "---|" * len(names)]
    for w, g in rows:
        lines.append(f"| {w.case} | {WINDOW_TEXT.get(w.label, w.label)} | " + " | ".join(g.values()) + " |")
    return lines


def dt_text(dt: float) -> str:
    if not math.isfinite(dt):
        return "-"
    return f"1/{round(1 / dt)}" if abs(1 / dt - round(1 / dt)) < 1e-9 else f"{dt:g}"


def notes(windows: Sequence[Window]) -> list[str]:
    """Unsupported scenes, cut and skipped windows, shared CPU, and the repeats' widest spread."""
    lines = []
    for w in windows:
        if w.note:
            lines.append(f"- {ENGINE_NAMES[w.engine]}, {w.case}, {WINDOW_TEXT.get(w.label, w.label)}: {w.note}")
        elif w.cut:
            lines.append(
                f"- {ENGINE_NAMES[w.engine]}, {w.case}, {WINDOW_TEXT.get(w.label, w.label)}: the budget cut the "
                f"window at {w.steps} of {w.wanted} steps ({w.steps * w.dt:.3g} s of {w.wanted * w.dt:.3g} s)"
            )
    timed = [w for w in windows if len(w.seconds) > 1 and w.cpu >= SPREAD_FROM]
    if timed:
        widest = max(timed, key=lambda w: w.spread)
        lines.append(
            f"- the repeats' widest spread, (slowest - fastest) / median, over the windows of {SPREAD_FROM * 1e3:g} ms "
            f"of CPU or more: {100 * widest.spread:.0f}% ({ENGINE_NAMES[widest.engine]}, {widest.case}, "
            f"{WINDOW_TEXT.get(widest.label, widest.label)})"
        )
    return lines


def loop_note(overhead: dict[str, float], windows: Sequence[Window]) -> list[str]:
    """What stepping from Python adds to the other engines' figures (``suite_runs.loop_overhead``'s us per step):
    the loop, and an empty Box2D v3 world's whole step as a share of Box2D v3's step in each scene of 20 boxes or
    fewer, the largest share over its windows in motion named."""
    if "loop" not in overhead:
        return []
    line = (
        "- Stepping from Python: Box2D v3, Box2D 2.3 and pymunk are stepped by a Python loop, one call a step, as "
        f"their users step them (ours runs a window in one call). The loop around a call that does nothing costs "
        f"{overhead['loop']:.3f} us a step"
    )
    empty = overhead.get("box2d3 empty")
    small = [w for w in windows if w.engine == RIVAL and w.n <= 20 and w.steps and w.seconds and w.label != "rest"]
    if empty is None or not small:
        return [line + "."]
    shares = [empty / (1e6 * w.cpu / w.steps) for w in small]
    top = small[shares.index(max(shares))]
    resting = [
        empty / (1e6 * w.cpu / w.steps) for w in windows if w.engine == RIVAL and w.label == "rest" and w.seconds
    ]
    rest_text = (
        f" In its windows at rest, where its bodies sleep, the empty world's step is {100 * min(resting):.0f}-"
        f"{100 * max(resting):.0f}% of its step."
        if resting
        else ""
    )
    return [
        line + f"; an empty Box2D v3 world's whole step through it, {empty:.2f} us (Box2D's fixed cost a step "
        f"included): in the scenes of 20 boxes or fewer, up to {100 * max(shares):.0f}% of Box2D v3's step "
        f"({top.case}, {WINDOW_TEXT.get(top.label, top.label)}: {empty * 1e-6 / (top.n * top.dt) * 1e6:.1f} of its "
        f"{top.us_per_body_second:.1f} us per body per simulated second).{rest_text}"
    ]


def losses(windows: Sequence[Window]) -> tuple[int, int]:
    """(windows where ours costs more than Box2D v3, windows where both have a figure)."""
    by = keyed(windows)
    pairs = [ratio(w, by.get((w.case, w.label, RIVAL))) for w in windows if w.engine == OURS]
    pairs = [p for p in pairs if math.isfinite(p)]
    return sum(p > 1.0 for p in pairs), len(pairs)


def readme_summary(windows: Sequence[Window], header: str, onbox_text: str) -> str:
    """Ours beside Box2D v3 at their defaults on README_ROWS, from the same run as the page."""
    by = keyed(windows)
    lines = [
        "| at the defaults, us per box per simulated second | ours | Box2D v3 | ours / Box2D v3 | "
        "max penetration [m]: ours | Box2D v3 |",
        "|---|---:|---:|---|---:|---:|",
    ]
    for case, label in README_ROWS:
        ours, rival = by.get((case, label, OURS)), by.get((case, label, RIVAL))
        if ours is None or rival is None or not ours.steps or not rival.steps:
            continue
        lines.append(
            f"| {case}, {WINDOW_TEXT[label]} | {cost_cell(ours)} | {cost_cell(rival)} | "
            f"{verdict(ratio(ours, rival))} | {fmt(ours.quality.penetration, '.1e')} | "
            f"{fmt(rival.quality.penetration, '.1e')} |"
        )
    lost, compared = losses(windows)
    text = (
        f"{header} Ours costs more than Box2D v3 in {lost} of the {compared} windows of the suite; every case, "
        f"engine and measure: [the page](docs/engine_scale.md).{onbox_text}"
    )
    return "\n".join([*lines, "", text])


def plot(windows: Sequence[Window], path: Path) -> None:
    """Left: piles, us per body per simulated second against boxes (solid dropped, dashed kept awake). Right: ours /
    Box2D v3 for every window, at the defaults (and tuned, hollow)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 6.5), gridspec_kw={"width_ratios": [1, 1.2]})
    piles = [w for w in windows if w.case.startswith("pile ") and w.steps and w.seconds]
    for k, engine in enumerate(e for e in ENGINE_NAMES if any(w.engine == e for w in piles)):
        for label, style in (("drop", "-"), ("awake", "--")):
            points = sorted((w.n, w.us_per_body_second) for w in piles if w.engine == engine and w.label == label)
            if points:
                name = f"{ENGINE_NAMES[engine]}, {WINDOW_TEXT[label]}"
                left.loglog(*zip(*points, strict=True), style, marker="o", color=f"C{k}", label=name)
    left.set_xlabel("boxes in the pile")
    left.set_ylabel("thread CPU per body per simulated second [us]")
    left.set_title("Piles, each engine at its defaults, one thread")
    left.grid(True, which="both", alpha=0.3)
    if piles:
        left.legend(fontsize=7)
    plot_ratios(right, windows)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def plot_ratios(ax, windows: Sequence[Window]) -> None:
    by = keyed(windows)
    keys = [k for k in window_keys(windows) if (*k, OURS) in by and (*k, RIVAL) in by]
    names = [f"{case}, {WINDOW_TEXT.get(label, label)}" for case, label in keys]
    ys = range(len(keys))
    for engine, marker, fill in ((OURS, "o", True), (OURS_TUNED, "o", False)):
        values = [ratio(by.get((*k, engine)), by.get((*k, RIVAL))) for k in keys]
        colours = ["C3" if v > 1 else "C2" for v in values]
        face = colours if fill else "none"
        ax.scatter(values, ys, marker=marker, facecolors=face, edgecolors=colours, label=ENGINE_NAMES[engine])
    ax.axvline(1.0, color="k", lw=1)
    ax.set_xscale("log")
    ax.set_yticks(list(ys), names, fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("ours / Box2D v3, CPU per body per simulated second (red: ours loses, green: wins)")
    ax.set_title("Every window of the suite")
    ax.grid(True, which="both", axis="x", alpha=0.3)
    ax.legend(fontsize=7)
