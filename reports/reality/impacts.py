"""Post-impact velocity error: the impact alone, on the square drops' first impacts and on the ellipse impacts.

    python -m reports.reality.impacts --data DIR [--ellipse FILE] --write-docs   # its section of docs/reality.md
    python -m reports.reality.impacts --data DIR [--ellipse FILE]   # of build/reports/reality.md (ignored by git)

**Square** (``--data``: the folder of ``traj_N.csv``, cleaned by ``data.load``). For each usable drop, the
measured pre-impact state is its free-flight fit 3 frames before the first impact (as the trajectory report
starts); the measured post-impact velocity is the central difference of the poses over frames impact+1 ..
impact+3 (the velocity at frame impact+2, exact for a free flight); every model's prediction goes through the
same central difference of its poses, so both sides are read alike. A model is either an engine simulating the
6 frames (ours with the robust solver: the impact at the instant a corner reaches the floor, and the second
corner's impact of a flat landing if it comes within the frames; the other engines of the trajectory report)
or a point-contact impact map at the lowest corner, applied at the instant the fitted free flight's lowest corner
reaches the floor, free flight before and after (``impact_law``: our engine's law and Newton + Coulomb).
Corner impacts land more than 15 deg from flat. Restitution and friction are fitted per model on the training
drops (odd numbers) of the class reported, by grid search of the mean normalised error; figures are on the
held-out drops (even numbers).

**Ellipse** (``--ellipse``: ``data_ellipse.mat`` of mcubelab/planar-impact-dataset, read where the user put it,
e.g. with ``python -m reports.reality.download --ellipse --out DIR``; it has no licence and is not in this
repository). 1,718 measured impacts of an ellipse (36.4 g, semi-axes 35 x
25 mm, radius of gyration 19.2 mm) with pre- and post-impact states and the contact Jacobian's normal and tangent
rows; the impact laws are applied with that Jacobian; training rows are the even ones (0-based), held-out the odd
ones. If ``v_models.mat`` (the six published models' predictions) lies beside it, their errors on the same
held-out rows are computed too.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import data, error, impact_law
from .download import OneLineParser
from .error import Material, Model

SECTION = "reality-impacts"
PAGE = Path(__file__).resolve().parents[2] / "docs" / "reality.md"  # --write-docs rewrites its section
QUICK_PAGE = Path(__file__).resolve().parents[2] / "build" / "reports" / "reality.md"  # the default, ignored by git
SQUARE_GYRATION = data.SIDE / math.sqrt(6.0)  # [m] a uniform square: I = m s^2 / 6
BEFORE = data.START_BEFORE_IMPACT  # frames from the start to the impact frame
FRAMES = BEFORE + 3  # simulated frames: to impact + 3
CORNER_TILT = math.radians(15.0)
FLAT_TILT = math.radians(5.0)
SEARCH_STEP = 1e-5  # [s] the scan for the instant the free flight's lowest corner reaches the floor

ELLIPSE_MASS = 36.4e-3  # [kg]
ELLIPSE_GYRATION = 0.0192  # [m]
PUBLISHED = ("Drumwright-Shell", "AP Poisson", "AP Newton", "Mirtich", "Wang-Mason", "Whittaker")
PUBLISHED_RANGE = "0.59-0.64 mean / 0.51-0.55 median (Fazeli et al. 2017)"
TARGET_CORNER = (0.38, 0.27)  # the target: a point-contact Newton + Coulomb map's error on the corner impacts
ENGINES = ("pymunk", "box2d", "box2d-v3", "mujoco")


# -- the square's first impacts ------------------------------------------------------------------------------
@dataclass
class SquareImpacts:
    """The first impacts of the usable drops: what is measured of each."""

    numbers: np.ndarray  # drop numbers
    states: np.ndarray  # (n, 6) fitted free-flight state at the start frame (BEFORE frames before the impact)
    before: np.ndarray  # (n, 3) measured velocity at frame impact - 2 (central difference of frames -3, -1)
    after: np.ndarray  # (n, 3) measured velocity at frame impact + 2 (central difference of frames +1, +3)
    tilt: np.ndarray  # (n,) angle of the nearest face to the floor at the impact frame [rad]

    def mask(self, kind: str) -> np.ndarray:
        return self.tilt > CORNER_TILT if kind == "corner" else np.ones(len(self.tilt), bool)

    def subset(self, mask) -> SquareImpacts:
        return SquareImpacts(*(a[mask] for a in (self.numbers, self.states, self.before, self.after, self.tilt)))


def central(poses: np.ndarray, first: int) -> np.ndarray:
    """(n, 3) (poses[:, first + 2] - poses[:, first]) / (2 frames)."""
    return (poses[:, first + 2] - poses[:, first]) / (2 * data.FRAME)


def square_impacts(drops: list[data.Drop]) -> SquareImpacts:
    """The first impacts of ``drops`` whose recording goes on 3 frames past it."""
    drops = [d for d in drops if d.impact + 3 < data.FRAMES]
    poses = np.stack([d.pose[d.impact - BEFORE : d.impact + 4] for d in drops])
    return SquareImpacts(
        np.array([d.number for d in drops]),
        error.initial_states(drops),
        central(poses, 0),
        central(poses, BEFORE + 1),
        np.abs(data.face_angle([d.pose[d.impact, 2] for d in drops])),
    )


def flight(states: np.ndarray, t, gravity: float = error.EARTH) -> np.ndarray:
    """Poses (..., 3) of free flights from ``states`` (n, 6) after times ``t`` (n,) or (n, k)."""
    t = np.asarray(t, dtype=float)
    s = states if t.ndim == 1 else states[:, None, :]
    return np.stack(
        [s[..., 0] + s[..., 3] * t, s[..., 1] + s[..., 4] * t + 0.5 * gravity * t**2, s[..., 2] + s[..., 5] * t],
        axis=-1,
    )


def contact_instant(states: np.ndarray, horizon: float = FRAMES * data.FRAME) -> np.ndarray:
    """(n,) first time the lowest corner of each free flight reaches the floor (scanned every 10 SEARCH_STEP, then
    bisected to SEARCH_STEP), or, for a flight that never does before ``horizon``, the time it comes closest."""
    step = 10 * SEARCH_STEP
    t = np.arange(0.0, horizon + step / 2, step)
    poses = flight(states, np.broadcast_to(t, (len(states), len(t))))
    height = data.lowest_corner(poses[..., 1], poses[..., 2])
    below = height <= 0.0
    touches = below.any(axis=1)
    first = np.argmax(below, axis=1)
    high, low = t[first], t[np.maximum(first - 1, 0)]
    while np.any(high - low > SEARCH_STEP / 2):  # the corner is above the floor at low, on or below it at high
        middle = 0.5 * (low + high)
        pose = flight(states, middle)
        down = data.lowest_corner(pose[:, 1], pose[:, 2]) <= 0.0
        high, low = np.where(down, middle, high), np.where(down, low, middle)
    return np.where(touches, high, t[np.argmin(height, axis=1)])


def lever_arms(angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rx, ry) of the lowest corner of the square at ``angle`` (n,)."""
    signs = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]]) * data.HALF
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    rx = c * signs[:, 0] - s * signs[:, 1]
    ry = s * signs[:, 0] + c * signs[:, 1]
    lowest = np.argmin(ry, axis=1)
    rows = np.arange(len(angle))
    return rx[rows, lowest], ry[rows, lowest]


