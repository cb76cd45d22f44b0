"""Throws per second of one ``BoxToss-Stack-v0`` env made with ``gymnasium.make``: whole episodes (``reset`` and
one ``step`` per box of the hand, until the episode ends), with random actions and with a lob onto the stack's top
(the throw command c = (0.6, 0, 0) of ``envs.stack_commands``, whose episodes build the whole stack). Prints
measured figures; asserts nothing.

    python -m benchmarks.stack_throughput [--episodes 100] [--batch 64]

``--batch N`` also times the native batched env (``gymnasium.make_vec``, N envs, one engine thread) for as many
throws.

A throw's cost grows with the scene: every body of it is simulated until all of them rest (the engine's colliding
kernel, with sleeping islands). The first episode (loading the compiled kernel) is not timed.
"""

from __future__ import annotations

import argparse
import os
import time

import gymnasium as gym
import numpy as np

import box_toss_env  # noqa: F401  (registers BoxToss-Stack-v0)
from agents.doc_sections import replace_section
from box_toss_env.envs.stack_commands import command_actions

LOB = np.array([[0.6, 0.0, 0.0]])


def episodes_per_policy(env: gym.Env, n_episodes: int, act) -> tuple[float, float]:
    """(throws per second, throws per episode) of ``act(observation)`` over ``n_episodes`` seeded 0, 1, ..."""
    throws = 0
    start = time.perf_counter()
    for seed in range(n_episodes):
        observation, _ = env.reset(seed=seed)
        terminated = False
        while not terminated:
            observation, _, terminated, _, _ = env.step(act(observation))
            throws += 1
    return throws / (time.perf_counter() - start), throws / n_episodes


def batched_throws_per_second(n_envs: int, n_throws: int, lob: bool) -> float:
    """Throws per second of the native batched env (one engine thread), random actions or lobs."""
    envs = gym.make_vec("BoxToss-Stack-v0", num_envs=n_envs, threads=1)
    config = envs.unwrapped.config
    rng = np.random.default_rng(0)
    observations, _ = envs.reset(seed=0)

    def act(observations):
        if lob:
            return np.concatenate([command_actions(o, LOB, config) for o in observations]).astype(np.float32)
        return rng.uniform(-1, 1, (n_envs, 3)).astype(np.float32)

    for _ in range(config.n_boxes):  # load the compiled kernels (one per scene size)
        observations = envs.step(act(observations))[0]
    steps = max(1, n_throws // n_envs)
    start = time.perf_counter()
    for _ in range(steps):
        observations = envs.step(act(observations))[0]
    return steps * n_envs / (time.perf_counter() - start)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.stack_throughput", description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--batch", type=int, default=0, help="also time a batched env of this many envs")
    parser.add_argument("--readme", action="store_true", help="write the figures into docs/stack.md")
    args = parser.parse_args(argv)
    env = gym.make("BoxToss-Stack-v0")
    config = env.unwrapped.config
    rng = np.random.default_rng(0)
    policies = {
        "random actions": lambda observation: rng.uniform(-1, 1, 3).astype(np.float32),
        "lob onto the stack": lambda observation: command_actions(observation, LOB, config)[0],
    }
    episodes_per_policy(env, 1, policies["lob onto the stack"])  # load the compiled kernel
    lines = []
    for name, act in policies.items():
        rate, length = episodes_per_policy(env, args.episodes, act)
        line = f"{name}: {rate:.0f} throws/s through `gymnasium.make` ({length:.2f} throws per episode)"
        if args.batch:
            batched = batched_throws_per_second(args.batch, round(length * args.episodes), name != "random actions")
            line += f", {batched:.0f} throws/s batched ({args.batch} envs, one engine thread)"
        print(f"BoxToss-Stack-v0, {line}", flush=True)
        lines.append(f"- {line}")
    if args.readme:
        load = os.getloadavg()[0]
        command = (
            f"python -m benchmarks.stack_throughput --episodes {args.episodes}"
            + (f" --batch {args.batch}" if args.batch else "")
            + " --readme"
        )
        replace_section(
            "stack-throughput",
            f"Measured by `{command}` ({args.episodes} episodes each; load average "
            f"{load:.1f} on the 2 shared cores):\n\n" + "\n".join(lines),
        )


if __name__ == "__main__":
    main()
