"""The package installs: ``python -m build`` makes a wheel and an sdist that ``twine check`` accepts, and the wheel
alone, installed in a fresh venv, runs ``box-toss train`` with a tiny budget and ``box-toss evaluate`` from an empty
folder (no repository on the path: what the subcommands need is in the wheel).

The fresh venv gets the wheel only (``pip install --no-deps``); its dependencies come from this test environment's
site-packages, added to the venv's path by a ``.pth`` line. A path line adds the folder without processing the
``.pth`` files in it, so the editable install of the repository that the test environment holds is not active there:
``box_toss_env`` and ``agents`` are imported from the wheel (the test checks it).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SOURCES = ("pyproject.toml", "README.md", "LICENSE", "box_toss_env", "agents")
TINY = ["n_timesteps=64", "n_envs=8", "n_steps=8", "batch_size=16", "eval_freq=0", "checkpoint_freq=0"]


def run(*command: str | Path, cwd: Path = REPO) -> subprocess.CompletedProcess:
    """``command`` in ``cwd``, as a user runs it: without the test suite's switch that makes the engine compile
    before the first throw (tests/conftest.py), so the fresh install starts as a user's does."""
    env = {key: value for key, value in os.environ.items() if key != "BOX_TOSS_ENV_START_INTERPRETED"}
    done = subprocess.run(
        [str(part) for part in command], cwd=cwd, capture_output=True, text=True, timeout=600, env=env
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done


def build(tmp_path: Path) -> tuple[Path, Path]:
    """The wheel and the sdist, built from a copy of the package's sources (the repository is left untouched)."""
    source = tmp_path / "source"
    source.mkdir()
    caches = shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc", "*.egg-info")
    for name in SOURCES:
        path = REPO / name
        (shutil.copytree(path, source / name, ignore=caches) if path.is_dir() else shutil.copy(path, source / name))
    run(sys.executable, "-m", "build", "--no-isolation", "--outdir", tmp_path / "dist", source)
    wheel, sdist = sorted((tmp_path / "dist").glob("*.whl")), sorted((tmp_path / "dist").glob("*.tar.gz"))
    assert len(wheel) == 1 and len(sdist) == 1
    run(sys.executable, "-m", "twine", "check", "--strict", wheel[0], sdist[0])
    return wheel[0], sdist[0]


def fresh_venv(tmp_path: Path, wheel: Path) -> Path:
    """A venv holding the wheel alone, with this environment's site-packages behind it; its bin folder."""
    venv = tmp_path / "venv"
    run(sys.executable, "-m", "venv", "--without-pip", venv)
    python = venv / "bin" / "python"
    run(sys.executable, "-m", "pip", "--python", python, "install", "--no-deps", "--no-index", "-q", wheel)
    site = run(python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])").stdout.strip()
    outer = dict.fromkeys([sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]])
    Path(site, "test_environment.pth").write_text("\n".join(outer) + "\n")
    return venv / "bin"


def test_the_wheel_alone_trains_and_evaluates_from_an_empty_folder(tmp_path):
    wheel, _ = build(tmp_path)
    names = set(zipfile.ZipFile(wheel).namelist())
    assert {"agents/hyperparams/ppo.yml", "agents/hyperparams/raw/ppo.yml", "agents/train.py"} <= names
    assert {"box_toss_env/cli.py", "box_toss_env/envs/goal_vector.py"} <= names
    assert not any(name.startswith(("tests/", "benchmarks/", "reports/", "docs/")) for name in names)
    bin_dir = fresh_venv(tmp_path, wheel)
    empty = tmp_path / "empty"
    empty.mkdir()
    imports = "import agents, box_toss_env; print(agents.__file__, box_toss_env.__file__)"
    where = run(bin_dir / "python", "-c", imports, cwd=empty)
    assert str(REPO) not in where.stdout and str(tmp_path / "venv") in where.stdout, where.stdout
    trained = run(
        bin_dir / "box-toss", "train", "--name", "tiny", "--no-progress", "--no-eval", "--set", *TINY, cwd=empty
    )
    assert "trained 64 steps" in trained.stdout
    evaluated = run(bin_dir / "box-toss", "evaluate", "runs/tiny", "--targets", "8", "--no-plots", cwd=empty)
    assert "results in runs/tiny/eval/targets=8" in evaluated.stdout
    assert sorted(path.name for path in empty.iterdir()) == ["runs"]
