"""First use: how soon a fresh process throws, and how fast it throws in its first minute, for every
registered id, with numba's cache empty and with the cache an earlier process of the same id left.
Prints measured figures; asserts nothing.

    python -m benchmarks.cold_start [--ids ID ...] [--seconds 60] [--window 5] [--install editable|wheel]
                                    [--write-docs]

Each case is an id made either by ``gym.make`` (one env) or by ``gym.make_vec`` (the batch of ``VECTOR_ENVS``),
run twice in fresh interpreters whose working folder is an empty temporary directory, with
``NUMBA_CACHE_DIR`` pointing at a fresh temporary directory:

- **empty**: the cache empty. The env's first throws run its kernel's interpreted copy while a worker
  process compiles the kernel (``box_toss_env.physics.compile.background_compile``); the process throws on
  for ``--seconds`` (then waits for the worker, so that the cache is whole);
- **warm**: the same cache, which the empty run's worker filled, in a new process.

Per run: the first throw [s] (wall time from before ``gym.make`` to the end of the first ``step``, the
package imported already; the import is its own column), the interpreter's CPU time to that point, the
numba compilations in the process (none is expected: a cold kernel compiles in the worker, a warm one is
loaded), whether the first throw ran interpreted, the throughput in each ``--window``-second window from
the end of the first throw for ``--seconds`` [throws/s], and the moment the last interpreted throw ended.
The worker's compile time comes from its log (``box_toss_env-compile.log`` in the cache). The compiled
throughput an id is held to is the median window of its warm run. A single env throws once an episode
(``reset`` + ``step``; ``BoxToss-Stack-v0`` resets when its episode ends); a batched one steps its batch
(every env throws, autoreset).

Goals (issue 42): a warm process's first throw within 1 s of ``gym.make`` and its first window at 90% or
more of the compiled throughput; an empty cache's first throw within 3 s. Timings are wall times on a
shared machine: the load average is printed beside each row.

``--install wheel`` measures the package built as a wheel (``pip wheel``) and installed into a temporary
folder, instead of this checkout; ``--pythonpath DIR`` measures the package found in DIR.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import gymnasium as gym

import box_toss_env  # noqa: F401  (registers the ids)
from agents.doc_sections import replace_section

REPO = Path(__file__).resolve().parent.parent
IDS = tuple(env_id for env_id in gym.registry if env_id.startswith("BoxToss-"))
"""Every registered id, in the order the package registers them."""
VECTOR_ENVS = {"BoxToss-OnBox-v0": 8, "BoxToss-Stack-v0": 8, "BoxToss-Goal-v0": 8}  # the others: 64
"""The batch ``make_vec`` is measured with: 64 envs, or 8 where a throw lands on boxes (a colliding throw run
interpreted costs ~30 floor-only ones, and 64 of them in a step would take seconds: a batch runs interpreted in
calls of ``physics.grouped.MAX_INTERPRETED_GROUPED_BODIES`` bodies) and for the goal env (Gymnasium's
``SyncVectorEnv`` of single envs: it has no batched env of its own)."""
FIRST_THROW_EMPTY, FIRST_THROW_WARM, FIRST_WINDOW_SHARE = 3.0, 1.0, 0.9

PROBE = textwrap.dedent("""
    import json, os, sys, time
    env_id, num_envs, seconds, window = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
    cpu_start, wall_start = time.process_time(), time.perf_counter()
    import gymnasium as gym
    import numpy as np
    import box_toss_env
    from numba.core import event
    from box_toss_env.physics.compile import background_compile
    imported = time.perf_counter() - wall_start
    interpreted = {"runs": 0, "last": None}
    original_run = background_compile.InterpretedStart.run

    def counted_run(self, args, outputs):  # counts the runs of interpreted copies
        ran = original_run(self, args, outputs)
        if ran:
            interpreted["runs"] += 1
            interpreted["last"] = time.perf_counter()
        return ran

    background_compile.InterpretedStart.run = counted_run
    recording = event.install_recorder("numba:compile")
    recorder = recording.__enter__()
    made = time.perf_counter()
    env = gym.make_vec(env_id, num_envs=num_envs) if num_envs else gym.make(env_id)
    env.action_space.seed(0)
    env.reset(seed=0)
    _, _, terminated, truncated, _ = env.step(env.action_space.sample())
    first = time.perf_counter()
    result = {"first_throw": first - made, "import": imported, "cpu": time.process_time() - cpu_start,
              "compiled_here": sum(1 for _, e in recorder.buffer if e.is_start),
              "first_interpreted": interpreted["runs"] > 0, "package": box_toss_env.__file__}
    windows, cpu_windows, interpreted_windows = [], [], []
    end, count, runs, cpu = first + window, 0, interpreted["runs"], time.process_time()
    while len(windows) < round(seconds / window):
        if not num_envs and np.any(terminated | truncated):
            env.reset()
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        count += max(num_envs, 1)
        now = time.perf_counter()
        if now >= end:
            windows.append(count / (now - end + window))
            cpu_windows.append(count / (time.process_time() - cpu))
            interpreted_windows.append(interpreted["runs"] > runs)
            end, count, runs, cpu = now + window, 0, interpreted["runs"], time.process_time()
    last = interpreted["last"]
    result.update(windows=windows, cpu_windows=cpu_windows, interpreted_windows=interpreted_windows,
                  compiled_after=None if last is None else last - made, load=os.getloadavg()[0])
    background_compile.wait_for_workers()  # the worker's kernel in the cache before the warm run
    print(json.dumps(result))
