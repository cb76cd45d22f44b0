"""How the engine is compiled: one kernel shared by the single and the batched env, one compilation
per stage, numba's cache where it is told to be (or none, with a warning, on a read-only install), and
one compilation for processes that need the same kernel at once. Structure, not time: these tests read
numba's dispatchers, compile events and cache statistics."""

import collections
import importlib
import json
import os
import pkgutil
import shutil
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from numba.core import event
from numba.core.caching import IndexDataCacheFile

import box_toss_env
from box_toss_env.physics import KernelFlags, geometry, kernel_support, make_kernel
from box_toss_env.physics.compile.compilation import EngineDispatcher
from box_toss_env.physics.reference import reference_solver
from box_toss_env.physics.robust import (
    contact_solver,
    contact_step,
    energy_limit,
    flight,
    memory,
    penalty,
    restitution,
    robust_solver,
)

PACKAGE = Path(box_toss_env.__file__).parent
STAGE_MODULES = (
    contact_solver,
    contact_step,
    energy_limit,
    flight,
    geometry,
    kernel_support,
    memory,
    penalty,
    restitution,
    robust_solver,
    reference_solver,
)


def compile_events(function) -> list[str]:
    """Names of the functions numba compiled (or loaded from its disk cache: no event) during ``function()``."""
    with event.install_recorder("numba:compile") as recorder:
        function()
    return [e.data["dispatcher"].py_func.__qualname__ for _, e in recorder.buffer if e.is_start]


def throw(env) -> None:
    env.reset(seed=0)
    env.step(env.action_space.sample())


def test_after_the_batched_env_the_single_env_compiles_nothing():
    batched = gym.make_vec("BoxToss-v0", num_envs=3, threads=2)
    throw(batched)
    kernel = batched.unwrapped.simulator.kernel
    signatures = list(kernel.signatures)
    single = gym.make("BoxToss-v0")
    assert compile_events(lambda: throw(single)) == []
    assert single.unwrapped._simulator.kernel is kernel
    assert kernel.signatures == signatures and len(signatures) == 1


def test_after_the_single_env_the_batched_env_compiles_nothing_in_the_engine():
    single = gym.make("BoxToss-v0", friction=0.0)  # a kernel of its own (no friction stage)
    throw(single)
    batched = gym.make_vec("BoxToss-v0", num_envs=5, friction=0.0)
    batched.reset(seed=0)  # draws the episodes with the batch's compiled random streams
    events = compile_events(lambda: batched.step(batched.action_space.sample()))
    assert events == []
    assert batched.unwrapped.simulator.kernel is single.unwrapped._simulator.kernel


STAGE_COUNT_PROBE = textwrap.dedent("""
    import collections, json
    from numba.core import event
    from box_toss_env.physics import scenes, simulate
    with event.install_recorder("numba:compile") as recorder:
        for solver in ("robust", "seed"):
            for record in (False, True):
                for friction in (0.0, 0.5):
                    simulate(scenes.toss(solver=solver, friction=friction), duration=1.0, until_rest=True,
                             record=record)
    names = [e.data["dispatcher"].py_func for _, e in recorder.buffer if e.is_start]
    print(json.dumps(collections.Counter(f"{f.__module__}.{f.__qualname__}" for f in names)))
""")


