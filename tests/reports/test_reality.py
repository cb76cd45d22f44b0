"""The real-data report's pieces, on a small synthetic fixture in the measured files' format, made by our own
engine with the rig's frame offsets and noise (``reports.reality.synthetic``); the measured data are not in
the repository and are not needed here."""

import math
import re

import numpy as np
import pytest

from reports.reality import data, download, error, report, synthetic

N_DROPS = 24
E, MU = 0.4, 0.3


@pytest.fixture(scope="module")
def fixture(tmp_path_factory):
    folder = tmp_path_factory.mktemp("drops")
    truth = synthetic.write_drops(folder, n=N_DROPS, e=E, mu=MU)
    return folder, truth


def test_the_fixture_has_the_measured_format(fixture):
    folder, _ = fixture
    lines = (folder / "traj_1.csv").read_text().splitlines()
    assert lines[0] == "x,z,th,vx,vz,vth" and len(lines) == 201
    table = np.loadtxt(folder / "traj_1.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[1:, 3:], np.diff(table[:, :3], axis=0) * 250.0)  # raw backward differences
    assert np.all(np.abs(table[:, 2]) <= math.pi / 4)  # the angle wrapped as the tracker reports a square


def test_cleaning_finds_the_frame_offsets_and_unwraps(fixture):
    folder, truth = fixture
    drops, cleaning = data.load(folder)
    assert cleaning.files == N_DROPS and cleaning.rest_drops == N_DROPS
    assert cleaning.rest_height == pytest.approx(data.HALF + synthetic.HEIGHT_OFFSET, abs=1e-4)
    assert cleaning.rest_angle == pytest.approx(synthetic.ANGLE_OFFSET, abs=math.radians(0.05))
    assert cleaning.angle_jumps > 0
    for d in drops:
        true = truth[d.number - 1]
        np.testing.assert_allclose(d.pose[:, :2], true[:, :2], atol=5e-4)
        offset = d.pose[:, 2] - true[:, 2]  # the same angle up to one whole quarter turn for the whole drop
        assert np.ptp(offset) < 0.02
        assert abs(data.face_angle(offset[0])) < 0.01


def test_first_impact_is_the_first_touch(fixture):
    folder, truth = fixture
    drops, _ = data.load(folder)
    assert len(drops) >= N_DROPS // 2
    for d in drops:
        true = truth[d.number - 1]
        corner = data.lowest_corner(true[:, 1], true[:, 2])
        rises = int(np.argmax(np.diff(true[:, 1]) > 0))  # the impact lies between frames rises - 1 and rises + 1
        touch = min(rises, int(np.argmax(corner < data.CONTACT_HEIGHT)))
        assert touch - 1 <= d.impact <= touch + 2
        assert d.flight_gravity == pytest.approx(-9.81, abs=0.6)


def test_bad_files_are_dropped_with_their_reason(tmp_path):
    rng = np.random.default_rng(0)
    poses = synthetic.simulated_drops(2, seed=3)
    for k in (1, 2):
        data.write_csv(tmp_path / f"traj_{k}.csv", synthetic.measured_like(poses[k - 1], rng, 3e-5))
    (tmp_path / "traj_3.csv").write_text("x,z,th,vx,vz,vth\n1,2,3,4,5,6\n")  # one row
    table = synthetic.measured_like(poses[0], rng, 3e-5)
    table[5, 1] = np.nan
    data.write_csv(tmp_path / "traj_4.csv", table)
    (tmp_path / "traj_5.csv").write_text("not,a,csv\nfile\n")
    data.write_csv(tmp_path / "trajSim_1.csv", table)  # simulated output beside the data: not read
    raw, cleaning = data.read_folder(tmp_path)
    assert sorted(raw) == [1, 2] and cleaning.files == 5
    assert sorted(n for numbers in cleaning.dropped.values() for n in numbers) == [3, 4, 5]
    assert cleaning.n_dropped == 3


def test_an_early_impact_is_dropped_and_counted(fixture, tmp_path):
    _, truth = fixture
    pose = np.concatenate([truth[0][8:], np.repeat(truth[0][-1:], 8, axis=0)])  # recorded 8 frames late
    data.write_csv(tmp_path / "traj_1.csv", synthetic.measured_like(pose, np.random.default_rng(0), 3e-5))
    drops, cleaning = data.load(tmp_path)
    assert drops == [] and [len(v) for v in cleaning.dropped.values()] == [1]
    assert "free flight" in next(iter(cleaning.dropped))


@pytest.mark.parametrize("make", ["missing", "file", "empty"])
def test_a_bad_data_folder_is_a_one_line_error(tmp_path, make):
    path = tmp_path / "drops"
    if make == "file":
        path.write_text("")
    elif make == "empty":
        path.mkdir()
    with pytest.raises(ValueError, match="^--data: "):
        data.load(path)


def test_the_manifest_lists_the_500_files():
    entries = download.manifest()
    assert sorted(entries, key=lambda n: int(n[5:-4])) == [f"traj_{k}.csv" for k in range(1, 501)]
    assert all(re.fullmatch("[0-9a-f]{64}", digest) for digest in entries.values())
    assert len(set(entries.values())) == 500


def test_verify_reports_missing_and_altered_files(tmp_path):
    (tmp_path / "traj_1.csv").write_text("a\n")
    (tmp_path / "traj_2.csv").write_text("b\n")
    expected = {"traj_1.csv": download.sha256(tmp_path / "traj_1.csv"), "traj_2.csv": "0" * 64, "traj_3.csv": "1" * 64}
    assert download.verify(tmp_path, expected) == {"traj_2.csv": "checksum", "traj_3.csv": "missing"}


def test_download_rejects_a_bad_out_in_one_line(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    with pytest.raises(SystemExit, match=r"^python -m reports.reality.download: error: --out: .* is not a folder$"):
        download.main(["--out", str(tmp_path / "file")])
    with pytest.raises(SystemExit, match="--out: .* does not exist"):
        download.main(["--out", str(tmp_path / "none"), "--check"])


def test_the_fit_finds_the_material_the_fixture_was_made_with(fixture):
    folder, _ = fixture
    drops, _ = data.load(folder)
    train, held = error.split(drops)
    assert {d.number % 2 for d in train} == {1} and {d.number % 2 for d in held} == {0}
    material, value = error.fit_material(train, error.Model())
    assert material.restitution == pytest.approx(E, abs=0.05) and material.friction == pytest.approx(MU, abs=0.05)
    evaluation = error.evaluate(held, error.Model(), material)
    position, angle = evaluation.at(20)
    assert position < 3e-3 and angle < math.radians(5)  # the engine against itself, from a fitted initial state
    wrong = error.evaluate(held, error.Model(), error.Material(0.0, 10.0))
    assert wrong.mean_over(50)[0] > 5 * evaluation.mean_over(50)[0]


def test_the_noise_floor_is_the_fixture_noise(fixture):
    folder, _ = fixture
    drops, _ = data.load(folder)
    noise = error.noise_floor(drops)
    sigma = 3e-5  # synthetic.write_drops' default
    assert noise["rest position"] == pytest.approx(math.sqrt(2) * sigma, rel=0.5)
    assert noise["flight position"] == pytest.approx(math.sqrt(2) * sigma, rel=0.5)


def test_the_report_command_writes_the_page_and_figures(fixture, tmp_path, capsys):
    folder, _ = fixture
    assert report.main(["--data", str(folder), "--quick", "--out", str(tmp_path)]) == 0
    page = (tmp_path / "reality.md").read_text()
    assert "Quick run" in page and "## What it teaches" in page and "ours, robust, dt = 4 ms |" in page
    assert (tmp_path / "figures" / "reality_error_time.png").stat().st_size > 10_000
    assert (tmp_path / "figures" / "reality_work.png").stat().st_size > 10_000
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize("make", ["missing", "empty"])
def test_the_report_command_rejects_bad_data_in_one_line(tmp_path, make):
    path = tmp_path / "drops"
    if make == "empty":
        path.mkdir()
    with pytest.raises(SystemExit, match=r"^python -m reports.reality: error: --data: [^\n]*$"):
        report.main(["--data", str(path), "--quick", "--out", str(tmp_path / "out")])


def test_box2d_v3_builds_the_square_as_the_other_engines_do():
    pytest.importorskip("pyb2d3")
    from benchmarks.other_engines import Toss
    from reports.reality.box2d_v3 import Box2DV3Engine

    toss = Toss(
        length=data.SIDE,
        width=data.SIDE,
        mass=0.05,
        x=0.0,
        y=0.2,
        angle=0.3,
        vx=0.5,
        vy=-1.0,
        omega=2.0,
        restitution=0.4,
        friction=0.2,
    )
    engine = Box2DV3Engine()
    mass, moment = engine.mass_properties(toss)
    assert mass == pytest.approx(toss.mass, rel=1e-6) and moment == pytest.approx(toss.moment, rel=1e-6)
    states = engine.simulate_toss(toss, data.FRAME, 150, record=True).states
    t = 10 * data.FRAME  # in free flight: symplectic Euler below the parabola by |g| t h / 2, h = dt / 4 substeps
    assert states[10, 0] == pytest.approx(0.5 * t, abs=1e-6)
    assert states[10, 1] == pytest.approx(0.2 - t - 0.5 * 9.81 * t**2 - 0.5 * 9.81 * t * data.FRAME / 4, abs=1e-5)
    assert states[10, 2] == pytest.approx(0.3 + 2.0 * t, abs=1e-5)
    assert abs(data.lowest_corner(states[-1, 1], states[-1, 2])) < 6e-3  # landed and at rest on the floor


def test_the_committed_page_is_the_command_output():
    """docs/reality.md is written by the command (not by hand): its figures exist and its tables have the rows the
    command writes for the full report."""
    page = (report.REPO / "docs" / "reality.md").read_text()
    assert page.startswith("# Error against reality") and "Quick run" not in page
    for figure in re.findall(r"\(figures/([\w.]+\.png)\)", page):
        assert (report.REPO / "docs" / "figures" / figure).is_file()
    for model in report.OUR_MODELS:
        assert f"| {model.name} |" in page


def test_a_missing_option_is_a_one_line_error():
    with pytest.raises(SystemExit, match=r"^python -m reports.reality: error: .*--data$"):
        report.main([])
    with pytest.raises(SystemExit, match=r"^python -m reports.reality.download: error: .*--out$"):
        download.main([])
