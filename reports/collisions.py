"""Boxes that collide with one another: the named multi-box scenes in our two solvers, pymunk and Box2D,
and who agrees with whom.

    python -m reports.collisions --write-docs   # the full report: docs/collisions.md, its block of docs/reports.md
    python -m reports.collisions                # the full report into build/reports/ (ignored by git), or --out DIR
    python -m reports.collisions --quick        # shorter runs, into build/reports/ (the tests run this)

Three stages, each a function:

1. ``run_methods``: each named scene of ``box_toss_env.physics.scenes`` (stack, pyramid, drop on a box,
   flight collision, Newton row) simulated by every method for the scene's duration, states recorded
   (our engine through ``simulate``, the others through ``benchmarks.other_scenes`` with their documented
   settings);
2. ``Outcome``: per scene, the outcome that matters, measured on each method's states (a stack's rest
   drift, whether the pyramid holds, where the dropped box rests and on which face, the velocities after
   a collision in flight and the momentum kept, the row's final velocities);
3. ``write_report``: a table per scene of what each method did, the pairwise distance between methods on
   that outcome against the scene's tolerance (who agrees with whom), and a summary over the scenes.

A method that cannot run a scene (a scene an engine cannot represent, a run that goes non-finite) is kept
in the tables with the reason, never dropped.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmarks.other_scenes import PYMUNK_ITERATIONS, UnsupportedScene, available_scene_engines, simulate_scene
from box_toss_env.files import write_atomic
from box_toss_env.physics import NonFiniteStateError, Scene, face_down, scenes, simulate

from . import document
from .cases import corner_radius, wrap
from .document import sci, table
from .timing import Stopwatch

SOLVERS = ("robust", "seed")
OTHER_ENGINES = ("pymunk", "box2d")
SETTLE_TIME = 1.0  # [s] a stack or pyramid settles for this long before its drift is measured
REST_DRIFT_MAX = 1e-3  # [m] the criterion for a resting stack
HOLD_MOVE_MAX = 0.02  # [m] a pyramid holds if no box moves more than this from its start
BOX2D_RESTITUTION_THRESHOLD = 1.0  # [m/s] b2_velocityThreshold: slower impacts are perfectly inelastic in Box2D
KEPT_TO = 1e-9  # relative error the issue allows our engine on momentum and angular momentum in flight


# -- running ---------------------------------------------------------------------------------------------------
@dataclass
class MethodRun:
    """One method on one scene: states (T, n, 6) on the scene's grid, or why there are none."""

    method: str
    states: np.ndarray | None
    seconds: float  # wall time of the whole call, construction included (not a timing figure)
    problem: str = ""

    @property
    def ran(self) -> bool:
        return self.states is not None and bool(np.isfinite(self.states).all())


def run_method(method: str, scene: Scene, steps: int) -> MethodRun:
    """``scene`` by one method; a method that cannot run it returns the reason instead of raising."""
    with Stopwatch() as watch:
        try:
            if method in SOLVERS:
                states = simulate(scene.replace(solver=method), steps=steps, record=True).trajectory.state
            else:
                states = simulate_scene(method, scene, steps, record=True).states
        except UnsupportedScene as error:
            return MethodRun(method, None, math.nan, f"cannot run: {error}")
        except NonFiniteStateError as error:
            return MethodRun(method, None, math.nan, f"non-finite at step {error.step}")
    if states.shape[0] < steps + 1:  # every body asleep early: the rest of the grid holds the final state
        states = np.concatenate([states, np.repeat(states[-1:], steps + 1 - states.shape[0], axis=0)])
    run = MethodRun(method, states, watch.seconds)
    if not run.ran:
        run.problem = "non-finite"
    return run


# -- what each scene measures --------------------------------------------------------------------------------
@dataclass
class Outcome:
    """What one method did on one scene: figures to show, and what the pairwise distance compares."""

    values: dict  # name -> float, shown in the scene's table
    compared: np.ndarray  # the outcome compared between methods
    label: str = ""  # a discrete outcome that must be equal for two methods to agree ("" if none)
    checks: dict = field(default_factory=dict)  # name -> bool, physics checks shown as pass/fail


def body_radius(scene: Scene) -> np.ndarray:
    return np.array([corner_radius(box) for box in scene.boxes])