def test_every_stage_is_compiled_once_for_plain_argument_types(tmp_path):
    """With an empty cache, every solver and recording variant: each stage compiles once, whatever
    the constants its callers pass (a corner index, True) and whichever kernel calls it."""
    done = subprocess.run(
        [sys.executable, "-c", STAGE_COUNT_PROBE],
        capture_output=True,
        text=True,
        timeout=600,
        env=probe_env(PYTHONPATH=PACKAGE.parent, NUMBA_CACHE_DIR=tmp_path),
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    counts = json.loads(done.stdout.strip().splitlines()[-1])
    stages = {
        f"{value.py_func.__module__}.{value.py_func.__qualname__}"
        for module in STAGE_MODULES
        for value in vars(module).values()
        if isinstance(value, EngineDispatcher) and value.targetoptions["inline"] != "always"
    }
    assert len(stages) > 20 and stages <= set(counts)
    assert {name: counts[name] for name in stages if counts[name] != 1} == {}
    variants = {name: count for name, count in counts.items() if "_kernel.<locals>.run_v" in name}
    assert set(variants.values()) == {1}  # each variant compiled once, under a name of its own
    assert collections.Counter(name.rsplit("_v", 1)[0] for name in variants) == {
        "box_toss_env.physics.robust.robust_solver.make_robust_kernel.<locals>.run": 4,
        "box_toss_env.physics.reference.reference_solver.make_reference_kernel.<locals>.run": 4,
    }


def test_stages_have_no_python_wrapper_and_kernels_release_the_gil():
    assert restitution.resolve_impact.targetoptions["no_cpython_wrapper"]
    # and no reference counting: a stage allocates nothing, so the counts of its caller's arrays need no upkeep
    # (only the cold start's guess of a pile's loads, which allocates its work arrays, keeps it; the kernels build
    # and grow their arrays in stages inlined into them)
    from box_toss_env.physics import colliding

    colliding_modules = [
        importlib.import_module(f"{colliding.__name__}.{info.name}")
        for info in pkgutil.iter_modules(colliding.__path__)
    ]
    stages = [
        value
        for module in (*STAGE_MODULES, *colliding_modules)
        for value in vars(module).values()
        if isinstance(value, EngineDispatcher)
        and value.py_func.__module__ == module.__name__
        and value.targetoptions.get("no_cpython_wrapper")
    ]
    counted = sorted(stage.py_func.__name__ for stage in stages if stage.targetoptions["_nrt"])
    assert len(stages) > 40 and counted == ["resting_loads"]
    assert make_kernel(KernelFlags()).targetoptions["nogil"]
    assert make_kernel(KernelFlags(parallel=True)) is make_kernel(KernelFlags())


# -- numba's disk cache, in fresh interpreters ------------------------------------------------------
VARIANT_PROBE = textwrap.dedent("""
    import json, sys
    import numpy as np
    from box_toss_env.physics import KernelFlags, layout, make_settings, scenes, simulate
    from box_toss_env.physics.grouped import GroupedSimulator
    step = sys.argv[1]
    if step == "fill":  # compiles every stage of the colliding seed kernel, then the kernel
        simulate(scenes.pile(4, seed=1, solver="seed"), duration=0.2)
    elif step == "frictionless":  # stages from the cache: the kernel is this process's first compilation
        simulate(scenes.pile(4, seed=1, solver="seed", friction=0.0), duration=0.2)
    elif step == "without-penalty":  # the same, for another variant
        simulate(scenes.pile(4, seed=1, solver="seed", use_penalty=False), duration=0.2)
    else:  # (the variant without penalty loaded, then) the grouped kernel calling the frictionless one
        if step == "both":
            simulate(scenes.pile(4, seed=1, solver="seed", use_penalty=False), duration=0.2)
        scene = scenes.drop_on_box(solver="seed", friction=0.0)
        state = np.concatenate([scene.initial_state()] * 2)
        params = np.concatenate([scene.body_params()] * 2)
        stats = np.zeros((len(state), layout.STATS_SIZE))
        flags = KernelFlags(solver="seed", use_friction=False, boxes_collide=True)
        GroupedSimulator(flags, 2, threads=1).run(state, params, make_settings(scene, 256, until_rest=False), stats)
        print(json.dumps(state.tolist()))
""")


def test_a_kernel_calls_its_own_variant_whatever_other_variants_the_process_loaded(tmp_path):
    """Two variants of a kernel compiled each as the first function of its process got the same symbol
    from numba; a process that loaded one and then a grouped kernel calling the other ran the first's
    body (numba issue #10486; here the grouped kernel moved the boxes as if without penalty). Each
    variant has a name of its own now (``compilation.name_variant``)."""

    def run(step: str, cache: Path) -> str:
        done = subprocess.run(
            [sys.executable, "-c", VARIANT_PROBE, step],
            capture_output=True,
            text=True,
            timeout=600,
            env=probe_env(PYTHONPATH=PACKAGE.parent, NUMBA_CACHE_DIR=cache, BOX_TOSS_ENV_START_INTERPRETED=0),
            cwd=tmp_path,
        )
        assert done.returncode == 0, done.stderr
        return done.stdout.strip()

    for step in ("fill", "frictionless", "without-penalty"):
        run(step, tmp_path)
    alone = run("grouped", tmp_path)  # compiles the grouped kernel into the cache
    assert run("both", tmp_path) == alone  # loads it from there after the other variant
    kernels = {
        flags: make_kernel(flags).py_func.__qualname__
        for flags in (
            KernelFlags(),
            KernelFlags(use_friction=False),
            KernelFlags(solver="seed", boxes_collide=True),
            KernelFlags(solver="seed", boxes_collide=True, use_penalty=False),
        )
    }
    assert len(set(kernels.values())) == len(kernels)


PROBE = textwrap.dedent("""
    import json, os, sys, time, warnings
    warnings.simplefilter("always")
    import gymnasium as gym
    import numpy as np
    import box_toss_env
    from box_toss_env.physics.kernel_support import engine_cache_location
    ready, go = os.environ.get("PROBE_READY"), os.environ.get("PROBE_GO")
    env = gym.make("BoxToss-v0")
    env.reset(seed=0)
    if ready:  # wait until every probe is here, then throw together
        open(ready, "w").close()
        while not os.path.exists(go):
            time.sleep(0.01)
    obs, reward, *_ = env.step(np.array([0.5, 0.2, -0.3], dtype=np.float32))
    stats = env.unwrapped._simulator.kernel.stats
    print(json.dumps({"package": box_toss_env.__file__, "cache": engine_cache_location(), "reward": reward,
                      "compiled": sum(stats.cache_misses.values()), "loaded": sum(stats.cache_hits.values())}))
""")


def run_probe(env: dict, cwd: Path) -> tuple[dict, str]:
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, cwd=cwd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1]), done.stderr