def point_map_poses(states: np.ndarray, law: str, restitution, friction) -> np.ndarray:
    """(n, FRAMES + 1, 3) poses on the frames: free flight to the contact instant, ``law`` at the lowest corner,
    free flight after (no second impact)."""
    tc = contact_instant(states)
    at = flight(states, tc)
    pre = states[:, 3:].copy()
    pre[:, 1] += error.EARTH * tc
    rx, ry = lever_arms(at[:, 2])
    inertia = error.MASS * SQUARE_GYRATION**2
    post = impact_law.apply(law, pre, rx, ry, restitution, friction, error.MASS, inertia)
    t = np.arange(FRAMES + 1) * data.FRAME
    before = flight(states, np.broadcast_to(t, (len(states), len(t))))
    after = flight(np.hstack([at, post]), t[None, :] - tc[:, None])
    return np.where((t[None, :] < tc[:, None])[..., None], before, after)


def predict(impacts: SquareImpacts, model: str, e, mu) -> tuple[np.ndarray, float]:
    """(n, 3) predicted velocities at frame impact + 2 by ``model`` ("map: ours", "map: newton", or an engine's
    name for ``error.simulate``: "ours" is our robust solver), e and mu scalars or (n,); and the run's seconds."""
    n = len(impacts.states)
    begin = time.perf_counter()
    if model.startswith("map: "):
        poses = point_map_poses(impacts.states, model.removeprefix("map: "), e, mu)
    else:
        e, mu = (np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in (e, mu))
        materials = [Material(float(a), float(b)) for a, b in zip(e, mu, strict=True)]
        engine = Model("ours", "robust") if model == "ours" else Model(model)
        poses, _ = error.simulate(impacts.states, materials, engine, FRAMES)
    return central(poses, BEFORE + 1), time.perf_counter() - begin


def fit_square(impacts: SquareImpacts, model: str) -> tuple[float, float]:
    """e and mu minimising the mean normalised error of ``model`` on ``impacts`` (all grid points of a search in one
    run: one scene for our engine)."""
    n = len(impacts.states)

    def loss(e, mu):
        tiled = SquareImpacts(
            *(
                np.tile(a, (len(e),) + (1,) * (a.ndim - 1))
                for a in (impacts.numbers, impacts.states, impacts.before, impacts.after, impacts.tilt)
            )
        )
        predicted, _ = predict(tiled, model, np.repeat(e, n), np.repeat(mu, n))
        errors = impact_law.normalised_error(predicted, tiled.after, SQUARE_GYRATION).reshape(len(e), n)
        return np.where(np.isfinite(errors).all(axis=1), errors.mean(axis=1), np.inf)

    e, mu, _ = impact_law.grid_fit(loss, coarse=np.linspace(0.0, 1.0, 6), friction_max=1.0)
    return e, mu


