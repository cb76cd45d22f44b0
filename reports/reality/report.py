"""Error against reality: the report (docs/reality.md and its figures) from a folder of the measured drops.

    python -m reports.reality --data DIR --write-docs  # docs/reality.md, docs/figures/reality_*.png
    python -m reports.reality --data DIR               # the same into build/reports/ (ignored by git), or --out DIR
    python -m reports.reality --data DIR --quick       # ours only, few drops, into build/reports/ (the tests)

Get DIR with ``python -m reports.reality.download --out DIR``. Every figure and number in the page is
computed here from the data; the page says which drops were dropped and why.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from box_toss_env.files import write_atomic

from .. import document
from ..document import DOCS, QUICK_OUT, REPO, table
from . import data, error
from .download import OneLineParser
from .error import HORIZONS, Evaluation, Material, Model

OUR_MODELS = (
    Model("ours", "robust", 1),
    Model("ours", "robust", 4),
    Model("ours", "seed", 1),
    Model("ours", "seed", 4),
    Model("ours", "seed", 16),
)
OTHER_SUBSTEPS = (1, 4, 16)
OTHER_ENGINES = ("pymunk", "box2d", "box2d-v3", "mujoco")
DEFAULT = Model("ours", "robust", 1)
CORNER_TILT = math.radians(15.0)  # a first impact this far from flat is a corner landing
FLAT_TILT = math.radians(5.0)  # this close, a face landing
QUICK_DROPS = 16


@dataclass
class Report:
    cleaning: data.Cleaning
    n_used: int
    n_train: int
    n_fit: int
    n_held: int
    gravity: dict[str, float]  # median, p10, p90 of the training drops' free flight
    flat_share: float  # held-out first impacts within FLAT_TILT of flat
    noise: dict[str, float]
    evaluations: list[Evaluation] = field(default_factory=list)
    extra: dict[str, Evaluation] = field(default_factory=dict)  # baselines and variants, by label
    landing: dict[str, np.ndarray] = field(default_factory=dict)  # held-out masks: corner, flat
    tilts: np.ndarray | None = None  # held-out: tilt of the nearest face at the first impact [rad]
    held: list = field(default_factory=list)  # the held-out drops
    skipped: list[str] = field(default_factory=list)
    run_seconds: float = 0.0


def models(quick: bool) -> tuple[list[Model], list[str]]:
    """The models to run, and the engines skipped because their package is not installed."""
    if quick:
        return [DEFAULT, Model("ours", "seed", 4)], []
    engines = error.other_engines()
    others = [Model(name, substeps=k) for name in OTHER_ENGINES if engines[name].available() for k in OTHER_SUBSTEPS]
    skipped = [
        f"{name} (`pip install {engines[name].package}`)" for name in OTHER_ENGINES if not engines[name].available()
    ]
    return list(OUR_MODELS) + others, skipped


def run(folder: Path, quick: bool = False) -> Report:
    begin = time.perf_counter()
    drops, cleaning = data.load(folder)
    if len(drops) < 4:
        raise ValueError(f"--data: only {len(drops)} usable drops in {folder}, at least 4 are needed")
    train, held = error.split(drops)
    if quick:
        train, held = train[: QUICK_DROPS // 2], held[: QUICK_DROPS // 2]
    fit_set = train[: error.FIT_DROPS]
    flights = np.array([d.flight_gravity for d in train])
    tilts = np.abs(data.face_angle([d.pose[d.impact, 2] for d in held]))
    report = Report(
        cleaning,
        len(drops),
        len(train),
        len(fit_set),
        len(held),
        {
            "median": float(np.median(flights)),
            "p10": float(np.percentile(flights, 10)),
            "p90": float(np.percentile(flights, 90)),
        },
        float(np.mean(tilts < FLAT_TILT)),
        error.noise_floor(drops),
        landing={"corner": tilts > CORNER_TILT, "flat": tilts < FLAT_TILT},
        tilts=tilts,
        held=held,
    )
    chosen, report.skipped = models(quick)
    for model in chosen:
        material, _ = error.fit_material(fit_set, model)
        report.evaluations.append(error.evaluate(held, model, material))
        print(f"{model.name}: e = {material.restitution:.2f}, mu = {material.friction:.2f}", flush=True)
    default = report.evaluations[0]
    gravity = report.gravity["median"]
    material, _ = error.fit_material(fit_set, DEFAULT, gravity)
    report.extra["ours, robust, fitted gravity"] = error.evaluate(held, DEFAULT, material)
    report.extra["dead drop: ours, robust, e = 0, mu = 10"] = error.evaluate(held, DEFAULT, Material(0.0, 10.0))
    report.extra["free flight, no floor"] = error.evaluate(held, DEFAULT, default.material, floorless=True)
    report.run_seconds = time.perf_counter() - begin
    return report


# -- the page -----------------------------------------------------------------------------------------------
def mm(value: float) -> str:
    return "-" if math.isnan(value) else f"{1e3 * value:.1f}"


def fine_mm(value: float) -> str:
    return f"{1e3 * value:.3f}"


def fine_deg(value: float) -> str:
    return f"{math.degrees(value):.3f}"


def deg(value: float) -> str:
    return "-" if math.isnan(value) else f"{math.degrees(value):.1f}"


def error_row(label: str, ev: Evaluation, with_time: bool = True) -> list[str]:
    cells = [label]
    cells += [mm(ev.at(h)[0]) for h in HORIZONS] + [deg(ev.at(h)[1]) for h in HORIZONS]
    position, angle = ev.mean_over(error.FIT_FRAMES)
    cells += [mm(position), deg(angle)]
    if with_time:
        cells += [
            f"{ev.material.restitution:.2f}",
            f"{ev.material.friction:.2f}",
            document.seconds(ev.seconds / ev.position.shape[0]) if ev.seconds else "-",
        ]
    return cells


ERROR_HEADER = (
    ["model"]
    + [f"position {h} [mm]" for h in HORIZONS]
    + [f"angle {h} [deg]" for h in HORIZONS]
    + [f"mean position 1-{error.FIT_FRAMES} [mm]", f"mean angle 1-{error.FIT_FRAMES} [deg]"]
)


def cleaning_section(report: Report) -> str:
    c = report.cleaning
    rows = [["files read", str(c.files)]]
    rows += [
        [
            f"dropped: {reason}",
            f"{len(numbers)} ({', '.join(map(str, numbers[:12]))}{', ...' if len(numbers) > 12 else ''})",
        ]
        for reason, numbers in c.dropped.items()
    ]
    rows += [
        ["used", str(report.n_used)],
        ["training / fitted on / held out", f"{report.n_train} / {report.n_fit} / {report.n_held}"],
        ["drops at rest at their end (for the offsets)", str(c.rest_drops)],
        [
            "rest height read (half side 30 mm)",
            f"{mm(c.rest_height)} mm, subtracted: {mm(c.rest_height - data.HALF)} mm",
        ],
        ["rest angle read", f"{deg(c.rest_angle)} deg, subtracted"],
        ["quarter turns removed by unwrapping", str(c.angle_jumps)],
        [f"raw frames with abs(vth) > {data.RAW_VTH_OUTLIER:g} rad/s (velocities recomputed)", str(c.raw_vth_outliers)],
        [
            "free-flight vertical acceleration, training drops (median, 10-90%)",
            f"{report.gravity['median']:.2f} m/s^2 ({report.gravity['p10']:.2f} to {report.gravity['p90']:.2f})",
        ],
        [
            f"held-out first impacts within {math.degrees(FLAT_TILT):.0f} deg of flat",
            f"{document.percent(report.flat_share)}",
        ],
    ]
    return table(["", ""], rows)


IMPACTS_START, IMPACTS_END = "<!-- reality-impacts:start -->", "<!-- reality-impacts:end -->"
IMPACTS_PLACEHOLDER = (
    "The impact-alone section is written here by `python -m reports.reality.impacts --data DIR --ellipse FILE` "
    "(with `--write-docs` for docs/reality.md)."
)


def impacts_section_of(page: Path) -> str:
    """What stands between the impacts markers of ``page`` (written by ``reports.reality.impacts``), kept when this
    report rewrites the page; a placeholder if there is none."""
    text = page.read_text() if page.is_file() else ""
    if IMPACTS_START in text and IMPACTS_END in text:
        return text.split(IMPACTS_START, 1)[1].split(IMPACTS_END, 1)[0].strip()
    return IMPACTS_PLACEHOLDER


def header_lines(report: Report, quick: bool) -> list[str]:
    """The page's head: where the data come from and how every engine is measured against them."""
    held = report.n_held
    return [
        "# Error against reality: measured drops of a real square",
        "",
        "Generated by `python -m reports.reality --data DIR --write-docs` from the measured drops (get them with",
        "`python -m reports.reality.download --out DIR`); do not edit by hand."
        + (" **Quick run (`--quick`): a few drops, our engine only; not the report.**" if quick else ""),
        "",
        "**Data.** 500 drops of a 0.06 m square onto a flat surface in a vertical channel, tracked at 250 Hz for",
        "200 frames (x, z, theta and their backward differences), from the GitHub repository DAIRLab/ImpactModeling,",
        "`Wang/Wang-Mason Square/dice-data-processed/traj_N.csv` (BSD-3-Clause, Copyright (c) 2020 Dynamic Autonomy",
        "and Intelligent Robotics Lab; measured on Fazeli's MCube rig). The data are not in this repository;",
        "`reports/reality/square_drops.sha256` holds their checksums.",
        "",
        "**Method.** From the state fitted to each drop's free flight, "
        f"{data.START_BEFORE_IMPACT} frames before its first impact, every engine simulates",
        f"{max(HORIZONS)} frames; position error is the distance between the simulated and measured centres, angle",
        "error the difference of the angles folded to the nearest quarter turn (the square's symmetry), both against",
        "time (ContactNets' metric). Restitution and friction are fitted per engine and step on the same training",
        f"drops (odd numbers, the first {error.FIT_DROPS}) by a grid search of the mean error over the first "
        f"{error.FIT_FRAMES} frames; all figures",
        f"below are on the {held} held-out drops (even numbers). Gravity is -9.81 m/s^2 unless said.",
        "Every engine builds the square as in `benchmarks/other_engines.py` (ours with mass "
        f"{error.MASS} kg and penalty stiffness {error.STIFFNESS:g} N/m;",
        "box2d is Box2D 2.3 (pybox2d: its 1 cm skin rounds the corners of the 6 cm square), box2d-v3 is pyb2d3",
        "with 4 substeps a step (`reports/reality/box2d_v3.py`), mujoco is MuJoCo in 2D (slide, slide, hinge)).",
        "A step of 4 ms / k is k steps a frame.",
        "",
    ]


