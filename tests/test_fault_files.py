"""A damaged file is one line naming it and what is wrong, and nothing is rewritten before the whole input is known
good: one test per kind of file the tools read (config.yml, a checkpoint's model, model.zip, the VecNormalize
statistics, a replay buffer, timing.json, the CSV logs, the measured drops). A resume whose newest checkpoint is
damaged offers the newest intact one, and resumes from it when asked. Temporary files an interrupted write left
behind are removed by the next command that owns their folder."""

from __future__ import annotations

import shutil
import zipfile
from pathlib import Path

import pytest
from fault_injection import tree_state

from agents import evaluate, train
from agents.run_folder import read_csv

TINY = [
    "n_envs=4",
    "n_steps=16",
    "batch_size=64",
    "n_epochs=1",
    "eval_freq=64",
    "eval_targets=4",
    "checkpoint_freq=64",
    "policy_kwargs.net_arch=[8]",
]
RESUME = ["--no-progress", "--no-eval", "--set", "n_timesteps=192"]


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    """A PPO run of 128 throws: checkpoints at 64 and 128, best models, logs."""
    runs = tmp_path_factory.mktemp("runs")
    argv = ["--runs-dir", str(runs), "--name", "run", "--no-progress", "--no-eval", "--set", "n_timesteps=128", *TINY]
    return train.main(argv)


@pytest.fixture
def run(trained, tmp_path) -> Path:
    """A copy of the trained run to damage."""
    copy = tmp_path / "run"
    shutil.copytree(trained, copy, ignore=shutil.ignore_patterns(".lock"))
    return copy


def refused(capsys, command, argv: list[str], *words: str) -> str:
    """The one line ``command`` ends with (a non-zero exit, no traceback), holding every one of ``words``."""
    with pytest.raises(SystemExit) as done:
        command(argv)
    assert done.value.code not in (0, None)
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, err
    return err


def cut(path: Path, keep: int = 300) -> None:
    path.write_bytes(path.read_bytes()[:keep])


def test_a_cut_checkpoint_is_named_the_older_intact_one_offered_and_resumed_from_when_asked(run, capsys):
    newest = run / "checkpoints" / "ppo_128_steps.zip"
    cut(newest)
    before = tree_state(run)
    refused(capsys, train.main, ["--resume", str(run), *RESUME], str(newest), "not a whole zip", "--from-steps 64")
    assert tree_state(run) == before  # config.yml, logs, best model: nothing rewritten
    train.main(["--resume", str(run), "--from-steps", "64", *RESUME])
    assert (run / "checkpoints" / "ppo_128_steps.zip.damaged").exists()  # set aside, not deleted
    assert zipfile.ZipFile(newest).testzip() is None  # written again by the resumed training
    steps = [int(row["timesteps"]) for row in read_csv(run / "evaluations.csv")[1]]
    assert steps == sorted(set(steps)) and steps[-1] == 192  # no row duplicated


def test_from_steps_refuses_while_a_newer_checkpoint_is_intact(run, capsys):
    before = tree_state(run)
    refused(capsys, train.main, ["--resume", str(run), "--from-steps", "64", *RESUME], "128 steps is newer and intact")
    refused(capsys, train.main, ["--resume", str(run), "--from-steps", "100", *RESUME], "no checkpoint at it")
    assert tree_state(run) == before


@pytest.mark.parametrize(
    "name, damage, words",
    [
        ("checkpoints/ppo_vecnormalize_128_steps.pkl", lambda p: cut(p, 100), ["does not unpickle", "--from-steps 64"]),
        ("checkpoints/ppo_vecnormalize_128_steps.pkl", lambda p: p.write_bytes(b""), ["is empty"]),
        ("checkpoints/ppo_replay_buffer_128_steps.pkl", lambda p: p.write_bytes(b"\x80\x04K\x01."), ["replay buffer"]),
        (
            "checkpoints/ppo_128_steps.zip",
            lambda p: shutil.copy(p.with_name("ppo_64_steps.zip"), p),
            ["64 steps, not 128"],
        ),
        ("config.yml", lambda p: p.write_text(""), ["is empty"]),
        ("config.yml", lambda p: p.write_text("algo: [ppo\n"), ["not valid YAML"]),
        ("config.yml", lambda p: p.write_text("- a list\n"), ["holds a list"]),
        ("config.yml", lambda p: p.write_text(p.read_text().replace("n_epochs: 1", "n_epochs: lots")), ["n_epochs"]),
        ("timing.json", lambda p: cut(p, 20), ["not valid JSON"]),
        ("evaluations.csv", lambda p: p.write_text(p.read_text().replace("\n64,", "\nsixty-four,")), ["row 3"]),
        ("logs/progress.csv", lambda p: p.write_bytes(b"\xff\xfe\x00"), ["not text"]),
    ],
)
def test_a_damaged_file_stops_a_resume_in_one_line_naming_it_and_rewrites_nothing(run, capsys, name, damage, words):
    damage(run / name)
    before = tree_state(run)
    refused(capsys, train.main, ["--resume", str(run), *RESUME], name.split("/")[-1], *words)
    assert tree_state(run) == before