@dataclass
class Result:
    """One model on one class of held-out impacts."""

    model: str
    kind: str  # "corner" or "all"
    e: float
    mu: float
    errors: np.ndarray  # (n,) held-out normalised errors
    seconds: float = 0.0
    et: float = math.nan  # the tangential restitution, for the proposal's law
    predicted: np.ndarray | None = None  # (n, 3) the predicted post-impact velocities

    @property
    def mean(self) -> float:
        return float(np.nanmean(self.errors))

    @property
    def median(self) -> float:
        return float(np.nanmedian(self.errors))


def square_models(engines: bool) -> list[str]:
    names = ["ours", "map: ours", "map: newton"]
    if engines:
        others = error.other_engines()
        names += [name for name in ENGINES if others[name].available()]
    return names


ELLIPSE_LABELS = {
    "ours": "our engine's impact law (Poisson + Coulomb, robust solver)",
    "newton": "point contact, Newton + Coulomb",
}
MODEL_LABELS = {
    "ours": "ours, robust solver, dt = 4 ms (both corners of a flat landing)",
    "map: ours": "our impact law at the lowest corner only (one impact)",
    "map: newton": "point contact, Newton + Coulomb (the kind of map that set the target)",
}


def dropped_text(cleaning: data.Cleaning) -> str:
    """What the cleaning dropped, by reason, for an error message."""
    reasons = [f"{len(numbers)} {reason}" for reason, numbers in cleaning.dropped.items()]
    return f"of {cleaning.files} traj_N.csv files, dropped: {'; '.join(reasons) or 'none'}"


def check_sets(folder: Path, train: SquareImpacts, held: SquareImpacts, cleaning: data.Cleaning) -> None:
    """A ValueError (``--data: ...``, one line) unless each class of impacts has a training drop (odd number) and
    a held-out one (even number)."""
    for kind in ("corner", "all"):
        fit, test = int(train.mask(kind).sum()), int(held.mask(kind).sum())
        if not fit or not test:
            raise ValueError(
                f"--data: {folder} has {fit} odd-numbered (fitted) and {test} even-numbered (held-out) usable "
                f"{'corner ' if kind == 'corner' else ''}impacts; the report needs one of each at least "
                f"({dropped_text(cleaning)})"
            )


def run_square(folder: Path, engines: bool = True, quick: bool = False) -> dict:
    drops, cleaning = data.load(folder)
    drops = [d for d in drops if d.impact + 3 < data.FRAMES]  # recorded 3 frames past the impact (square_impacts)
    if not drops:
        raise ValueError(f"--data: no usable drop in {folder} ({dropped_text(cleaning)})")
    impacts = square_impacts(drops)
    train = impacts.subset(impacts.numbers % 2 == 1)
    held = impacts.subset(impacts.numbers % 2 == 0)
    check_sets(folder, train, held, cleaning)
    results = []
    for kind in ("corner", "all"):
        fit_on, test_on = train.subset(train.mask(kind)), held.subset(held.mask(kind))
        if quick:
            fit_on, test_on = fit_on.subset(slice(0, 12)), test_on.subset(slice(0, 12))
        for model in square_models(engines and not quick):
            e, mu = fit_square(fit_on, model)
            predicted, seconds = predict(test_on, model, e, mu)
            errors = impact_law.normalised_error(predicted, test_on.after, SQUARE_GYRATION)
            results.append(Result(model, kind, e, mu, errors, seconds, predicted=predicted))
            print(
                f"square, {kind}, {model}: e = {e:.2f}, mu = {mu:.2f}, mean {results[-1].mean:.3f}, "
                f"median {results[-1].median:.3f}",
                flush=True,
            )
    # the flat landings of the held-out set under each model fitted on all impacts
    return {
        "impacts": impacts,
        "train": train,
        "held": held,
        "results": results,
        "cleaning": cleaning,
        "proposal": tilt_restitution(train, held, quick),
    }


def tilt_restitution(train: SquareImpacts, held: SquareImpacts, quick: bool) -> dict:
    """The proposal measured: our engine with e and mu fitted separately on flat-ish (< 15 deg) and corner
    landings (chosen by the tilt at the impact frame), against one pair for all."""
    out = {}
    predicted = np.empty_like(held.after)
    for name, select in (("flat-ish", lambda s: s.tilt <= CORNER_TILT), ("corner", lambda s: s.tilt > CORNER_TILT)):
        fit_on = train.subset(select(train))
        test_mask = select(held)
        if quick:
            fit_on = fit_on.subset(slice(0, 12))
        e, mu = fit_square(fit_on, "ours")
        predicted[test_mask], _ = predict(held.subset(test_mask), "ours", e, mu)
        out[name] = (e, mu)
    out["errors"] = impact_law.normalised_error(predicted, held.after, SQUARE_GYRATION)
    return out