def noise_lines(noise: dict) -> list[str]:
    """The noise floor's heading and table: how far the data are from themselves."""
    return [
        "## Noise floor: the data against itself",
        "",
        table(
            ["", "position [mm]", "angle [deg]"],
            [
                [
                    "frame-to-frame noise at rest (sigma from second differences)",
                    fine_mm(noise["rest position"]),
                    fine_deg(noise["rest angle"]),
                ],
                [
                    "RMS residual of the free-flight fits",
                    fine_mm(noise["flight position"]),
                    fine_deg(noise["flight angle"]),
                ],
            ],
        ),
        "",
    ]


def markdown(report: Report, figures: dict[str, str], quick: bool, impacts_section: str = IMPACTS_PLACEHOLDER) -> str:
    default = report.evaluations[0]
    held = report.n_held
    lines = [
        *header_lines(report, quick),
        "## Cleaning: what was done, what was dropped and why",
        "",
        cleaning_section(report),
        "",
        *noise_lines(report.noise),
        "No model can be judged below these: they are how far the data are from themselves.",
        "",
        f"## Held-out error (median over {held} drops at {', '.join(map(str, HORIZONS))} frames after the start)",
        "",
        table(
            ERROR_HEADER + ["e", "mu", "run time / drop"], [error_row(ev.model.name, ev) for ev in report.evaluations]
        ),
        "",
        "Baselines and variants (our robust solver at dt = 4 ms):",
        "",
        table(ERROR_HEADER + ["e", "mu", "run time / drop"], [error_row(k, ev) for k, ev in report.extra.items()]),
        "",
        f"![error against time](figures/{figures['time']})",
        "",
        f"![error against run time](figures/{figures['work']})",
        "",
        "Run time: wall time of the stepping of one drop's "
        f"{max(HORIZONS)} frames ({max(HORIZONS) * data.FRAME:.1f} s);",
        "ours runs all held-out drops as one scene on one thread (numba), the others step one drop at a time from",
        f"Python reading the state after every step. Machine: {document.machine()}; {document.load()}.",
        "",
        "## By landing: corner against flat first impacts",
        "",
        table(
            ["first impact", "drops"] + ERROR_HEADER[1:],
            [
                [
                    f"{name} ({'more than' if name == 'corner' else 'less than'} "
                    f"{math.degrees(CORNER_TILT if name == 'corner' else FLAT_TILT):.0f} deg from flat)",
                    str(int(mask.sum())),
                ]
                + error_row("", subset(default, mask), with_time=False)[1:]
                for name, mask in report.landing.items()
            ],
        ),
        "",
        f"({default.model.name}, e = {default.material.restitution:.2f}, mu = {default.material.friction:.2f}.)",
        "",
        "The first bounce, measured against simulated (same model), by how far from flat the square lands: the",
        "centre's vertical velocity over the two frames after the impact against the two before (frames 1 to 3 from",
        "the impact frame, so a bounce is not timed to the frame) and the spin after it.",
        "",
        table(BOUNCE_HEADER, bounces(report)),
        "",
        "## What it teaches",
        "",
        lessons(report),
        "",
    ]
    if report.skipped:
        lines += ["Skipped: " + "; ".join(report.skipped), ""]
    lines += [IMPACTS_START, impacts_section, IMPACTS_END, ""]
    return "\n".join(lines)


