"""Run folders never lose or mix data: atomic names and files, appended logs, resumes that continue
exactly at their checkpoint (or refuse, naming why), kills at any point (``kill -9``)."""

import csv
import hashlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import yaml

from agents.run_folder import (
    AppendingCSVOutput,
    RunFolderError,
    atomic_path,
    check_component,
    claim_folder,
    read_csv,
    truncate_csv,
    unlock_run,
    write_atomic,
)
from agents.training import latest_checkpoint, model_timesteps, new_run_dir, restore_best

REPO = Path(__file__).resolve().parents[2]
# a rollout (n_envs x n_steps), a checkpoint and a validation every 64 throws: rows at 0, 64, 128, ...
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


def run(*args: str, ok: bool = True) -> subprocess.CompletedProcess:
    done = subprocess.run([sys.executable, "-m", *args], cwd=REPO, capture_output=True, text=True, timeout=300)
    if ok:
        assert done.returncode == 0, done.stdout + done.stderr
    return done


def train_tiny(runs: Path, name: str, steps: int, *extra: str) -> list[str]:
    return [
        "agents.train",
        "--runs-dir",
        str(runs),
        "--name",
        name,
        "--no-progress",
        "--no-eval",
        "--set",
        f"n_timesteps={steps}",
        *TINY,
        *extra,
    ]


def one_line_error(done: subprocess.CompletedProcess, message: str, code: int = 2) -> None:
    """A bad option exits with 2; a run folder that cannot be used as asked (``code=1``) with 1."""
    assert done.returncode == code, done.stdout + done.stderr
    assert message in done.stderr and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr


# -- names and files -----------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["../x", "a/b", "..", ".", "", "/abs"])
def test_names_and_tags_are_single_folder_names(name):
    with pytest.raises(RunFolderError, match="single folder name"):
        check_component(name, "--name")
    assert check_component("short-2", "--name") == "short-2"


def test_runs_started_together_get_different_folders(tmp_path):
    with ThreadPoolExecutor(8) as pool:
        folders = list(pool.map(lambda _: claim_folder(tmp_path, "ppo-BoxToss-v0-20260101-000000"), range(16)))
    assert len(set(folders)) == 16 and all(folder.is_dir() for folder in folders)
    assert new_run_dir(tmp_path, None, "BoxToss-v0", "ppo") != new_run_dir(tmp_path, None, "BoxToss-v0", "ppo")
    with pytest.raises(RunFolderError, match="already holds a run"):
        new_run_dir(tmp_path, folders[0].name, "BoxToss-v0", "ppo")


def test_a_write_cut_short_leaves_the_old_file(tmp_path):
    path = tmp_path / "results.json"
    write_atomic(path, "old")
    with pytest.raises(KeyboardInterrupt), atomic_path(path) as temp:
        temp.write_text("half of the ne")
        raise KeyboardInterrupt  # a kill in the middle of the write
    assert path.read_text() == "old" and os.listdir(tmp_path) == ["results.json"]


def test_logs_are_appended_and_truncated_to_the_checkpoint(tmp_path):
    path = tmp_path / "progress.csv"
    output = AppendingCSVOutput(path)
    output.write({"time/total_timesteps": 64, "a": 1.0}, {})
    output.write({"time/total_timesteps": 128, "a": 2.0, "b": 3.0}, {})  # a new key widens the header
    output.write({"time/total_timesteps": 192, "a": 4.0, "b": 5.0}, {})
    with open(path, "a") as file:
        file.write("256,6.0")  # a line cut by a kill
    columns, rows = read_csv(path)
    assert set(columns) == {"time/total_timesteps", "a", "b"} and [row["a"] for row in rows] == ["1.0", "2.0", "4.0"]
    assert truncate_csv(path, "time/total_timesteps", 128) == (2, 2)  # 192 and the cut line dropped
    AppendingCSVOutput(path).write({"time/total_timesteps": 192, "a": 7.0, "b": 8.0}, {})
    assert [row["time/total_timesteps"] for row in read_csv(path)[1]] == ["64", "128", "192"]


