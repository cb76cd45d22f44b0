"""Train PPO on a task where the landing face counts, evaluate it next to the baselines, print the table.

    python -m agents.main                   # short PPO run on BoxToss-ThisSideUp-v0 (runs/short), random and oracle
    python -m agents.main --full --readme   # also the full run and the physics-fidelity evaluations, then
                                            # rewrite docs/methodology/main-command.md, docs/agents/ and the
                                            # headline figures (docs/generated/figures.yml, the README's)

Everything is evaluated on the same 1,024 fixed test targets (``agents.evaluate``). To train longer,
change ``n_timesteps`` in ``agents/hyperparams/ppo.yml`` and run ``python -m agents.train``; for every
variant and algorithm, ``python -m agents.benchmark``.
"""

from __future__ import annotations

import os
import shlex
import sys
import time
from pathlib import Path
from typing import Any

from agents import evaluation, report, train
from agents.config import OneLineParser
from agents.run_folder import RunFolderError, check_runs_dir
from agents.training import RUNS

ENV_ID = "BoxToss-ThisSideUp-v0"  # one face drawn per episode must end down: the pose counts
SHORT_TIMESTEPS = 500_000  # the default run (about 2 min); the full run uses n_timesteps of agents/hyperparams/ppo.yml
SEED_DT = 1 / 1024  # a step at which the seed scheme keeps its energy at the default stiffness
# (run, tag, env kwargs, label) of the physics-fidelity evaluations
FIDELITY_SETTINGS: list[tuple[str, str, dict[str, Any], str]] = [
    ("full", "robust-dt1024", {"dt": SEED_DT}, "robust solver, dt = 1/1024 s"),
    ("full", "seed-default-dt", {"solver": "seed"}, "seed scheme, the default dt = 1/128 s"),
    ("full", "seed-dt1024", {"solver": "seed", "dt": SEED_DT}, "seed scheme, dt = 1/1024 s"),
    ("oracle", "seed-dt1024", {"solver": "seed", "dt": SEED_DT}, "seed scheme, dt = 1/1024 s"),
]
FIDELITY = [(run, tag, label) for run, tag, _, label in FIDELITY_SETTINGS]


def free_name(runs_dir: Path, name: str) -> str:
    """``name``, or ``name-<time>`` (``-2``, ``-3``, ... after it) if ``runs_dir`` already has that folder."""
    if not (runs_dir / name).exists():
        return name
    stamped = f"{name}-{time.strftime('%Y%m%d-%H%M%S')}"
    return next(
        candidate
        for n in range(1, 10_000)
        if not (runs_dir / (candidate := stamped if n == 1 else f"{stamped}-{n}")).exists()
    )


class Stopwatch:
    """Wall and CPU time (this process's, every thread) over the spans between ``start`` and ``stop``."""

    def __init__(self):
        self.wall = self.cpu = 0.0
        self.start()

    def start(self) -> None:
        self._wall, self._cpu = time.perf_counter(), time.process_time()

    def stop(self) -> None:
        self.wall += time.perf_counter() - self._wall
        self.cpu += time.process_time() - self._cpu

    def seconds(self) -> dict[str, float]:
        return {"wall": self.wall, "cpu": self.cpu}


def machine_note() -> str:
    """Where the figures were measured: the date, the cores and the load at the end (a shared machine)."""
    load = f"load {os.getloadavg()[0]:.1f} at the end, " if hasattr(os, "getloadavg") else ""
    return f"a {os.cpu_count()}-core machine shared with other jobs ({load}{time.strftime('%Y-%m-%d')})"


def baseline(algo: str, runs_dir: Path, *, replan: bool = True) -> Path:
    """Evaluate a baseline into ``runs_dir/algo`` (kept if already evaluated and not ``replan``)."""
    run_dir = runs_dir / algo
    if replan or report.read_results(run_dir) is None:
        print(f"evaluating the {algo} baseline on {evaluation.TEST_TARGETS:,} test targets ...")
        evaluation.make_baseline_run(algo, run_dir, ENV_ID, command=f"python -m agents.baselines {algo} --env {ENV_ID}")
        evaluation.evaluate_run(run_dir, quiet=True)
    return run_dir


