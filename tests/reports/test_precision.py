"""The quick work-precision report runs, writes its files and backs the claims of the full one."""

import math

import numpy as np
import pytest

from reports import cases, precision


@pytest.fixture(scope="module")
def report():
    return precision.run(quick=True, log=lambda *args: None)


def points(report, case, method):
    return report.points_of(case, method)


def test_every_method_has_a_point_at_every_dt_of_every_case(report):
    for case in cases.exact_cases():
        for method in report.methods:
            assert [p.exponent for p in points(report, case.name, method)] == list(report.exponents)
    assert set(report.engines) | set(report.missing) == {"pymunk", "box2d", "mujoco"}


def test_failed_runs_are_marked_and_kept(report):
    """The seed's explicit spring at k = 1e5 N/m blows up at 2^-5 s: kept, marked, with a time."""
    flat = next(p for p in points(report, "flat_drop", "seed") if p.exponent == 5)
    assert flat.failed and "blow-up" in flat.failure and flat.seconds > 0


def test_robust_solver_is_exact_where_the_answer_is_closed_form(report):
    for case in ("free_flight", "corner_impact", "flat_drop", "resting"):
        assert all(not p.failed and p.error <= 1e-12 for p in points(report, case, "robust")), case
    orders = report.orders()
    assert precision.order_text(orders[("free_flight", "robust")], points(report, "free_flight", "robust")) == "exact"


def test_fitted_orders_on_smooth_cases(report):
    orders = report.orders()
    assert orders[("slide", "robust")] == pytest.approx(1.0, abs=0.1)
    assert orders[("free_flight", "seed")] == pytest.approx(1.0, abs=0.01)


def test_throws_are_compared_with_a_reference_16_times_finer(report):
    assert report.throws.n == precision.QUICK_N_THROWS
    for solver in precision.SOLVERS:
        settings, reference = report.throw_results[solver]
        assert [s.exponent for s in settings] == list(precision.QUICK_THROW_EXPONENTS)
        assert reference.exponent == max(precision.QUICK_THROW_EXPONENTS) + 4
        assert not (reference.accepted & ~reference.valid).any()
        for s in settings:
            assert s.seconds_per_throw > 0
            assert 0.0 <= s.face_agreement_all <= 1.0
            assert s.position_errors.size <= reference.accepted.sum()
    robust, _ = report.throw_results["robust"]
    assert not any(s.failed.any() for s in robust)


def test_acceptance_keeps_a_throw_only_if_the_reference_resolves_its_errors():
    n = 3
    reference_states = np.zeros((n, 6))
    setting = precision.Setting(
        "robust", 8, 1e-4, reference_states + [[1e-3, 0, 0, 0, 0, 0]], np.zeros(n, bool), np.ones(n, bool)
    )
    reference = precision.Reference(
        "robust",
        12,
        reference_states,
        reference_states,
        np.array([1e-5, 1e-4, 1e-3]),
        np.zeros(n),
        np.ones(n, bool),
        np.ones(n, bool),
        {},
        np.ones(n, bool),
        0.0,
    )
    precision.compare([setting], reference)
    np.testing.assert_array_equal(reference.accepted, [True, False, False])  # < a tenth of the 1 mm error
    assert setting.face_agreement == 1.0 and setting.position_errors == pytest.approx([1e-3])


def test_recommendation_is_the_cheapest_setting_meeting_the_criterion():
    def setting(exponent, seconds, position_error, faces, judged_share=1.0):
        s = precision.Setting("robust", exponent, seconds, np.zeros((4, 6)), np.zeros(4, bool), np.ones(4, bool))
        s.judged_face_agreement = faces
        s.judged_position_errors = np.full(4, position_error)
        s.judged_angle_errors = np.zeros(4)
        s.judged_share = judged_share
        return s

    candidates = [
        setting(6, 1e-5, 0.05, 1.0),
        setting(8, 3e-5, 0.005, 1.0),
        setting(10, 9e-5, 0.001, 1.0),
        setting(7, 2e-5, 0.001, 0.9),
        setting(5, 1e-6, 0.001, 1.0, judged_share=0.5),
    ]
    assert precision.recommend({"robust": (candidates, None)}) is candidates[1]
    assert precision.recommend({"robust": (candidates[:1], None)}) is None
    assert candidates[4].verdict() == "undecided" and candidates[0].verdict() == "no"


def test_the_criterion_is_judged_where_the_reference_resolves_it():
    n = 3
    reference_states = np.zeros((n, 6))
    setting = precision.Setting(
        "robust", 8, 1e-4, reference_states + [[5e-3, 0, 0, 0, 0, 0]], np.zeros(n, bool), np.ones(n, bool)
    )
    reference = precision.Reference(
        "robust",
        12,
        reference_states,
        reference_states,
        np.array([1e-4, 5e-4, 2e-3]),
        np.zeros(n),
        np.ones(n, bool),
        np.ones(n, bool),
        {},
        np.ones(n, bool),
        0.0,
    )
    precision.compare([setting], reference)
    np.testing.assert_array_equal(reference.judged, [True, True, False])  # < 1 mm, a tenth of the 1 cm threshold
    assert setting.judged_share == pytest.approx(2 / 3) and not setting.decidable


def test_the_report_and_its_figures_are_written(report, tmp_path):
    path = precision.write_report(report, tmp_path)
    text = path.read_text()
    for name in ("precision_work.png", "precision_order.png", "precision_faces.png"):
        assert (tmp_path / "figures" / name).stat().st_size > 10_000
        assert f"figures/{name}" in text
    assert "## The env's default setting" in text and "dt=0.0078125" in text
    for case in cases.exact_cases():
        assert f"### {case.title}" in text
    assert "FAIL: blow-up" in text
    assert not math.isnan(report.run_seconds)


def test_per_throw_order_of_landing_x_is_the_slope_over_resolved_errors():
    """Throw 0 lands C dt from the reference (order 1), throw 1 C dt^2 (order 2), throw 2 within the reference's
    own resolution at every dt (not measurable), throw 3 failed at one dt (not measured)."""
    exponents = (5, 6, 7, 8)
    reference_states = np.zeros((4, 6))
    check = reference_states.copy()
    check[2, 0] = 1e-3  # the reference of throw 2 moves 1 mm when its step is halved
    reference = precision.Reference(
        "robust",
        12,
        reference_states,
        check,
        np.zeros(4),
        np.zeros(4),
        np.ones(4, bool),
        np.ones(4, bool),
        {},
        np.ones(4, bool),
        0.0,
    )
    settings = []
    for k in exponents:
        dt = 2.0**-k
        states = np.zeros((4, 6))
        states[:, 0] = [0.3 * dt, 2.0 * dt**2, 1e-3 * dt, 0.3 * dt]
        failed = np.array([False, False, False, k == 7])
        settings.append(precision.Setting("robust", k, 1e-5, states, failed, np.ones(4, bool)))
    orders = precision.throw_orders(settings, reference)
    assert orders[0] == pytest.approx(1.0) and orders[1] == pytest.approx(2.0)
    assert math.isnan(orders[2]) and math.isnan(orders[3])
    summary = precision.order_summaries(settings, reference)[0]
    assert summary.share_at_least(1.0) == 1.0 and summary.measured.size == 2


def test_the_report_states_the_measured_convergence_order(report):
    text = precision.convergence_text(report)
    assert "per-throw order of landing x" in text and ("met" in text)
    assert precision.convergence_text(report) in precision.readme_block(report)
