"""The held-out split (``split="train"``/``"test"``, ``envs.arguments.SPLITS``) and the drawn box size it uses: each
episode's box is the size it observes, in the engine, the reward, the ballistic command and the oracle's replay."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import box_toss_env  # noqa: F401  (registers the BoxToss envs)
from box_toss_env.envs import task
from box_toss_env.envs.arguments import SPLITS
from box_toss_env.envs.ballistic import ballistic_throws, check_command_settings
from box_toss_env.envs.functional import BoxTossFunctional, episodes_from_reset_infos
from box_toss_env.physics import layout


@pytest.mark.parametrize("split", ["train", "test"])
def test_a_split_draws_every_quantity_in_its_ranges_and_observes_it(split):
    env = gym.make("BoxToss-OnBox-v0", split=split)
    config = env.unwrapped.config
    names = task.observation_names(config)
    ranges = SPLITS[split]
    for seed in range(40):
        obs, info = env.reset(seed=seed)
        for name, key in (("box length", "box_length"), ("box width", "box_width"), ("mass", "mass")):
            low, high = ranges[f"{key}_range"]
            assert low <= info[key] <= high and obs[names.index(name)] == np.float32(info[key])
        assert ranges["target_x_range"][0] <= info["target_x"] <= ranges["target_x_range"][1]
    assert names[-6:] == task.BASE_OBSERVATION_NAMES  # the base box's columns stay last


def test_the_test_ranges_reach_past_the_training_ones():
    train, test = SPLITS["train"], SPLITS["test"]
    for name, value in train.items():
        if name == "observe_dynamics":
            continue
        (low, high), (test_low, test_high) = value, test[name]
        assert test_high > high  # beyond the training range on the far side
        overlap = min(high, test_high) - max(low, test_low)
        assert overlap > 0 and (test_low < low or name == "target_x_range")


def test_a_split_refuses_a_setting_it_makes_and_an_unknown_split():
    with pytest.raises(ValueError, match="split='test' sets friction_range"):
        gym.make("BoxToss-v0", split="test", friction_range=(0.1, 0.2))
    with pytest.raises(ValueError, match="split must be None, 'train' or 'test'"):
        gym.make("BoxToss-v0", split="validation")


def test_the_engine_throws_the_box_the_episode_drew():
    core = BoxTossFunctional(box_length_range=(0.3, 0.6), box_width_range=(0.1, 0.2), mass_range=(1.0, 3.0))
    batch = core.initial(np.random.default_rng(3), core.empty(16))
    lengths, widths = (batch.episodes.data[:, c] for c in core.config.box_size_columns)
    np.testing.assert_allclose(batch.params[:, layout.HALF_LENGTH], 0.5 * lengths)
    np.testing.assert_allclose(batch.params[:, layout.HALF_WIDTH], 0.5 * widths)
    mass = batch.episodes.data[:, task.EP_MASS]
    np.testing.assert_allclose(batch.params[:, layout.INERTIA], mass * (lengths**2 + widths**2) / 12.0)
    assert len(np.unique(lengths)) == 16
    # a box at rest on its long side: its centre at half its width, whatever its size
    batch.state[:, :] = 0.0
    batch.state[:, layout.Y] = 0.5 * widths
    core.simulate(batch, core.make_simulator(parallel=True, threads=1))
    np.testing.assert_allclose(batch.state[:, layout.Y], 0.5 * widths, atol=2e-3)


def test_the_reset_info_gives_back_the_episodes_and_the_vector_env_draws_as_the_single_one():
    vector = gym.make_vec("BoxToss-v0", num_envs=4, vectorization_mode="vector_entry_point", split="test", threads=1)
    observations, infos = vector.reset(seed=11)
    single = gym.make("BoxToss-v0", split="test")
    per_env = [single.reset(seed=11 + i) for i in range(4)]
    np.testing.assert_array_equal(observations, np.stack([obs for obs, _ in per_env]))
    episodes = episodes_from_reset_infos([info for _, info in per_env])
    np.testing.assert_array_equal(episodes.data, vector.unwrapped._episodes.data)
    assert infos["box_length"][2] == per_env[2][1]["box_length"]


def test_the_ballistic_command_touches_down_with_the_episodes_box():
    env = gym.make("BoxToss-v0", split="train")
    config = env.unwrapped.config
    obs, _ = env.reset(seed=0)
    bigger = obs.copy()
    length, width = config.box_size_observed
    bigger[length] += 0.1
    bigger[width] += 0.05
    settings = check_command_settings(config, None, 0.5, 0.8)
    throws = ballistic_throws(np.stack([obs, bigger]), np.zeros((2, 3)), config, *settings)
    # flat on a long side: the centre touches down half a width up; a wider box, higher: it is thrown less steeply
    vy = throws[:, 0] * np.sin(throws[:, 1])
    flight = 0.2 + (2 * config.max_speed / config.gravity - 0.2) * 0.5
    assert vy[1] - vy[0] == pytest.approx(0.5 * 0.05 / flight, rel=1e-6)


@pytest.mark.parametrize("env_id", ["BoxToss-ThisSideUp-v0", "BoxToss-OnBox-v0"])
def test_both_checkers_pass_on_the_test_split(env_id):
    check_env(gym.make(env_id, split="test").unwrapped, skip_render_check=True)
    sb3_check_env(gym.make(env_id, split="test"))
