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


HEAVY = ("torch", "stable_baselines3", "numba", "matplotlib", "pygame", "scipy")


@pytest.mark.parametrize("command", ["train", "evaluate", "main"])
def test_help_parses_before_anything_heavy_is_imported_and_names_box_toss(command):
    """``box-toss train --help`` took ~13 s with torch imported before parsing; now nothing heavy is loaded before the
    options are parsed (measured: 0.2 s of CPU), and the usage line names the console command."""
    code = (
        "import sys\n"
        "from box_toss_env import cli\n"
        f"try:\n    cli.main([{command!r}, '--help'])\n"
        "except SystemExit:\n    pass\n"
        f"print('loaded:', sorted(name for name in {HEAVY!r} if name in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"usage: box-toss {command} ") and "loaded: []" in done.stdout, done.stdout


def test_a_subcommand_whose_extra_is_missing_names_the_extra(monkeypatch, capsys):
    import importlib.util

    from box_toss_env import cli

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "pygame" else real(name, *a))
    with pytest.raises(SystemExit) as done:
        cli.main(["view"])
    assert "needs pygame-ce, which the render extra installs: pip install 'box_toss_env[render]'" in str(done.value)


def test_evaluate_video_without_the_render_extra_is_one_line_naming_it(tmp_path, monkeypatch, capsys):
    import importlib.util

    from agents import evaluate
    from agents.evaluation import make_baseline_run

    run_dir = make_baseline_run("random", tmp_path / "random")
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "pygame" else real(name, *a))
    with pytest.raises(SystemExit) as done:
        evaluate.main([str(run_dir), "--video", "4"])
    err = capsys.readouterr().err.strip()
    assert done.value.code == 2 and len(err.splitlines()) == 1, err
    assert "--video needs pygame-ce" in err and "the render extra" in err and "box_toss_env[render]" in err
    assert sorted(p.name for p in run_dir.iterdir()) == ["config.yml"]  # nothing evaluated


def test_bench_outside_a_clone_says_what_it_needs(tmp_path):
    """The benchmarks are the repository's, not the package's: from any other folder, bench says so in one line."""
    done = subprocess.run(
        [*BOX_TOSS, "bench", "engine", "--help"], cwd=tmp_path, capture_output=True, text=True, timeout=120
    )
    assert done.returncode != 0 and "Traceback" not in done.stderr
    assert "the benchmarks are the repository's" in done.stderr and "clone" in done.stderr


def test_throughput_writes_the_docs_only_when_told(monkeypatch):
    """``box-toss bench throughput --quick`` rewrote the tracked docs/throughput.md; now only --readme writes (its
    section and the headline figures). The measurements are replaced by constants: what is tested is where the
    report goes."""
    import benchmarks.throughput as throughput

    written = []
    monkeypatch.setattr(throughput, "single_env_rate", lambda *a: 1.0)
    monkeypatch.setattr(throughput, "vector_rate", lambda *a: 1.0)
    monkeypatch.setattr(throughput.gym, "make_vec", lambda *a, **k: None)
    monkeypatch.setattr(throughput, "toss_per_throw", lambda *a: (1e-5, 1e-6, 1.0, 10))
    monkeypatch.setattr(throughput, "other_engine_rows", lambda *a: [])
    monkeypatch.setattr(throughput, "missing_engines", lambda: [])
    monkeypatch.setattr(throughput, "memory_per_env", lambda: (100.0, 50.0))
    monkeypatch.setattr(throughput, "pixel_cost", lambda *a: (1e-5, 1.5e-5))
    monkeypatch.setattr(throughput, "replace_section", lambda name, *a, **k: written.append(name))
    monkeypatch.setattr(throughput.figures, "update", lambda name, *a, **k: written.append(name))
    monkeypatch.setattr(sys, "argv", ["box-toss bench throughput", "--quick"])
    throughput.main()
    assert written == []
    monkeypatch.setattr(sys, "argv", ["box-toss bench throughput", "--quick", "--readme"])
    throughput.main()
    assert written == ["throughput-pixels", "throughput", "throughput"]