def main(argv: list[str] | None = None) -> None:
    parser = OneLineParser(prog="python -m agents.main", description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs-dir", type=Path, default=RUNS)
    parser.add_argument("--timesteps", type=int, default=SHORT_TIMESTEPS, help="budget of the short run")
    parser.add_argument("--full", action="store_true", help="also train the full run and evaluate physics fidelity")
    parser.add_argument(
        "--readme",
        action="store_true",
        help="write the results into the docs (the main command's page and headline figures)",
    )
    parser.add_argument("--no-oracle", action="store_true", help="skip the oracle (it plans for ~20 s)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    if args.timesteps < 1:
        parser.error(f"--timesteps must be an integer >= 1, got {args.timesteps}")
    try:
        check_runs_dir(args.runs_dir)
    except RunFolderError as error:
        parser.error(str(error))
    start = time.perf_counter()
    runs_dir: Path = args.runs_dir
    progress = ["--no-progress"] if args.no_progress else []
    common = ["--env", ENV_ID, "--runs-dir", str(runs_dir), *progress]

    if args.readme:
        if not args.full or args.no_oracle:
            sys.exit("--readme needs --full and the oracle")
        taken = [str(runs_dir / name) for name in ("short", "full") if (runs_dir / name / "config.yml").exists()]
        if taken:
            sys.exit(f"--readme trains {' and '.join(taken)} afresh: move the existing runs away first")
    # the main command's own time, wall and CPU: what runs without --full (random, the short run, the oracle)
    command = Stopwatch()
    rows = {"random": baseline("random", runs_dir)}
    short = free_name(runs_dir, "short") if not args.readme else "short"
    training = Stopwatch()
    rows["short"] = train.main([*common, "--name", short, "--set", f"n_timesteps={args.timesteps}"])
    training.stop()
    command.stop()
    if args.full:
        rows["full"] = train.main([*common, "--name", free_name(runs_dir, "full") if not args.readme else "full"])
    if not args.no_oracle:
        command.start()
        rows["oracle"] = baseline("oracle", runs_dir, replan=args.readme)
        command.stop()
    fidelity = []
    if args.full:
        for name, tag, kwargs, label in FIDELITY_SETTINGS:
            if name in rows:
                print(f"evaluating {name} under {label} ...")
                results = evaluation.evaluate_run(rows[name], env_kwargs=kwargs, tag=tag, quiet=True)
                fidelity.append({"agent": f"{name}: {label}", **results})

    table = [row for name, run in rows.items() if (row := report.summary_row(name, run)) is not None]
    print()
    print(
        f"{ENV_ID}: {evaluation.TEST_TARGETS:,} fixed test targets (seeds {evaluation.TEST_FIRST_SEED}-"
        f"{evaluation.TEST_FIRST_SEED + evaluation.TEST_TARGETS - 1}), deterministic policies"
    )
    print(report.text_table(table))
    if "oracle" in rows:
        print(report.ceiling_note(ENV_ID))
    if fidelity:
        print("\nphysics fidelity (the same targets under another solver or step; failures: throws the env refused)")
        print(evaluation.format_table(fidelity))
    ppo = report.summary_row("short", rows["short"])
    assert ppo is not None  # the run just trained
    print(
        f"\nPPO: the env took {ppo['env_share']:.0%} of the training loop's wall time; the run is in {rows['short']} "
        f"(python -m agents.evaluate {rows['short']} --video 4 for plots and a GIF; "
        f"tensorboard --logdir {rows['short'] / 'logs'})"
    )
    if args.readme:
        times = {"command": command.seconds(), "training": training.seconds()}
        report.write_docs(rows, FIDELITY, times=times, machine=machine_note())
    print(
        f"total wall time {time.perf_counter() - start:.0f} s  "
        f"(command: python -m agents.main {shlex.join(argv if argv is not None else sys.argv[1:])})"
    )


if __name__ == "__main__":
    main()
