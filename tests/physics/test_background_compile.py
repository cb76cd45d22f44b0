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
from box_toss_env.physics import grouped, layout
from box_toss_env.physics.compile import background_compile, compilation
from box_toss_env.physics.compile.background_compile import MAX_INTERPRETED_BODIES, InterpretedStart, interpreted_copy
from box_toss_env.physics.compile.compilation import jit_kernel
from box_toss_env.physics.kernels import KernelFlags

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
    """A stand-in for a background compile that never finishes."""

    def ready(self) -> bool:
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


def test_a_batch_onto_boxes_starts_the_grouped_kernels_background_compile(monkeypatch):
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


COLLIDING = KernelFlags(boxes_collide=True, parallel=True)


def group_arrays(groups: int, size: int) -> tuple:
    """``GroupedSimulator.run``'s arrays for ``groups`` scenes of ``size`` bodies (zeros: a stand-in copy runs them)."""
    rows = groups * size
    return (
        np.zeros((rows, layout.STATE_SIZE)),
        np.zeros((rows, layout.PARAM_SIZE)),
        np.zeros(layout.SETTINGS_SIZE),
        np.zeros((rows, layout.STATS_SIZE)),
    )


@pytest.mark.parametrize("size, calls", [(3, [15, 15, 3]), (20, [20, 20])], ids=["small-scenes", "large-scenes"])
def test_a_large_batch_onto_boxes_runs_interpreted_in_calls_of_whole_scenes_and_never_waits(monkeypatch, size, calls):
    """A batch of more bodies than one interpreted call takes (a cold ``BoxToss-Stack-v0`` batch of 8 at its third
    throw: 24 bodies) runs interpreted in calls of whole scenes while the worker compiles: it neither compiles
    the kernel here nor waits on the compile lock the worker holds (that wait was the whole compile, 175 s)."""
    monkeypatch.setenv(background_compile.SWITCH, "1")
    monkeypatch.setattr(background_compile, "start", lambda kernel, recipe, args: RunningWorker())
    rows = []
    monkeypatch.setattr(background_compile, "interpreted_copy", lambda kernel: lambda *a: rows.append(a[0].shape[0]))

    def waits(kernel, args):
        raise AssertionError("the step waited for the compiled kernel")

    monkeypatch.setattr(grouped, "ensure_compiled", waits)
    simulator = grouped.GroupedSimulator(COLLIDING, size, start_interpreted=True)
    groups = sum(calls) // size
    simulator.run(*group_arrays(groups, size), warm_start=np.zeros((groups, 1, layout.WARM_START_SIZE)))
    assert rows == calls and simulator.interpreted and not simulator._ready


class ReadyAfter:
    """A stand-in for a background compile whose kernel is ready after ``checks`` looks."""

    def __init__(self, checks: int):
        self.checks = checks
        self.started = 0.0

    def ready(self) -> bool:
        self.checks -= 1
        return self.checks < 0


def test_a_batch_finishes_compiled_once_the_kernel_is_ready_with_the_same_results(monkeypatch):
    """The compiled kernel ready after the first interpreted call of a step: that call's scenes ran interpreted,
    the step's other scenes run compiled, and every scene ends as in a step that ran compiled throughout."""
    actions = np.random.default_rng(2).uniform(-1, 1, (2, 3, 3)).astype(np.float32)
    results = []
    for switch in ("0", "1"):  # compiled throughout; interpreted until the kernel is ready
        monkeypatch.setenv(background_compile.SWITCH, switch)
        monkeypatch.setattr(background_compile, "start", lambda kernel, recipe, args: ReadyAfter(1))
        monkeypatch.setattr(grouped, "MAX_INTERPRETED_GROUPED_BODIES", 2)  # a call of one scene of two boxes
        batch = gym.make_vec("BoxToss-OnBox-v0", num_envs=3)
        batch.reset(seed=5)
        steps = [batch.step(action) for action in actions]
        results.append([np.concatenate([step[0].ravel(), step[1]]) for step in steps])
        simulator = batch.unwrapped.simulator
        assert simulator._ready and simulator.interpreted is False  # the second step ran compiled
        assert simulator._start.interpreted_runs == (1 if switch == "1" else 0)
    assert np.array_equal(results[0], results[1])


def test_a_kernel_seen_in_the_cache_is_ready_for_every_caller_at_once(monkeypatch):
    """The single and the batched env (or a batch's scene sizes) share a background compile: once one of them has
    seen the compiled kernel in the cache, the next asks and gets it at once, not after another look."""
    monkeypatch.setattr(background_compile, "compiling_elsewhere", lambda kernel, signature: True)  # no worker
    looks = iter([True])
    monkeypatch.setattr(background_compile, "cached_for", lambda kernel, signature: next(looks, False))
    compilation = background_compile.BackgroundCompile(floor_of_third, ("unused", "unused", {}), (np.zeros(3),))
    compilation._next_check = 0.0
    assert compilation.ready() and compilation.ready() and compilation.worker is None


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
    assert "compiles in the background" in done.stderr  # the log line that says why the first throws are slow
    logs = list((tmp_path / "cache").rglob(background_compile.LOG_NAME))
    compiled = [line.split(": ", 1)[1].split(" in ")[0] for log in logs for line in log.read_text().splitlines()]
    assert sorted(line for line in compiled if line.startswith("compiled ")) == [
        "compiled fill_uniform_kernel()",  # the batch's random streams, by a worker of their own
        "compiled make_kernel_of(" + KERNEL_FIELDS + ")",
    ]


