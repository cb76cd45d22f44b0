"""Cold start: how long the first throw takes in a fresh interpreter, with numba's cache empty (cold)
and filled by the run before (warm). Prints measured figures; asserts nothing.

    python -m benchmarks.cold_start [--repeats 3] [--readme]

Each case runs in a fresh interpreter with ``NUMBA_CACHE_DIR`` pointing at a fresh temporary
directory: the cold run, then the warm run in the same directory. Times are wall times [s]:

- ``gym.make`` and ``make_vec``: from ``import gymnasium, box_toss_env`` to the end of the first
  ``step`` (making the env, ``reset`` and one throw); ``make_vec`` once more with the cache holding what
  a ``gym.make`` run compiled (does the batched env reuse the single env's kernel?);
- the same for ``BoxToss-OnBox-v0`` (its colliding kernel; batched: 8 envs, the most that start
  interpreted);
- SB3 ``SubprocVecEnv`` with 4 workers: from creating it (Stable-Baselines3, torch and the package are
  imported in the parent already) to the end of its first ``step``, each worker importing the
  package and throwing once. The same with CartPole-v1 is what SB3's workers cost by themselves
  (each starts and imports SB3 and torch).

On a cold cache the envs throw with the kernel's interpreted copy while a worker process compiles it
(``box_toss_env.physics.compile.background_compile``); each case then throws on until every env runs the
compiled kernel, and that moment is reported too ("compiled after"). The warm run starts once the
cold run's compile workers are done.

``--pythonpath DIR`` measures the package found in DIR instead (e.g. an older checkout).
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

from agents.doc_sections import replace_section

REPO = Path(__file__).resolve().parent.parent

PROBE = textwrap.dedent("""
    import json, sys, time
    case = sys.argv[1]
    start, start_cpu = time.perf_counter(), time.process_time()
    import numba  # timed on its own: the package imports it anyway
    numba_import = time.process_time() - start_cpu
    import gymnasium as gym
    import box_toss_env
    try:
        from box_toss_env.physics.compile.background_compile import wait_for_workers
    except ImportError:  # a checkout from before the interpreted start
        def wait_for_workers():
            pass
    compiled = cpu = None
    if case == "subproc":
        import numpy as np
        from stable_baselines3.common.vec_env import SubprocVecEnv

        class Probe(gym.Wrapper):
            def kernel_interpreted(self):  # whether this worker's last throw ran the interpreted kernel
                return bool(getattr(self.env.unwrapped._simulator, "interpreted", False))

            def wait_for_workers(self):
                wait_for_workers()

        start = time.perf_counter()
        envs = SubprocVecEnv([lambda: Probe(gym.make("box_toss_env:BoxToss-v0"))] * 4)
        envs.reset()
        action = np.zeros((4, 3), dtype=np.float32)
        envs.step(action)
        seconds = time.perf_counter() - start
        while any(envs.env_method("kernel_interpreted")):
            envs.step(action)
        compiled_after = time.perf_counter() - start
        envs.env_method("wait_for_workers")
        envs.close()
    elif case == "subproc_cartpole":
        import numpy as np
        from stable_baselines3.common.vec_env import SubprocVecEnv

        start = time.perf_counter()
        envs = SubprocVecEnv([lambda: gym.make("CartPole-v1")] * 4)
        envs.reset()
        envs.step(np.zeros(4, dtype=np.int64))
        seconds = compiled_after = time.perf_counter() - start
        envs.close()
    else:
        from numba.core import event
        env_id, num_envs = {"make": ("BoxToss-v0", 0), "make_vec": ("BoxToss-v0", 64),
                            "make_on_box": ("BoxToss-OnBox-v0", 0), "make_vec_on_box": ("BoxToss-OnBox-v0", 8)}[case]
        with event.install_recorder("numba:compile") as recorder:
            env = gym.make_vec(env_id, num_envs=num_envs) if num_envs else gym.make(env_id)
            env.reset(seed=0)
            env.step(env.action_space.sample())
        seconds, cpu = time.perf_counter() - start, time.process_time() - start_cpu
        compiled = sum(1 for _, e in recorder.buffer if e.is_start)  # numba compilations here (loads not counted)
        simulator = env.unwrapped.simulator if num_envs else env.unwrapped._simulator
        while getattr(simulator, "interpreted", False):  # throwing on, as a training loop would
            env.reset()
            env.step(env.action_space.sample())
        compiled_after = time.perf_counter() - start
        wait_for_workers()  # a worker still compiling other kernels (none expected) finishes before the warm run
    print(json.dumps({"seconds": seconds, "cpu": cpu, "compiled": compiled, "numba_import": numba_import,
                      "compiled_after": compiled_after, "package": box_toss_env.__file__}))
