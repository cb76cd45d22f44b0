"""The ``box-toss`` console command dispatches to the modules, whose ``--help`` lists every option."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
# the installed console script if this environment has it, else the same entry point through python -m
BOX_TOSS = [shutil.which("box-toss")] if shutil.which("box-toss") else [sys.executable, "-m", "box_toss_env.cli"]


def box_toss(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([*BOX_TOSS, *args], cwd=REPO, capture_output=True, text=True, timeout=300)


def test_help_lists_the_subcommands_and_benchmarks():
    done = box_toss("--help")
    assert done.returncode == 0, done.stderr
    for word in ("train", "evaluate", "view", "bench", "main", "engine", "throughput", "cold_start"):
        assert word in done.stdout


@pytest.mark.parametrize(
    ("args", "options"),
    [
        (["train", "--help"], ["--algo", "--env", "--set", "--resume"]),
        (["evaluate", "--help"], ["--video", "--env-kwargs"]),
        (["bench", "engine", "--help"], ["--readme"]),
    ],
)
def test_subcommand_help_is_the_module_help(args, options):
    done = box_toss(*args)
    assert done.returncode == 0, done.stderr[-2000:]
    for option in options:
        assert option in done.stdout


def test_unknown_subcommand_fails_naming_it():
    done = box_toss("fly")
    assert done.returncode != 0 and "fly" in done.stderr
