"""Every registered BoxToss id passes SB3's ``check_env`` and Gymnasium's, on what ``gymnasium.make`` returns (the
goal env is made without the wrappers that hide ``compute_reward``)."""

import warnings

import gymnasium as gym
import pytest
from gymnasium.utils.env_checker import check_env as gymnasium_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import box_toss_env  # noqa: F401

IDS = sorted(env_id for env_id in gym.registry if env_id.startswith("BoxToss"))


def test_every_variant_is_checked():
    assert {"BoxToss-v0", "BoxToss-Goal-v0", "BoxToss-Stack-v0", "BoxToss-OnBox-v0"} <= set(IDS)


@pytest.mark.parametrize("env_id", IDS)
def test_sb3_check_env_passes_through_gym_make(env_id):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb3_check_env(gym.make(env_id))


@pytest.mark.parametrize("env_id", IDS)
def test_gymnasiums_check_env_passes_on_the_env(env_id):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gymnasium_check_env(gym.make(env_id).unwrapped)


def test_the_goal_env_through_gym_make_is_the_env_and_still_orders_reset_before_step():
    env = gym.make("BoxToss-Goal-v0")
    assert env is env.unwrapped and hasattr(env, "compute_reward")
    with pytest.raises(gym.error.ResetNeeded):
        env.step(env.action_space.sample())
