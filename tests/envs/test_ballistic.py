"""Ballistic throw commands: the closed form they invert, the wrappers, their checks."""

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest

import box_toss_env  # noqa: F401
from box_toss_env.envs import task, task_columns
from box_toss_env.envs.ballistic import (
    DEFAULT_TURN_RANGE,
    BallisticThrows,
    ballistic_actions,
    ballistic_throws,
    check_command_settings,
    face_angles,
)
from box_toss_env.physics import Box, Scene, simulate
from box_toss_env.wrappers.ballistic import BallisticThrowsVector

ENV_ID = "BoxToss-ShortEnd-v0"


def first_observations(n: int, env_id: str = ENV_ID) -> np.ndarray:
    env = gym.make(env_id)
    return np.stack([env.reset(seed=seed)[0] for seed in range(n)])


@pytest.mark.parametrize("command", [(-0.8, 0.0, 0.02), (0.0, 0.6, -0.05), (0.9, -1.0, 0.08), (0.3, 0.3, 0.0)])
def test_free_flight_reaches_the_commanded_touchdown_pose(command):
    """Simulated by the engine from the throw, at t = T the centre is at (x*, h(phi)) with angle phi:
    the box's lowest corner just touches the floor there (and not before: no impact yet)."""
    env = gym.make(ENV_ID)
    config = env.unwrapped.config
    obs, _ = env.reset(seed=3)
    settings = check_command_settings(config, None, 0.5, DEFAULT_TURN_RANGE)
    speed, angle, spin = ballistic_throws(obs[None], np.array([command]), config, *settings)[0]
    (t_low, t_high), offset_range, turn_range = settings
    flight_time = t_low + (t_high - t_low) * (command[0] + 1) / 2
    x0, y0, theta0 = float(obs[0]), float(obs[1]), math.atan2(float(obs[3]), float(obs[2]))
    phi = face_angles(np.array([theta0]), obs[None, task_columns.OBS_TARGET_FACES])[0] + turn_range * command[2]
    box = Box(
        length=2 * config.half_length,
        width=2 * config.half_width,
        mass=2.0,
        position=(x0, y0),
        angle=theta0,
        velocity=(speed * math.cos(angle), speed * math.sin(angle)),
        spin=spin,
    )
    scene = Scene(boxes=(box,), dt=flight_time / 64, gravity=-config.gravity, restitution=0.3, friction=0.5)
    result = simulate(scene, steps=64, record=True)
    x, y, final_angle = result.final_state[0, :3]
    height = config.half_length * abs(math.sin(phi)) + config.half_width * abs(math.cos(phi))
    assert x == pytest.approx(float(obs[task_columns.OBS_TARGET_X]) + offset_range * command[1], abs=1e-9)
    assert y == pytest.approx(height, abs=1e-9)
    assert final_angle == pytest.approx(phi, abs=1e-9)
    assert result.impacts[0].shape[0] == 0 or result.impacts[0][0, 0] >= flight_time - 1e-9


def test_without_turning_the_env_reports_the_commanded_flight_time():
    """No rotation (phi = theta0, face 0 being the prior's face): the first floor contact comes at T
    (event-located; to float32, the precision of the env's actions)."""
    env = BallisticThrows(gym.make("BoxToss-v0"))
    config = env.unwrapped.config
    (t_low, t_high), _, turn_range = env.settings
    for seed, c0 in enumerate((-0.9, -0.3, 0.2, 0.7)):
        obs, _ = env.reset(seed=seed)
        theta0 = math.atan2(float(obs[3]), float(obs[2]))
        _, _, _, _, info = env.step(np.array([c0, 0.0, theta0 / turn_range], dtype=np.float32))  # phi_face = 0
        assert not info["command_clipped"]
        assert info["flight_time"] == pytest.approx(t_low + (t_high - t_low) * (c0 + 1) / 2, rel=1e-6)
        assert config is env.config


def test_face_angles_are_the_nearest_angle_with_a_target_face_down():
    rng = np.random.default_rng(2)
    theta0 = rng.uniform(-7.0, 7.0, 500)
    faces = (rng.uniform(size=(500, 4)) < 0.5).astype(float)
    faces[faces.sum(axis=1) == 0, 1] = 1.0
    angles = face_angles(theta0, faces)
    assert faces[np.arange(500), task.faces_down(angles)].all()
    # brute force over faces and whole turns
    brute = [
        min(
            (abs(-f * math.pi / 2 + 2 * math.pi * k - t), -f * math.pi / 2 + 2 * math.pi * k)
            for f in range(4)
            if row[f]
            for k in range(-3, 4)
        )[1]
        for t, row in zip(theta0, faces, strict=True)
    ]
    np.testing.assert_allclose(angles, brute, atol=1e-12)
    assert face_angles(np.array([0.2]), np.array([[1.0, 1.0, 1.0, 1.0]]))[0] == 0.0  # "any": land flat as released


