"""Throughput of BoxToss against the engines a user would pick instead. Prints measured figures (with
``--readme`` also into ``docs/throughput.md`` and the headline figures, ``agents.figures``); asserts nothing.

    python -m benchmarks.throughput [--quick] [--readme]

Measured on this machine in one run:
- throws per second of one ``BoxToss-v0`` through ``gymnasium.make`` (its wrappers included);
- throws per second of the native batched env, ``gymnasium.make_vec("BoxToss-v0", num_envs=N)``,
  for N in {1, 16, 256, 4096} on 1 and 2 engine threads, and of Gymnasium's own sync vector env;
- the same toss (the engine's named scene ``toss``, simulated until it rests) in pymunk, Box2D and
  MuJoCo at the same time step, per throw, with the ratio to ours (those missing are named);
- memory per env of the batched env beyond its observation buffers;
- the env cost per throw of pixel observations (``observation_mode="pixels"``) against the state's, batch of 256.
Random actions are drawn before timing; every figure is the best of a few repeats after a warm-up.
"""

from __future__ import annotations

import argparse
import os
import time
import tracemalloc

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode

import box_toss_env  # noqa: F401  (registers BoxToss-v0)
from agents import figures
from agents.doc_sections import replace_section
from benchmarks.env_throughput import throws_per_second
from benchmarks.other_engines import ENGINES, Toss, missing_engines, steps_for_duration
from box_toss_env.envs.box_toss_vector import BoxTossVectorEnv
from box_toss_env.physics import Simulator, layout, make_settings, scenes


def best_rate(run, throws_per_call: int, repeats: int) -> float:
    """Best throws per second over ``repeats`` timed calls of ``run`` after one warm-up call."""
    run()
    best = 0.0
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = max(best, throws_per_call / (time.perf_counter() - start))
    return best


def vector_rate(envs, steps: int, repeats: int) -> float:
    actions = np.random.default_rng(0).uniform(-1, 1, (steps,) + envs.action_space.shape).astype(np.float32)
    envs.reset(seed=0)

    def run():
        for action in actions:
            envs.step(action)

    return best_rate(run, steps * envs.num_envs, repeats)


def single_env_rate(throws: int, repeats: int) -> float:
    env = gym.make("BoxToss-v0")
    env.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (throws, 3)).astype(np.float32)
    return best_rate(lambda: throws_per_second(env, actions), throws, repeats)


def toss_per_throw(repeats: int) -> tuple[float, float, float, int]:
    """Our engine on the named toss, simulated until at rest: (s per throw for one box per call,
    s per throw in a batch of 256 on one thread, simulated seconds until rest, grid steps)."""
    scene = scenes.toss()
    one = Simulator.for_scene(scene)
    state, params = scene.initial_state(), scene.body_params()
    settings = make_settings(scene, int(10 / scene.dt), until_rest=True)
    stats = np.zeros((1, layout.STATS_SIZE))
    work = state.copy()

    def run_one():
        work[:] = state
        one.run(work, params, settings, stats)

    per_throw = 1.0 / best_rate(run_one, 1, repeats * 200)
    rest, steps = float(stats[0, layout.REST_TIME]), int(stats[0, layout.N_STEPS])
    batch = Simulator.for_scene(scene, parallel=True, threads=1)
    states, batch_params = np.repeat(state, 256, axis=0), np.repeat(params, 256, axis=0)
    batch_stats = np.zeros((256, layout.STATS_SIZE))
    batch_work = states.copy()

    def run_batch():
        batch_work[:] = states
        batch.run(batch_work, batch_params, settings, batch_stats)

    return per_throw, 1.0 / best_rate(run_batch, 256, repeats), rest, steps


