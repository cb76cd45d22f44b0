"""The native batched BoxToss-Goal-v0: ``gym.make_vec("BoxToss-Goal-v0")`` is ``BoxTossGoalVectorEnv``, env i is a
single goal env seeded the same way, and arguments and seeds are checked as the other batched envs check them."""

import gymnasium as gym
import numba
import numpy as np
import pytest
from gymnasium.error import ResetNeeded

import box_toss_env  # noqa: F401
from box_toss_env.envs.goal_vector import BoxTossGoalVectorEnv

THREADS = numba.config.NUMBA_NUM_THREADS


def test_make_vec_returns_the_native_goal_env():
    envs = gym.make_vec("BoxToss-Goal-v0", num_envs=3)
    assert isinstance(envs, BoxTossGoalVectorEnv) and envs.num_envs == 3
    assert envs.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP
    assert envs.single_observation_space == gym.make("BoxToss-Goal-v0").observation_space


@pytest.mark.parametrize("target_face", ["any", "mixed"])
def test_env_i_is_the_single_goal_env_seeded_the_same_way(target_face):
    """Two steps of 8 envs from seed 40 against single goal envs seeded 40..47, then reset at their next episodes:
    observations, rewards, final observations and successes alike (the same float32 goals, the same reward)."""
    n, rng = 8, np.random.default_rng(1)
    envs = BoxTossGoalVectorEnv(n, threads=1, target_face=target_face)
    singles = [gym.make("BoxToss-Goal-v0", target_face=target_face) for _ in range(n)]
    obs, _ = envs.reset(seed=40)
    single_obs = [env.reset(seed=40 + i)[0] for i, env in enumerate(singles)]
    for _ in range(2):
        actions = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
        for key in obs:
            np.testing.assert_array_equal(obs[key], np.stack([o[key] for o in single_obs]))
        obs, reward, terminated, truncated, info = envs.step(actions)
        steps = [env.step(actions[i]) for i, env in enumerate(singles)]
        np.testing.assert_array_equal(reward, [step[1] for step in steps])
        assert terminated.all() and not truncated.any()
        for key in ("observation", "achieved_goal", "desired_goal"):
            np.testing.assert_array_equal(info["final_obs"][key], np.stack([step[0][key] for step in steps]))
        np.testing.assert_array_equal(info["final_info"]["is_success"], [step[4]["is_success"] for step in steps])
        single_obs = [env.reset()[0] for env in singles]  # the single envs' next episodes, as the batch's autoreset


def test_compute_reward_is_the_single_envs_over_a_batch():
    envs, single = BoxTossGoalVectorEnv(4), gym.make("BoxToss-Goal-v0")
    obs, _ = envs.reset(seed=3)
    np.testing.assert_array_equal(
        envs.compute_reward(obs["achieved_goal"], obs["desired_goal"], {}),
        single.compute_reward(obs["achieved_goal"], obs["desired_goal"], {}),
    )


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        (dict(num_envs=0), ValueError, r"num_envs must be an integer in \[1, 1048576\]"),
        (dict(num_envs=10**8), ValueError, r"num_envs must be an integer in \[1, 1048576\]"),
        (dict(num_envs=2.0), TypeError, "num_envs must be an integer"),
        (dict(num_envs=True), TypeError, "num_envs must be an integer"),
        (dict(num_envs=2, threads=THREADS + 1), ValueError, rf"threads must be an integer in \[1, {THREADS}\]"),
        (dict(num_envs=2, render_mode="human"), ValueError, "render_mode must be None or 'rgb_array'"),
        (dict(num_envs=2, dt=-1.0), ValueError, r"dt must be in \[1e-7, 1\] s"),
        (dict(num_envs=2, base_box=True), ValueError, "does not take base_box=True"),
    ],
)
def test_bad_arguments_are_refused_as_the_other_batched_envs_refuse_them(kwargs, error, message):
    with pytest.raises(error, match=message):
        gym.make_vec("BoxToss-Goal-v0", **kwargs)


@pytest.mark.parametrize(
    "seed, error", [(1.5, TypeError), (True, TypeError), ([0, 1, 2], ValueError), (-1, ValueError)]
)
def test_bad_seeds_are_refused_naming_seed(seed, error):
    with pytest.raises(error, match="seed must be None, an int or a list of 2 ints or Nones"):
        BoxTossGoalVectorEnv(2).reset(seed=seed)


def test_a_bad_seed_in_a_list_is_named_and_no_env_is_reseeded_before_it():
    envs = BoxTossGoalVectorEnv(3)
    first, _ = envs.reset(seed=[5, 6, 7])
    with pytest.raises(ValueError, match=r"seed\[2\] is -1"):
        envs.reset(seed=[1, 2, -1])
    again, _ = envs.reset()  # the envs' streams went on from seeds 5, 6, 7, untouched by the refused list
    reference = BoxTossGoalVectorEnv(3)
    reference.reset(seed=[5, 6, 7])
    expected, _ = reference.reset()
    np.testing.assert_array_equal(again["desired_goal"], expected["desired_goal"])
    assert not np.array_equal(first["desired_goal"], again["desired_goal"])


def test_a_step_before_reset_raises_reset_needed():
    with pytest.raises(ResetNeeded):
        BoxTossGoalVectorEnv(2).step(np.zeros((2, 3)))


def test_renders_one_frame_per_env():
    envs = BoxTossGoalVectorEnv(2, render_mode="rgb_array")
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 2 and frames[0].ndim == 3
