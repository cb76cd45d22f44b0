"""The interpreted start: on a cold cache an env throws with the kernel's interpreted copy while a
worker process compiles the kernel, then with the compiled kernel. The copy must give the compiled
kernel's results bit for bit, or a run's results would depend on how fast the machine compiles."""

import importlib
import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import box_toss_env
from box_toss_env.envs.random_streams import RandomStreams, fill_uniform
from box_toss_env.physics import grouped
from box_toss_env.physics.compile import background_compile
from box_toss_env.physics.compile.background_compile import MAX_INTERPRETED_BODIES, InterpretedStart, interpreted_copy
from box_toss_env.physics.compile.compilation import jit_kernel

PACKAGE = Path(box_toss_env.__file__).parent


def compiled_and_interpreted(env_id: str, throws: int, **env_kwargs):
    """(state, statistics) after each of ``throws`` seeded throws, with the compiled kernel and with its
    interpreted copy."""
    env = gym.make(env_id, **env_kwargs).unwrapped
    space = env.action_space
    actions = np.random.default_rng(0).uniform(space.low, space.high, (throws, *space.shape)).astype(space.dtype)
    simulator = env._build_simulator()
    compiled = simulator.kernel
    results = []
    for kernel in (compiled, interpreted_copy(compiled)):
        simulator.kernel = kernel
        states, stats = [], []
        for seed, action in enumerate(actions):
            env.reset(seed=seed)
            env.step(action)
            states.append(env._state.copy())
            stats.append(env._stats.copy())
        results.append((np.array(states), np.array(stats)))
    return results


@pytest.mark.parametrize(
    "env_id, throws, env_kwargs",
    [
        ("BoxToss-v0", 200, {}),
        ("BoxToss-ThisSideUp-v0", 100, {"friction": 0.0}),
        ("BoxToss-v0", 20, {"solver": "seed", "dt": 1 / 1024}),
        ("BoxToss-OnBox-v0", 6, {}),
    ],
    ids=["robust", "robust-frictionless", "seed", "boxes-collide"],
)
def test_the_interpreted_copy_gives_the_compiled_results_bit_for_bit(env_id, throws, env_kwargs):
    (state_c, stats_c), (state_i, stats_i) = compiled_and_interpreted(env_id, throws, **env_kwargs)
    assert np.array_equal(state_c, state_i)
    assert np.array_equal(stats_c, stats_i, equal_nan=True)


def test_the_interpreted_grouped_kernel_gives_the_batched_on_box_results_bit_for_bit():
    batch = gym.make_vec("BoxToss-OnBox-v0", num_envs=3)
    actions = np.random.default_rng(1).uniform(-1, 1, (2, 3, 3)).astype(np.float32)
    simulator = batch.unwrapped.simulator
    results = []
    for kernel in (simulator.kernel, interpreted_copy(simulator.kernel)):
        simulator.kernel = kernel
        batch.reset(seed=5)
        steps = [batch.step(action) for action in actions]  # the second step throws from the first's reset
        results.append([np.concatenate([step[0].ravel(), step[1]]) for step in steps])
    assert simulator.interpreted is False and simulator._ready  # the compiled kernel ran first
    assert np.array_equal(results[0], results[1])


def test_the_interpreted_random_streams_draw_what_the_compiled_ones_draw():
    compiled, interpreted = RandomStreams(4), RandomStreams(4)
    for i in range(4):
        compiled.seed(i, 11 * i)
        interpreted.seed(i, 11 * i)
    out_c, out_i = np.empty((4, 7)), np.empty((4, 7))
    fill_uniform(compiled.states, out_c)
    with np.errstate(over="ignore"):
        interpreted_copy(fill_uniform)(interpreted.states, out_i)
    assert np.array_equal(out_c, out_i) and np.array_equal(compiled.states, interpreted.states)
    assert np.array_equal(out_c[2], np.random.default_rng(22).random(7))


class RunningWorker:
    """A stand-in for a worker that never finishes."""

    def done(self) -> bool:
        return False


@jit_kernel
def floor_of_third(values):
    values[0] = 1.0
    values[1] = math.floor(values[2])  # the interpreter raises on NaN where compiled code carries on


def test_interpreted_only_while_a_worker_compiles_and_for_small_batches(monkeypatch):
    monkeypatch.setenv(background_compile.SWITCH, "1")
    monkeypatch.setattr(background_compile, "start", lambda kernel, recipe, args: RunningWorker())
    values = np.array([0.0, 0.0, 2.5])
    start = InterpretedStart(floor_of_third, ("unused", "unused", {}))
    assert start.run((values,), (values,)) and values.tolist() == [1.0, 2.0, 2.5]
    assert not floor_of_third.overloads  # the compiled kernel was not needed
    large = np.zeros((MAX_INTERPRETED_BODIES + 1,))
    assert not InterpretedStart(floor_of_third, ("unused", "unused", {})).run((large,), (large,))
    monkeypatch.setenv(background_compile.SWITCH, "0")
    assert not InterpretedStart(floor_of_third, ("unused", "unused", {})).run((values,), (values,))