""")

CASES = {
    "make": 'gym.make("BoxToss-v0")',
    "make_vec": 'make_vec("BoxToss-v0", num_envs=64)',
    "make_vec_after_make": "make_vec(64) after a gym.make throw",
    "make_on_box": 'gym.make("BoxToss-OnBox-v0")',
    "make_vec_on_box": 'make_vec("BoxToss-OnBox-v0", num_envs=8)',
    "subproc": "SB3 SubprocVecEnv, 4 workers",
    "subproc_cartpole": "the same with CartPole-v1 (SB3's own start)",
}


def run_case(case: str, cache: str, pythonpath: str) -> dict:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, "PYTHONPATH": pythonpath, "BOX_TOSS_ENV_START_INTERPRETED": "1"}
    done = subprocess.run(
        [sys.executable, "-c", PROBE, case],
        env=env,
        capture_output=True,
        text=True,
        check=False,
        cwd=tempfile.gettempdir(),
        timeout=1800,
    )
    if done.returncode != 0:
        raise RuntimeError(f"case {case} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def measure(repeats: int, pythonpath: str, cases: list[str], log=print) -> dict[str, dict[str, list]]:
    """Per case, the cold and the warm runs' results, ``repeats`` of each (a fresh cache per repeat)."""
    results = {case: {"cold": [], "warm": []} for case in cases}
    for repeat in range(repeats):
        for case in cases:
            with tempfile.TemporaryDirectory(prefix="box_toss_cold_start_") as cache:
                if case == "make_vec_after_make":  # "cold": only the single env's throw is cached
                    run_case("make", cache, pythonpath)
                for state in ("cold", "warm"):
                    result = run_case("make_vec" if case == "make_vec_after_make" else case, cache, pythonpath)
                    results[case][state].append(result)
                    log(f"  repeat {repeat + 1}/{repeats} {case:8} {state}: {result['seconds']:.2f} s")
    return results


def summary(values: list[float]) -> str:
    """Median and range of ``values``."""
    if len(values) == 1:
        return f"{values[0]:.2f}"
    return f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})"


def report(results: dict[str, dict[str, list]], repeats: int) -> str:
    import numba

    load = ", ".join(f"{value:.1f}" for value in os.getloadavg()) if hasattr(os, "getloadavg") else "n/a"
    lines = [
        f"numba {numba.__version__}, {os.cpu_count()} cores (load average {load} at the end: a shared machine)",
        f"first throw in a fresh interpreter: wall time [s], median of {repeats} (min-max), and the interpreter's "
        "CPU time [s], median",
        "cold: NUMBA_CACHE_DIR empty; warm: filled by the cold run; compiled after: when "
        "the throws (going on) ran the compiled kernel, not its interpreted copy, in the cold run [s], median; "
        "compilations: numba compilations in the measured process in the cold run",
        "",
        f"{'case':44} {'cold':>19} {'cpu':>5} {'warm':>17} {'cpu':>5} {'compiled after':>15} {'compilations':>13}",
    ]
    for case, runs in results.items():
        cells = []
        for state in ("cold", "warm"):
            cells.append(summary([r["seconds"] for r in runs[state]]))
            cpu = [r["cpu"] for r in runs[state] if r["cpu"] is not None]
            cells.append(f"{statistics.median(cpu):.2f}" if cpu else "-")
        after = f"{statistics.median(r['compiled_after'] for r in runs['cold']):.2f}"
        compiled = "-" if case.startswith("subproc") else str(runs["cold"][0]["compiled"])
        lines.append(
            f"{CASES[case]:44} {cells[0]:>19} {cells[1]:>5} {cells[2]:>17} {cells[3]:>5} {after:>15} {compiled:>13}"
        )
    numba_import = [r["numba_import"] for runs in results.values() for r in runs["warm"]]
    lines += ["", f"of which `import numba` alone: {statistics.median(numba_import):.2f} s of CPU (median, warm runs)"]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3, help="cold and warm runs per case (default 3)")
    parser.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    parser.add_argument(
        "--pythonpath", default=str(REPO), help="where the measured box_toss_env is (default: this checkout)"
    )
    parser.add_argument("--readme", action="store_true", help="also write the figures into docs/cold-start.md")
    args = parser.parse_args()
    results = measure(args.repeats, args.pythonpath, args.cases)
    package = results[args.cases[0]]["cold"][0]["package"]
    text = report(results, args.repeats)
    print(f"\n$ python -m benchmarks.cold_start  (package: {package})\n{text}")
    if args.readme:
        replace_section("cold-start", f"```text\n$ python -m benchmarks.cold_start\n{text}\n```")


if __name__ == "__main__":
    main()
