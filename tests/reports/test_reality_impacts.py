"""The impact-alone report (``reports.reality.impacts``) on synthetic impacts made by the laws themselves and on the
synthetic square drops: what a law made must come back with zero error and its e and mu; the measured data are
not needed (neither the square drops nor the ellipse file is in the repository)."""

import math

import numpy as np
import pytest

from reports.reality import data, download, impact_law, impacts, report, synthetic

MASS, GYRATION = impacts.ELLIPSE_MASS, impacts.ELLIPSE_GYRATION
INERTIA = MASS * GYRATION**2
E, MU = 0.5, 0.2  # on the fits' grids


def ellipse_like(n: int, seed: int = 0):
    """Pre-impact velocities and lever arms like the ellipse set's (falling at 2-3 m/s, contact below the centre)."""
    rng = np.random.default_rng(seed)
    velocity = np.column_stack([rng.uniform(-1, 1, n), rng.uniform(-3, -2, n), rng.uniform(-10, 10, n)])
    return velocity, rng.uniform(-0.01, 0.01, n), -rng.uniform(0.025, 0.035, n)


def test_the_laws_are_newton_without_friction():
    velocity, rx, ry = ellipse_like(50)
    u_n = velocity[:, 1] + velocity[:, 2] * rx
    for law in impact_law.LAWS:
        after = impact_law.apply(law, velocity, rx, ry, 0.6, 0.0, MASS, INERTIA)
        np.testing.assert_allclose(after[:, 1] + after[:, 2] * rx, -0.6 * u_n, rtol=1e-12)
        np.testing.assert_allclose(after[:, 0], velocity[:, 0])  # no friction: no tangential impulse
    proposal = impact_law.tangential(velocity, rx, ry, 0.6, 0.3, 0.0, MASS, INERTIA)
    np.testing.assert_allclose(
        proposal, impact_law.apply("newton", velocity, rx, ry, 0.6, 0.3, MASS, INERTIA), atol=1e-12
    )  # e_t = 0 is Newton + Coulomb, with the engine's sliding direction


def test_the_laws_never_create_energy_and_friction_stays_in_the_cone():
    velocity, rx, ry = ellipse_like(200, seed=1)
    weights = np.array([MASS, MASS, INERTIA])
    before = 0.5 * np.sum(weights * velocity**2, axis=1)
    after = impact_law.apply("ours", velocity, rx, ry, 0.9, 0.5, MASS, INERTIA)
    assert np.all(0.5 * np.sum(weights * after**2, axis=1) <= before * (1 + 1e-12))
    impulse = (after - velocity) * weights  # (q, lam, torque)
    assert np.all(impulse[:, 1] > 0) and np.all(np.abs(impulse[:, 0]) <= 0.5 * impulse[:, 1] * (1 + 1e-9))


def test_the_normalised_error_of_zero_velocity_is_one():
    measured = np.array([[1.0, 2.0, 30.0], [-0.5, 1.0, -3.0]])
    np.testing.assert_allclose(impact_law.normalised_error(np.zeros((2, 3)), measured, 0.02), 1.0)
    np.testing.assert_allclose(impact_law.normalised_error(measured, measured, 0.02), 0.0)


def write_ellipse(path, n=200, e=E, mu=MU, with_models=True):
    """A file in data_ellipse.mat's format whose post-impact states our law made (and v_models.mat beside it)."""
    import scipy.io

    velocity, rx, ry = ellipse_like(n, seed=2)
    after = impact_law.apply("ours", velocity, rx, ry, e, mu, MASS, INERTIA)
    pose = np.column_stack([np.full(n, 0.3), np.full(n, 0.07), np.zeros(n)])
    struct = {
        "states_i": np.hstack([pose, velocity]),
        "states_f": np.hstack([pose, after]),
        "n": np.column_stack([np.zeros(n), np.ones(n), rx]),
        "d": np.column_stack([np.ones(n), np.zeros(n), -ry]),
    }
    scipy.io.savemat(path, {"data": struct})
    if with_models:
        scipy.io.savemat(path.with_name("v_models.mat"), {"v_models": np.tile(after * 0.9, (1, 6))})
    return after


def test_impacts_our_law_made_come_back_with_their_e_and_mu(tmp_path):
    pytest.importorskip("scipy")
    write_ellipse(tmp_path / "data_ellipse.mat")
    result = impacts.run_ellipse(tmp_path / "data_ellipse.mat")
    ours = result["results"][0]
    assert (ours.model, ours.e, ours.mu) == ("ours", pytest.approx(E), pytest.approx(MU))
    assert ours.mean < 1e-9 and result["held"] == 100
    published = result["published"]
    assert len(published) == 6 and published[0].mean == pytest.approx(0.1)  # 0.9 v*: error 0.1 exactly
    assert result["zero"].mean == 1.0


