"""BoxToss-Goal-v0: env checkers, compute_reward against the step's reward, seeding, HER smoke training."""

import warnings

import gymnasium
import numpy as np
import pytest

import box_toss_env  # noqa: F401


def make():
    return gymnasium.make("BoxToss-Goal-v0")


def test_env_checkers_pass_without_warnings():
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(make().unwrapped)
        sb3_check_env(make().unwrapped)


def test_compute_reward_matches_step_and_is_vectorised():
    env = make()
    rewards, achieved, desired = [], [], []
    for seed in range(8):
        obs, _ = env.reset(seed=seed)
        assert obs["achieved_goal"][1] == 0.0  # in the hand, not at rest
        obs, reward, terminated, _, info = env.step(env.action_space.sample())
        assert terminated
        assert reward == pytest.approx(float(env.unwrapped.compute_reward(obs["achieved_goal"], obs["desired_goal"],
                                                                          info)))
        rewards.append(reward)
        achieved.append(obs["achieved_goal"])
        desired.append(obs["desired_goal"])
    batch = env.unwrapped.compute_reward(np.array(achieved), np.array(desired), None)
    np.testing.assert_allclose(batch, rewards, rtol=1e-6)
    batch2 = env.unwrapped.compute_reward(np.array(achieved).reshape(2, 4, 6), np.array(desired).reshape(2, 4, 6), None)
    np.testing.assert_allclose(batch2.ravel(), rewards, rtol=1e-6)
    # relabelled: every landing at rest is a success for its own achieved goal
    relabelled = env.unwrapped.compute_success(np.array(achieved), np.array(achieved))
    np.testing.assert_array_equal(relabelled, np.array(achieved)[:, 1] > 0.5)


def test_reward_matches_box_toss_reward_for_flat_landings():
    env = make()
    for seed in range(8):
        env.reset(seed=seed)
        _, reward, _, _, info = env.step(env.action_space.sample())
        if info["at_rest"] and info["orientation_error"] < 1e-3:
            assert reward == pytest.approx(info["reward_distance"] + info["reward_orientation"]
                                           + info["reward_success"], abs=1e-3)


def test_deterministic_under_seeding():
    outs = []
    for _ in range(2):
        env = make()
        env.action_space.seed(3)
        obs, _ = env.reset(seed=3)
        obs2, reward, *_ = env.step(env.action_space.sample())
        outs.append((obs, obs2, reward))
    for key in ("observation", "achieved_goal", "desired_goal"):
        np.testing.assert_array_equal(outs[0][0][key], outs[1][0][key])
        np.testing.assert_array_equal(outs[0][1][key], outs[1][1][key])
    assert outs[0][2] == outs[1][2]


@pytest.mark.parametrize("algo", ["SAC", "TD3"])
def test_her_trains_a_few_hundred_steps(algo):
    import stable_baselines3
    from stable_baselines3 import HerReplayBuffer

    model = getattr(stable_baselines3, algo)("MultiInputPolicy", make(), replay_buffer_class=HerReplayBuffer,
                                             replay_buffer_kwargs={"n_sampled_goal": 4,
                                                                   "goal_selection_strategy": "future"},
                                             learning_starts=50, batch_size=32, policy_kwargs={"net_arch": [32]},
                                             seed=0, device="cpu")
    model.learn(200)


def test_sac_recipe_passes_her_through():
    from stable_baselines3 import HerReplayBuffer

    from agents import config

    entry = config.load_hyperparams("sac", "BoxToss-Goal-v0")
    kwargs = config.algorithm_kwargs(entry, "sac")
    assert kwargs["replay_buffer_class"] is HerReplayBuffer
    assert kwargs["replay_buffer_kwargs"]["goal_selection_strategy"] == "future"
    assert kwargs["policy"] == "MultiInputPolicy"