def test_the_zero_command_lands_a_target_face_flat_on_the_target():
    """The prior alone (c = 0), with no bounce (e = 0) and sticking friction, on every target whose
    face is a long side (an end needs a lean against the slide, which is what is left to learn)."""
    env = BallisticThrows(gym.make("BoxToss-ThisSideUp-v0", restitution=0.0, friction=2.0))
    long_side_targets = 0
    for seed in range(40):
        obs, _ = env.reset(seed=seed)
        if obs[task_columns.OBS_TARGET_FACES][[0, 2]].any():
            _, _, _, _, info = env.step(np.zeros(3, dtype=np.float32))
            assert info["success"], (seed, info)
            long_side_targets += 1
    assert long_side_targets > 10


def test_wrapper_throws_what_the_mapping_says():
    wrapped, plain = BallisticThrows(gym.make(ENV_ID)), gym.make(ENV_ID)
    commands = np.random.default_rng(0).uniform(-1, 1, (20, 3)).astype(np.float32)
    for seed, command in enumerate(commands):
        obs, _ = wrapped.reset(seed=seed)
        plain.reset(seed=seed)
        actions, clipped = ballistic_actions(obs[None], command[None], wrapped.config)
        _, reward, _, _, info = wrapped.step(command)
        _, plain_reward, _, _, plain_info = plain.step(actions[0])
        assert reward == plain_reward and info["final_x"] == plain_info["final_x"]
        assert info["command_clipped"] == clipped[0]


def test_throws_beyond_the_env_limits_are_clipped_and_flagged():
    obs = first_observations(1, "BoxToss-v0")
    config = gym.make("BoxToss-v0").unwrapped.config
    # the shortest flight to 0.5 m beyond the farthest target needs more than max_speed
    far = np.array([[-1.0, 1.0, 0.0]])
    actions, clipped = ballistic_actions(obs, far, config)
    assert clipped[0] and actions[0, 0] == 1.0
    near = np.array([[0.0, 0.0, 0.0]])
    assert not ballistic_actions(obs, near, config)[1][0]


def test_vector_wrapper_equals_single_wrappers():
    n = 6
    envs = BallisticThrowsVector(gym.make_vec(ENV_ID, num_envs=n, vectorization_mode="vector_entry_point"))
    envs.reset(seed=100)
    commands = np.random.default_rng(1).uniform(-1, 1, (2, n, 3)).astype(np.float32)
    batched = [envs.step(commands[k]) for k in range(2)]
    for i in range(n):
        single = BallisticThrows(gym.make(ENV_ID))
        single.reset(seed=100 + i)
        for k in range(2):
            obs, reward, *_ = single.step(commands[k, i])
            assert reward == pytest.approx(batched[k][1][i], abs=1e-6)
            np.testing.assert_allclose(batched[k][4]["final_obs"][i], obs, atol=1e-6)
            np.testing.assert_allclose(batched[k][0][i], single.reset()[0], atol=1e-6)  # the next episode's start


def test_env_checkers_pass_on_the_wrapped_env():
    from gymnasium.utils.env_checker import check_env as gymnasium_check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gymnasium_check_env(BallisticThrows(gym.make(ENV_ID)).unwrapped)
        sb3_check_env(BallisticThrows(gym.make(ENV_ID)))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"flight_time_range": (1.0, 0.5)}, "flight_time_range must have low <= high"),
        ({"flight_time_range": (0.5, 0.5)}, "flight_time_range must have low < high"),
        ({"flight_time_range": (0.0, 1.0)}, "flight_time_range"),
        ({"offset_range": -0.1}, "offset_range"),
        ({"turn_range": 20.0}, "turn_range"),
    ],
)
def test_bad_settings_name_the_argument(kwargs, message):
    with pytest.raises(ValueError, match=message):
        BallisticThrows(gym.make(ENV_ID), **kwargs)


def test_step_before_reset_and_bad_commands():
    env = BallisticThrows(gym.make(ENV_ID))
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(3, dtype=np.float32))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0, 0]))
    with pytest.raises(TypeError):
        BallisticThrowsVector(gym.make_vec("CartPole-v1", num_envs=2))