def test_a_bad_ellipse_file_is_a_one_line_error(tmp_path):
    with pytest.raises(SystemExit, match=r"^python -m reports.reality.impacts: error: --ellipse: .* not a file"):
        impacts.main(["--ellipse", str(tmp_path / "none.mat"), "--page", str(tmp_path / "page.md")])
    with pytest.raises(SystemExit, match="give --data, --ellipse or both"):
        impacts.main([])


def square_states(n: int, seed: int = 0) -> np.ndarray:
    """Free-flight states 3 frames (12 ms) before the lowest corner reaches the floor, at any angle."""
    rng = np.random.default_rng(seed)
    angle = rng.uniform(-math.pi, math.pi, n)
    vy = rng.uniform(-2.2, -1.6, n)
    t = data.START_BEFORE_IMPACT * data.FRAME - 0.002
    height = data.lowest_corner(np.zeros(n), angle)  # centre 0: the lowest corner's offset
    y = -height - vy * t - 0.5 * -9.81 * t**2
    spin = rng.uniform(-3, 3, n)
    return np.column_stack([rng.uniform(-0.1, 0.1, n), y, angle - spin * t, rng.uniform(-0.5, 0.5, n), vy, spin])


def test_square_impacts_the_point_map_made_come_back_exactly():
    e = 0.44  # on the square fit's grid (0.2, refined by 0.04)
    states = square_states(40)
    poses = impacts.point_map_poses(states, "ours", e, MU)
    measured = impacts.SquareImpacts(
        np.arange(40), states, impacts.central(poses, 0), impacts.central(poses, impacts.BEFORE + 1), np.full(40, 0.5)
    )
    predicted, _ = impacts.predict(measured, "map: ours", e, MU)
    assert impact_law.normalised_error(predicted, measured.after, impacts.SQUARE_GYRATION).max() < 1e-9
    assert impacts.fit_square(measured, "map: ours") == (pytest.approx(e), pytest.approx(MU))
    tc = impacts.contact_instant(states)
    assert np.all(np.abs(tc - (data.START_BEFORE_IMPACT * data.FRAME - 0.002)) < 2 * impacts.SEARCH_STEP)


@pytest.fixture(scope="module")
def drops(tmp_path_factory):
    folder = tmp_path_factory.mktemp("drops")
    synthetic.write_drops(folder, n=24, e=0.4, mu=0.3)
    return folder


def test_our_engine_on_its_own_drops_finds_its_material(drops):
    found = impacts.square_impacts(data.load(drops)[0])
    assert len(found.numbers) >= 12
    assert np.mean(found.after[:, 1] > 0) > 0.8  # the centre goes up after most first impacts
    e, mu = impacts.fit_square(found, "ours")
    assert e == pytest.approx(0.4, abs=0.05) and mu == pytest.approx(0.3, abs=0.1)
    predicted, _ = impacts.predict(found, "ours", 0.4, 0.3)
    errors = impact_law.normalised_error(predicted, found.after, impacts.SQUARE_GYRATION)
    assert np.median(errors) < 0.05  # from a fitted free flight, against noisy poses


def test_the_command_writes_its_section_and_the_trajectory_report_keeps_it(drops, tmp_path):
    pytest.importorskip("scipy")
    write_ellipse(tmp_path / "data_ellipse.mat")
    page = tmp_path / "reality.md"
    page.write_text(f"# page\n\n{report.IMPACTS_START}\nold\n{report.IMPACTS_END}\n\ntail\n")
    assert (
        impacts.main(
            [
                "--data",
                str(drops),
                "--ellipse",
                str(tmp_path / "data_ellipse.mat"),
                "--page",
                str(page),
                "--quick",
                "--no-engines",
            ]
        )
        == 0
    )
    text = page.read_text()
    assert "old" not in text and text.endswith("tail\n")
    section = report.impacts_section_of(page)
    for words in (
        "### The square's first impacts",
        "| ours, robust solver",
        "### The ellipse impacts",
        "published: AP Poisson",
        "**Proposal.**",
    ):
        assert words in section
    assert report.impacts_section_of(tmp_path / "none.md") == report.IMPACTS_PLACEHOLDER


def test_the_committed_page_has_the_impacts_section():
    page = report.REPO / "docs" / "reality.md"
    section = report.impacts_section_of(page)
    assert section.startswith("## The impact alone") and "### The square's first impacts" in section


def test_the_ellipse_download_is_pinned_and_checked(tmp_path):
    assert set(download.ELLIPSE_FILES) == {"data_ellipse.mat", "v_models.mat"} and len(download.ELLIPSE_COMMIT) == 40
    (tmp_path / "data_ellipse.mat").write_bytes(b"not the file")
    assert download.verify(tmp_path, download.ELLIPSE_FILES) == {
        "data_ellipse.mat": "checksum",
        "v_models.mat": "missing",
    }
    assert download.main(["--ellipse", "--check", "--out", str(tmp_path)]) == 1