# -- the commands --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory) -> Path:
    runs = tmp_path_factory.mktemp("runs")
    run(*train_tiny(runs, "tiny", 128))
    return runs / "tiny"


def test_a_named_folder_is_cleared_only_if_its_run_died_before_a_checkpoint(tiny_run, tmp_path):
    dead = tmp_path / "dead"
    dead.mkdir()
    (dead / "config.yml").write_text("algo: ppo\n")
    (dead / "evaluations.csv").write_text("timesteps\n0\n")
    assert new_run_dir(tmp_path, "dead", "BoxToss-v0", "ppo") == dead and os.listdir(dead) == [".lock"]
    with pytest.raises(RunFolderError, match="already holds a run"):
        new_run_dir(tiny_run.parent, "tiny", "BoxToss-v0", "ppo")
    unlock_run(dead)
    (dead / "config.yml").write_text("algo: ppo\n")
    live = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time; from agents.run_folder import lock_run; "
            f"lock_run({str(dead)!r}); print('locked', flush=True); time.sleep(60)",
        ],
        cwd=REPO,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert live.stdout.readline().strip() == "locked"
        one_line_error(run(*train_tiny(tmp_path, "dead", 64), ok=False), "is in use by another training")
    finally:
        live.kill()
        live.wait()


def test_a_run_records_what_it_trains(tiny_run):
    saved = yaml.safe_load((tiny_run / "config.yml").read_text())
    assert saved["algo"] == "ppo" and saved["env_id"] == "BoxToss-v0" and saved["version"]
    assert latest_checkpoint(tiny_run, "ppo")[2] == 128


def test_a_resume_that_disagrees_with_the_run_refuses(tiny_run):
    one_line_error(
        run("agents.train", "--resume", str(tiny_run), "--algo", "sac", ok=False), "trained with --algo ppo, not sac"
    )
    one_line_error(
        run("agents.train", "--resume", str(tiny_run), "--env", "BoxToss-OnBox-v0", ok=False),
        "trained with --env BoxToss-v0",
    )


def test_a_resume_without_checkpoint_or_statistics_refuses_naming_the_file(tiny_run, tmp_path):
    copy = tmp_path / "copy"
    subprocess.run(["cp", "-r", str(tiny_run), str(copy)], check=True)
    for path in copy.glob("checkpoints/ppo_vecnormalize_128_steps.pkl"):
        path.unlink()
    one_line_error(run("agents.train", "--resume", str(copy), ok=False), "ppo_vecnormalize_128_steps.pkl is missing", 1)
    (copy / "vecnormalize.pkl").unlink()
    one_line_error(run("agents.evaluate", str(copy), "--targets", "4", ok=False), "vecnormalize.pkl is missing", 1)
    for path in list(copy.glob("checkpoints/*")) + [copy / "model.zip"]:
        path.unlink()
    one_line_error(run("agents.train", "--resume", str(copy), ok=False), "no checkpoint to resume from", 1)


def test_paths_never_escape_the_runs_folder(tiny_run, tmp_path):
    one_line_error(run(*train_tiny(tmp_path, "../x", 64), ok=False), "--name: must be a single folder name")
    one_line_error(
        run("agents.evaluate", str(tiny_run), "--tag", "../../x", ok=False), "--tag: must be a single folder name"
    )
    (tmp_path / "file").write_text("")
    one_line_error(run(*train_tiny(tmp_path / "file", "x", 64), ok=False), "is a file, not a folder")
    assert sorted(os.listdir(tmp_path)) == ["file"]


