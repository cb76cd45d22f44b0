"""The quick collision report runs every method on every named multi-box scene, writes its page, and the
physics it reports holds."""

import math

import pytest

from reports import collisions


@pytest.fixture(scope="module")
def report():
    return collisions.run(quick=True, log=lambda *args: None)


def outcome(report, scene, method):
    result = report.result(scene)
    assert method in result.outcomes, result.runs[method].problem
    return result.outcomes[method]


def test_every_method_runs_every_scene_or_says_why(report):
    assert [r.spec.name for r in report.results] == [
        "stack",
        "pyramid",
        "drop_on_box",
        "flight_collision",
        "newton_row",
    ]
    assert set(report.methods) | set(report.missing) == {"robust", "seed", "pymunk", "box2d"}
    for result in report.results:
        for method in report.methods:
            run = result.runs[method]
            assert run.ran == (method in result.outcomes)
            assert run.ran or run.problem, (result.spec.name, method)


def test_our_solvers_run_every_scene(report):
    for result in report.results:
        assert "robust" in result.outcomes, result.runs["robust"].problem
        assert result.runs["seed"].ran or result.runs["seed"].problem.startswith("non-finite")


@pytest.mark.parametrize("engine", ["pymunk", "box2d"])
def test_other_engines_keep_the_flight_collisions_momentum(report, engine):
    if engine in report.missing:
        pytest.skip(f"{engine} not installed")
    values = outcome(report, "flight_collision", engine).values
    assert values["momentum error (rel.)"] <= 1e-5  # Box2D is float32
    assert values["energy gain (rel.)"] <= 1e-6
    assert values["energy kept"] < 1.0  # e < 1 and friction: the collision loses energy


def test_our_robust_solver_keeps_momentum_and_angular_momentum_in_flight(report):
    checks = outcome(report, "flight_collision", "robust").checks
    assert all(checks.values()), checks


@pytest.mark.parametrize("engine", ["pymunk", "box2d"])
def test_the_stack_comes_to_rest_in_the_other_engines(report, engine):
    if engine in report.missing:
        pytest.skip(f"{engine} not installed")
    values = outcome(report, "stack", engine).values
    assert values["largest move from start [m]"] < 5e-3
    assert outcome(report, "pyramid", engine).label == "holds"


def test_the_robust_stack_rests_and_the_pyramid_holds(report):
    assert outcome(report, "stack", "robust").checks["rests (drift < 1 mm)"]
    assert outcome(report, "pyramid", "robust").label == "holds"


@pytest.mark.parametrize("method", ["robust", "pymunk"])
def test_the_newton_row_passes_the_momentum_to_its_last_box(report, method):
    if method in report.missing:
        pytest.skip(f"{method} not installed")
    values = outcome(report, "newton_row", method).values
    velocities = values["final vx per box [m/s]"]
    assert velocities[-1] == pytest.approx(report.result("newton_row").scene.boxes[0].velocity[0], rel=0.01)
    assert max(abs(v) for v in velocities[:-1]) < 0.02 * abs(velocities[-1])


def test_box2d_moves_the_newton_row_together_below_its_restitution_threshold(report):
    """The row's impacts are not faster than b2_velocityThreshold = 1 m/s, so Box2D makes them perfectly inelastic:
    the five boxes end moving together at v0 / 5 (documented in benchmarks/other_engines.py)."""
    if "box2d" in report.missing:
        pytest.skip("box2d not installed")
    v0 = report.result("newton_row").scene.boxes[0].velocity[0]
    assert v0 <= collisions.BOX2D_RESTITUTION_THRESHOLD
    velocities = outcome(report, "newton_row", "box2d").values["final vx per box [m/s]"]
    assert velocities == pytest.approx([v0 / 5] * 5, rel=0.05)


def test_distances_are_symmetric_and_a_different_face_never_agrees(report):
    for result in report.results:
        for a, b in report.pairs():
            d_ab, d_ba = result.distance(a, b), result.distance(b, a)
            assert (math.isnan(d_ab) and math.isnan(d_ba)) or d_ab == pytest.approx(d_ba, rel=1e-12)
    drop = report.result("drop_on_box")
    for a, b in report.pairs():
        if a in drop.outcomes and b in drop.outcomes and drop.outcomes[a].label != drop.outcomes[b].label:
            assert drop.agree(a, b) is False


def test_the_report_is_written(report, tmp_path):
    path = collisions.write_report(report, tmp_path)
    text = path.read_text()
    assert "## Who agrees with whom" in text and "## Physics checks" in text
    for result in report.results:
        assert f"## {result.spec.title}" in text
    assert "Who agrees" not in collisions.readme_block(report) and "| pair |" in collisions.readme_block(report)


@pytest.mark.parametrize("scene", ["flight_collision", "newton_row", "stack", "pyramid"])
def test_the_robust_solver_agrees_with_pymunk(report, scene):
    """Both apply Newton's impact law with sharp corners: the same post-collision velocities (to rounding in
    flight), the same row, the same resting stack and pyramid (within pymunk's 1 mm slop per contact)."""
    if "pymunk" in report.missing:
        pytest.skip("pymunk not installed")
    result = report.result(scene)
    assert result.agree("robust", "pymunk"), result.distance("robust", "pymunk")
    if scene == "flight_collision":
        assert result.distance("robust", "pymunk") < 1e-9
