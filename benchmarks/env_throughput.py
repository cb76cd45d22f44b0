"""Throws per second of one BoxToss-v0 env made with ``gymnasium.make`` (its default wrappers
included), each throw being ``reset()`` + ``step(action)`` with random actions. Prints measured
figures; asserts nothing.

    python -m benchmarks.env_throughput [--throws 5000] [--repeats 5] [--solver robust] [--dt 0.0078125]
    python -m benchmarks.env_throughput --env BoxToss-OnBox-v0 --batch 256   # another variant, and a batch
    python -m benchmarks.env_throughput --observation-mode pixels --batch 256   # observing images of the scene

``--batch N`` also times the native batched env (``gymnasium.make_vec``, N envs, one engine thread).

The actions are drawn before timing; a warm-up pass first loads the compiled kernel and fills the
caches. Reported: the median over repeats, with the spread, and the part spent in the engine
kernel alone (the same throws re-run on raw arrays), so Python overhead is visible.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import gymnasium as gym
import numpy as np

import box_toss_env  # noqa: F401  (registers BoxToss-v0)


def throws_per_second(env: gym.Env, actions: np.ndarray) -> float:
    start = time.perf_counter()
    for action in actions:
        env.reset()
        env.step(action)
    return len(actions) / (time.perf_counter() - start)


def kernel_seconds_per_throw(env: gym.Env, actions: np.ndarray, clock=time.perf_counter) -> float:
    """Time of the engine kernel alone for the same kind of throws [s], by ``clock`` (wall time by default;
    ``time.thread_time`` for CPU time, the kernel running on the calling thread)."""
    unwrapped = env.unwrapped
    core = unwrapped.core  # the env's throw (envs.functional): it rebuilds each throw's initial state
    batches = []
    for action in actions:
        unwrapped.reset()
        unwrapped.step(action)  # draws the episode; its initial state is rebuilt below
        batch = dataclasses.replace(
            unwrapped._batch, state=unwrapped._batch.state.copy(), params=unwrapped._batch.params.copy()
        )
        batches.append(core.launch(batch, core.check_actions(action, (3,))))
    stats = unwrapped._stats.copy()
    simulator = unwrapped._simulator
    start = clock()
    for batch in batches:
        simulator.run(batch.state, batch.params, core.settings, stats)
    return (clock() - start) / len(batches)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--throws", type=int, default=5000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--solver", default="robust")
    parser.add_argument("--dt", type=float, default=1 / 128)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--env", default="BoxToss-v0", help="the registered variant (default BoxToss-v0)")
    parser.add_argument("--batch", type=int, default=0, help="also time a batched env of this many envs")
    parser.add_argument("--observation-mode", default="state", choices=("state", "pixels"))
    args = parser.parse_args()

    env = gym.make(args.env, solver=args.solver, dt=args.dt, observation_mode=args.observation_mode)
    env.reset(seed=args.seed)
    actions = np.random.default_rng(args.seed).uniform(-1.0, 1.0, (args.throws, 3)).astype(np.float32)
    throws_per_second(env, actions[: min(500, args.throws)])  # warm-up
    rates = [throws_per_second(env, actions) for _ in range(args.repeats)]
    kernel = kernel_seconds_per_throw(env, actions[: min(2000, args.throws)])
    median = statistics.median(rates)
    print(
        f"{args.env} via gymnasium.make, solver={args.solver}, dt={args.dt:g} s, "
        f"observation_mode={args.observation_mode}, random actions"
    )
    print(
        f"throws/s (reset + step), median of {args.repeats} x {args.throws}: {median:,.0f} "
        f"(min {min(rates):,.0f}, max {max(rates):,.0f})"
    )
    print(f"per throw: {1e6 / median:.0f} us, of which engine kernel {1e6 * kernel:.0f} us")
    if args.batch:
        envs = gym.make_vec(
            args.env,
            num_envs=args.batch,
            vectorization_mode="vector_entry_point",
            threads=1,
            solver=args.solver,
            dt=args.dt,
            observation_mode=args.observation_mode,
        )
        envs.reset(seed=args.seed)
        batch_actions = actions[: args.batch * (len(actions) // args.batch)].reshape(-1, args.batch, 3)
        envs.step(batch_actions[0])  # warm-up
        rates = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            for step_actions in batch_actions:
                envs.step(step_actions)
            rates.append(batch_actions.size / 3 / (time.perf_counter() - start))
        print(
            f"batched, make_vec num_envs={args.batch}, 1 engine thread: {statistics.median(rates):,.0f} throws/s "
            f"(min {min(rates):,.0f}, max {max(rates):,.0f})"
        )


if __name__ == "__main__":
    main()
