"""When the file system says no (read-only, full, a size limit, no permission, missing), a command ends with one
sentence naming the path and the action, a non-zero exit and no traceback, and the run stays as it was and
resumable. The faults are injected without privileges (``fault_injection``: an audit hook in this process, a
file-size limit for a child process), so the tests run in an unprivileged CI.
"""

from __future__ import annotations

import errno
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from fault_injection import refuse, size_limited, tree_state
from test_fault_files import RESUME, TINY, refused, trained  # noqa: F401  (trained: the run these tests copy)

from agents import evaluate, train
from agents.run_folder import read_csv

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture
def run(trained, tmp_path) -> Path:  # noqa: F811  (the fixture imported above)
    copy = tmp_path / "runs" / "run"
    shutil.copytree(trained, copy, ignore=shutil.ignore_patterns(".lock"))
    return copy


def test_a_read_only_runs_folder_refuses_a_new_training_in_one_line_and_holds_nothing_new(tmp_path, capsys):
    runs = tmp_path / "runs"
    runs.mkdir()
    argv = ["--runs-dir", str(runs), "--name", "new", "--no-progress", "--set", "n_timesteps=64", *TINY]
    with refuse(runs, errno.EROFS):
        refused(capsys, train.main, argv, f"cannot make the run folder {runs / 'new'}", "read-only")
    assert not any(runs.iterdir())


def test_a_read_only_run_refuses_resume_and_evaluation_and_stays_as_it_was(run, capsys):
    before = tree_state(run)
    with refuse(run, errno.EROFS):
        refused(capsys, train.main, ["--resume", str(run), *RESUME], str(run / ".lock"), "read-only")
        refused(capsys, evaluate.main, [str(run), "--targets", "4", "--no-plots"], "cannot make the results folder")
    assert tree_state(run) == before
    train.main(["--resume", str(run), *RESUME])  # writable again: resumable


def test_a_disk_that_fills_during_training_stops_it_in_one_line_and_the_run_resumes(tmp_path, capsys):
    runs = tmp_path / "runs"
    argv = ["--runs-dir", str(runs), "--name", "full", "--no-progress", "--no-eval", "--set", "n_timesteps=192", *TINY]
    with refuse(runs, errno.ENOSPC, pattern="*ppo_128_steps*"):  # the disk fills at the second checkpoint
        refused(
            capsys,
            train.main,
            argv,
            f"cannot write {runs / 'full' / 'checkpoints' / 'ppo_128_steps.zip'}: the disk is full",
            f"--resume {runs / 'full'}",
        )
    assert not [path for path in (runs / "full").rglob("*") if ".tmp" in path.name]  # no half file left
    train.main(["--resume", str(runs / "full"), *RESUME])
    steps = [int(row["timesteps"]) for row in read_csv(runs / "full" / "evaluations.csv")[1]]
    assert steps == sorted(set(steps)) and steps[-1] == 192


def test_a_disk_that_fills_during_evaluation_leaves_no_empty_results_folder(run, capsys):
    before = tree_state(run)
    with refuse(run, errno.ENOSPC, pattern="*throws*"):  # the disk fills as the throws are written
        refused(capsys, evaluate.main, [str(run), "--targets", "4", "--no-plots"], "the disk is full")
    assert tree_state(run) == before and not (run / "eval" / "targets=4").exists()  # no folder holding a lock
    evaluate.main([str(run), "--targets", "4", "--no-plots"])  # room again: the evaluation goes through
    assert (run / "eval" / "targets=4" / "results.json").is_file()


def test_a_file_without_read_permission_is_named(run, capsys):
    before = tree_state(run)
    with refuse(run, errno.EACCES, reads=True, pattern="*/config.yml"):
        refused(capsys, evaluate.main, [str(run), "--no-plots"], f"cannot read {run / 'config.yml'}: permission denied")
        refused(capsys, train.main, ["--resume", str(run)], "config.yml: permission denied")
    assert tree_state(run) == before


def test_a_size_limited_runs_folder_stops_training_in_one_line_without_a_traceback(tmp_path):
    """A child process may write no file over 100 kB (RLIMIT_FSIZE: the kernel fails the write with EFBIG inside
    SB3's zip writer): the first model saved is larger."""
    runs = tmp_path / "runs"
    argv = ["--runs-dir", str(runs), "--name", "big", "--no-progress", "--no-eval", "--set", "n_timesteps=64", *TINY]
    argv[-1] = "policy_kwargs.net_arch=[256, 256]"  # a model of about 700 kB
    done = subprocess.run(
        [sys.executable, "-m", "agents.train", *argv],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=size_limited(100_000),
    )
    assert done.returncode == 1, done.stdout + done.stderr
    err = done.stderr.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert "size limit" in err and str(runs / "big") in err, err
    assert not [path for path in (runs / "big").rglob("*") if ".tmp" in path.name]