# -- the ellipse --------------------------------------------------------------------------------------------
@dataclass
class EllipseImpacts:
    before: np.ndarray  # (n, 6) x, y, theta, vx, vy, omega before the impact
    after: np.ndarray  # (n, 6) after
    normal: np.ndarray  # (n, 3) the contact Jacobian's normal row
    tangent: np.ndarray  # (n, 3) its tangent row
    published: np.ndarray | None = None  # (n, 6, 3) the six published models' post-impact velocities


def read_mat(path: Path) -> dict:
    """The variables of a MATLAB file: scipy.io for versions 4 to 7.2, h5py for 7.3 (HDF5)."""
    try:
        import scipy.io
    except ImportError as missing:
        raise SystemExit("reading a .mat file needs scipy: pip install scipy") from missing
    try:
        return scipy.io.loadmat(path, squeeze_me=True, struct_as_record=False)
    except NotImplementedError:  # MATLAB 7.3: HDF5
        import h5py

        with h5py.File(path, "r") as f:
            return {
                key: {k: np.asarray(v).T for k, v in f[key].items()}
                if isinstance(f[key], h5py.Group)
                else np.asarray(f[key]).T
                for key in f
            }


def ellipse_arrays(path: Path) -> EllipseImpacts:
    """The four arrays of ``data_ellipse.mat``'s struct ``data``, checked: a ValueError (``--ellipse: ...``)
    naming the file and what is wrong if it is not a MATLAB file, or not of the dataset's layout."""
    try:
        record = read_mat(path)["data"]
        field_of = (lambda name: record[name]) if isinstance(record, dict) else (lambda name: getattr(record, name))
        arrays = [np.asarray(field_of(name), dtype=float) for name in ("states_i", "states_f", "n", "d")]
    except Exception as error:  # scipy and h5py raise a dozen types for a file that is not theirs
        if isinstance(error, OSError) and error.errno is not None:
            raise  # the file system's refusal: said by main
        raise ValueError(
            f"--ellipse: {path} is not the planar impact dataset's data_ellipse.mat (a MATLAB struct data with "
            f"states_i, states_f, n, d): {type(error).__name__}: {' '.join(str(error).split())[:120]}"
        ) from None
    shapes = [array.shape for array in arrays]
    rows = shapes[0][0] if shapes[0] else 0
    if not rows or [shape[1:] for shape in shapes] != [(6,), (6,), (3,), (3,)] or {s[0] for s in shapes} != {rows}:
        raise ValueError(f"--ellipse: {path}: its arrays are of shapes {shapes}, not (n, 6), (n, 6), (n, 3), (n, 3)")
    return EllipseImpacts(*arrays)