def probe_env(**overrides) -> dict:
    env = {
        key: value
        for key, value in os.environ.items()
        if key not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME", "PYTHONPATH", "NUMBA_DISABLE_JIT")
    }
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    env.update({key: str(value) for key, value in overrides.items()})
    return env


def files_under(path: Path) -> set[Path]:
    return {p for p in path.rglob("*") if p.is_file()}


@pytest.fixture
def read_only_install(tmp_path):
    """A copy of the package that nothing can be written into, for root too (which ignores file modes):
    every ``__pycache__`` is a plain file, so no cache directory can be made next to the sources."""
    site = tmp_path / "site"
    shutil.copytree(PACKAGE, site / "box_toss_env", ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    directories = [site, *(p for p in site.rglob("*") if p.is_dir())]
    for directory in directories:
        (directory / "__pycache__").write_text("not a directory")
    for path in [*files_under(site), *directories]:
        path.chmod(path.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    yield site
    for path in [*directories, *files_under(site)]:
        path.chmod(path.stat().st_mode | stat.S_IWUSR)


def test_a_read_only_install_with_no_writable_home_runs_and_warns(read_only_install, tmp_path):
    before = files_under(read_only_install)
    result, stderr = run_probe(probe_env(PYTHONPATH=read_only_install, HOME="/dev/null"), cwd=tmp_path)
    assert result["package"].startswith(str(read_only_install))
    assert result["cache"] is None and result["compiled"] == 1
    assert np.isfinite(result["reward"])
    assert "CacheWarning" in stderr and "NUMBA_CACHE_DIR" in stderr
    assert files_under(read_only_install) == before


def test_numba_cache_dir_sets_where_a_read_only_install_caches(read_only_install, tmp_path):
    cache = tmp_path / "numba cache"
    env = probe_env(PYTHONPATH=read_only_install, HOME="/dev/null", NUMBA_CACHE_DIR=cache)
    first, stderr = run_probe(env, cwd=tmp_path)
    assert first["cache"].startswith(str(cache)) and first["compiled"] == 1
    assert "CacheWarning" not in stderr
    assert any(path.suffix == ".nbc" for path in files_under(cache))
    second, _ = run_probe(env, cwd=tmp_path)
    assert second["compiled"] == 0 and second["loaded"] == 1
    assert second["reward"] == first["reward"]


def test_processes_throwing_at_once_compile_the_kernel_once(tmp_path):
    """Three interpreters with one empty cache reach their first throw together (as vector-env workers
    do): one compiles the kernel, the others wait for it and load it from the cache."""
    go = tmp_path / "go"
    probes = []
    for k in range(3):
        env = probe_env(
            PYTHONPATH=PACKAGE.parent,
            NUMBA_CACHE_DIR=tmp_path / "cache",
            PROBE_READY=tmp_path / f"ready{k}",
            PROBE_GO=go,
        )
        probes.append(
            subprocess.Popen(
                [sys.executable, "-c", PROBE],
                env=env,
                cwd=tmp_path,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
        )
    deadline = time.monotonic() + 300
    while not all((tmp_path / f"ready{k}").exists() for k in range(3)):
        assert time.monotonic() < deadline and all(p.poll() is None for p in probes), [p.communicate() for p in probes]
        time.sleep(0.05)
    go.touch()
    results = []
    for probe in probes:
        out, err = probe.communicate(timeout=600)
        assert probe.returncode == 0, err
        results.append(json.loads(out.strip().splitlines()[-1]))
    assert sorted(r["compiled"] for r in results) == [0, 0, 1]
    assert sorted(r["loaded"] for r in results) == [0, 1, 1]
    later, _ = run_probe(probe_env(PYTHONPATH=PACKAGE.parent, NUMBA_CACHE_DIR=tmp_path / "cache"), cwd=tmp_path)
    assert later["compiled"] == 0 and later["loaded"] == 1  # the cache they left is whole and valid
    assert {r["reward"] for r in [*results, later]} == {later["reward"]}  # and every process threw alike


EDIT_PROBE = textwrap.dedent("""
    import numba
    import numpy as np
    from box_toss_env.physics.colliding.alone import bounds_touch

    @numba.njit
    def touch(pose, half, radius, awake):
        return bounds_touch(pose, half, radius, awake)

    half = np.array([[0.2, 0.1], [0.2, 0.1]])
    pose = np.array([[0.0, 0.1, 0.0], [0.41, 0.1, 0.0]])  # bounding boxes 1 cm apart
    print(touch(pose, half, np.hypot(half[:, 0], half[:, 1]), np.array([True, False])))
""")


def test_an_edited_engine_file_reaches_the_cached_stages_that_call_it(tmp_path):
    """numba keys a cached function by its own bytecode and its own file's time stamp, so ``alone.bounds_touch``
    (file unchanged) was loaded from the cache with the ``broadphase.box_bound`` it was compiled with, after
    ``broadphase.py`` was edited. The engine's cache keys carry a digest of every engine source
    (``compilation.EngineCache``): the edit reaches it."""
    site = tmp_path / "site"
    shutil.copytree(PACKAGE, site / "box_toss_env", ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    env = probe_env(PYTHONPATH=site, NUMBA_CACHE_DIR=tmp_path / "cache", BOX_TOSS_ENV_START_INTERPRETED=0)

    def touch() -> str:
        done = subprocess.run(
            [sys.executable, "-c", EDIT_PROBE], env=env, cwd=tmp_path, capture_output=True, text=True, timeout=600
        )
        assert done.returncode == 0, done.stderr
        return done.stdout.strip()

    assert touch() == "False"
    broadphase = site / "box_toss_env" / "physics" / "colliding" / "broadphase.py"
    source = broadphase.read_text()
    bound = "    return (abs(cos_a) * half_length + abs(sin_a) * half_width,"
    assert bound in source
    broadphase.write_text(source.replace(bound, bound.replace("(abs(cos_a)", "(0.01 + abs(cos_a)")))  # 1 cm wider
    assert touch() == "True"


EVERY_ID_PROBE = textwrap.dedent("""
    import gc, json
    import gymnasium as gym
    import box_toss_env
    from numba.core import event
    from box_toss_env.physics.compile.compilation import EngineDispatcher
    ids = sorted(env_id for env_id in gym.registry if env_id.startswith("BoxToss-"))
    with event.install_recorder("numba:compile") as recorder:
        for env_id in ids:
            for env in (gym.make(env_id), gym.make_vec(env_id, num_envs=2)):
                env.reset(seed=0)
                env.step(env.action_space.sample())
    compiled = [e.data["dispatcher"].py_func.__qualname__ for _, e in recorder.buffer if e.is_start]
    loaded = [d.py_func.__qualname__ for d in gc.get_objects()
              if isinstance(d, EngineDispatcher) and sum(d.stats.cache_hits.values())]
    print(json.dumps({"ids": ids, "compiled": compiled, "loaded": sorted(loaded)}))
""")


def test_a_second_process_compiles_nothing_for_any_id(tmp_path):
    """Every registered id, made alone and batched, throws in a fresh process (working folder elsewhere, numba's
    cache wherever this test process has it): the first process compiles what the cache lacks (nothing, once the
    suite has thrown with every id), and a second one compiles nothing and loads its kernels from the cache."""
    env = probe_env(PYTHONPATH=PACKAGE.parent, BOX_TOSS_ENV_START_INTERPRETED=0)
    if os.environ.get("NUMBA_CACHE_DIR"):
        env["NUMBA_CACHE_DIR"] = os.environ["NUMBA_CACHE_DIR"]
    runs = []
    for _ in range(2):
        done = subprocess.run(
            [sys.executable, "-c", EVERY_ID_PROBE], env=env, cwd=tmp_path, capture_output=True, text=True, timeout=1800
        )
        assert done.returncode == 0, done.stderr
        runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
    second = runs[1]
    assert second["ids"] == sorted(env_id for env_id in gym.registry if env_id.startswith("BoxToss-"))
    assert second["compiled"] == []
    kinds = {name.split(".<locals>.")[0] for name in second["loaded"]}
    assert {"make_robust_kernel", "make_colliding_robust_kernel", "_grouped_kernel_source", "fill_uniform"} <= kinds


POISONED_MODULE = textwrap.dedent("""
    from box_toss_env.physics.compile.compilation import jit_kernel

    @jit_kernel
    def twice(x):
        return 2.0 * x
""")


def test_a_cache_index_naming_a_class_that_is_gone_compiles_anew(tmp_path, monkeypatch):
    """numba unpickles a function's whole cache index to look one entry up; an index written when a signature
    named a class that a later version deleted (or a truncated index) made every call of the function raise
    (ModuleNotFoundError, AttributeError, EOFError). The engine's cache reads it as empty: compile, and write a
    readable index in its place."""
    monkeypatch.syspath_prepend(str(tmp_path))
    (tmp_path / "poisoned_kernel.py").write_text(POISONED_MODULE)
    module = importlib.import_module("poisoned_kernel")
    cache_file = module.twice._cache._cache_file
    gone = type("Gone", (), {"__module__": "box_toss_env.a_module_that_was_deleted"})
    sys.modules["box_toss_env.a_module_that_was_deleted"] = type(sys)("box_toss_env.a_module_that_was_deleted")
    sys.modules["box_toss_env.a_module_that_was_deleted"].Gone = gone
    try:
        cache_file._save_index({(gone, "float64"): "twice-1.py311.1.nbc"})
    finally:
        del sys.modules["box_toss_env.a_module_that_was_deleted"]
    with pytest.raises(ModuleNotFoundError):
        IndexDataCacheFile._load_index(cache_file)  # numba's own reading of the index fails

    assert module.twice(1.5) == 3.0
    assert sum(module.twice.stats.cache_misses.values()) == 1
    assert len(IndexDataCacheFile._load_index(cache_file)) == 1  # rewritten, readable by numba again

    Path(cache_file._index_path).write_bytes(Path(cache_file._index_path).read_bytes()[:-7])  # truncated
    again = importlib.reload(module)
    assert again.twice(2.0) == 4.0