def subset(ev: Evaluation, mask: np.ndarray) -> Evaluation:
    predicted = None if ev.predicted is None else ev.predicted[mask]
    return Evaluation(ev.model, ev.material, ev.position[mask], ev.angle[mask], ev.seconds, ev.steps, predicted)


TILT_BINS = (0.0, 5.0, 15.0, 30.0, 45.0)  # [deg] tilt of the nearest face at the first impact


def bounce_medians(report: Report) -> list[tuple[float, float, int, np.ndarray, np.ndarray]]:
    """By tilt at the first impact (``TILT_BINS``, deg): (low, high, drops, measured, simulated), the last two
    (k, 2) arrays of the centre's bounce -vz after / vz before and the absolute spin after, the simulated ones
    from ours at its default (the first evaluation)."""
    default = report.evaluations[0]
    out = []
    for low, high in zip(TILT_BINS[:-1], TILT_BINS[1:], strict=True):
        mask = (report.tilts >= math.radians(low)) & (report.tilts < math.radians(high))
        if not mask.any():
            continue
        measured, simulated = [], []
        for k in np.flatnonzero(mask):
            drop = report.held[k]
            before, after, spin = error.first_bounce(drop.pose, drop.impact)
            measured.append((-after / before, abs(spin)))
            before, after, spin = error.first_bounce(default.predicted[k], data.START_BEFORE_IMPACT)
            simulated.append((-after / before, abs(spin)))
        out.append((low, high, int(mask.sum()), np.array(measured), np.array(simulated)))
    return out