def test_evaluations_with_other_settings_never_overwrite_each_other(tiny_run):
    run("agents.evaluate", str(tiny_run), "--targets", "8", "--no-plots")
    run("agents.evaluate", str(tiny_run), "--targets", "4", "--no-plots", "--tag", "mine")
    assert json.loads((tiny_run / "eval" / "targets=8" / "results.json").read_text())["n"] == 8
    assert not (tiny_run / "eval" / "default").exists()
    one_line_error(
        run("agents.evaluate", str(tiny_run), "--targets", "8", "--tag", "mine", ok=False),
        "holds an evaluation with other settings",
    )
    assert json.loads((tiny_run / "eval" / "mine" / "results.json").read_text())["n"] == 4


# -- kills ---------------------------------------------------------------------------------------
def steps_column(path: Path, column: str) -> list[int]:
    with open(path) as file:
        return [int(float(row[column])) for row in csv.DictReader(file)]


def test_kill_9_at_random_points_then_resume_loses_and_duplicates_nothing(tmp_path):
    """Killed twice at random moments (checkpoints are written every 64 throws, so a kill often lands in
    one), then resumed to the end: every rollout's row of progress.csv and every validation's row of
    evaluations.csv is there exactly once, and the wall time of the killed sessions is counted."""
    rng = random.Random(int(os.environ.get("KILL_SEED", time.time())))
    steps = 1024
    command = [sys.executable, "-m", *train_tiny(tmp_path, "killed", steps)]
    process = subprocess.Popen(command, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    run_dir = tmp_path / "killed"
    walls = []
    for _ in range(2):
        while latest_checkpoint(run_dir, "ppo") is None and process.poll() is None:  # training has begun
            time.sleep(0.05)
        time.sleep(rng.uniform(0.0, 2.0))
        process.send_signal(signal.SIGKILL)
        process.wait()
        timing = json.loads((run_dir / "timing.json").read_text())
        walls.append(timing["wall_seconds"])
        process = subprocess.Popen(
            [sys.executable, "-m", "agents.train", "--resume", str(run_dir), "--no-progress", "--no-eval"],
            cwd=REPO,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
    assert process.wait(timeout=300) == 0, process.stderr.read()
    assert steps_column(run_dir / "logs" / "progress.csv", "time/total_timesteps") == list(range(64, steps + 1, 64))
    assert steps_column(run_dir / "evaluations.csv", "timesteps") == list(range(0, steps + 1, 64))
    wall = steps_column(run_dir / "evaluations.csv", "wall_seconds")
    assert wall == sorted(wall)  # wall time never goes backwards
    assert json.loads((run_dir / "timing.json").read_text())["wall_seconds"] > walls[-1] >= walls[0] > 0
    # resuming a run that has reached its budget changes nothing
    before = (run_dir / "logs" / "progress.csv").read_text()
    run("agents.train", "--resume", str(run_dir), "--no-progress", "--no-eval")
    assert (run_dir / "logs" / "progress.csv").read_text() == before


def test_two_runs_started_together_without_a_name_get_two_folders(tmp_path):
    command = [
        sys.executable,
        "-m",
        "agents.train",
        "--runs-dir",
        str(tmp_path),
        "--no-progress",
        "--no-eval",
        "--set",
        "n_timesteps=64",
        *TINY,
    ]
    processes = [
        subprocess.Popen(command, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE) for _ in range(2)
    ]
    for process in processes:
        assert process.wait(timeout=300) == 0, process.stderr.read()
    folders = sorted(os.listdir(tmp_path))
    assert len(folders) == 2 and all((tmp_path / folder / "model.zip").exists() for folder in folders)


# a training whose checkpoint write at KILL_STEPS steps stops (and waits for its kill -9) at KILL_POINT:
# "half" with half of the model's zip in its temporary file, "rename" with the whole model written to its
# temporary file but not yet renamed; the marker file says the training got there
PAUSING_TRAIN = r"""
import os, sys, time
from pathlib import Path

import stable_baselines3.common.base_class as base_class

from agents import run_folder, train

point, steps, marker = os.environ["KILL_POINT"], os.environ["KILL_STEPS"], Path(os.environ["KILL_MARKER"])
model_name = f"ppo_{steps}_steps.zip"


def pause(what):
    marker.write_text(what)
    while True:
        time.sleep(1)


real_save, real_replace = base_class.save_to_zip_file, run_folder.os.replace


def save_to_zip_file(path, *args, **kwargs):
    real_save(path, *args, **kwargs)
    if point == "half" and Path(path).name.startswith(f".{model_name}."):
        Path(path).write_bytes(Path(path).read_bytes()[: Path(path).stat().st_size // 2])
        pause(str(path))


def replace(source, destination):
    if point == "rename" and Path(destination).name == model_name:
        pause(str(source))
    real_replace(source, destination)


base_class.save_to_zip_file, run_folder.os.replace = save_to_zip_file, replace
train.main(sys.argv[1:])
"""


def file_digests(folder: Path) -> dict[str, str]:
    return {path.name: hashlib.sha256(path.read_bytes()).hexdigest() for path in sorted(folder.iterdir())}


def train_until_killed(args: list[str], point: str, steps: int, marker: Path) -> str:
    """Run agents.train with ``args``; kill -9 it once its checkpoint at ``steps`` is paused at ``point``.
    Returns what it printed."""
    env = {**os.environ, "KILL_POINT": point, "KILL_STEPS": str(steps), "KILL_MARKER": str(marker)}
    marker.unlink(missing_ok=True)
    process = subprocess.Popen(
        [sys.executable, "-c", PAUSING_TRAIN, *args],
        cwd=REPO,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    deadline = time.monotonic() + 240
    while not marker.exists():
        assert process.poll() is None, process.stdout.read()
        assert time.monotonic() < deadline, "the training never reached the checkpoint write"
        time.sleep(0.05)
    process.send_signal(signal.SIGKILL)
    process.wait()
    return process.stdout.read()


def best_model_row(run_dir: Path) -> tuple[int, int]:
    """(steps of best_model.zip, steps of the first row of evaluations.csv with the best success rate)."""
    rows = read_csv(run_dir / "evaluations.csv")[1]
    best = max(float(row["success_rate"]) for row in rows)
    first = next(int(row["timesteps"]) for row in rows if float(row["success_rate"]) == best)
    return model_timesteps(run_dir / "best_model.zip"), first


def test_a_kill_9_inside_a_checkpoint_write_leaves_the_previous_checkpoint_and_loses_nothing(tmp_path):
    """kill -9 lands inside a checkpoint's write, where a test hook holds the training: once with half of
    the model's zip written to its temporary file, once with all of it written but not yet renamed. Each
    time the previous checkpoint is the newest complete one, byte for byte as it was, and the resume starts
    from it; in the end every rollout and validation has exactly one row, and no temporary file is left."""
    steps = 192  # checkpoints at 64 and 128, and at the end
    run_dir, checkpoints, marker = tmp_path / "killed", tmp_path / "killed" / "checkpoints", tmp_path / "paused"
    train_until_killed(train_tiny(tmp_path, "killed", steps)[1:], "half", 128, marker)
    half = Path(marker.read_text())
    assert half.parent == checkpoints and half.exists() and latest_checkpoint(run_dir, "ppo")[2] == 64
    assert not (checkpoints / "ppo_128_steps.zip").exists()
    before = {name: digest for name, digest in file_digests(checkpoints).items() if "_64_" in name}
    assert {"ppo_64_steps.zip", "ppo_vecnormalize_64_steps.pkl"} <= set(before)

    printed = train_until_killed(["--resume", str(run_dir), "--no-progress", "--no-eval"], "rename", 192, marker)
    assert "at 64 steps" in printed, printed
    whole = Path(marker.read_text())
    assert whole.exists() and model_timesteps(whole) == 192 and latest_checkpoint(run_dir, "ppo")[2] == 128
    assert {name: digest for name, digest in file_digests(checkpoints).items() if "_64_" in name} == before

    done = run("agents.train", "--resume", str(run_dir), "--no-progress", "--no-eval")
    assert "at 128 steps" in done.stdout, done.stdout
    assert steps_column(run_dir / "logs" / "progress.csv", "time/total_timesteps") == list(range(64, steps + 1, 64))
    assert steps_column(run_dir / "evaluations.csv", "timesteps") == list(range(0, steps + 1, 64))
    assert not list(run_dir.glob("**/.*.tmp*"))
    assert model_timesteps(checkpoints / "ppo_64_steps.zip") == 64
    assert best_model_row(run_dir)[0] == best_model_row(run_dir)[1]


def test_a_resume_puts_back_the_best_model_of_its_checkpoint(tiny_run, tmp_path):
    """A validation after the newest checkpoint may have saved best_model.zip before a kill; the resume
    drops that validation's row, so it puts back the best model as it was at the checkpoint: the best model
    is always the first row of evaluations.csv with the best success rate."""
    run_dir = tmp_path / "run"
    subprocess.run(["cp", "-r", str(tiny_run), str(run_dir)], check=True)
    for path in run_dir.glob("checkpoints/*_128_steps.*"):
        path.unlink()  # killed before the checkpoint at 128: the newest is at 64
    snapshot = run_dir / "checkpoints" / "ppo_best_model_64_steps.zip"
    assert snapshot.exists() and model_timesteps(snapshot) <= 64
    (run_dir / "best_model.zip").unlink()
    shutil.copyfile(run_dir / "model.zip", run_dir / "best_model.zip")  # as if the validation at 128 were best
    (run_dir / "model.zip").unlink()
    assert model_timesteps(run_dir / "best_model.zip") == 128
    done = run("agents.train", "--resume", str(run_dir), "--no-progress", "--no-eval")
    assert "best_model.zip put back as it was at 64 steps" in done.stdout, done.stdout
    assert best_model_row(run_dir)[0] == best_model_row(run_dir)[1] <= 64
    # a checkpoint from before these snapshots: a best model saved after it is removed, not kept
    shutil.copyfile(run_dir / "model.zip", run_dir / "best_model.zip")  # 128 steps; no snapshot at 96
    assert restore_best(run_dir, "ppo", 96) == (
        "; removed best_model.zip and best_vecnormalize.pkl (saved after 96 steps)"
    )
    assert not (run_dir / "best_model.zip").exists() and not (run_dir / "best_vecnormalize.pkl").exists()


def test_an_off_policy_run_keeps_the_replay_buffers_of_its_two_newest_checkpoints(tmp_path):
    """A replay buffer is written with every checkpoint (2.3 GB for SAC on pixels): the newest two are kept, an
    older checkpoint keeps its model, and a resume from it says its buffer starts empty."""
    sac = ["--algo", "sac", "--set", "learning_starts=16", "buffer_size=512", "train_freq=1", "gradient_steps=1"]
    tiny = ["n_envs=4", "eval_freq=0", "checkpoint_freq=64", "policy_kwargs.net_arch=[8]", "batch_size=8"]
    command = train_tiny(tmp_path, "sac", 256)
    command = [*command[: command.index("--set")], *sac, "n_timesteps=256", *tiny]
    run(*command)
    folder = tmp_path / "sac" / "checkpoints"
    assert sorted(p.name for p in folder.glob("sac_replay_buffer_*")) == [
        "sac_replay_buffer_192_steps.pkl",
        "sac_replay_buffer_256_steps.pkl",
    ]
    assert {p.name for p in folder.glob("sac_*_steps.zip")} >= {"sac_64_steps.zip", "sac_128_steps.zip"}
    for newer in ("192", "256"):  # damaged: the newest intact checkpoint is one without a buffer
        (folder / f"sac_{newer}_steps.zip").write_bytes(b"cut")
    done = run("agents.train", "--resume", str(tmp_path / "sac"), "--from-steps", "128", "--no-progress", "--no-eval")
    assert "no replay buffer kept with it" in done.stdout, done.stdout
