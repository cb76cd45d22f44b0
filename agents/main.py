"""Train PPO on a task where the landing face counts, evaluate it next to the baselines, print the table.

    box-toss main                   # short PPO run on BoxToss-ThisSideUp-v0 (runs/short), random and oracle
    box-toss main --full --readme   # also the full run and the physics-fidelity evaluations, then rewrite
                                    # docs/methodology/main-command.md, docs/agents/ and the headline figures
                                    # (docs/generated/figures.yml, the README's), in a clone

Everything is evaluated on the same 1,024 fixed test targets (``agents.evaluate``). To train longer,
change ``n_timesteps`` in ``agents/hyperparams/ppo.yml`` and run ``box-toss train``; for every
variant and algorithm, ``python -m agents.benchmark``. (``python -m agents.main`` is the same command.) Every
option, and the configuration of every training the command will run, is checked before anything is created.
"""

from __future__ import annotations

import os
import shlex
import sys
import time
from pathlib import Path
from typing import Any

from agents import train
from agents.command_line import COUNT, RUNS, CommandError, OneLineParser, folder, one_line_errors
from agents.targets import TEST_FIRST_SEED, TEST_TARGETS

PROG = "box-toss main"
DOCS = Path(__file__).resolve().parents[1] / "docs"  # the repository's pages, which --readme rewrites

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


def baseline(algo: str, runs_dir: Path, *, reevaluate: bool = True) -> Path:
    """Evaluate a baseline into ``runs_dir/algo`` (kept if already evaluated and not ``reevaluate``)."""
    from agents import evaluation, report

    run_dir = runs_dir / algo
    if reevaluate or report.read_results(run_dir) is None:
        print(f"evaluating the {algo} baseline on {TEST_TARGETS:,} test targets ...")
        evaluation.make_baseline_run(algo, run_dir, ENV_ID, command=f"python -m agents.baselines {algo} --env {ENV_ID}")
        evaluation.evaluate_run(run_dir, quiet=True)
    return run_dir


def make_parser() -> OneLineParser:
    """The command's options, each checked as it is parsed (its type names its range)."""
    parser = OneLineParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs-dir", type=folder, default=RUNS, help="folder of the run folders (default: runs)")
    parser.add_argument(
        "--timesteps", type=COUNT, default=SHORT_TIMESTEPS, help=f"budget of the short run, {COUNT.allowed}"
    )
    parser.add_argument("--full", action="store_true", help="also train the full run and evaluate physics fidelity")
    parser.add_argument(
        "--readme",
        action="store_true",
        help="with --full, in a clone: rewrite docs/methodology/main-command.md, docs/agents/ and the headline figures",
    )
    parser.add_argument("--no-oracle", action="store_true", help="skip the oracle (it plans for ~20 s)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser


def parse_args(argv: list[str] | None):
    return make_parser().parse_args(argv)


def check_options(args, common: list[str]) -> None:
    """Every option, and the configuration of each training the command runs, checked before anything is made."""
    if args.readme:
        if not args.full or args.no_oracle:
            raise CommandError("--readme needs --full and the oracle")
        if not (DOCS / "index.md").is_file():
            raise CommandError(f"--readme rewrites the repository's pages ({DOCS}): run it in a clone")
        taken = [
            str(args.runs_dir / name) for name in ("short", "full") if (args.runs_dir / name / "config.yml").exists()
        ]
        if taken:
            raise CommandError(f"--readme trains {' and '.join(taken)} afresh: move the existing runs away first")
    train.resolve(train.parse_args([*common, "--set", f"n_timesteps={args.timesteps}"]))
    if args.full:
        train.resolve(train.parse_args(common))
    from agents.run_folder import check_runs_dir

    check_runs_dir(args.runs_dir)


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    runs_dir: Path = args.runs_dir
    progress = ["--no-progress"] if args.no_progress else []
    common = ["--env", ENV_ID, "--runs-dir", str(runs_dir), *progress]
    with one_line_errors(PROG):
        check_options(args, common)
    start = time.perf_counter()
    # the main command's own time, wall and CPU: what runs without --full (random, the short run, the oracle)
    command = Stopwatch()
    with one_line_errors(PROG):
        rows = {"random": baseline("random", runs_dir, reevaluate=args.readme)}
    short = free_name(runs_dir, "short") if not args.readme else "short"
    training = Stopwatch()
    rows["short"] = train.main([*common, "--name", short, "--set", f"n_timesteps={args.timesteps}"])
    training.stop()
    command.stop()
    if args.full:
        rows["full"] = train.main([*common, "--name", free_name(runs_dir, "full") if not args.readme else "full"])
    with one_line_errors(PROG):
        if not args.no_oracle:
            command.start()
            rows["oracle"] = baseline("oracle", runs_dir, reevaluate=args.readme)
            command.stop()
        times = {"command": command.seconds(), "training": training.seconds()}
        report_results(args, rows, argv, start, times)


def report_results(args, rows: dict[str, Path], argv: list[str] | None, start: float, times: dict) -> None:
    """The physics-fidelity evaluations (``--full``), the table, and with ``--readme`` the agents page."""
    from agents import evaluation, report

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
        f"{ENV_ID}: {TEST_TARGETS:,} fixed test targets (seeds {TEST_FIRST_SEED}-"
        f"{TEST_FIRST_SEED + TEST_TARGETS - 1}), deterministic policies"
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
        f"(box-toss evaluate {rows['short']} --video 4 for plots and a GIF; "
        f"tensorboard --logdir {rows['short'] / 'logs'})"
    )
    if args.readme:
        report.write_docs(rows, FIDELITY, times=times, machine=machine_note())
    print(
        f"total wall time {time.perf_counter() - start:.0f} s  "
        f"(command: box-toss main {shlex.join(argv if argv is not None else sys.argv[1:])})"
    )


if __name__ == "__main__":
    main()
