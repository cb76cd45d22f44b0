"""Throws per second of RLlib's sampling on BoxToss-v0: the native batched env (vector entry point)
against RLlib's default vectorisation (a SyncVectorEnv of single envs), and each env alone. Prints
measured figures; asserts nothing. Needs the ``rllib`` extra.

    python -m benchmarks.rllib_sampling [--num-envs 32 256] [--throws 4096] [--repeats 5] [--readme]

RLlib: ``env_runner.sample(num_timesteps=throws)`` of a PPO algorithm's local env runner (the policy's
forward pass, the connectors and RLlib's episode bookkeeping included), after a warm-up sample; both
vectorisations are built first and sampled in turn, so the load of the shared machine falls on both
alike. Env alone: the same vector env that RLlib steps (``NEXT_STEP`` autoreset: each throw step is
followed by a reset step), stepped with random actions. Reported: the median over repeats, with the
range, in throws (finished episodes) per second.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import gymnasium as gym
import numpy as np
import ray

from agents.doc_sections import replace_section
from agents.rllib_envs import VECTORIZE_MODES, make_env, register_rllib_envs
from agents.rllib_ppo import make_config

ENV_ID = "BoxToss-v0"
LABELS = {"native": "native batched env (vector entry point)", "sync": "RLlib's default (SyncVectorEnv)"}


def vector_env(mode: str, num_envs: int) -> gym.vector.VectorEnv:
    """The vector env RLlib's runner builds for ``mode``."""
    if mode == "native":
        return make_env(ENV_ID, {"num_envs": num_envs, "threads": 1})  # as in agents.rllib_ppo
    return gym.make_vec(ENV_ID, num_envs=num_envs, vectorization_mode="sync")


def env_alone(mode: str, num_envs: int, throws: int, rng: np.random.Generator) -> float:
    """Throws per second of the vector env by itself (throw steps and reset steps)."""
    envs = vector_env(mode, num_envs)
    envs.reset(seed=0)
    steps = 2 * max(throws // num_envs, 1)
    actions = rng.uniform(-1, 1, (steps, num_envs, 3)).astype(np.float32)
    envs.step(actions[0])  # warm-up: the kernel loaded
    envs.step(actions[1])
    start = time.perf_counter()
    for action in actions:
        envs.step(action)
    seconds = time.perf_counter() - start
    envs.close()
    return steps // 2 * num_envs / seconds


def rllib_sampling(runner, throws: int) -> float:
    start = time.perf_counter()
    episodes = runner.sample(num_timesteps=throws, explore=True)
    seconds = time.perf_counter() - start
    return sum(len(episode) for episode in episodes) / seconds


def spread(values: list[float]) -> str:
    return f"{statistics.median(values):,.0f} ({min(values):,.0f}-{max(values):,.0f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--num-envs", type=int, nargs="+", default=[32, 256])
    parser.add_argument("--throws", type=int, default=4096)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--readme", action="store_true", help="write the table into docs/methodology/rllib.md")
    args = parser.parse_args()

    ray.init(address="local", num_cpus=1, include_dashboard=False)
    register_rllib_envs()
    rng = np.random.default_rng(0)
    rows = []
    for num_envs in args.num_envs:
        algos = {mode: make_config(ENV_ID, num_envs=num_envs, vectorize=mode).build_algo() for mode in VECTORIZE_MODES}
        for algo in algos.values():
            algo.env_runner.sample(num_timesteps=args.throws, explore=True)  # warm-up
        sampled = {mode: [] for mode in algos}
        alone = {mode: [] for mode in algos}
        for _ in range(args.repeats):
            for mode, algo in algos.items():
                sampled[mode].append(rllib_sampling(algo.env_runner, args.throws))
                alone[mode].append(env_alone(mode, num_envs, args.throws, rng))
        for mode, algo in algos.items():
            algo.stop()
            rows.append({"mode": mode, "num_envs": num_envs, "rllib": sampled[mode], "alone": alone[mode]})

    lines = [
        "| vectorisation | envs per runner | RLlib sampling [throws/s] | the env alone [throws/s] |",
        "|---|---:|---:|---:|",
    ]
    for row in rows:
        lines.append(f"| {LABELS[row['mode']]} | {row['num_envs']} | {spread(row['rllib'])} | {spread(row['alone'])} |")
    ratios = []
    for num_envs in args.num_envs:
        by_mode = {row["mode"]: row for row in rows if row["num_envs"] == num_envs}
        paired = [a / b for a, b in zip(by_mode["native"]["rllib"], by_mode["sync"]["rllib"], strict=True)]
        alone = [a / b for a, b in zip(by_mode["native"]["alone"], by_mode["sync"]["alone"], strict=True)]
        ratios.append(
            f"- {num_envs} envs: RLlib sampling, native / default: {statistics.median(paired):.2f}x "
            f"({min(paired):.2f}-{max(paired):.2f}x over the repeats); the env alone: "
            f"{statistics.median(alone):.1f}x"
        )
    text = "\n".join(
        [
            f"`python -m benchmarks.rllib_sampling --num-envs {' '.join(map(str, args.num_envs))} "
            f"--throws {args.throws} "
            f"--repeats {args.repeats}` (ray {ray.__version__}, PPO's local env runner, {os.cpu_count()} cores shared "
            f"with other work; median and range of {args.repeats} repeats, the two vectorisations sampled in turn):",
            "",
            *lines,
            "",
            *ratios,
        ]
    )
    print(text)
    if args.readme:
        replace_section("rllib-sampling", text)


if __name__ == "__main__":
    main()