def bounces(report: Report) -> list[list[str]]:
    """The rows of the bounce table."""

    def spread(values):
        return f"{np.median(values):.2f} ({np.percentile(values, 25):.2f} to {np.percentile(values, 75):.2f})"

    return [
        [
            f"{low:g}-{high:g}",
            str(n),
            spread(measured[:, 0]),
            spread(simulated[:, 0]),
            f"{np.median(measured[:, 1]):.1f}",
            f"{np.median(simulated[:, 1]):.1f}",
        ]
        for low, high, n, measured, simulated in bounce_medians(report)
    ]


BOUNCE_HEADER = [
    "tilt at first impact [deg]",
    "drops",
    "centre bounce -vz+/vz-, measured (25-75%)",
    "simulated (25-75%)",
    "spin after, measured [rad/s] (median abs)",
    "simulated",
]


def bounce_lesson(report: Report) -> str:
    rows = bounce_medians(report)
    if len(rows) < 2:
        return "- (too few drops for the bounce by tilt)"
    flat, steep = rows[0], rows[-1]
    words = []
    for low, high, n, measured, simulated in (flat, steep):
        words.append(
            f"{np.median(measured[:, 0]):.2f} measured against {np.median(simulated[:, 0]):.2f} simulated "
            f"at {low:g}-{high:g} deg ({n} drops)"
        )
    return (
        "- **One restitution does not fit every landing.** The centre bounces back (-vz after / vz before) "
        f"{words[0]}, and {words[1]}: the fitted e is a compromise between landings whose real bounce differs"
        " with the angle of impact. An impact law whose restitution depends on the tilt at impact (or a"
        " compliant contact for the two-corner case) is the change this data asks for; it belongs in the"
        " engine's contact model, measured here before it is adopted."
    )


