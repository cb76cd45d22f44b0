"""BoxToss-HiddenPhysics-v0: registration and both checkers, each throw exactly BoxToss-v0's throw of the same
episode, the dynamics drawn but never observed, the episode's end (first success or the budget of throws), the
native batch equal to single envs bit for bit, bad arguments named, rendering."""

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.error import ResetNeeded

import box_toss_env  # noqa: F401  (registers the ids)
from box_toss_env.envs import hidden_physics_task as hidden
from box_toss_env.envs import task_columns
from box_toss_env.envs.hidden_physics import BoxTossHiddenPhysicsEnv, BoxTossHiddenPhysicsVectorEnv
from box_toss_env.envs.multi_throw import MultiThrowFunctional

ENV_ID = "BoxToss-HiddenPhysics-v0"


def test_registered_and_both_checkers_pass_without_warnings():
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(ENV_ID)
    assert isinstance(env.unwrapped, BoxTossHiddenPhysicsEnv)
    assert env.observation_space.shape == (len(hidden.OBSERVATION_NAMES),)
    assert not env.unwrapped.flags.boxes_collide  # one box and the floor: the floor-only kernel
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)
        sb3_check_env(gym.make(ENV_ID, max_throws=2).unwrapped, warn=True)


def test_each_throw_is_the_one_throw_envs_throw_of_the_episode():
    env = gym.make(ENV_ID)
    one = gym.make("BoxToss-v0", **env.unwrapped.task.one_throw_arguments())
    rng = np.random.default_rng(0)
    for seed in range(12):
        _, info = env.reset(seed=seed)
        _, one_info = one.reset(seed=seed)
        assert all(np.all(one_info[key] == value) for key, value in info.items())
        action = rng.uniform(-1, 1, 3).astype(np.float32)
        expected = one.step(action)
        for throw in range(2):  # the same throw again, from the same release pose: the same landing
            if env.unwrapped.thrown == env.unwrapped.task.max_throws or expected[4]["success"] and throw:
                break
            observation, reward, terminated, truncated, info = env.step(action)
            assert reward == expected[1] and not truncated and info["thrown"] == throw + 1
            assert all(info[key] == value for key, value in expected[4].items())
            assert observation[hidden.O_LANDING] == np.float32(info["final_x"])
            if terminated:
                break


def test_the_dynamics_are_drawn_but_not_observed():
    """Two batches whose draws differ only in mass, friction and restitution: the same observations before the
    first throw, different landings after the same throw."""
    core = MultiThrowFunctional(hidden.HiddenPhysicsTask())
    uniforms = np.random.default_rng(1).random((64, core.task.episode_size))
    other = uniforms.copy()
    other[:, task_columns.EP_DYNAMICS] = np.random.default_rng(2).random((64, 3))
    first, second = (core.initial_from_uniforms(u, core.empty(64)) for u in (uniforms, other))
    assert core.observation(first).tobytes() == core.observation(second).tobytes()
    assert not np.array_equal(first.params, second.params)
    actions = np.random.default_rng(3).uniform(-1, 1, (64, 3))
    simulator = core.make_simulator()
    for batch in (first, second):
        core.transition(batch, actions, simulator)
    landed = core.observation(first)[:, hidden.O_LANDING], core.observation(second)[:, hidden.O_LANDING]
    assert np.mean(landed[0] != landed[1]) > 0.9


def test_the_episode_ends_at_the_first_success_or_after_the_budget():
    env = gym.make(ENV_ID, max_throws=3)
    observation, _ = env.reset(seed=4)
    rewards = []
    for throw in range(3):
        observation, reward, terminated, _, info = env.step(np.array([-1.0, 0.0, 0.0], np.float32))  # a drop
        rewards.append(reward)
        assert observation[hidden.O_THROWS] == throw + 1 and terminated == (throw == 2) and not info["success"]
    assert rewards[0] == rewards[1] == rewards[2]  # the same throw of the same box lands the same
    with pytest.raises(ResetNeeded):
        env.step(np.zeros(3, np.float32))
    # a throw that succeeds ends the episode: the one-throw oracle's throw of episode 0
    from agents.oracle import OraclePlanner, ThrowSimulator, episodes_from_infos

    one = gym.make("BoxToss-v0", **env.unwrapped.task.one_throw_arguments())
    _, info = env.reset(seed=0)
    action = OraclePlanner().plan(ThrowSimulator(one, threads=1), episodes_from_infos([info]))[0]
    _, reward, terminated, _, info = env.step(action.astype(np.float32))
    assert info["success"] and terminated and info["thrown"] == 1 and reward == pytest.approx(1.0, abs=0.1)


@pytest.mark.parametrize("threads", [1, 2])
def test_the_native_batch_is_the_single_envs_bit_for_bit(threads):
    n, n_steps = 5, 9
    actions = np.random.default_rng(8).uniform(-1, 1, (n_steps, n, 3)).astype(np.float32)
    envs = gym.make_vec(ENV_ID, num_envs=n, threads=threads, max_throws=3)
    assert isinstance(envs, BoxTossHiddenPhysicsVectorEnv)
    observations, _ = envs.reset(seed=30)
    singles = [gym.make(ENV_ID, max_throws=3) for _ in range(n)]
    for i, env in enumerate(singles):
        assert observations[i].tobytes() == env.reset(seed=30 + i)[0].tobytes()
    for step in range(n_steps):
        observations, rewards, terminated, truncated, info = envs.step(actions[step])
        for i, env in enumerate(singles):
            observation, reward, done, _, single_info = env.step(actions[step, i])
            assert rewards[i] == reward and terminated[i] == done and not truncated[i]
            source = info["final_info"] if done else info
            assert all(source[key][i] == value for key, value in single_info.items())
            if done:
                assert info["final_obs"][i].tobytes() == observation.tobytes()
                observation, _ = env.reset()
            assert observations[i].tobytes() == observation.tobytes()


@pytest.mark.parametrize(
    "kwargs, error",
    [
        ({"max_throws": 0}, ValueError),
        ({"max_throws": 1.5}, TypeError),
        ({"friction_range": (0.5, 0.1)}, ValueError),
        ({"restitution_range": (0.0, 1.5)}, ValueError),
        ({"observe_dynamics": True}, TypeError),
        ({"render_mode": "video"}, ValueError),
    ],
)
def test_bad_arguments_are_named(kwargs, error):
    name = next(iter(kwargs)) if "render_mode" not in kwargs else "render_mode"
    with pytest.raises(error, match=name):
        gym.make(ENV_ID, **kwargs)


def test_render_draws_the_box_the_target_and_the_throws():
    pytest.importorskip("pygame")
    env = gym.make(ENV_ID, render_mode="rgb_array")
    env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (400, 600, 3) and frame.dtype == np.uint8
    env.step(np.zeros(3, np.float32))
    assert env.render().tobytes() != frame.tobytes()