def read_ellipse(path: Path) -> EllipseImpacts:
    """``data_ellipse.mat`` (a struct ``data`` with states_i, states_f, n, d) and, if it lies beside it,
    ``v_models.mat`` (``v_models``, n x 18: six models' vx, vy, omega)."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(
            f"--ellipse: {path} is not a file (download processed_data/data_ellipse.mat of "
            "mcubelab/planar-impact-dataset)"
        )
    impacts = ellipse_arrays(path)
    if not (np.allclose(impacts.normal[:, :2], [0.0, 1.0]) and np.allclose(impacts.tangent[:, :2], [1.0, 0.0])):
        raise ValueError(f"--ellipse: {path}: the contact is not on a horizontal floor (normal rows (0, 1, .))")
    models = path.with_name("v_models.mat")
    if models.is_file():
        try:
            table = np.asarray(read_mat(models)["v_models"], dtype=float)
        except Exception as error:  # as in ellipse_arrays
            if isinstance(error, OSError) and error.errno is not None:
                raise
            raise ValueError(f"--ellipse: {models} (beside it) is not the published models' v_models.mat") from None
        if table.shape == (len(impacts.before), 3 * len(PUBLISHED)):
            impacts.published = table.reshape(len(table), len(PUBLISHED), 3)
    return impacts


def ellipse_predict(impacts: EllipseImpacts, rows, law: str, e, mu) -> np.ndarray:
    inertia = ELLIPSE_MASS * ELLIPSE_GYRATION**2
    return impact_law.apply(
        law, impacts.before[rows, 3:], impacts.normal[rows, 2], -impacts.tangent[rows, 2], e, mu, ELLIPSE_MASS, inertia
    )


def run_ellipse(path: Path) -> dict:
    impacts = read_ellipse(path)
    rows = np.arange(len(impacts.before))
    train, held = rows[rows % 2 == 0], rows[rows % 2 == 1]
    measured = impacts.after[held, 3:]
    results = []
    for law in impact_law.LAWS:

        def loss(e, mu, law=law):
            return np.array(
                [
                    impact_law.normalised_error(
                        ellipse_predict(impacts, train, law, a, b), impacts.after[train, 3:], ELLIPSE_GYRATION
                    ).mean()
                    for a, b in zip(e, mu, strict=True)
                ]
            )

        e, mu, _ = impact_law.grid_fit(loss)
        errors = impact_law.normalised_error(ellipse_predict(impacts, held, law, e, mu), measured, ELLIPSE_GYRATION)
        results.append(Result(law, "ellipse", e, mu, errors))
        print(f"ellipse, {law}: e = {e:.2f}, mu = {mu:.2f}, mean {results[-1].mean:.3f}", flush=True)
    inertia = ELLIPSE_MASS * ELLIPSE_GYRATION**2
    rx, ry = impacts.normal[:, 2], -impacts.tangent[:, 2]

    def loss3(e, mu, et):
        return np.array(
            [
                impact_law.normalised_error(
                    impact_law.tangential(
                        impacts.before[train, 3:], rx[train], ry[train], a, b, c, ELLIPSE_MASS, inertia
                    ),
                    impacts.after[train, 3:],
                    ELLIPSE_GYRATION,
                ).mean()
                for a, b, c in zip(e, mu, et, strict=True)
            ]
        )

    e, mu, et, _ = impact_law.grid_fit3(loss3)
    errors = impact_law.normalised_error(
        impact_law.tangential(impacts.before[held, 3:], rx[held], ry[held], e, mu, et, ELLIPSE_MASS, inertia),
        measured,
        ELLIPSE_GYRATION,
    )
    tangential = Result("tangential", "ellipse", e, mu, errors, et=et)
    print(f"ellipse, tangential restitution: e = {e:.2f}, mu = {mu:.2f}, e_t = {et:.2f}, mean {tangential.mean:.3f}")
    published = []
    if impacts.published is not None:
        for k, name in enumerate(PUBLISHED):
            errors = impact_law.normalised_error(impacts.published[held, k], measured, ELLIPSE_GYRATION)
            published.append(Result(name, "ellipse", math.nan, math.nan, errors))
    zero = Result("zero velocity", "ellipse", math.nan, math.nan, np.ones(len(held)))
    components = {}
    best = results[0]
    predicted = ellipse_predict(impacts, held, best.model, best.e, best.mu)
    w = np.array([1.0, 1.0, ELLIPSE_GYRATION])
    norm = np.linalg.norm(measured * w, axis=1)
    for k, name in enumerate(("vx", "vy", "k omega")):
        components[name] = float(np.mean(np.abs((predicted[:, k] - measured[:, k]) * w[k]) / norm))
    u_t = np.sum(impacts.tangent[held] * impacts.before[held, 3:], axis=1)
    reversed_share = {
        name: float(np.mean(np.sign(np.sum(impacts.tangent[held] * v, axis=1)) == -np.sign(u_t)))
        for name, v in (("measured", measured), ("ours", predicted))
    }
    return {
        "n": len(rows),
        "train": len(train),
        "held": len(held),
        "results": results,
        "published": published,
        "zero": zero,
        "components": components,
        "reversed": reversed_share,
        "tangential": tangential,
    }


# -- the section ------------------------------------------------------------------------------------------
def row(result: Result, label: str | None = None) -> list[str]:
    e = "-" if math.isnan(result.e) else f"{result.e:.2f}"
    mu = "-" if math.isnan(result.mu) else f"{result.mu:.2f}"
    return [
        label or MODEL_LABELS.get(result.model, result.model),
        str(len(result.errors)),
        f"{result.mean:.2f}",
        f"{result.median:.2f}",
        e,
        mu,
    ]


HEADER = ["model", "held-out impacts", "mean error", "median error", "e", "mu"]


def section(square: dict | None, ellipse: dict | None, ellipse_note: str) -> str:
    from ..document import table

    lines = [
        "## The impact alone: post-impact velocity error",
        "",
        "Generated by `python -m reports.reality.impacts --data DIR --ellipse FILE --write-docs` (module docstring: the"
        " method); do not edit by hand. Error of a predicted post-impact velocity v against the measured v*:"
        " |W (v - v*)| / |W v*| with W = (1, 1, radius of gyration) (Fazeli et al. 2017); predicting zero"
        " velocity scores 1. Restitution e and friction mu fitted per model on the training impacts, figures"
        " on the held-out ones.",
        "",
    ]
    if square is not None:
        results = square["results"]
        held = square["held"]
        lines += [
            "### The square's first impacts",
            "",
            f"{len(square['impacts'].numbers)} first impacts of the usable drops (training: odd drop numbers,"
            f" {len(square['train'].numbers)}; held out: even, {len(held.numbers)}); measured and predicted"
            " velocity both the central difference over frames impact+1 to impact+3. Radius of gyration"
            f" {SQUARE_GYRATION * 1e3:.1f} mm.",
            "",
        ]
        for kind, title in (
            (
                "corner",
                f"Corner impacts (more than {math.degrees(CORNER_TILT):.0f} deg from flat;"
                f" target: below {TARGET_CORNER[0]} mean / {TARGET_CORNER[1]} median)",
            ),
            ("all", "All usable first impacts (target: well below 1)"),
        ):
            lines += [
                f"{title}:",
                "",
                table(HEADER + ["run time / impact"], [row(r) + [seconds(r)] for r in results if r.kind == kind]),
                "",
            ]
        lines += flat_landings(square)
    if ellipse is not None:
        lines += [
            "### The ellipse impacts (the impact law alone)",
            "",
            f"{ellipse['n']} measured impacts of mcubelab/planar-impact-dataset `data_ellipse.mat` (training:"
            f" even rows, {ellipse['train']}; held out: odd, {ellipse['held']}); our impact law applied with"
            " the measured contact Jacobian (one point).",
            "",
            table(
                HEADER,
                [row(r, ELLIPSE_LABELS[r.model]) for r in ellipse["results"]]
                + [
                    row(
                        ellipse["tangential"],
                        "proposal: Newton + Coulomb with a tangential restitution"
                        f" e_t = {ellipse['tangential'].et:.2f} (fitted)",
                    )
                ]
                + [row(r, f"published: {r.model} (its own parameters)") for r in ellipse["published"]]
                + [row(ellipse["zero"])],
            ),
            "",
            f"Published range on this set: {PUBLISHED_RANGE}"
            + (
                "; the rows 'published' are their predictions (`v_models.mat`) scored on the same held-out rows."
                if ellipse["published"]
                else "."
            ),
            "",
        ]
    elif ellipse_note:
        lines += ["### The ellipse impacts (the impact law alone)", "", ellipse_note, ""]
    lines += ["### What the impacts teach, and the contact-model proposal", "", teaching(square, ellipse)]
    return "\n".join(lines)


def seconds(result: Result) -> str:
    from ..document import seconds as format_seconds

    return format_seconds(result.seconds / len(result.errors)) if result.seconds else "-"


def flat_landings(square: dict) -> list[str]:
    """What our two-point contact does on the flat landings, from the held-out impacts fitted on all."""
    from ..document import table

    held = square["held"]
    by_model = {r.model: r for r in square["results"] if r.kind == "all"}
    rows = []
    bins = ((0.0, FLAT_TILT), (FLAT_TILT, CORNER_TILT), (CORNER_TILT, math.pi / 4 + 1e-9))
    for low, high in bins:
        mask = (held.tilt >= low) & (held.tilt < high)
        if not mask.any():
            continue
        cells = [f"{math.degrees(low):.0f}-{min(45, math.degrees(high)):.0f}", str(int(mask.sum()))]
        cells += [
            f"{np.nanmean(by_model[m].errors[mask]):.2f}" if m in by_model else "-"
            for m in ("ours", "map: ours", "map: newton")
        ]
        cells += [f"{np.median(np.abs(held.after[mask, 2])):.1f}"]
        cells += [
            f"{np.median(np.abs(by_model[m].predicted[mask, 2])):.1f}" if m in by_model else "-"
            for m in ("ours", "map: ours")
        ]
        cells += [f"{np.median(held.after[mask, 1]):.2f}"]
        cells += [
            f"{np.median(by_model[m].predicted[mask, 1]):.2f}" if m in by_model else "-" for m in ("ours", "map: ours")
        ]
        rows.append(cells)
    return [
        "By tilt at the impact (held out, each model fitted on all impacts): mean error, the median spin"
        " after the impact (absolute) and the median vertical velocity of the centre after it, measured and"
        " predicted:",
        "",
        table(
            [
                "tilt [deg]",
                "impacts",
                "error: ours, robust solver",
                "error: our law, lowest corner only",
                "error: Newton + Coulomb, lowest corner",
                "spin after, measured [rad/s]",
                "spin: ours",
                "spin: lowest corner only",
                "vz after, measured [m/s]",
                "vz: ours",
                "vz: lowest corner only",
            ],
            rows,
        ),
        "",
    ]


def mujoco_contact_ms() -> float:
    """Half a period of MuJoCo's contact oscillator at dt = 4 ms [ms] (the duration of a rebound)."""
    from benchmarks.other_engines import MUJOCO_OMEGA_DT

    return 1e3 * math.pi * data.FRAME / MUJOCO_OMEGA_DT


