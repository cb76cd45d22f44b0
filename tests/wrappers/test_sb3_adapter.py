"""The adapter that lets SB3 train on the native batched env: SB3's VecEnv conventions (dones, terminal
observations, infos per env), training under VecMonitor and VecNormalize, and the refusal of next-step autoreset."""

import gymnasium as gym
import numpy as np
import pytest

import box_toss_env  # noqa: F401  (registers BoxToss-v0)


def random_actions(seed: int, n: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-1, 1, (n, 3)).astype(np.float32)


def test_sb3_trains_on_the_batched_env_through_the_adapter():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from box_toss_env.wrappers.sb3_adapter import SB3VecEnvAdapter

    adapter = SB3VecEnvAdapter(gym.make_vec("BoxToss-v0", num_envs=4))
    adapter.seed(3)
    first = adapter.reset()
    _, rewards, dones, infos = adapter.step(random_actions(0, 4))
    assert dones.all() and rewards.dtype == np.float32
    assert all("terminal_observation" in info and "success" in info for info in infos)
    assert not np.array_equal(first, np.stack([info["terminal_observation"] for info in infos]))
    venv = VecNormalize(VecMonitor(adapter))
    model = PPO("MlpPolicy", venv, n_steps=16, batch_size=32, n_epochs=1, seed=0)
    model.learn(total_timesteps=128)
    assert model.num_timesteps >= 128


def test_the_adapter_refuses_next_step_autoreset():
    from box_toss_env.wrappers.sb3_adapter import SB3VecEnvAdapter

    envs = gym.make_vec("BoxToss-v0", num_envs=2, vectorization_mode="sync")
    with pytest.raises(ValueError, match="SAME_STEP"):
        SB3VecEnvAdapter(envs)
