"""The first reset of a big native batched env: ``gymnasium.make_vec("BoxToss-v0", num_envs=N)`` then
``reset(seed=0)``, each measured in a fresh process. Prints measured figures; asserts nothing.

    python -m benchmarks.vector_reset [--envs 1000000] [--repeats 3] [--readme]

Each repeat runs in a new Python process (what a user's first reset is), which first resets a
5,000-env batch so that numba's one-time start and the loading of the compiled kernels from its cache
(about a second, whatever the batch) are measured apart. Reported per stage, in seconds: wall time,
and the process's CPU time split into user time (the computation) and system time (mostly the
kernel handing the batch's fresh memory to the process at its first touch). On a machine shared with
other work the wall time is above the CPU time; the CPU time is what the code costs. The seeding of
every env's stream alone (``RandomStreams.seed_all``) is timed too, against numpy's own seeding
(``np.random.Generator(PCG64(SeedSequence(seed)))``, one per env, as before) on a sample of envs.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

from agents.doc_sections import replace_section

ONE_RUN = r"""
import json, os, sys, time
import numpy as np
import gymnasium as gym
import box_toss_env  # noqa: F401
from box_toss_env.envs.random_streams import RandomStreams, check_seeds
from gymnasium.utils import seeding

n = int(sys.argv[1])
figures = {}

def timed(name, function):
    start, times = time.perf_counter(), os.times()
    result = function()
    end = os.times()
    figures[name] = {"wall": time.perf_counter() - start, "user": end.user - times.user,
                     "system": end.system - times.system}
    return result

warm = timed("numba start and kernels (5,000 envs)", lambda: gym.make_vec(
    "BoxToss-v0", num_envs=5000, vectorization_mode="vector_entry_point").reset(seed=0))
envs = timed("make_vec", lambda: gym.make_vec("BoxToss-v0", num_envs=n, vectorization_mode="vector_entry_point"))
timed("first reset(seed=0)", lambda: envs.reset(seed=0))
timed("second reset(seed=0)", lambda: envs.reset(seed=0))
streams = RandomStreams(n)
timed("seeding alone (seed_all)", lambda: streams.seed_all(check_seeds(0, n)))
sample = 20000
timed("numpy, one Generator per env (per env)", lambda: [seeding.np_random(seed) for seed in range(sample)])
figures["numpy, one Generator per env (per env)"] = {
    key: value / sample for key, value in figures["numpy, one Generator per env (per env)"].items()}
print(json.dumps(figures))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--envs", type=int, default=10**6, help="envs in the batch (default 1,000,000)")
    parser.add_argument("--repeats", type=int, default=3, help="fresh processes (default 3)")
    parser.add_argument("--readme", action="store_true", help="also write the methodology page")
    args = parser.parse_args()
    if args.envs < 1:
        parser.error(f"--envs must be >= 1, got {args.envs}")
    if args.repeats < 1:
        parser.error(f"--repeats must be >= 1, got {args.repeats}")
    runs = []
    for _ in range(args.repeats):
        done = subprocess.run(
            [sys.executable, "-c", ONE_RUN, str(args.envs)], capture_output=True, text=True, check=False
        )
        if done.returncode != 0:
            sys.exit(f"the measuring process failed:\n{done.stderr}")
        runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    lines = [
        f"Measured by `python -m benchmarks.vector_reset` on {os.cpu_count()} cores: "
        f'`make_vec("BoxToss-v0", num_envs={args.envs:,})` and its resets in {args.repeats} fresh processes, '
        f"median [min-max] seconds; load average {load} at the end (a shared machine: wall time above CPU time "
        "is other jobs' share of the cores).",
        "",
        "| stage | wall | CPU, user | CPU, system |",
        "|---|---:|---:|---:|",
    ]
    for stage in runs[0]:
        cells = []
        for key in ("wall", "user", "system"):
            values = [run[stage][key] for run in runs]
            scale, unit = (1e6, " us") if "per env" in stage else (1.0, "")
            cells.append(
                f"{statistics.median(values) * scale:.2f} [{min(values) * scale:.2f}-{max(values) * scale:.2f}]{unit}"
            )
        lines.append(f"| {stage} | {' | '.join(cells)} |")
    report = "\n".join(lines)
    print(report)
    if args.readme:
        replace_section("vector-reset", report)


if __name__ == "__main__":
    main()