KERNEL_FIELDS = (
    "solver='robust', use_impulses=True, use_penalty=True, use_friction=True, record=False, parallel=False, "
    "boxes_collide=False"
)

# -- one compile between processes: the kernel's compile lock ---------------------------------------------
TINY_KERNELS = """
from box_toss_env.physics.compile.compilation import jit_kernel
from box_toss_env.physics.kernels import KernelFlags


@jit_kernel
def add_one(values):
    for i in range(values.shape[0]):
        values[i] += 1.0


def kernel():
    return add_one
"""

CLAIM_PROBE = textwrap.dedent("""
    import json, os, sys, time
    import numpy as np
    from box_toss_env.physics.compile import background_compile, compilation
    import tiny_kernels
    start = background_compile.InterpretedStart(tiny_kernels.add_one, ("tiny_kernels", "kernel", {}))
    values, runs, go, deadline = np.ones(3), 0, sys.argv[1], time.monotonic() + 600
    while start.run((values,), (values,)):
        runs += 1
        if runs == 1:
            print(json.dumps({"worker_at_start": start.compilation.worker is not None}), flush=True)
        while go != "-" and not os.path.exists(go):  # the test holds the compile lock until it makes this file
            time.sleep(0.01)
        time.sleep(0.001)
        assert time.monotonic() < deadline
    start.kernel(values)  # compiled: loaded from the cache
    print(json.dumps({"runs": runs, "values": values.tolist(), "loaded": sum(start.kernel.stats.cache_hits.values()),
                      "compiled": sum(start.kernel.stats.cache_misses.values()),
                      "worker": getattr(start.compilation, "worker", None) is not None}))
""")


def claim_probe(tmp_path: Path, go: str) -> subprocess.Popen:
    env = {key: value for key, value in os.environ.items() if key not in ("NUMBA_DISABLE_JIT", "PYTHONPATH")}
    env.update(PYTHONPATH=os.pathsep.join([str(tmp_path), str(PACKAGE.parent)]), **{background_compile.SWITCH: "1"})
    return subprocess.Popen(
        [sys.executable, "-c", CLAIM_PROBE, go],
        env=env,
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def tiny_kernel(tmp_path: Path):
    (tmp_path / "tiny_kernels.py").write_text(TINY_KERNELS)
    sys.path.insert(0, str(tmp_path))
    try:
        return importlib.import_module("tiny_kernels").add_one
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("tiny_kernels", None)


def compile_log_lines(kernel) -> list[str]:
    log = Path(compilation.cache_location(kernel)) / background_compile.LOG_NAME
    return [line.split(": ", 1)[1] for line in log.read_text().splitlines()]


def test_a_process_starts_no_worker_while_another_holds_the_compile_lock(tmp_path):
    """While the kernel's compile lock is held (as by a process compiling it), a process that needs the kernel
    runs interpreted and starts no worker of its own; once the lock comes free with the kernel still not in the
    cache (its holder died), it starts one, which compiles the kernel, and then it runs compiled."""
    kernel = tiny_kernel(tmp_path)
    signature = compilation.argument_types(kernel, (np.ones(3),))
    lock = compilation.compile_lock(kernel, signature)
    go = tmp_path / "go"
    with lock:
        probe = claim_probe(tmp_path, str(go))
        first = json.loads(probe.stdout.readline())
        assert compilation.compiling_elsewhere(kernel, signature)  # as the probe saw it
    go.touch()
    out, err = probe.communicate(timeout=600)
    assert probe.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert first == {"worker_at_start": False} and "another process holds its compile lock" in err
    assert result["worker"] and result["runs"] >= 1 and result["loaded"] == 1 and result["compiled"] == 0
    assert result["values"] == [result["runs"] + 2.0] * 3  # each interpreted run and the compiled one added 1
    lines = compile_log_lines(kernel)  # one worker, started when the lock came free
    assert (
        len(lines) == 2 and lines[0].startswith("compiling kernel() for ") and lines[1].startswith("compiled kernel()")
    )


def test_processes_starting_together_compile_the_kernel_once_and_agree(tmp_path):
    """Two processes needing the same kernel at once on an empty cache: one worker compiles it (any other
    worker finds it in the cache), both switch to the compiled kernel with the same results, and a third
    process loads it and compiles nothing."""
    kernel = tiny_kernel(tmp_path)
    probes = [claim_probe(tmp_path, "-") for _ in range(2)]
    results = []
    for probe in probes:
        out, err = probe.communicate(timeout=600)
        assert probe.returncode == 0, err
        results.append(json.loads(out.strip().splitlines()[-1]))
    compiled = [line for line in compile_log_lines(kernel) if line.startswith("compiled ")]
    assert len(compiled) == 1 and all(r["compiled"] == 0 and r["loaded"] == 1 for r in results)
    assert [r["values"] for r in results] == [[r["runs"] + 2.0] * 3 for r in results]
    third = claim_probe(tmp_path, "-")
    out, err = third.communicate(timeout=600)
    assert third.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result == {"runs": 0, "values": [2.0] * 3, "loaded": 1, "compiled": 0, "worker": False}