@pytest.mark.parametrize(
    "name, damage, words",
    [
        ("model.zip", cut, ["model.zip is damaged", "not a whole zip"]),
        ("model.zip", lambda p: p.write_text("not a zip\n"), ["model.zip is damaged"]),
        ("vecnormalize.pkl", lambda p: cut(p, 50), ["vecnormalize.pkl is damaged"]),
        ("vecnormalize.pkl", lambda p: p.write_bytes(b"\x80\x04K\x01."), ["holds a int, not VecNormalize"]),
        ("config.yml", lambda p: p.write_text(""), ["config.yml is empty"]),
        ("config.yml", lambda p: p.write_text("algo: ppo\n"), ["env_id is None"]),
    ],
)
def test_a_damaged_file_stops_an_evaluation_in_one_line_naming_it_and_writes_nothing(run, capsys, name, damage, words):
    damage(run / name)
    before = tree_state(run)
    refused(capsys, evaluate.main, [str(run), "--targets", "4", "--no-plots"], *words)
    assert tree_state(run) == before and not (run / "eval").exists()


def test_a_later_command_removes_the_temporary_files_an_interrupted_write_left(run, capsys):
    evaluate.main([str(run), "--targets", "4", "--no-plots"])
    results = run / "eval" / "targets=4"
    leftovers = [results / ".results.json.k3jx_9qa.tmp.json", run / ".timing.json.abcdefgh.tmp.json"]
    leftovers.append(run / "checkpoints" / ".ppo_128_steps.zip.zz99yy88.tmp.zip")
    for path in leftovers:
        path.write_bytes(b"half a file")
    evaluate.main([str(run), "--targets", "4", "--no-plots"])
    assert not leftovers[0].exists() and leftovers[1].exists()  # the evaluation owns its results folder only
    train.main(["--resume", str(run), *RESUME])
    assert not any(path.exists() for path in leftovers)


def test_a_missing_run_is_one_line(tmp_path, capsys):
    refused(capsys, evaluate.main, [str(tmp_path / "nowhere")], "is not a run folder")
    (tmp_path / "config.yml").write_text("algo: ppo\n")
    refused(capsys, evaluate.main, [str(tmp_path / "config.yml")], "is a file, not a run folder")
    refused(capsys, train.main, ["--resume", str(tmp_path / "nowhere")], "--resume", "is not a run folder")
    assert not (tmp_path / "nowhere").exists()


# -- the measured drops (reports.reality) -----------------------------------------------------------------------
def reality_refusal(argv: list[str]) -> str:
    from reports.reality import impacts

    with pytest.raises(SystemExit) as done:
        impacts.main(argv)
    message = str(done.value.code)
    assert "\n" not in message and "Traceback" not in message, message
    return message


def test_too_short_or_unreadable_drop_files_are_one_line(tmp_path):
    (tmp_path / "traj_1.csv").write_text("x,z,th,vx,vz,vth\n0,0.1,0,0,0,0\n")  # one row of 200
    (tmp_path / "traj_2.csv").write_bytes(b"\xff\x00 not text")
    message = reality_refusal(["--data", str(tmp_path), "--no-engines", "--quick", "--page", str(tmp_path / "p.md")])
    assert "--data" in message and "no usable drop" in message and "1 unreadable" in message
    assert not (tmp_path / "p.md").exists()


def test_a_damaged_ellipse_file_is_one_line(tmp_path):
    (tmp_path / "data_ellipse.mat").write_bytes(b"MATLAB 5.0 MAT-file, cut")
    message = reality_refusal(["--ellipse", str(tmp_path / "data_ellipse.mat"), "--page", str(tmp_path / "p.md")])
    assert "--ellipse" in message and "data_ellipse.mat" in message
    assert not (tmp_path / "p.md").exists()