def pixel_cost(steps: int, repeats: int, n: int = 256) -> tuple[float, float]:
    """Thread CPU seconds per throw of the batched env (``n`` envs, one engine thread) observing the state and
    observing pixels (``observation_mode="pixels"``), the two stepped in turn on the same actions; the median
    over ``repeats`` x ``steps`` steps of each."""
    envs = {mode: gym.make_vec("BoxToss-v0", num_envs=n, threads=1, observation_mode=mode) for mode in PIXEL_MODES}
    rng = np.random.default_rng(0)
    times: dict[str, list[float]] = {mode: [] for mode in envs}
    for env in envs.values():
        env.reset(seed=0)
        env.step(rng.uniform(-1, 1, (n, 3)).astype(np.float32))  # warm-up: kernels compiled or loaded
    for _ in range(repeats * steps):
        actions = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
        for mode, env in envs.items():
            start = time.thread_time()
            env.step(actions)
            times[mode].append((time.thread_time() - start) / n)
    state, pixels = (float(np.median(times[mode])) for mode in PIXEL_MODES)
    return state, pixels


def batched_rates(quick: bool, repeats: int) -> dict[tuple[int, int], float]:
    """Throws per second of the batched env per (envs, engine threads)."""
    batched = {}
    for n in (1, 16, 256, 4096):
        steps = max(2, 4096 // n) if not quick else max(1, 512 // n)
        for threads in (1, 2):
            env = gym.make_vec("BoxToss-v0", num_envs=n, threads=threads)
            batched[n, threads] = vector_rate(env, steps, repeats)
    return batched


def load_average() -> str:
    """The machine's load averages (1, 5, 15 min), or n/a."""
    return ", ".join(f"{value:.1f}" for value in os.getloadavg()) if hasattr(os, "getloadavg") else "n/a"


def pixel_section(steps: int, repeats: int, readme: bool) -> None:
    """Measure the pixel observations' cost (``pixel_cost``), print it and, with ``readme``, write its section."""
    text = "\n".join(pixel_lines(*pixel_cost(steps, repeats))[1:])
    print(text)
    if readme:
        replace_section("throughput-pixels", text)


def pixel_lines(state: float, pixels: float) -> list[str]:
    """The section of pixel observations' cost: ``state`` and ``pixels`` seconds per throw (``pixel_cost``)."""
    return [
        "",
        "Measured by `python -m benchmarks.throughput --pixels-only` (and every full run): pixel observations "
        '(`observation_mode="pixels"`, 96 x 40 RGB, `envs.pixels`) against the state, '
        '`make_vec("BoxToss-v0", num_envs=256)`, one engine thread, stepped in turn on the same random actions, '
        f"thread CPU time per throw (median); load average {load_average()} at the end:",
        "",
        "| observation | us per throw | against the state |",
        "|---|---:|---:|",
        f"| state (12 numbers) | {state * 1e6:.1f} | 1.00x |",
        f"| pixels (the image before the throw and where the box came to rest) | {pixels * 1e6:.1f} | "
        f"{pixels / state:.2f}x |",
    ]


PIXEL_MODES = ("state", "pixels")


def other_engine_rows(duration: float, dt: float, repeats: int) -> list[tuple[str, float]]:
    """Seconds per throw of the same toss in each available engine, simulated for ``duration``."""
    box = scenes.toss().boxes[0]
    toss = Toss(
        length=box.length,
        width=box.width,
        mass=box.mass,
        x=box.position[0],
        y=box.position[1],
        angle=box.angle,
        vx=box.velocity[0],
        vy=box.velocity[1],
        omega=box.spin,
        restitution=scenes.TOSS_MATERIAL["restitution"],
        friction=scenes.TOSS_MATERIAL["friction"],
    )
    n_steps = steps_for_duration(duration, dt)
    rows = []
    for name, engine in ENGINES.items():
        if engine.available():
            engine.simulate_toss(toss, dt, n_steps)  # warm-up
            seconds = min(engine.simulate_toss(toss, dt, n_steps).wall_seconds for _ in range(repeats))
            rows.append((name, seconds))
    return rows


def memory_per_env(small: int = 256, large: int = 4096) -> tuple[float, float]:
    """Bytes allocated per env by the batched env (made, reset and stepped once), from the growth
    between ``small`` and ``large`` envs: (all, beyond the observation buffers). A first env of each
    size is made and stepped outside the measurement, so kernels and caches are already loaded."""
    sizes = []
    for n in (small, large):
        actions = np.zeros((n, 3), dtype=np.float32)
        warm = BoxTossVectorEnv(n)
        warm.reset(seed=0)
        warm.step(actions)
        tracemalloc.start()
        envs = BoxTossVectorEnv(n)
        obs, _ = envs.reset(seed=0)
        result = envs.step(actions)
        current, _ = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        observation_bytes = obs.nbytes + result[0].nbytes + result[4]["final_obs"].nbytes
        sizes.append((current, observation_bytes))
        del warm, envs, obs, result
    per_env = (sizes[1][0] - sizes[0][0]) / (large - small)
    per_env_obs = (sizes[1][1] - sizes[0][1]) / (large - small)
    return per_env, per_env - per_env_obs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and throws")
    parser.add_argument(
        "--pixels-only", action="store_true", help="only the pixel observations' cost against the state's"
    )
    parser.add_argument(
        "--readme", action="store_true", help="also write docs/throughput.md's section and the headline figures"
    )
    args = parser.parse_args()
    repeats = 2 if args.quick else 5
    pixel_section(8 if args.quick else 40, repeats, args.readme)
    if args.pixels_only:
        return
    import numba

    lines = [
        f"Measured by `python -m benchmarks.throughput` on {os.cpu_count()} cores "
        f"(numba {numba.__version__}, {numba.get_num_threads()} threads available), random actions.",
        "",
    ]
    lines += ["| setting | throws/s |", "|---|---:|"]
    single = single_env_rate(1000 if args.quick else 5000, repeats)
    lines.append(f"| one `BoxToss-v0` via `gymnasium.make` | {single:,.0f} |")
    batched = batched_rates(args.quick, repeats)
    for (n, threads), rate in batched.items():
        lines.append(f'| `make_vec("BoxToss-v0", num_envs={n})`, {threads} thread{"s" * (threads > 1)} | {rate:,.0f} |')
    sync = gym.make_vec(
        "BoxToss-v0", num_envs=16, vectorization_mode="sync", vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP}
    )
    sync_rate = vector_rate(sync, 32 if args.quick else 256, repeats)
    lines.append(f"| Gymnasium `SyncVectorEnv`, 16 envs | {sync_rate:,.0f} |")

    ours_one, ours_batch, rest, steps = toss_per_throw(repeats)
    dt = scenes.toss().dt
    lines += [
        "",
        "The same toss (`scenes.toss()`: a 0.4 x 0.2 m, 2 kg box, e 0.3, mu 0.5) at "
        f"dt = 1/{round(1 / dt)} s, simulated for {rest:.2f} s (until our robust solver finds it at rest "
        f"after {steps} contact steps), one thread:",
        "",
        "| engine | us per throw | ours faster by |",
        "|---|---:|---:|",
        f"| BoxToss engine, one box per call | {ours_one * 1e6:.1f} | 1.0x |",
        f"| BoxToss engine, batch of 256 | {ours_batch * 1e6:.1f} | {ours_one / ours_batch:.1f}x |",
    ]
    for name, seconds in other_engine_rows(rest, dt, repeats):
        lines.append(
            f"| {name} (Python loop over its `step`) | {seconds * 1e6:.1f} | "
            f"{seconds / ours_one:.0f}x (batch: {seconds / ours_batch:.0f}x) |"
        )
    missing = missing_engines()
    if missing:
        lines.append(f'\nNot installed (`pip install -e ".[benchmark]"`): {", ".join(missing)}.')
    per_env, beyond_obs = memory_per_env()
    lines += [
        "",
        f"Memory of the batched env: {per_env:,.0f} bytes per env, {beyond_obs:,.0f} beyond the "
        "observation buffers (growth from 256 to 4,096 envs, measured with tracemalloc).",
    ]
    lines[0] = (
        lines[0][:-1] + f"; load average {load_average()} at the end (a shared machine: other jobs' load lowers these)."
    )
    report = "\n".join(lines)
    print(report)
    if args.readme:
        replace_section("throughput", report)
        (n, threads), rate = max(batched.items(), key=lambda item: item[1])
        figures.update(
            "throughput",
            {
                "single": figures.count(single),
                "batched": figures.count(rate),
                "batched_envs": figures.count(n),
                "batched_threads": f"{threads} engine thread{'s' * (threads > 1)}",
                "engine_us": f"{ours_one * 1e6:.0f}",
            },
        )


if __name__ == "__main__":
    main()