def lessons(report: Report) -> str:
    """The findings, each sentence's numbers taken from the report."""
    default = report.evaluations[0]
    extra = report.extra
    by_name = {ev.model.name: ev for ev in report.evaluations}
    p20, a20 = default.at(20)
    p150, _ = default.at(150)
    dead20, _ = extra["dead drop: ours, robust, e = 0, mu = 10"].at(20)
    fitted = extra["ours, robust, fitted gravity"]
    corner, flat = (subset(default, report.landing[k]).at(20) for k in ("corner", "flat"))
    others = [ev for ev in report.evaluations if ev.model.engine != "ours" and ev.model.substeps == 1]
    best_other = min(others, key=lambda ev: ev.mean_over(error.FIT_FRAMES)[0]) if others else None
    seed = by_name.get(Model("ours", "seed", 4).name)
    fine = by_name.get(Model("ours", "robust", 4).name)
    items = [
        f"- **The contact model, not the solver, sets the error.** Our robust solver at 4 ms is {mm(p20)} mm and "
        f"{deg(a20)} deg off 20 frames (80 ms) after the start, against a noise floor of "
        f"{fine_mm(report.noise['flight position'])} mm and {fine_deg(report.noise['flight angle'])} deg; its result"
        " does not move with the step"
        + (f" (4 ms and 1 ms agree to {mm(abs(default.at(50)[0] - fine.at(50)[0]))} mm at 50 frames)" if fine else "")
        + ", so what is left is the model: "
        f"one restitution (e = {default.material.restitution:.2f}) and one friction (mu = "
        f"{default.material.friction:.2f}) for every impact.",
        f"- **Impacts are where it goes wrong.** The error grows from the first impact on and is {mm(p150)} mm at "
        f"{max(HORIZONS)} frames, where the square lies still: where it comes to rest, and on which face, is "
        "decided by the bounces, which one restitution and one friction do not predict. A model that lets the "
        f"square die where it lands (e = 0, mu = 10) is {mm(dead20)} mm off at 20 frames.",
        f"- **The spin after an impact is not predicted.** The angle error is {deg(default.at(5)[1])} deg 5 frames"
        f" after the start (2 after the impact), {deg(default.at(10)[1])} deg at 10 and {deg(a20)} deg at 20 frames,"
        " where a random angle would be 22.5 deg off (the median of a uniform error in [0, 45] deg, the square's"
        " folded symmetry): the measured spin after the first impact is not the one a rigid square with one e and"
        " one mu gets (see the bounce table), in every engine alike.",
        bounce_lesson(report),
        f"- **Corner and flat landings differ.** Corner first impacts: {mm(corner[0])} mm and {deg(corner[1])} deg at"
        f" 20 frames; flat ones (within {math.degrees(FLAT_TILT):.0f} deg, {document.percent(report.flat_share)} of"
        f" the drops): {mm(flat[0])} mm and {deg(flat[1])} deg. A flat landing puts two corners on the floor"
        " at nearly the same time, and which one hits first (a matter of a fraction of a degree) decides the spin"
        " after it; the measured square does not land as a rigid square on a rigid floor would.",
        f"- **Gravity.** The free flight fits {report.gravity['median']:.2f} m/s^2 (not -9.81); with that gravity"
        f" (restitution and friction fitted again) the error at 50 frames is {mm(fitted.at(50)[0])} mm against"
        f" {mm(default.at(50)[0])} mm with -9.81, "
        + (
            "so it is not worth the change: the difference is more likely a timing or scale error of the tracking"
            " than gravity, and fitting it would hide that."
            if fitted.mean_over(50)[0] >= 0.95 * default.mean_over(50)[0]
            else "a gain: the tracking's time or length scale is off, and the fitted value absorbs it."
        ),
    ]
    if seed is not None:
        items.append(
            f"- **The seed scheme** at 1 ms is {mm(seed.at(20)[0])} mm off at 20 frames against "
            f"{mm(p20)} mm for the robust solver: its time-stepped impacts land at the wrong instant."
        )
    if best_other is not None:
        at_4ms = sorted([default] + others, key=lambda ev: ev.mean_over(error.FIT_FRAMES)[0])
        ranking = ", ".join(
            f"{ev.model.name.split(', dt')[0]} {mm(ev.mean_over(error.FIT_FRAMES)[0])} mm in "
            f"{document.seconds(ev.seconds / ev.position.shape[0])}"
            for ev in at_4ms
        )
        items.append(
            f"- **Against the other engines**, fitted the same way, at 4 ms (mean position error over frames "
            f"1-{error.FIT_FRAMES}, run time a drop): {ranking}. Smaller steps change the others by a few mm"
            " (see the table) and ours by nothing; every engine's error is the model's, of the same size."
        )
    return "\n".join(items)


