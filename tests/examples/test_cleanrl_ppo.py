"""The CleanRL-style PPO example, our vector ``NormalizeObservation``, and which of Gymnasium's vector
wrappers work on the native batched env (``AutoresetMode.SAME_STEP``); the list in docs/batched.md comes from here."""

import os
import pickle
import re
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode
from gymnasium.wrappers import vector as V

import box_toss_env  # noqa: F401  (registers BoxToss-v0)
from box_toss_env.wrappers.normalize import NormalizeObservation

ROOT = Path(__file__).resolve().parents[2]
N = 8


def make(num_envs: int = N):
    return gym.make_vec("BoxToss-v0", num_envs=num_envs, threads=1)


def random_actions(rng: np.random.Generator, n: int = N) -> np.ndarray:
    return rng.uniform(-1, 1, (n, 3)).astype(np.float32)


# -- the example ----------------------------------------------------------------------------------
def test_cleanrl_ppo_on_a_tiny_budget_beats_random_and_the_initial_policy():
    """8,192 throws with small updates (256 throws each, constant learning rate 1e-3): 88-96% success
    and 0.03-0.05 m mean distance over seeds 0-3 (about 6 s). The untrained policy throws the mean
    action 0 (7.5% success, 0.77 m on these targets); uniform random actions 2-3% and 2.2 m."""
    command = [
        sys.executable,
        str(ROOT / "examples" / "cleanrl_ppo.py"),
        "--total-timesteps",
        "8192",
        "--num-steps",
        "8",
        "--num-minibatches",
        "4",
        "--learning-rate",
        "1e-3",
        "--anneal-lr",
        "false",
        "--seed",
        "0",
        "--log-every",
        "0",
    ]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    result = subprocess.run(command, capture_output=True, text=True, timeout=120, env=env, cwd=ROOT)
    assert result.returncode == 0, result.stderr[-3000:]
    success = float(re.search(r"success rate: ([0-9.]+)", result.stdout).group(1))
    distance = float(re.search(r"mean distance ([0-9.]+) m", result.stdout).group(1))
    assert success > 0.5, result.stdout
    assert distance < 0.2, result.stdout


# -- our NormalizeObservation ---------------------------------------------------------------------
def test_running_stats_are_numpy_mean_and_var_of_the_observed_batches():
    envs = NormalizeObservation(make())
    rng = np.random.default_rng(0)
    raw_envs = make()  # the same envs, seeded the same, unwrapped: the raw observations
    seen = [raw_envs.reset(seed=3)[0]]
    envs.reset(seed=3)
    for _ in range(5):
        actions = random_actions(rng)
        seen.append(raw_envs.step(actions)[0])
        obs, *_ = envs.step(actions)
    seen = np.concatenate(seen).astype(np.float64)
    # RunningMeanStd starts from mean 0, var 1 with count 1e-4: a 1e-4 / count relative pull (2e-6 here)
    np.testing.assert_allclose(envs.obs_rms.mean, seen.mean(axis=0), rtol=1e-5, atol=1e-9)
    np.testing.assert_allclose(envs.obs_rms.var, seen.var(axis=0), rtol=1e-5, atol=1e-5)
    assert envs.obs_rms.count == pytest.approx(len(seen), abs=1e-3)
    expected = (seen[-N:] - envs.obs_rms.mean) / np.sqrt(envs.obs_rms.var + envs.epsilon)
    np.testing.assert_allclose(obs, expected, rtol=1e-5, atol=1e-5)
    assert obs.dtype == np.float32 and envs.observation_space.contains(obs)


def test_final_obs_is_normalised_with_the_same_stats_and_does_not_update_them():
    envs = NormalizeObservation(make())
    raw_envs = make()
    rng = np.random.default_rng(1)
    envs.reset(seed=5)
    raw_envs.reset(seed=5)
    actions = random_actions(rng)
    count = envs.obs_rms.count
    obs, _, _, _, info = envs.step(actions)
    raw_obs, _, _, _, raw_info = raw_envs.step(actions)
    assert envs.obs_rms.count == pytest.approx(count + N)  # obs only, not final_obs
    scale = np.sqrt(envs.obs_rms.var + envs.epsilon)
    np.testing.assert_allclose(
        info["final_obs"], (raw_info["final_obs"] - envs.obs_rms.mean) / scale, rtol=1e-5, atol=1e-5
    )
    np.testing.assert_allclose(obs, (raw_obs - envs.obs_rms.mean) / scale, rtol=1e-5, atol=1e-5)
    assert info["_final_obs"].all() and info["final_info"]["success"].shape == (N,)