def teaching(square: dict | None, ellipse: dict | None) -> str:
    items = []
    if square is not None:
        by = {(r.model, r.kind): r for r in square["results"]}
        held = square["held"]
        ours_c, ours_a = by[("ours", "corner")], by[("ours", "all")]
        newton_c, newton_a = by[("map: newton", "corner")], by[("map: newton", "all")]
        one_a, one_c = by[("map: ours", "all")], by[("map: ours", "corner")]
        others = [r for r in square["results"] if r.kind == "corner" and r.model in ENGINES]
        flat = held.tilt < FLAT_TILT
        spins = [np.median(np.abs(v[flat, 2])) for v in (held.after, ours_a.predicted, one_a.predicted)]
        items.append(
            f"- **Corner impacts.** Our robust solver predicts the post-impact velocity of the held-out corner"
            f" impacts to {ours_c.mean:.2f} mean / {ours_c.median:.2f} median (e = {ours_c.e:.2f}, mu ="
            f" {ours_c.mu:.2f}), against {newton_c.mean:.2f} / {newton_c.median:.2f} for the point-contact"
            f" Newton + Coulomb map on the same impacts and the same measurement, and the target"
            f" {TARGET_CORNER[0]} / {TARGET_CORNER[1]} (such a map on its own reading of the velocities)"
            + (
                ": the other engines, each simulating the same frames fitted the same way, "
                + ", ".join(f"{r.model} {r.mean:.2f} / {r.median:.2f}" for r in others)
                if others
                else ""
            )
            + (
                f" (MuJoCo's soft contact, its stiffness set by the step as in `benchmarks/other_engines.py`, lasts"
                f" about {mujoco_contact_ms():.0f} ms at 4 ms, longer than the"
                " 3 frames read after the impact: its figure is of an impact not yet over)"
                if any(r.model == "mujoco" for r in others)
                else ""
            )
            + f". Our law at the lowest corner alone (one impact, no simulation) is {one_c.mean:.2f} /"
            f" {one_c.median:.2f}: where it is worse than the solver, the square turned onto a second corner"
            " within the frames read, which the solver simulates and a one-impact map does not."
        )
        items.append(
            f"- **All impacts, and what the two-point contact does on flat landings.** On all"
            f" {len(held.numbers)} held-out first impacts ours is {ours_a.mean:.2f} / {ours_a.median:.2f}, the"
            f" point map {newton_a.mean:.2f} / {newton_a.median:.2f} and our own law at the lowest corner only"
            f" {one_a.mean:.2f} / {one_a.median:.2f}. On the {int(flat.sum())} landings within"
            f" {math.degrees(FLAT_TILT):.0f} deg of flat (mean {np.mean(ours_a.errors[flat]):.2f} ours,"
            f" {np.mean(newton_a.errors[flat]):.2f} the point map): one corner hits, the square turns about it"
            " and the other corner of the face hits within a millisecond; our solver takes that second impact"
            " (and a simultaneous pair together, Poisson on both corners), so the square comes off the floor"
            f" moving up and spinning little ({spins[1]:.1f} rad/s, median absolute spin after; measured"
            f" {spins[0]:.1f}), where a map at one corner sends it off spinning about that corner"
            f" ({spins[2]:.1f} rad/s)."
        )
        proposal = square["proposal"]
        gain = np.mean(proposal["errors"])
        items.append(
            f"- **Restitution by landing, measured.** Fitting e and mu separately for landings within"
            f" {math.degrees(CORNER_TILT):.0f} deg of flat (e = {proposal['flat-ish'][0]:.2f}, mu ="
            f" {proposal['flat-ish'][1]:.2f}) and corner landings (e = {proposal['corner'][0]:.2f}, mu ="
            f" {proposal['corner'][1]:.2f}) gives {gain:.2f} mean / {np.median(proposal['errors']):.2f} median"
            f" on all held-out impacts, against {ours_a.mean:.2f} / {ours_a.median:.2f} with one pair."
        )
    if ellipse is not None:
        ours = ellipse["results"][0]
        published = ellipse["published"]
        best = min(published, key=lambda r: r.mean) if published else None
        comp = ellipse["components"]
        items.append(
            f"- **Ellipse.** Our engine's impact law, fitted (e = {ours.e:.2f}, mu = {ours.mu:.2f}), is"
            f" {ours.mean:.2f} mean / {ours.median:.2f} median on the held-out impacts"
            + (
                f", the best published model {best.mean:.2f} / {best.median:.2f} ({best.model}) on the same rows"
                if best
                else f", the published models {PUBLISHED_RANGE}"
            )
            + f". Its error is mostly the spin: per impact, the share of the error in vx, vy and k omega is"
            f" {comp['vx']:.2f}, {comp['vy']:.2f} and {comp['k omega']:.2f} (mean |component| / |W v*|). The"
            " contact point's tangential velocity comes out of the impact reversed in"
            f" {ellipse['reversed']['measured'] * 100:.0f}% of the held-out impacts measured and"
            f" {ellipse['reversed']['ours'] * 100:.0f}% predicted (the normal impulse, off the centre, turns the"
            " ellipse and reverses the slip; friction does not): the law gets the kind of outcome, not its size,"
            " and the same pre-impact state ends in a spread of measured spins that no deterministic law follows."
        )
    items.append(proposal_text(square, ellipse))
    return "\n".join(items)