# -- the figures -------------------------------------------------------------------------------------------
def plot_time(report: Report, path: Path) -> None:
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, 2, figsize=(11, 4))
    shown = [ev for ev in report.evaluations if ev.model.substeps == 1 or ev.model == Model("ours", "seed", 4)]
    shown = [ev for ev in shown if ev.model != Model("ours", "seed", 1)]
    t = np.arange(max(HORIZONS) + 1) * data.FRAME * 1e3
    for ev in shown:
        for axis, values, scale in ((axes[0], ev.position, 1e3), (axes[1], ev.angle, 180 / math.pi)):
            median = np.nanmedian(values, axis=0) * scale
            (line,) = axis.plot(t, median, label=ev.model.name, lw=2 if ev.model == DEFAULT else 1)
            if ev.model == DEFAULT:
                low, high = (np.nanpercentile(values, q, axis=0) * scale for q in (25, 75))
                axis.fill_between(t, low, high, color=line.get_color(), alpha=0.2, label="ours robust: 25-75%")
    axes[0].axhline(report.noise["flight position"] * 1e3, color="k", ls=":", label="noise floor (free flight)")
    axes[1].axhline(math.degrees(report.noise["flight angle"]), color="k", ls=":", label="noise floor (free flight)")
    axes[0].set(
        xlabel="time after the start [ms]",
        ylabel="position error [mm] (median)",
        title=f"held-out drops ({report.n_held})",
    )
    axes[1].set(xlabel="time after the start [ms]", ylabel="angle error [deg] (median)")
    for axis in axes:
        axis.axvline(data.START_BEFORE_IMPACT * data.FRAME * 1e3, color="grey", lw=0.8)
        axis.grid(alpha=0.3)
    axes[1].legend(fontsize=7)
    document.save_figure(figure, path)