def test_update_off_freezes_the_stats_and_the_stats_pickle():
    envs = NormalizeObservation(make())
    rng = np.random.default_rng(2)
    envs.reset(seed=0)
    envs.step(random_actions(rng))
    envs.update_running_mean = False
    frozen = pickle.loads(pickle.dumps(envs.obs_rms))
    obs, *_ = envs.reset(seed=1)
    obs, *_ = envs.step(random_actions(rng))
    for key in ("mean", "var", "count"):
        np.testing.assert_array_equal(getattr(envs.obs_rms, key), getattr(frozen, key))
    # statistics loaded into a fresh wrapper normalise identically (the evaluation path of the example)
    other = NormalizeObservation(make())
    other.obs_rms, other.update_running_mean = frozen, False
    envs.reset(seed=9)
    other.reset(seed=9)
    actions = random_actions(rng)
    np.testing.assert_array_equal(envs.step(actions)[0], other.step(actions)[0])
    # the whole wrapped env pickles too (the engine kernel is rebuilt from numba's cache)
    copy = pickle.loads(pickle.dumps(envs))
    np.testing.assert_array_equal(copy.obs_rms.mean, envs.obs_rms.mean)


def test_clip_and_gymnasium_sync_env_final_obs():
    """``clip`` bounds the output; on a SyncVectorEnv with SAME_STEP (``final_obs`` an object array)
    only the envs that ended are normalised."""
    envs = NormalizeObservation(make(), clip=0.5)
    envs.reset(seed=0)
    obs, _, _, _, info = envs.step(random_actions(np.random.default_rng(3)))
    assert np.abs(obs).max() <= 0.5 and np.abs(info["final_obs"]).max() <= 0.5
    sync = gym.make_vec(
        "BoxToss-v0", num_envs=3, vectorization_mode="sync", vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP}
    )
    wrapped = NormalizeObservation(sync)
    wrapped.reset(seed=0)
    _, _, _, _, info = wrapped.step(random_actions(np.random.default_rng(4), 3))
    assert info["final_obs"].dtype == object and all(o.dtype == np.float32 for o in info["final_obs"])


# -- Gymnasium's vector wrappers on the native env (docs/batched.md: "Gymnasium vector wrappers") -----------
WORKING = {
    "RecordEpisodeStatistics": lambda e: V.RecordEpisodeStatistics(e),
    "ClipAction": lambda e: V.ClipAction(e),
    "RescaleAction": lambda e: V.RescaleAction(e, 0.0, 1.0),
    "TransformAction": lambda e: V.TransformAction(e, lambda a: a),
    "NormalizeReward": lambda e: V.NormalizeReward(e),
    "TransformReward": lambda e: V.TransformReward(e, lambda r: 2 * r),
    "ClipReward": lambda e: V.ClipReward(e, -1.0, 1.0),
    "DictInfoToList": lambda e: V.DictInfoToList(e),
}
REFUSED = {
    "NormalizeObservation": lambda e: V.NormalizeObservation(e),
    "TransformObservation": lambda e: V.TransformObservation(e, lambda o: o),
    "RescaleObservation": lambda e: V.RescaleObservation(e, -1.0, 1.0),
    "DtypeObservation": lambda e: V.DtypeObservation(e, np.float64),
    "FlattenObservation": lambda e: V.FlattenObservation(e),
}


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("name", sorted(WORKING))
def test_gymnasium_vector_wrapper_works_on_the_native_env(name):
    envs = WORKING[name](make())
    envs.reset(seed=0)
    for _ in range(3):
        obs, reward, terminated, _, info = envs.step(envs.action_space.sample())
        assert obs.shape == (N, 12) and reward.shape == (N,) and terminated.all()
    if name == "RecordEpisodeStatistics":
        np.testing.assert_array_equal(info["episode"]["l"], np.ones(N))
    if name == "DictInfoToList":
        assert len(info) == N and "final_obs" in info[0] and "success" in info[0]["final_info"]


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_gymnasium_observation_wrappers_refuse_same_step(name):
    with pytest.raises(ValueError, match="autoreset_mode"):
        REFUSED[name](make())


def test_make_vec_wrappers_argument_needs_sync_or_async():
    with pytest.raises(gym.error.Error, match="wrappers"):
        gym.make_vec("BoxToss-v0", num_envs=2, wrappers=[gym.wrappers.ClipAction])
    envs = gym.make_vec(
        "BoxToss-v0",
        num_envs=2,
        vectorization_mode="sync",
        wrappers=[gym.wrappers.ClipAction],
        vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP},
    )
    envs.reset(seed=0)
    _, _, terminated, _, info = envs.step(np.full((2, 3), 5.0, dtype=np.float32))  # clipped to 1
    assert terminated.all() and info["_final_obs"].all()
    envs.close()