def test_a_batch_onto_boxes_runs_interpreted_only_up_to_its_own_smaller_size(monkeypatch):
    monkeypatch.setenv(background_compile.SWITCH, "1")
    started = []
    monkeypatch.setattr(
        background_compile, "start", lambda kernel, recipe, args: started.append(recipe) or RunningWorker()
    )
    monkeypatch.setattr(background_compile, "interpreted_copy", lambda kernel: lambda *args: None)
    envs = grouped.MAX_INTERPRETED_GROUPED_BODIES // 2
    small = gym.make_vec("BoxToss-OnBox-v0", num_envs=envs)
    small.reset(seed=0)
    small.step(np.zeros((envs, 3), np.float32))
    assert small.unwrapped.simulator.interpreted
    assert (
        "box_toss_env.physics.grouped",
        "make_grouped_kernel",  # how the worker rebuilds it
        {"solver": "robust", "use_impulses": True, "use_penalty": True, "use_friction": True},
    ) in started
    module, factory, kwargs = started[-1]
    assert getattr(importlib.import_module(module), factory)(**kwargs) is small.unwrapped.simulator.kernel
    simulator = grouped.GroupedSimulator(small.unwrapped.simulator.flags, 2, start_interpreted=True)
    state = np.zeros((grouped.MAX_INTERPRETED_GROUPED_BODIES + 2, 6))
    assert not simulator._start.run((state, None, None, None, 2), ())  # one group too many: compiled


def test_a_copy_that_raises_leaves_the_arrays_as_they_were(monkeypatch):
    monkeypatch.setenv(background_compile.SWITCH, "1")
    monkeypatch.setattr(background_compile, "start", lambda kernel, recipe, args: RunningWorker())
    values = np.array([0.0, 0.0, np.nan])
    start = InterpretedStart(floor_of_third, ("unused", "unused", {}))
    assert not start.run((values,), (values,))
    assert values[0] == 0.0 and start.compiled  # put back; from now on the caller runs the compiled kernel


PROBE = textwrap.dedent("""
    import json, time
    import gymnasium as gym
    import numpy as np
    import box_toss_env
    from box_toss_env.physics.compile.background_compile import wait_for_workers
    from box_toss_env.physics.compile.compilation import cached_on_disk
    action = np.array([0.5, 0.2, -0.3], dtype=np.float32)
    env = gym.make("BoxToss-v0")
    batch = gym.make_vec("BoxToss-v0", num_envs=3)
    env.reset(seed=0)
    first = env.step(action)
    simulator = env.unwrapped._simulator
    batch.reset(seed=0)
    first_batch = batch.step(np.tile(action, (3, 1)))
    result = {"interpreted": simulator.interpreted, "compiled_here": len(simulator.kernel.overloads),
              "batch_interpreted": batch.unwrapped.simulator.interpreted}
    wait_for_workers()
    env.reset(seed=0)
    second = env.step(action)
    batch.reset(seed=0)
    second_batch = batch.step(np.tile(action, (3, 1)))
    result.update(later_interpreted=simulator.interpreted, loaded=sum(simulator.kernel.stats.cache_hits.values()),
                  compiled_after=sum(simulator.kernel.stats.cache_misses.values()),
                  batch_later_interpreted=batch.unwrapped.simulator.interpreted,
                  same=bool(np.array_equal(first[0], second[0]) and first[1] == second[1]),
                  same_batch=bool(np.array_equal(first_batch[0], second_batch[0])
                                  and np.array_equal(first_batch[1], second_batch[1])))
    print(json.dumps(result))
""")


def test_a_cold_env_throws_at_once_and_then_runs_the_kernel_a_worker_compiled(tmp_path):
    env = {key: value for key, value in os.environ.items() if key not in ("NUMBA_DISABLE_JIT", "PYTHONPATH")}
    env.update(
        NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=str(PACKAGE.parent), **{background_compile.SWITCH: "1"}
    )
    done = subprocess.run(
        [sys.executable, "-c", PROBE], env=env, cwd=tmp_path, capture_output=True, text=True, timeout=900
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["interpreted"] and result["batch_interpreted"] and result["compiled_here"] == 0
    assert not result["later_interpreted"] and not result["batch_later_interpreted"]
    assert result["loaded"] == 1 and result["compiled_after"] == 0  # the worker's kernel, loaded from the cache
    assert result["same"] and result["same_batch"]
