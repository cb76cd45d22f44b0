"""Play mode's logic: a drag becomes the env's action, the env scores the throw."""

import math

import gymnasium as gym
import numpy as np
import pytest

import box_toss_env  # noqa: F401  (registers the envs)
from box_toss_env.envs import task
from box_toss_env.viewer import THROW_GAIN, PlayController, throw_to_action
from box_toss_env.viewer.play import clip_launch_angle


@pytest.fixture
def env():
    environment = gym.make("BoxToss-v0")
    yield environment
    environment.close()


def test_throw_to_action_inverts_the_env_mapping(env):
    config = env.unwrapped.config
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, size=(50, 3))
    actions[:, 0] = np.maximum(actions[:, 0], -0.99)  # speed 0 has no direction
    for action, (speed, theta, spin) in zip(actions, task.actions_to_throws(actions, config), strict=True):
        recovered, clipped = throw_to_action(speed * np.array([math.cos(theta), math.sin(theta)]), spin, config)
        np.testing.assert_allclose(recovered, action, atol=1e-12)
        assert not clipped


def test_throws_outside_the_action_space_are_clipped_into_it(env):
    config = env.unwrapped.config  # launch directions from -45 to +90 degrees, speed up to 8 m/s, spin 20 rad/s
    low, high = config.launch_angle_range
    action, clipped = throw_to_action((-3.0, 0.5), 0.0, config)  # backwards and up: straight up is nearest
    assert clipped and action[1] == pytest.approx(1.0)
    action, clipped = throw_to_action((-1.0, -2.0), 0.0, config)  # backwards and down: -45 degrees is nearest
    assert clipped and action[1] == pytest.approx(-1.0)
    action, clipped = throw_to_action((30.0, 0.0), 50.0, config)
    assert clipped and action[0] == 1.0 and action[2] == 1.0
    assert clip_launch_angle(math.pi, low, high) == high
    assert clip_launch_angle(-0.75 * math.pi, low, high) == low
    assert clip_launch_angle(0.3, low, high) == 0.3


def test_a_scripted_drag_throws_and_shows_the_env_reward(env):
    play = PlayController(env, seed=3)
    centre = play.release[:2]
    play.begin_drag(centre)
    play.drag_to(centre + [0.5, 0.6])
    play.change_spin(+2)
    assert play.aiming and play.spin == pytest.approx(4.0)
    np.testing.assert_allclose(play.velocity, [0.5 * THROW_GAIN, 0.6 * THROW_GAIN])
    action, throw, clipped = play.aimed()
    assert not clipped
    np.testing.assert_allclose(throw, [THROW_GAIN * math.hypot(0.5, 0.6), math.atan2(0.6, 0.5), 4.0])
    path = play.preview_path()
    np.testing.assert_allclose(path[0], centre)
    assert path[-1, 1] == pytest.approx(0.0, abs=1e-9)

    result = play.end_drag()
    assert play.thrown and not play.aiming and result is play.result
    np.testing.assert_allclose(result.action, action)
    assert result.reward == sum(result.terms.values())
    assert set(result.terms) == set(task.REWARD_TERMS)
    # exactly what the env gives an agent for that action in that episode
    fresh = gym.make("BoxToss-v0")
    fresh.reset(seed=play.episode_seed)
    _, reward, terminated, _, info = fresh.step(result.action.astype(np.float32))
    assert terminated and reward == result.reward
    assert info["final_x"] == result.info["final_x"] and info["target_x"] == play.target_x
    fresh.close()


def test_retry_keeps_the_target_and_new_target_changes_it(env):
    play = PlayController(env, seed=1)
    target, release = play.target_x, play.release
    first = play.throw((2.0, 2.0), 0.0)
    play.begin_drag(play.release[:2])  # a drag after a throw starts over on the same target
    assert not play.thrown and play.target_x == target
    np.testing.assert_array_equal(play.release, release)
    play.cancel_drag()
    assert not play.aiming and play.end_drag() is None
    second = play.throw((2.0, 2.0), 0.0)
    assert second.reward == first.reward
    play.new_target()
    assert play.target_x != target and not play.thrown
    assert play.target_label == "any face"


def test_spin_keys_stay_within_max_spin(env):
    play = PlayController(env)
    play.change_spin(+100)
    assert play.spin == env.unwrapped.config.max_spin
    play.change_spin(-3)
    assert play.spin == pytest.approx(14.0)
    play.reset_spin()
    assert play.spin == 0.0
