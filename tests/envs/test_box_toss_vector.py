"""The native batched BoxToss env: parity with the single env, autoreset, threads, arguments, pickling."""

import pickle

import gymnasium as gym
import numba
import numpy as np
import pytest
from gymnasium.error import ResetNeeded
from gymnasium.vector import AutoresetMode

import box_toss_env  # noqa: F401  (registers BoxToss-v0)
from box_toss_env.envs.box_toss_vector import BoxTossVectorEnv

N = 6


def random_actions(seed: int, n: int = N) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-1, 1, (n, 3)).astype(np.float32)


def test_make_vec_returns_the_native_env_with_same_step_autoreset():
    envs = gym.make_vec("BoxToss-v0", num_envs=N)
    assert isinstance(envs.unwrapped, BoxTossVectorEnv)
    assert envs.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    assert envs.observation_space.shape == (N, 12) and envs.action_space.shape == (N, 3)
    envs.close()


def test_env_i_of_the_batch_is_the_single_env_seeded_the_same_way():
    envs = gym.make_vec("BoxToss-v0", num_envs=N, friction_range=(0.2, 0.8), restitution_range=(0.0, 0.5))
    obs, _ = envs.reset(seed=11)
    steps = [envs.step(random_actions(k)) for k in range(2)]
    for i in range(N):
        env = gym.make("BoxToss-v0", friction_range=(0.2, 0.8), restitution_range=(0.0, 0.5))
        single_obs, _ = env.reset(seed=11 + i)
        np.testing.assert_array_equal(single_obs, obs[i])
        for k, (next_obs, reward, terminated, truncated, info) in enumerate(steps):
            final_obs, single_reward, single_terminated, single_truncated, single_info = env.step(random_actions(k)[i])
            np.testing.assert_array_equal(final_obs, info["final_obs"][i])
            assert single_reward == reward[i]
            assert (single_terminated, single_truncated) == (terminated[i], truncated[i]) == (True, False)
            for key, value in single_info.items():
                np.testing.assert_array_equal(np.asarray(value), np.asarray(info["final_info"][key][i]), err_msg=key)
            single_obs, _ = env.reset()  # the vector env reset env i in the same step
            np.testing.assert_array_equal(single_obs, next_obs[i])


def test_autoreset_returns_the_next_episodes_first_observation():
    envs = BoxTossVectorEnv(N)
    envs.reset(seed=0)
    obs, reward, terminated, truncated, info = envs.step(random_actions(1))
    assert terminated.all() and not truncated.any() and reward.shape == (N,)
    assert info["_final_obs"].all() and info["_final_info"].all()
    np.testing.assert_array_equal(obs[:, 4:7], 0.0)  # the new boxes are at rest in the hand
    assert not np.array_equal(obs, info["final_obs"])
    assert set(info["final_info"]) >= {"success", "distance", "reward_distance", "_success"}


def test_results_do_not_depend_on_the_thread_count():
    results = []
    for threads in (1, 2):
        envs = BoxTossVectorEnv(N, threads=threads)
        envs.reset(seed=5)
        results.append(envs.step(random_actions(2)))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])
    np.testing.assert_array_equal(results[0][4]["final_obs"], results[1][4]["final_obs"])


def test_gymnasiums_own_vector_envs_still_work():
    for mode in ("sync", "async"):
        envs = gym.make_vec(
            "box_toss_env:BoxToss-v0",
            num_envs=2,
            vectorization_mode=mode,
            vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP},
        )
        envs.reset(seed=0)
        obs, reward, terminated, *_ = envs.step(random_actions(0, 2))
        assert obs.shape == (2, 12) and terminated.all()
        envs.close()


THREADS = numba.config.NUMBA_NUM_THREADS


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(num_envs=0), r"num_envs must be an integer in \[1, 1048576\]"),
        (dict(num_envs=10**8), r"num_envs must be an integer in \[1, 1048576\]"),  # refused before allocating
        (dict(num_envs=2, threads=0), rf"threads must be an integer in \[1, {THREADS}\]"),
        (dict(num_envs=2, threads=THREADS + 1), rf"threads must be an integer in \[1, {THREADS}\]"),
        (dict(num_envs=2, render_mode="human"), "render_mode must be None or 'rgb_array'"),
        (dict(num_envs=2, dt=-1.0), r"dt must be in \[1e-7, 1\] s"),
    ],
)
def test_bad_arguments_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        BoxTossVectorEnv(**kwargs)
    with pytest.raises(ValueError, match=message):
        gym.make_vec("BoxToss-v0", **kwargs)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(num_envs=2.0), "num_envs"),
        (dict(num_envs=True), "num_envs"),
        (dict(num_envs=2, threads="1"), "threads"),
        (dict(num_envs=2, render_mode=1), "render_mode"),
        (dict(num_envs=2, mass="2"), "mass"),
    ],
)
def test_arguments_of_the_wrong_type_are_type_errors(kwargs, name):
    with pytest.raises(TypeError, match=rf"^{name} must be"):
        BoxTossVectorEnv(**kwargs)


@pytest.mark.parametrize(
    "seed, error",
    [
        (1.5, TypeError),
        ("1", TypeError),
        (True, TypeError),
        ([0, 1.5], TypeError),
        ([0, True], TypeError),
        ([0, 1, 2], ValueError),
    ],
)
def test_bad_seeds_are_refused_naming_seed(seed, error):
    with pytest.raises(error, match="seed must be None, an int or a list of 2 ints or Nones"):
        BoxTossVectorEnv(2).reset(seed=seed)


def test_seeds_may_be_numpy_ints_or_none():
    envs = BoxTossVectorEnv(2)
    first, _ = envs.reset(seed=np.int64(4))
    again, _ = envs.reset(seed=[4, 5])
    np.testing.assert_array_equal(first, again)
    envs.reset(seed=[None, 7])


def test_a_step_before_reset_raises_reset_needed_like_the_single_env():
    with pytest.raises(ResetNeeded):
        BoxTossVectorEnv(2).step(np.zeros((2, 3)))


def test_bad_actions_are_refused():
    envs = BoxTossVectorEnv(2)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        envs.step(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="finite"):
        envs.step(np.full((2, 3), np.nan))


def test_pickles_and_renders():
    envs = BoxTossVectorEnv(2, render_mode="rgb_array")
    envs.reset(seed=0)
    clone = pickle.loads(pickle.dumps(envs))
    a, b = envs.step(random_actions(0, 2)), clone.step(random_actions(0, 2))
    np.testing.assert_array_equal(a[0], b[0])
    frames = envs.render()
    assert len(frames) == 2 and frames[0].ndim == 3 and frames[0].dtype == np.uint8
