"""How long CI takes: ``bash .ci/run`` in a fresh clone of this checkout's HEAD (with ``../shared`` beside
it, as CI has it), timed step by step. Prints measured figures; asserts nothing.

    python -m benchmarks.ci_time [--write-docs]

The clone gets fresh virtual environments (``.ci/run`` makes them; pip's own cache is used as CI's is) and an
empty numba cache (nothing is compiled in a fresh clone). Each line of ``.ci/run`` is timed by bash itself
(``set -x``, ``PS4`` stamping every command with ``EPOCHREALTIME``); the CPU time is that of every process
``.ci/run`` waited for (``getrusage``). The load average before and after says how busy the machine was: the goal
(issue 42) is 15 minutes on an idle 2-core machine.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from agents.doc_sections import replace_section

REPO = Path(__file__).resolve().parent.parent
CONTRIBUTING = REPO / "CONTRIBUTING.md"
GOAL_MINUTES = 15.0
TRACED = "PS4='+ ${EPOCHREALTIME} '; set -x; . .ci/run"  # (bash takes no PS4 from the environment as root)


def clone(folder: Path, shared: Path) -> Path:
    """A clone of this checkout's HEAD in ``folder``/repo, with ``folder``/shared linked to ``shared``."""
    subprocess.run(["git", "clone", "-q", str(REPO), str(folder / "repo")], check=True)
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO, capture_output=True, text=True, check=True)
    subprocess.run(["git", "checkout", "-q", head.stdout.strip()], cwd=folder / "repo", check=True)
    if shared.exists():
        (folder / "shared").symlink_to(shared.resolve())
    return folder / "repo"


def steps(trace: str, end: float) -> list[tuple[str, float]]:
    """(command, seconds) of each command of ``.ci/run`` in the trace of ``TRACED`` (it sources ``.ci/run``, whose
    commands are traced as ``++ STAMP command``; what they expand in subshells as ``+++ ...``)."""
    starts = []
    for line in trace.splitlines():
        if line.startswith("++ "):
            stamp, _, command = line[3:].partition(" ")
            try:
                starts.append((float(stamp), command))
            except ValueError:
                continue
    return [
        (command, (starts[i + 1][0] if i + 1 < len(starts) else end) - stamp)
        for i, (stamp, command) in enumerate(starts)
    ]


def run_ci(repo: Path) -> dict:
    """Run ``.ci/run`` in ``repo``; its steps, wall and CPU time, exit code and the load before and after."""
    env = {key: value for key, value in os.environ.items() if key not in ("NUMBA_CACHE_DIR", "VIRTUAL_ENV")}
    load = os.getloadavg()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.time()
    done = subprocess.run(
        ["bash", "-c", TRACED, ".ci/run"], cwd=repo, env=env, capture_output=True, text=True, check=False
    )
    end = time.time()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    return {
        "steps": steps(done.stderr, end),
        "seconds": end - start,
        "cpu": cpu,
        "returncode": done.returncode,
        "load_before": load,
        "load_after": os.getloadavg(),
        "tail": done.stdout[-3000:] + done.stderr[-3000:],
    }


def report(result: dict, commit: str) -> str:
    minutes = result["seconds"] / 60
    verdict = "passed" if result["returncode"] == 0 else f"FAILED (exit code {result['returncode']})"
    lines = [
        f"commit {commit}, {os.cpu_count()} cores, load average {'/'.join(f'{v:.1f}' for v in result['load_before'])} "
        f"before, {'/'.join(f'{v:.1f}' for v in result['load_after'])} after (1/5/15 min)",
        f".ci/run {verdict}: {minutes:.1f} min of wall time (goal: {GOAL_MINUTES:g} on an idle machine), "
        f"{result['cpu'] / 60:.1f} min of CPU",
        "",
        f"{'step':70} {'min':>6}",
    ]
    for command, seconds in result["steps"]:
        if seconds >= 1.0:
            lines.append(f"{command[:70]:70} {seconds / 60:>6.2f}")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--write-docs", action="store_true", help="also write the figures into CONTRIBUTING.md")
    parser.add_argument(
        "--shared",
        type=Path,
        default=REPO.parent / "shared",
        help="the data folder CI has beside the clone (default: ../shared; tests skip without it)",
    )
    args = parser.parse_args()
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True, check=True
    ).stdout.strip()
    with tempfile.TemporaryDirectory(prefix="box_toss_ci_time_") as folder:
        result = run_ci(clone(Path(folder), args.shared))
    text = report(result, commit)
    print(f"$ python -m benchmarks.ci_time\n{text}")
    if result["returncode"] != 0:
        print(result["tail"], file=sys.stderr)
    if args.write_docs:
        replace_section("ci-time", f"```text\n$ python -m benchmarks.ci_time\n{text}\n```", CONTRIBUTING)


if __name__ == "__main__":
    main()