""")


def run_probe(env_id: str, num_envs: int, cache: str, pythonpath: str, seconds: float, window: float) -> dict:
    """One run in a fresh interpreter (working folder: a new empty directory)."""
    env = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "NUMBA_DISABLE_JIT")}
    env.update(NUMBA_CACHE_DIR=cache, PYTHONPATH=pythonpath, BOX_TOSS_ENV_START_INTERPRETED="1")
    with tempfile.TemporaryDirectory(prefix="box_toss_cold_start_cwd_") as folder:
        done = subprocess.run(
            [sys.executable, "-c", PROBE, env_id, str(num_envs), str(seconds), str(window)],
            env=env,
            capture_output=True,
            text=True,
            check=False,
            cwd=folder,
            timeout=seconds + 1800,
        )
    if done.returncode != 0:
        raise RuntimeError(f"{env_id} (num_envs {num_envs}) failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def env_load() -> float:
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


def worker_compiles(cache: str) -> list[tuple[str, float]]:
    """(kernel, CPU seconds) of every compile the workers logged in ``cache``."""
    found = []
    for log in sorted(Path(cache).rglob("box_toss_env-compile.log")):
        for line in log.read_text().splitlines():
            if ": compiled " in line and " s of CPU)" in line:
                kernel = line.split(": compiled ", 1)[1].rsplit(" in ", 1)[0]
                found.append((kernel, float(line.rsplit("(", 1)[1].split(" s of CPU")[0])))
    return found


def measure(ids, pythonpath: str, seconds: float, window: float, log=print) -> list[dict]:
    """Per id and mode (single, batched), the empty-cache and the warm run, each in a fresh cache."""
    cases = []
    for env_id in ids:
        for num_envs in (0, VECTOR_ENVS.get(env_id, 64)):
            with tempfile.TemporaryDirectory(prefix="box_toss_cold_start_cache_") as cache:
                load = env_load()
                empty = run_probe(env_id, num_envs, cache, pythonpath, seconds, window)
                compiles = worker_compiles(cache)
                warm = run_probe(env_id, num_envs, cache, pythonpath, seconds, window)
            case = {"id": env_id, "num_envs": num_envs, "empty": empty, "warm": warm, "worker": compiles, "load": load}
            cases.append(case)
            log(
                f"  {env_id} {num_envs or 'single'}: empty {empty['first_throw']:.2f} s, warm "
                f"{warm['first_throw']:.2f} s, worker {sum(c for _, c in compiles):.1f} s of CPU (load {load:.1f})"
            )
    return cases


def first_window_share(run: dict, key: str = "cpu_windows") -> float:
    """The first window's throughput over the median window's (of the same run): per second of the process's
    CPU (``cpu_windows``: what a busy machine does not change) or of wall time (``windows``)."""
    windows = run[key]
    return windows[0] / statistics.median(windows) if windows else float("nan")


def report(cases: list[dict], seconds: float, window: float) -> str:
    import numba

    lines = [
        f"numba {numba.__version__}, {os.cpu_count()} cores, a shared machine: load = the 1-minute load average "
        "before the case",
        "first [s]: from gym.make to the end of the first step (the package imported), wall; cpu [s]: the "
        "interpreter's CPU to that point, import included; interp: the first throw ran interpreted; compiled after "
        "[s]: the end of the last interpreted throw; worker [s]: CPU of the background compile (its log); "
        "compiles: numba compilations in the warm process; first window: the throughput of the first "
        f"{window:g} s after the first throw over the run's median {window:g}-s window, per second of the "
        "process's CPU (per second of wall time in brackets); compiled: the warm run's median window [throws "
        "per second of wall time]",
        f"goals: empty first <= {FIRST_THROW_EMPTY:g} s; warm first <= {FIRST_THROW_WARM:g} s, warm first window "
        f">= {FIRST_WINDOW_SHARE:.0%}",
        "",
        f"{'id':22} {'envs':>4} | {'empty: first':>12} {'cpu':>5} {'interp':>6} {'compiled after':>14} "
        f"{'worker':>6} | {'warm: first':>11} {'cpu':>5} {'compiles':>8} {'first window':>13} {'compiled':>9} | "
        f"{'load':>4}",
    ]
    for case in cases:
        empty, warm = case["empty"], case["warm"]
        after = "-" if empty["compiled_after"] is None else f"{empty['compiled_after']:.1f}"
        compiled = statistics.median(warm["windows"]) if warm["windows"] else float("nan")
        share = f"{first_window_share(warm):.0%} ({first_window_share(warm, 'windows'):.0%})"
        lines.append(
            f"{case['id']:22} {case['num_envs'] or 1:>4} | {empty['first_throw']:>12.2f} {empty['cpu']:>5.2f} "
            f"{'yes' if empty['first_interpreted'] else 'no':>6} {after:>14} "
            f"{sum(c for _, c in case['worker']):>6.1f} | {warm['first_throw']:>11.2f} {warm['cpu']:>5.2f} "
            f"{warm['compiled_here']:>8} {share:>13} {compiled:>9.0f} | {case['load']:>4.1f}"
        )
    return "\n".join(lines + window_lines(cases, seconds, window) + compile_lines(cases))


def window_lines(cases: list[dict], seconds: float, window: float) -> list[str]:
    lines = [
        "",
        f"throughput in each {window:g}-s window for {seconds:g} s [throws per second of wall time] (*: a "
        "window with interpreted throws)",
    ]
    for case in cases:
        for state in ("empty", "warm"):
            run = case[state]
            cells = " ".join(
                f"{w:.0f}{'*' if i else ''}" for w, i in zip(run["windows"], run["interpreted_windows"], strict=True)
            )
            lines.append(f"{case['id']:22} {case['num_envs'] or 1:>4} {state:5}: {cells}")
    return lines


def compile_lines(cases: list[dict]) -> list[str]:
    kernels: dict[str, list[float]] = {}
    for case in cases:
        for kernel, cpu in case["worker"]:
            kernels.setdefault(kernel, []).append(cpu)
    lines = ["", "background compiles in the empty runs [s of CPU, min-max over the runs that compiled the kernel]"]
    return lines + [f"{min(cpus):5.1f}-{max(cpus):5.1f} ({len(cpus)}x) {kernel}" for kernel, cpus in kernels.items()]


def wheel_install(folder: Path) -> str:
    """Build this checkout's wheel and install it (without dependencies: the running environment has
    them) into ``folder``; returns the folder to put on PYTHONPATH."""
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(folder / "wheel"), str(REPO)], check=True
    )
    wheel = next((folder / "wheel").glob("box_toss_env-*.whl"))
    site = folder / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(site), str(wheel)], check=True
    )
    return str(site)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ids", nargs="+", choices=IDS, default=list(IDS))
    parser.add_argument("--seconds", type=float, default=60.0, help="how long each run throws (default 60)")
    parser.add_argument("--window", type=float, default=5.0, help="throughput window [s] (default 5)")
    parser.add_argument(
        "--install",
        choices=("editable", "wheel"),
        default="editable",
        help="this checkout as it is, or built into a wheel and installed in a temporary folder",
    )
    parser.add_argument("--pythonpath", default=None, help="measure the box_toss_env found in DIR instead")
    parser.add_argument(
        "--write-docs",
        "--readme",
        dest="write_docs",
        action="store_true",
        help="also write the figures into docs/cold-start.md",
    )
    args = parser.parse_args()
    if args.seconds < args.window or args.window <= 0:
        parser.error(f"--window must be > 0 and at most --seconds, got {args.window} and {args.seconds}")
    with tempfile.TemporaryDirectory(prefix="box_toss_cold_start_wheel_") as folder:
        pythonpath = args.pythonpath or (wheel_install(Path(folder)) if args.install == "wheel" else str(REPO))
        cases = measure(args.ids, pythonpath, args.seconds, args.window)
    package = cases[0]["empty"]["package"]
    command = "python -m benchmarks.cold_start" + (" --install wheel" if args.install == "wheel" else "")
    text = report(cases, args.seconds, args.window)
    print(f"\n$ {command}  (package: {package})\n{text}")
    if args.write_docs:
        replace_section("cold-start", f"```text\n$ {command}\n{text}\n```")


if __name__ == "__main__":
    main()