WORTH = 0.02  # a change of the contact model must lower the held-out mean error by this much to be proposed


def proposal_text(square: dict | None, ellipse: dict | None) -> str:
    """The contact-model proposal, decided by the measured gains of the two candidate changes."""
    parts = ["- **Proposal.** Two changes of the contact model were measured against one e and one mu."]
    gains = []
    if square is not None:
        by = {(r.model, r.kind): r for r in square["results"]}
        ours_a = by[("ours", "all")]
        gain = ours_a.mean - float(np.mean(square["proposal"]["errors"]))
        gains.append(gain)
        parts.append(
            f"A restitution and friction chosen by the tilt at the impact (a second pair for face landings,"
            " the change the bounce table above points to) changes the held-out mean error on all square"
            f" impacts by {-gain:+.2f}."
        )
    if ellipse is not None:
        gain = ellipse["results"][1].mean - ellipse["tangential"].mean
        gains.append(gain)
        parts.append(
            f"A tangential restitution (the contact point springs back along the floor, a third fitted"
            f" parameter) is fitted to e_t = {ellipse['tangential'].et:.2f} and changes the ellipse's"
            f" held-out mean error by {-gain:+.2f}."
        )
    if gains and max(gains) > WORTH:
        parts.append(
            "The larger gain is worth an engine option (off by default, so the exact cases and the"
            " seeded results do not change), measured again on the trajectories before it is adopted."
        )
    else:
        parts.append(
            f"Neither gains {WORTH} of the mean error, so neither is worth a parameter: the model to keep is"
            " the one we have (Poisson restitution, Coulomb friction, the two-point contact of flat"
            " landings). What is left is the scatter of real impacts (the same pre-impact state ends in"
            " different post-impact spins, Fazeli et al. 2017), which a deterministic rigid law does"
            " not follow; a stochastic contact (e and mu drawn per impact from their fitted spread) is"
            " the direction for an agent that must be robust to it, a change of the env's randomisation"
            " rather than of the engine."
        )
    return " ".join(parts)


