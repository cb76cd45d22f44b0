"""The quick stability report runs, writes its files and backs the claims of the full one."""

import pytest

from reports import stability

# Rows the robust default fails inside its declared range because of an engine issue reported to the lead, with
# the reason; strict, so an entry must go once the engine is fixed (and the reports regenerated). The push-out
# (k = 1e2 at fine dt), the energy gain of Newton restitution with friction, the drift of stacks at coarse
# steps and a box struck from above pushed into the floor (body_impacts) were fixed in the engine.
KNOWN_ENGINE_FAILURES: dict[str, str] = {}


@pytest.fixture(scope="module")
def report():
    return stability.run(quick=True, log=lambda *args: None)


def test_every_row_runs_both_solvers_on_the_same_points(report):
    assert [row.name for row in report.rows] == [
        "stiffness_map",
        "elastic_bouncing",
        "long_rest",
        "sliding",
        "fast_impacts",
        "fast_spin",
        "thin_boxes",
        "masses",
        "embedded",
        "far_from_origin",
        "corner_friction",
        "stacks",
        "body_impacts",
        "mass_ratio_stacks",
        "random_scenes",
    ]
    for row in report.rows:
        assert row.criterion and row.declared
        robust, seed = row.of("robust"), row.of("seed")
        assert robust and [c.point for c in robust] == [c.point for c in seed], row.name


BOX_CONTACT_ROWS = ("stacks", "body_impacts", "mass_ratio_stacks")


@pytest.mark.parametrize(
    "name",
    [
        "stiffness_map",
        "elastic_bouncing",
        "long_rest",
        "sliding",
        "fast_impacts",
        "fast_spin",
        "thin_boxes",
        "masses",
        "embedded",
        "far_from_origin",
        "corner_friction",
        *BOX_CONTACT_ROWS,
        "random_scenes",
    ],
)
def test_the_robust_default_passes_every_row_in_its_declared_range(report, name, request):
    if name in KNOWN_ENGINE_FAILURES:
        request.applymarker(pytest.mark.xfail(reason=KNOWN_ENGINE_FAILURES[name], strict=True))
    row = report.row(name)
    assert row.passed("robust"), row.verdict("robust")


def test_the_seed_scheme_fails_beyond_omega_dt_2_in_the_map(report):
    failed, total = report.seed_beyond_line()
    assert total >= 3 and failed == total
    below = [c for c in report.row("stiffness_map").of("seed") if c.values["omega_dt"] < 0.5]
    assert below and all(c.passed for c in below)  # and holds well inside it


def test_the_kept_random_example_is_always_run(report):
    points = [c.point["example"] for c in report.row("random_scenes").of("robust")]
    assert len(points) == 10 + len(stability.KNOWN_EXAMPLES)
    assert points[0].startswith("(1, 1, 0, 0")


def test_the_report_and_its_map_are_written(report, tmp_path):
    path = stability.write_report(report, tmp_path)
    text = path.read_text()
    assert (tmp_path / "figures" / "stability_map.png").stat().st_size > 10_000
    assert "figures/stability_map.png" in text
    assert "## The robust default's declared range" in text
    for row in report.rows:
        assert row.title in text


def test_the_report_runs_every_fuzz_and_the_robust_default_passes_them(report, tmp_path):
    assert [result.name for result in report.fuzz] == list(stability.fuzz.FUZZES)
    for result in report.fuzz:
        assert result.examples == stability.fuzz.REDUCED.examples
        assert result.passed, result.failures[:2]
        assert not any(solver == "robust" for solver, _ in result.documented_errors)
    text = stability.write_report(report, tmp_path).read_text()
    assert "## Property-based fuzz (hypothesis)" in text
    assert "Property-based fuzz" in stability.readme_block(report)