def plot_work(report: Report, path: Path) -> None:
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(6.5, 4.5))
    groups: dict[str, list[Evaluation]] = {}
    for ev in report.evaluations:
        groups.setdefault(ev.model.engine if ev.model.engine != "ours" else f"ours, {ev.model.solver}", []).append(ev)
    for name, evs in groups.items():
        x = [ev.seconds / ev.position.shape[0] for ev in evs]
        y = [ev.mean_over(error.FIT_FRAMES)[0] * 1e3 for ev in evs]
        axis.plot(x, y, "o-", label=name)
        for ev, xi, yi in zip(evs, x, y, strict=True):
            axis.annotate(f"/{ev.model.substeps}", (xi, yi), fontsize=7, textcoords="offset points", xytext=(3, 3))
    axis.axhline(report.noise["flight position"] * 1e3, color="k", ls=":", label="noise floor")
    axis.set(
        xscale="log",
        xlabel=f"run time per drop ({max(HORIZONS)} frames) [s]",
        ylabel=f"mean position error, frames 1-{error.FIT_FRAMES} [mm]",
        title="error against reality against run time (held out; /k: dt = 4 ms / k)",
    )
    axis.grid(alpha=0.3, which="both")
    axis.legend(fontsize=8)
    document.save_figure(figure, path)


def write_report(report: Report, out: Path, quick: bool = False) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    figures = {"time": "reality_error_time.png", "work": "reality_work.png"}
    plot_time(report, out / "figures" / figures["time"])
    plot_work(report, out / "figures" / figures["work"])
    path = out / "reality.md"
    write_atomic(path, markdown(report, figures, quick, impacts_section_of(path)))
    return path


def main(argv=None) -> int:
    parser = OneLineParser(prog="python -m reports.reality", description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, required=True, help="folder of the measured traj_N.csv files")
    parser.add_argument("--quick", action="store_true", help=f"{QUICK_DROPS} drops, our engine only (the tests)")
    parser.add_argument(
        "--out", type=Path, default=None, help=f"output folder (default: {QUICK_OUT.relative_to(REPO)}, ignored by git)"
    )
    parser.add_argument(
        "--write-docs", action="store_true", help="write the full report into docs/reality.md (a tracked file)"
    )
    args = parser.parse_args(argv)
    if args.write_docs and (args.quick or args.out is not None):
        parser.error("--write-docs writes the full report into docs/: drop " + ("--quick" if args.quick else "--out"))
    out = DOCS if args.write_docs else (args.out or QUICK_OUT)
    if out.exists() and not out.is_dir():
        raise SystemExit(f"{parser.prog}: error: --out: {out} is not a folder")
    try:
        report = run(args.data, quick=args.quick)
    except ValueError as problem:
        if str(problem).startswith("--data"):
            raise SystemExit(f"{parser.prog}: error: {problem}") from None
        raise
    path = write_report(report, out, args.quick)
    print(Path(path).read_text().split("## What it teaches")[0].split("## Cleaning")[1])
    print(f"wrote {path} in {report.run_seconds:.0f} s")
    return 0