def main(argv=None) -> int:
    parser = OneLineParser(prog="python -m reports.reality.impacts", description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=None, help="folder of the measured traj_N.csv files")
    parser.add_argument("--ellipse", type=Path, default=None, help="data_ellipse.mat of the planar impact dataset")
    parser.add_argument(
        "--page",
        type=Path,
        default=None,
        help=f"page whose impacts section is rewritten (default: {QUICK_PAGE.relative_to(QUICK_PAGE.parents[2])}, "
        "created if absent)",
    )
    parser.add_argument(
        "--write-docs", action="store_true", help=f"rewrite the section of {PAGE.name} in docs/ (a tracked file)"
    )
    parser.add_argument("--no-engines", action="store_true", help="ours and the impact maps only")
    parser.add_argument("--quick", action="store_true", help="12 impacts a class (the tests)")
    args = parser.parse_args(argv)
    if args.data is None and args.ellipse is None:
        raise SystemExit(f"{parser.prog}: error: give --data, --ellipse or both")
    if args.write_docs and args.page is not None:
        raise SystemExit(f"{parser.prog}: error: --write-docs rewrites docs/{PAGE.name}: drop --page")
    page = PAGE if args.write_docs else (args.page or QUICK_PAGE)
    try:
        square = run_square(args.data, not args.no_engines, args.quick) if args.data is not None else None
        ellipse = run_ellipse(args.ellipse) if args.ellipse is not None else None
    except ValueError as problem:
        if str(problem).startswith("--"):
            raise SystemExit(f"{parser.prog}: error: {problem}") from None
        raise
    except OSError as problem:
        from box_toss_env.files import describe_os_error

        raise SystemExit(f"{parser.prog}: error: {describe_os_error(problem)}") from None
    note = (
        ""
        if ellipse is not None
        else "Skipped: no `--ellipse FILE` given (`python -m reports.reality.download --ellipse --out DIR` downloads"
        " `data_ellipse.mat`, and `v_models.mat` for the published models, from the GitHub repository"
        " mcubelab/planar-impact-dataset at a pinned commit, checked by SHA-256; it has no licence and is"
        " not in this repository)."
    )
    text = section(square, ellipse, note)
    write_section(text, page)
    print(text)
    print(f"wrote the {SECTION} section of {page}")
    return 0


def write_section(text: str, page: Path) -> None:
    """Put ``text`` between the impacts markers of ``page``. The default page in build/reports/ is created with
    the section alone if ``python -m reports.reality`` has not written its page there yet (that command keeps the
    section when it writes the page)."""
    from agents.doc_sections import replace_section

    if page == QUICK_PAGE and not page.exists():
        from box_toss_env.files import write_atomic

        page.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(page, f"<!-- {SECTION}:start -->\n{text}\n<!-- {SECTION}:end -->\n")
        return
    replace_section(SECTION, text, page)


if __name__ == "__main__":
    raise SystemExit(main())
