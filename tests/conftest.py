"""The test session's environment, set before anything imports numba or torch, and inherited by every process a
test starts (trainings, Zoo, Ray, probes):

- the compiled engine: an env's first throws on a cold cache would otherwise run the kernel's interpreted copy
  while a worker compiles it (``box_toss_env.physics.compile.background_compile``), which
  ``tests/physics/test_background_compile.py`` turns on where it tests exactly that;
- SB3's logs of the tests' own models in one folder of the session, removed at its end;
- one OpenMP (torch) and one OpenBLAS thread a process: the tests' networks are small, and on a busy 2-core
  machine torch's spinning second thread made a 300-throw TD3 run in Zoo take 60 s of CPU instead of 9 s
  (212 s instead of 35 s of wall time, at load 9-10). What the tests assert does not depend on it.

And the engine compiled ahead: a run of the whole suite (``COMPILE_AHEAD_MIN_TESTS`` tests or more) starts a
process that throws once with ``BoxToss-v0`` and ``BoxToss-OnBox-v0``, alone and batched, so that their kernels
(the colliding one alone is most of a minute of CPU on a cold cache, as in a fresh clone) compile on the
second core while the first tests run, and the tests load them from numba's cache (a test that needs a kernel
it is compiling waits for it: ``compilation.compile_lock``). ``BOX_TOSS_ENV_TEST_COMPILE_AHEAD=0`` turns it off.
"""

import atexit
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("BOX_TOSS_ENV_START_INTERPRETED", "0")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# SB3's default logger (a model that logs nowhere) makes a folder SB3-<date and time> in the temp directory at each
# learn; the tests' models put theirs in one folder of the session, removed at its end (the commands set a logger)
if "SB3_LOGDIR" not in os.environ:
    os.environ["SB3_LOGDIR"] = tempfile.mkdtemp(prefix="box-toss-tests-sb3-")
    atexit.register(shutil.rmtree, os.environ["SB3_LOGDIR"], ignore_errors=True)

ROOT = Path(__file__).resolve().parents[1]
COMPILE_AHEAD_MIN_TESTS = 300
COMPILE_AHEAD = """
import gymnasium as gym
import box_toss_env
for env_id in ("BoxToss-v0", "BoxToss-OnBox-v0"):
    for env in (gym.make(env_id), gym.make_vec(env_id, num_envs=2)):
        env.reset(seed=0)
        env.step(env.action_space.sample())
"""
_compiling: list[subprocess.Popen] = []


def pytest_collection_finish(session):
    if len(session.items) >= COMPILE_AHEAD_MIN_TESTS and os.environ.get("BOX_TOSS_ENV_TEST_COMPILE_AHEAD") != "0":
        _compiling.append(
            subprocess.Popen(
                [sys.executable, "-c", COMPILE_AHEAD], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
            )
        )


def pytest_sessionfinish(session, exitstatus):
    for process in _compiling:  # a short session leaves no process behind (what it compiled stays cached)
        if process.poll() is None:
            process.terminate()
        process.wait()