def pose_moves(states: np.ndarray, reference: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """(T, n) |dx| + R |da| of every box against ``reference`` (n, 6): how far any point of it moved."""
    moved = np.hypot(states[..., 0] - reference[:, 0], states[..., 1] - reference[:, 1])
    return moved + radius * np.abs(wrap(states[..., 2] - reference[:, 2]))


def momentum(scene: Scene, states: np.ndarray) -> np.ndarray:
    """(..., 2) total linear momentum [kg m/s]."""
    mass = np.array([box.mass for box in scene.boxes])
    return np.einsum("n,...nk->...k", mass, states[..., 3:5])


def angular_momentum(scene: Scene, states: np.ndarray) -> np.ndarray:
    """(...,) angular momentum about the common centre of mass [kg m^2/s] (uniform gravity exerts no torque
    about it, so it is kept in flight)."""
    mass = np.array([box.mass for box in scene.boxes])
    inertia = np.array([box.inertia for box in scene.boxes])
    total = mass.sum()
    centre = np.einsum("n,...nk->...k", mass, states[..., 0:2]) / total
    velocity = np.einsum("n,...nk->...k", mass, states[..., 3:5]) / total
    r = states[..., 0:2] - centre[..., None, :]
    v = states[..., 3:5] - velocity[..., None, :]
    return np.einsum("n,...n->...", mass, r[..., 0] * v[..., 1] - r[..., 1] * v[..., 0]) + np.einsum(
        "n,...n->...", inertia, states[..., 5]
    )


def relative_kinetic_energy(scene: Scene, states: np.ndarray) -> np.ndarray:
    """(...,) kinetic energy of the motion about the common centre of mass [J]: uniform gravity does no work on
    it, so only contacts change it."""
    mass = np.array([box.mass for box in scene.boxes])
    velocity = momentum(scene, states) / mass.sum()
    return kinetic_energy(scene, states) - 0.5 * mass.sum() * (velocity**2).sum(axis=-1)


def kinetic_energy(scene: Scene, states: np.ndarray) -> np.ndarray:
    """(...,) 0.5 m |v|^2 + 0.5 I w^2 summed over the boxes [J]."""
    mass = np.array([box.mass for box in scene.boxes])
    inertia = np.array([box.inertia for box in scene.boxes])
    return 0.5 * (
        np.einsum("n,...nk->...", mass, states[..., 3:5] ** 2) + np.einsum("n,...n->...", inertia, states[..., 5] ** 2)
    )


@dataclass(frozen=True)
class CollisionScene:
    """A named scene, how long it runs, what is measured on it and when two methods agree on it."""

    name: str
    title: str
    build: Callable[[], Scene]
    duration: float  # [s], full report
    quick_duration: float  # [s], --quick
    outcome_text: str  # what is compared, in words
    tolerance: float  # two methods agree when their distance is at most this
    unit: str  # of the distance

    def scene(self) -> Scene:
        return self.build()

    def measure(self, scene: Scene, states: np.ndarray) -> Outcome:
        raise NotImplementedError

    def distance(self, a: Outcome, b: Outcome) -> float:
        """Largest difference of the compared outcome; inf when the discrete labels differ."""
        if a.label != b.label:
            return math.inf
        return float(np.abs(a.compared - b.compared).max())


class Stack(CollisionScene):
    def measure(self, scene, states):
        radius = body_radius(scene)
        settle = min(int(round(SETTLE_TIME / scene.dt)), states.shape[0] - 1)
        drift = float(pose_moves(states[settle:], states[settle], radius).max())
        final = states[-1]
        start = states[0]
        sink = float(start[-1, 1] - final[-1, 1])
        moves = pose_moves(final[None], start, radius)[0]
        return Outcome(
            {"drift after 1 s [m]": drift, "top sinks [m]": sink, "largest move from start [m]": float(moves.max())},
            moves_vector(final, radius),
            checks={"rests (drift < 1 mm)": drift < REST_DRIFT_MAX},
        )

    def distance(self, a, b):
        return largest_pose_difference(a.compared, b.compared)


class Pyramid(CollisionScene):
    def measure(self, scene, states):
        radius = body_radius(scene)
        top = int(np.argmax(states[0, :, 1]))
        settle = min(int(round(SETTLE_TIME / scene.dt)), states.shape[0] - 1)
        moves = pose_moves(states[-1][None], states[0], radius)[0]
        holds = bool(moves.max() <= HOLD_MOVE_MAX)
        top_drift = float(
            pose_moves(states[settle:, top : top + 1], states[settle, top : top + 1], radius[top : top + 1]).max()
        )
        return Outcome(
            {"largest move from start [m]": float(moves.max()), "top drift after 1 s [m]": top_drift},
            moves_vector(states[-1], radius)[top : top + 1],
            label="holds" if holds else "falls",
            checks={"holds (no box moves > 2 cm)": holds},
        )

    def distance(self, a, b):
        return math.inf if a.label != b.label else largest_pose_difference(a.compared, b.compared)


class DropOnBox(CollisionScene):
    def measure(self, scene, states):
        dropped = int(np.argmax(states[0, :, 1]))
        x, y, angle = states[-1, dropped, :3]
        face = face_down(float(angle))
        speed = float(np.abs(states[-1, :, 3:5]).max())
        return Outcome(
            {"rest x [m]": float(x), "rest y [m]": float(y), "face down": face, "largest final speed [m/s]": speed},
            np.array([x, y]),
            label=f"face {face}",
            checks={"at rest (< 1 cm/s)": speed < 0.01},
        )

    def distance(self, a, b):
        return math.inf if a.label != b.label else float(np.hypot(*(a.compared - b.compared)))


class FlightCollision(CollisionScene):
    def measure(self, scene, states):
        time = np.arange(states.shape[0]) * scene.dt
        mass = np.array([box.mass for box in scene.boxes])
        p = momentum(scene, states)
        expected = p[0] + np.outer(time, [0.0, mass.sum() * scene.gravity])  # gravity's impulse
        scale = float(np.einsum("n,n->", mass, np.hypot(states[0, :, 3], states[0, :, 4])))  # sum of m |v|
        p_error = float(np.abs(p - expected).max() / scale)
        spin = angular_momentum(scene, states)
        l_scale = abs(float(spin[0])) + scale * float(body_radius(scene).max())
        l_error = float(np.abs(spin - spin[0]).max() / l_scale)
        relative = relative_kinetic_energy(scene, states)  # gravity does no work on the motion about the centre
        gain = float((relative - relative[0]).max() / relative[0])
        final = states[-1]
        velocity = np.concatenate([final[:, 3:5], (body_radius(scene) * final[:, 5])[:, None]], axis=1)
        return Outcome(
            {
                "momentum error (rel.)": p_error,
                "angular momentum error (rel.)": l_error,
                "energy gain (rel.)": max(gain, 0.0),
                "energy kept": float(relative[-1] / relative[0]),
                "final vx per box [m/s]": tuple(final[:, 3]),
            },
            velocity,
            checks={
                "momentum kept to 1e-9": p_error <= KEPT_TO,
                "angular momentum kept to 1e-9": l_error <= KEPT_TO,
                "no energy gain": gain <= KEPT_TO,
            },
        )


class NewtonRow(CollisionScene):
    def measure(self, scene, states):
        vx = states[-1, :, 3]
        v0 = float(states[0, 0, 3])
        p = momentum(scene, states)
        p_error = float(np.abs(p[-1, 0] - p[0, 0]) / max(abs(p[0, 0]), 1e-300))
        ke = kinetic_energy(scene, states)
        return Outcome(
            {
                "final vx per box [m/s]": tuple(vx),
                "momentum error (rel.)": p_error,
                "kinetic energy kept": float(ke[-1] / ke[0]),
            },
            vx,
            checks={
                "momentum kept to 1e-9": p_error <= KEPT_TO,
                "last box leaves at v0 (within 1%)": abs(vx[-1] - v0) <= 0.01 * abs(v0),
            },
        )


def moves_vector(final: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """(n, 4): x, y, angle and corner radius R of each box, to compare poses between methods."""
    return np.column_stack([final[:, 0], final[:, 1], final[:, 2], radius])


def largest_pose_difference(a: np.ndarray, b: np.ndarray) -> float:
    """max over boxes of |dx| + R |da| between two ``moves_vector``s [m]."""
    return float((np.hypot(a[:, 0] - b[:, 0], a[:, 1] - b[:, 1]) + a[:, 3] * np.abs(wrap(a[:, 2] - b[:, 2]))).max())


def collision_scenes() -> tuple[CollisionScene, ...]:
    """The report's scenes, each the named scene of ``box_toss_env.physics.scenes``."""
    return (
        Stack(
            "stack",
            "Stack of 10",
            lambda: scene_of("stack", n=10),
            60.0,
            5.0,
            "final pose of every box (|dx| + R |da|, largest over the boxes)",
            5e-3,
            "m",
        ),
        Pyramid(
            "pyramid",
            "Pyramid of 15",
            lambda: scene_of("pyramid", rows=5),
            20.0,
            3.0,
            "whether it holds, then the top box's final pose",
            5e-3,
            "m",
        ),
        DropOnBox(
            "drop_on_box",
            "Box dropped on a box",
            lambda: scene_of("drop_on_box"),
            5.0,
            3.0,
            "the dropped box's face down, then its rest position",
            0.02,
            "m",
        ),
        FlightCollision(
            "flight_collision",
            "Collision in flight",
            lambda: scene_of("flight_collision"),
            0.5,
            0.5,
            "every box's velocity after the collision (|dv| + R |dw|, largest over the boxes)",
            0.01,
            "m/s",
        ),
        NewtonRow(
            "newton_row",
            "Newton row of 5 (e = 1, mu = 0)",
            lambda: scene_of("newton_row", n=5),
            2.0,
            2.0,
            "every box's final vx",
            0.05,
            "m/s",
        ),
    )


def scene_of(name: str, **arguments) -> Scene:
    """The named scene from ``box_toss_env.physics.scenes``."""
    return getattr(scenes, name)(**arguments)


# -- the report ----------------------------------------------------------------------------------------------------
@dataclass
class SceneResult:
    spec: CollisionScene
    scene: Scene | None
    runs: dict  # method -> MethodRun
    outcomes: dict  # method -> Outcome, for the methods that ran
    problem: str = ""  # why the scene itself could not be built

    def distance(self, a: str, b: str) -> float:
        if a not in self.outcomes or b not in self.outcomes:
            return math.nan
        return self.spec.distance(self.outcomes[a], self.outcomes[b])

    def agree(self, a: str, b: str) -> bool | None:
        distance = self.distance(a, b)
        return None if math.isnan(distance) else distance <= self.spec.tolerance


@dataclass
class CollisionReport:
    quick: bool
    methods: tuple
    missing: tuple
    results: list[SceneResult]
    run_seconds: float = math.nan
    load: str = ""  # the machine's load when the report ran (``document.load``)

    def result(self, name: str) -> SceneResult:
        return next(r for r in self.results if r.spec.name == name)

    def pairs(self) -> list[tuple[str, str]]:
        return [(a, b) for i, a in enumerate(self.methods) for b in self.methods[i + 1 :]]


def run_scene(spec: CollisionScene, methods, quick: bool, log=print) -> SceneResult:
    try:
        scene = spec.scene()
    except (AttributeError, TypeError) as error:  # the named scene does not exist (yet)
        problem = f"scene not available: {type(error).__name__}: {error}"
        return SceneResult(spec, None, {m: MethodRun(m, None, math.nan, problem) for m in methods}, {}, problem)
    steps = int(round((spec.quick_duration if quick else spec.duration) / scene.dt))
    runs, outcomes = {}, {}
    for method in methods:
        runs[method] = run_method(method, scene, steps)
        if runs[method].ran:
            outcomes[method] = spec.measure(scene, runs[method].states)
        log(f"  {spec.name:16} {method:7} {runs[method].problem or 'ran'}")
    return SceneResult(spec, scene, runs, outcomes)


def run(quick: bool = False, log=print) -> CollisionReport:
    with Stopwatch() as watch:
        engines = tuple(name for name in available_scene_engines() if name in OTHER_ENGINES)
        missing = tuple(name for name in OTHER_ENGINES if name not in engines)
        methods = (*SOLVERS, *engines)
        results = [run_scene(spec, methods, quick, log) for spec in collision_scenes()]
    return CollisionReport(quick, methods, missing, results, watch.seconds, document.load())


def value_text(value) -> str:
    if isinstance(value, tuple):
        return "(" + ", ".join(f"{v:+.3f}" for v in value) + ")"
    if isinstance(value, int):
        return str(value)
    return sci(value)


def method_table(result: SceneResult, methods) -> str:
    names = next((list(o.values) for o in result.outcomes.values()), [])
    checks = next((list(o.checks) for o in result.outcomes.values()), [])
    rows = []
    for method in methods:
        run = result.runs[method]
        outcome = result.outcomes.get(method)
        if outcome is None:
            rows.append([method] + [run.problem] + [""] * (len(names) + len(checks) - 1))
            continue
        rows.append(
            [method]
            + [value_text(outcome.values[n]) for n in names]
            + [("pass" if outcome.checks[c] else "**FAIL**") for c in checks]
        )
    if not names and not checks:
        return table(["method", "result"], [[m, result.runs[m].problem] for m in methods])
    return table(["method"] + names + checks, rows)


def agreement_cell(result: SceneResult, a: str, b: str) -> str:
    distance = result.distance(a, b)
    if math.isnan(distance):
        return "-"
    if math.isinf(distance):
        return f"differ ({result.outcomes[a].label} / {result.outcomes[b].label})"
    return f"{sci(distance)} " + ("agree" if distance <= result.spec.tolerance else "**differ**")


def agreement_matrix(result: SceneResult, methods) -> str:
    rows = [[a] + [("" if a == b else agreement_cell(result, a, b)) for b in methods] for a in methods]
    return table([f"distance [{result.spec.unit}]"] + list(methods), rows)


def summary_table(report: CollisionReport) -> str:
    header = ["pair"] + [f"{r.spec.title} (tol. {sci(r.spec.tolerance)} {r.spec.unit})" for r in report.results]
    rows = [[f"{a} - {b}"] + [agreement_cell(r, a, b) for r in report.results] for a, b in report.pairs()]
    return table(header, rows)


def checks_table(report: CollisionReport) -> str:
    """Per scene and method, the physics checks: pass / FAIL, or why it did not run."""
    rows = []
    for result in report.results:
        cells = []
        for method in report.methods:
            outcome = result.outcomes.get(method)
            if outcome is None:
                cells.append(result.runs[method].problem.split(":")[0])
                continue
            failed = [name for name, ok in outcome.checks.items() if not ok]
            cells.append("pass" if not failed else "**FAIL**: " + "; ".join(failed))
        rows.append([result.spec.title] + cells)
    return table(["scene"] + list(report.methods), rows)


def settings_text() -> str:
    return (
        "Our engine runs each scene as it is defined in `box_toss_env/physics/scenes.py` (its dt, material, "
        "penalty stiffness and thresholds), once per solver. pymunk and Box2D run the same boxes, material, dt "
        "and gravity through `benchmarks/other_scenes.py`, with their documented defaults otherwise: pymunk "
        "10 iterations, no sleeping, collision slop 1 mm (its default 0.1 is meant for pixels), every shape "
        "sqrt(e) and sqrt(mu) so that every pair multiplies back to e and mu; Box2D 2.3 (float32) 8 velocity and "
        "3 position iterations, sleeping on, boxes not bullets, 1 cm polygon skin (the polygon is the box shrunk "
        "by it, the floor edge 1 cm low), restitution only above 1 m/s of approach, up to 5 mm of overlap left "
        "per contact. Neither has a counterpart to our penalty stiffness, restitution threshold or sleep "
        "settings."
    )


def markdown(report: CollisionReport) -> str:
    parts = [
        "# Boxes that collide: who agrees with whom",
        "",
        f"Generated by `python -m reports.collisions{' --quick' if report.quick else ' --write-docs'}` in "
        f"{report.run_seconds / 60:.1f} min on {document.machine()} ({report.load}; no figure here is a "
        "timing). Every number below comes from that command; edit `reports/collisions.py`, not this file.",
        "",
        "## What is compared",
        "",
        f"Methods: {', '.join(report.methods)}"
        + (f"; not installed, so not shown: {', '.join(report.missing)}" if report.missing else "")
        + ". "
        + settings_text(),
        "",
        "Two methods agree on a scene when the distance between their outcomes is at most the scene's tolerance; "
        "a discrete outcome (the face down, whether the pyramid holds) must be equal first. The tolerance is "
        "what a user would call the same result, not a bound on any engine's error: Box2D keeps bodies apart by "
        "its skins and leaves up to 5 mm of overlap, pymunk up to 1 mm.",
        "",
        "## Who agrees with whom",
        "",
        summary_table(report),
        "",
        "## Physics checks",
        "",
        checks_table(report),
        "",
        "## What explains a disagreement",
        "",
        explanations(report),
        "",
    ]
    for result in report.results:
        spec = result.spec
        duration = spec.quick_duration if report.quick else spec.duration
        parts += [f"## {spec.title}", ""]
        if result.scene is None:
            parts += [result.problem, ""]
            continue
        parts += [
            f"`scenes.{spec.name}`: {describe_scene(result.scene)}; {duration:g} s. Compared: "
            f"{spec.outcome_text}; tolerance {sci(spec.tolerance)} {spec.unit}.",
            "",
            method_table(result, report.methods),
            "",
            agreement_matrix(result, report.methods),
            "",
        ]
    return "\n".join(parts)


def explanations(report: CollisionReport) -> str:
    """Known causes of the disagreements, each stated from the scenes' values and the engines' documented limits
    (``benchmarks/other_engines.py``); a disagreement not listed here has no known cause."""
    lines = []
    row = report.result("newton_row")
    if row.scene is not None:
        v0 = max(abs(box.velocity[0]) for box in row.scene.boxes)
        if v0 <= BOX2D_RESTITUTION_THRESHOLD:
            lines.append(
                f"- Newton row, Box2D: the first box arrives at {v0:g} m/s, not above Box2D's compiled-in "
                f"restitution threshold (b2_velocityThreshold = {BOX2D_RESTITUTION_THRESHOLD:g} m/s), so "
                "Box2D treats every impact of the row as perfectly inelastic and the boxes end moving "
                "together."
            )
    explained = {("newton_row", "box2d")} if lines else set()
    for result in report.results:
        for method in outliers(result):
            if method == "box2d" and (result.spec.name, method) not in explained:
                lines.append(
                    f"- {result.spec.title}, Box2D against the rest: its boxes have corners rounded to 1 cm "
                    "(the polygon skin), so a corner-first contact has its point and normal off a sharp "
                    "corner's (the difference shrinks in proportion when the scene is scaled up)."
                )
            elif (result.spec.name, method) not in explained:
                others = [m for m in IMPULSE_METHODS if m != method]
                lines.append(
                    f"- {result.spec.title}: {method} differs from {' and '.join(others)}, which agree with "
                    "each other; no known cause."
                )
    stack = report.result("stack")
    if "pymunk" in stack.outcomes and not all(stack.outcomes["pymunk"].checks.values()):
        lines.append(
            f"- Stack, pymunk: with its default {PYMUNK_ITERATIONS} solver iterations a stack of "
            f"{stack.scene.n_bodies} is still settling after {SETTLE_TIME:g} s (it sinks by up to its 1 mm "
            "collision slop per contact and shifts sideways meanwhile); more iterations settle it sooner."
        )
    seed_failed = [
        r.spec.title
        for r in report.results
        if "seed" in r.runs and ("seed" not in r.outcomes or not all(r.outcomes["seed"].checks.values()))
    ]
    if seed_failed:
        lines.append(
            f"- The seed scheme (the text's formulas, extended to pairs of boxes) fails the checks of: "
            f"{', '.join(seed_failed)} (see `docs/stability.md` for where its explicit scheme holds)."
        )
    return "\n".join(lines)


IMPULSE_METHODS = ("robust", "pymunk", "box2d")  # the methods expected to agree (the seed scheme is explicit)


def outliers(result: SceneResult) -> list[str]:
    """Those of IMPULSE_METHODS that disagree with both others on ``result`` while the other two agree."""
    found = []
    for method in IMPULSE_METHODS:
        a, b = (m for m in IMPULSE_METHODS if m != method)
        if result.agree(a, b) and result.agree(method, a) is False and result.agree(method, b) is False:
            found.append(method)
    return found


def describe_scene(scene: Scene) -> str:
    sizes = sorted({(b.length, b.width) for b in scene.boxes})
    masses = sorted({b.mass for b in scene.boxes})
    return (
        f"{scene.n_bodies} boxes of {', '.join(f'{a:g} x {b:g} m' for a, b in sizes)}, "
        f"{', '.join(f'{m:g}' for m in masses)} kg, e {scene.restitution:g}, mu {scene.friction:g}, "
        f"dt {scene.dt:.6g} s, g {scene.gravity:g} m/s^2"
    )


def readme_block(report: CollisionReport) -> str:
    return "\n".join(
        [
            f"**Boxes that collide** (`docs/collisions.md`): `python -m reports.collisions --write-docs` "
            f"({report.run_seconds / 60:.1f} min on {document.machine().split(',')[1].strip()}, {report.load}; "
            "`--quick` for the reduced version the tests run). The named multi-box scenes in our two solvers, pymunk "
            "and Box2D; a cell is the distance between two methods' outcomes and whether it is within the scene's "
            "tolerance:",
            "",
            summary_table(report),
        ]
    )


def write_report(report: CollisionReport, out: Path, readme: Path | None = None) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    path = out / "collisions.md"
    write_atomic(path, markdown(report))
    if readme is not None:
        document.update_readme("collisions", readme_block(report), readme)
    return path


def main(argv=None) -> int:
    return document.report_command("collisions", __doc__, run, write_report, argv)


if __name__ == "__main__":
    raise SystemExit(main())
