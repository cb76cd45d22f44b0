"""BoxToss-v0 as every Gymnasium user expects it: checkers, determinism, pickling, bad input,
reward terms, rendering headless, and a landing predicted by hand."""

import math
import os
import pickle
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from episodes import assert_identical, rollout
from gymnasium.error import DependencyNotInstalled, ResetNeeded

import box_toss_env  # noqa: F401  (registers the ids)
from box_toss_env.envs import record_throws, task, task_columns
from box_toss_env.envs.box_toss import BoxTossEnv
from box_toss_env.envs.functional import EnergyGainError
from box_toss_env.physics import layout
from box_toss_env.rendering import Palette

os.environ["SDL_VIDEODRIVER"] = "dummy"  # headless window, read when pygame.display starts
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

ENV_ID = "BoxToss-v0"
RANDOMISED = dict(
    target_face="mixed",
    mass_range=(0.5, 5.0),
    friction_range=(0.0, 1.5),
    restitution_range=(0.0, 1.0),
    observe_dynamics=True,
)
STEP_INFO_KEYS = {
    "final_x": float,
    "final_y": float,
    "final_angle": float,
    "face_down": int,
    "at_rest": bool,
    "success": bool,
    "distance": float,
    "orientation_error": float,
    "flight_time": float,
    "n_impacts": int,
    "n_steps": int,
    "max_penetration": float,
    "sim_time": float,
    "reward_distance": float,
    "reward_orientation": float,
    "reward_success": float,
    "target_x": float,
    "mass": float,
    "friction": float,
    "restitution": float,
}


def random_actions(n, seed=0):
    return list(np.random.default_rng(seed).uniform(-1.0, 1.0, (n, 3)).astype(np.float32))


# -- registration and checkers -----------------------------------------------------------------
def test_make_in_a_fresh_interpreter_without_import():
    code = (
        "import sys, gymnasium\n"
        "env = gymnasium.make('box_toss_env:BoxToss-v0')\n"
        "env.reset(seed=0); env.step(env.action_space.sample())\n"
        "assert 'pygame' not in sys.modules\n"
        "import box_toss_env\n"
        "for name in ('BoxToss-LongSide-v0', 'BoxToss-ShortEnd-v0', 'BoxToss-ThisSideUp-v0'):\n"
        "    assert name in gymnasium.registry\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)


def test_importing_the_package_imports_neither_pygame_nor_the_envs():
    code = "import sys, box_toss_env; assert 'pygame' not in sys.modules and 'box_toss_env.envs' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)


@pytest.mark.parametrize("kwargs", [{}, {"observe_dynamics": True}, {"target_x_range": (2.0, 2.0)}])
def test_gymnasium_check_env_without_warnings(kwargs):
    """Also with fixed quantities in the observation (dynamics not drawn, one target x): their bounds are
    one float32 step either side of the value, never equal (which the checker warns about)."""
    from gymnasium.utils.env_checker import check_env

    env = gym.make(ENV_ID, **kwargs)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)  # includes every render mode (headless) and close twice
    env.close()


@pytest.mark.parametrize("kwargs", [{}, RANDOMISED])
def test_sb3_check_env_without_warnings(kwargs):
    from stable_baselines3.common.env_checker import check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make(ENV_ID, **kwargs))


def test_spaces_and_return_types():
    env = gym.make(ENV_ID)
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (3,), np.float32)
    assert env.observation_space.dtype == np.float32 and env.observation_space.shape == (12,)
    assert np.all(np.isfinite(env.observation_space.low)) and np.all(np.isfinite(env.observation_space.high))
    obs, info = env.reset(seed=0)
    assert obs.dtype == np.float32 and env.observation_space.contains(obs)
    assert obs[task_columns.OBS_VX : task_columns.OBS_SPIN + 1].tolist() == [0.0, 0.0, 0.0]  # at rest in the hand
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert type(reward) is float and terminated is True and truncated is False
    assert {key: type(info[key]) for key in STEP_INFO_KEYS} == STEP_INFO_KEYS
    assert obs[task_columns.OBS_X] == np.float32(info["final_x"]) and obs[task_columns.OBS_Y] == np.float32(
        info["final_y"]
    )


# -- determinism and pickling ---------------------------------------------------------------------
@pytest.mark.parametrize("kwargs", [{}, RANDOMISED])
def test_same_seed_and_actions_give_bit_identical_episodes(kwargs):
    actions = random_actions(8)
    first = rollout(gym.make(ENV_ID, **kwargs), 7, actions)
    second = rollout(gym.make(ENV_ID, **kwargs), 7, actions)
    assert_identical(first, second)
    other_seed = rollout(gym.make(ENV_ID, **kwargs), 8, actions)
    assert first[0][0].tobytes() != other_seed[0][0].tobytes()


def test_pickled_env_continues_identically():
    env = gym.make(ENV_ID, **RANDOMISED)
    env.reset(seed=3)
    for wrapped in (env, env.unwrapped):
        copy = pickle.loads(pickle.dumps(wrapped))
        actions = random_actions(3, seed=1)
        assert_identical(rollout(copy, None, actions), rollout(pickle.loads(pickle.dumps(wrapped)), None, actions))
        copy.close()


def test_async_vector_env_from_the_string_id():
    envs = gym.make_vec(
        "box_toss_env:BoxToss-v0",
        num_envs=2,
        vectorization_mode="async",
        vector_kwargs={"autoreset_mode": gym.vector.AutoresetMode.SAME_STEP},
    )
    try:
        obs, _ = envs.reset(seed=0)
        assert obs.shape == (2, 12)
        obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
        assert terminated.tolist() == [True, True] and np.all(np.isfinite(reward))
        assert "final_obs" in info
    finally:
        envs.close()


def test_vector_entry_point_placeholder():
    envs = gym.make_vec(ENV_ID, num_envs=3)  # the registered vector_entry_point
    obs, _ = envs.reset(seed=0)
    assert obs.shape == (3, 12)
    _, reward, terminated, _, info = envs.step(envs.action_space.sample())
    assert terminated.all() and reward.shape == (3,) and info["final_info"]["success"].shape == (3,)
    envs.close()


# -- bad input ------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("action", "message"),
    [
        ([np.nan, 0.0, 0.0], "finite"),
        ([0.0, np.inf, 0.0], "finite"),
        ([0.0, 0.0, -np.inf], "finite"),
        ([0.0, 0.0], r"shape \(3,\)"),
        ([[0.0, 0.0, 0.0]], r"shape \(3,\)"),
    ],
)
def test_bad_actions_raise_clear_value_errors(action, message):
    env = BoxTossEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


@pytest.mark.parametrize(
    "action", ["fast", "000", ["0", "0", "0"], np.array([1j, 0.0, 0.0]), [True, False, True], [0.0, None, 0.0]]
)
def test_actions_that_are_not_real_numbers_are_type_errors(action):
    env = BoxTossEnv()
    env.reset(seed=0)
    with pytest.raises(TypeError, match="action must hold real numbers"):
        env.step(action)


def test_actions_outside_the_box_are_clipped():
    env = BoxTossEnv()
    env.reset(seed=0)
    clipped = env.step(np.array([1.0, -1.0, 0.3]))
    env.reset(seed=0)
    assert_identical(env.step(np.array([7.0, -2.5, 0.3])), clipped)


def test_step_needs_a_reset():
    env = BoxTossEnv()
    with pytest.raises(ResetNeeded):
        env.step(np.zeros(3))
    env.reset(seed=0)
    env.step(np.zeros(3))
    with pytest.raises(ResetNeeded):
        env.step(np.zeros(3))


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"box_length": 0.0}, "box_length"),
        ({"box_width": -1.0}, "box_width"),
        ({"mass": np.nan}, "mass"),
        ({"friction": -0.1}, "friction"),
        ({"restitution": 1.5}, "restitution"),
        ({"penalty_stiffness": -1.0}, "penalty_stiffness"),
        ({"gravity": 0.0}, "gravity"),
        ({"release_height_range": (0.1, 1.0)}, "release_height_range"),
        ({"release_x_range": (1.0, 0.0)}, "release_x_range"),
        ({"release_angle_range": (0.0, 4.0)}, "release_angle_range"),
        ({"target_face": "top"}, "target_face"),
        ({"max_speed": 0.0}, "max_speed"),
        ({"launch_angle_range": (0.0, np.inf)}, "launch_angle_range"),
        ({"max_spin": -2.0}, "max_spin"),
        ({"position_tolerance": 0.0}, "position_tolerance"),
        ({"distance_weight": -1.0}, "distance_weight"),
        ({"success_bonus": -1.0}, "success_bonus"),
        ({"mass_range": (0.0, 1.0)}, "mass_range"),
        ({"friction_range": (-1.0, 1.0)}, "friction_range"),
        ({"restitution_range": (0.5, 1.2)}, "restitution_range"),
        ({"solver": "rk4"}, "solver"),
        ({"dt": 0.0}, "dt"),
        ({"max_sim_time": 0.0}, "max_sim_time"),
        ({"render_fps": 0}, "render_fps"),
        ({"render_width": 5}, "render_width"),
        # what the engine and the env cannot honour (docs/ranges.md)
        ({"mass": 1e300}, r"mass must be in \[1e-6, 1e6\] kg"),
        ({"mass": 1e-300}, r"mass must be in \[1e-6, 1e6\] kg"),
        ({"dt": 1e-300}, r"dt must be in \[1e-7, 1\] s"),
        ({"dt": 1e-12}, r"dt must be in \[1e-7, 1\] s"),
        ({"dt": 1e-7, "max_sim_time": 20.0}, r"max_sim_time / dt must be at most 1e8 steps"),
        ({"box_width": 1e-300}, r"box_width must be in \[0.0001, 1000\] m"),
        ({"box_length": 1e-160}, r"box_length must be in \[0.0001, 1000\] m"),
        ({"release_height_range": (1e39, 1e39)}, r"release_height_range\[0\] must be in \(0, 10000\] m"),
        ({"mass_range": (1.0, 1e39)}, r"mass_range\[1\] must be in \[1e-6, 1e6\] kg"),
        ({"friction_range": (0.0, 1e39)}, r"friction_range\[1\] must be in \[0, 10\]"),
        ({"friction": 1e39}, r"friction must be in \[0, 10\]"),
        ({"gravity": 1e-300}, r"gravity must be in \[0.001, 10000\] m/s\^2"),
        ({"distance_weight": 1e308}, r"distance_weight must be in \[0, 1e6\] 1/m"),
    ],
)
def test_bad_kwargs_raise_value_errors_naming_them(kwargs, name):
    with pytest.raises(ValueError, match=name):
        gym.make(ENV_ID, **kwargs)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"mass": "2"}, "mass"),
        ({"restitution": True}, "restitution"),
        ({"release_x_range": "01"}, "release_x_range"),
        ({"release_x_range": ("0", "1")}, r"release_x_range\[0\]"),
        ({"target_x_range": 3.0}, "target_x_range"),
        ({"orientation_weight": "x"}, "orientation_weight"),
        ({"max_speed": 8 + 0j}, "max_speed"),
        ({"mass_range": (1, True)}, r"mass_range\[1\]"),
        ({"observe_dynamics": "yes"}, "observe_dynamics"),
        ({"target_face": 1}, "target_face"),
        ({"solver": None}, "solver"),
        ({"dt": "0.01"}, "dt"),
        ({"render_fps": "30"}, "render_fps"),
        ({"render_width": 600.0}, "render_width"),
        ({"render_mode": 1}, "render_mode"),
    ],
)
def test_kwargs_of_the_wrong_type_raise_type_errors_naming_them(kwargs, name):
    with pytest.raises(TypeError, match=rf"^{name} must be"):
        BoxTossEnv(**kwargs)
    with pytest.raises(TypeError, match=name):
        gym.make(ENV_ID, **kwargs)


def test_numpy_numbers_are_accepted():
    env = gym.make(ENV_ID, mass=np.float32(3.0), max_speed=np.int64(5), release_x_range=np.array([-0.1, 0.1]))
    assert env.unwrapped.config.mass_range == (3.0, 3.0) and env.unwrapped.config.max_speed == 5.0


def test_observation_bounds_are_finite_at_the_ends_of_every_range():
    """The widest corners of the declared ranges still give finite float32 bounds (no inf in observations)."""
    extreme = dict(
        box_length=1e3,
        box_width=1e-4,
        gravity=1e-3,
        release_height_range=(600.0, 1e4),
        release_x_range=(-1e3, 1e3),
        target_x_range=(-1e3, 1e3),
        max_speed=1e3,
        max_spin=1e4,
        max_sim_time=1e4,
        dt=0.1,
        mass_range=(1e-6, 1e6),
        friction_range=(0.0, 10.0),
        observe_dynamics=True,
    )
    space = gym.make(ENV_ID, **extreme).observation_space
    assert np.isfinite(space.low).all() and np.isfinite(space.high).all() and (space.low < space.high).all()


def test_unknown_render_mode():
    with pytest.raises(ValueError, match="render_mode"):
        BoxTossEnv(render_mode="ansi")


# -- reward, observations, task options -----------------------------------------------------------
def test_reward_is_the_sum_of_its_terms():
    env = gym.make(ENV_ID, target_face="mixed")
    env.reset(seed=0)
    for action in random_actions(20):
        env.reset()
        _, reward, _, _, info = env.step(action)
        terms = {name: info[name] for name in task.REWARD_TERMS}
        assert reward == sum(terms.values())
        final_state = env.unwrapped._state[0]  # the engine's final state, angle not wrapped
        assert final_state[:2].tolist() == [info["final_x"], info["final_y"]]
        assert env.unwrapped.landing_reward(final_state, info["at_rest"]) == (reward, terms)
        assert info["success"] == (info["reward_success"] > 0.0)


def test_random_throws_stay_inside_the_observation_space_and_the_ranges():
    env = gym.make(ENV_ID, **RANDOMISED)
    space = env.observation_space
    config = env.unwrapped.config
    successes = 0
    for reset_obs, reset_info, (obs, reward, _, _, info) in rollout(env, 0, random_actions(200)):
        assert space.contains(reset_obs) and space.contains(obs) and math.isfinite(reward)
        for name, column in (
            ("mass", task_columns.OBS_MASS),
            ("friction", task_columns.OBS_FRICTION),
            ("restitution", task_columns.OBS_RESTITUTION),
        ):
            low, high = getattr(config, f"{name}_range")
            assert low <= reset_info[name] <= high and info[name] == reset_info[name]
            assert reset_obs[column] == obs[column] == np.float32(reset_info[name])  # observed
        assert reset_obs[task_columns.OBS_TARGET_X] == np.float32(reset_info["target_x"])
        assert reset_obs[task_columns.OBS_TARGET_FACES].tolist() == reset_info["target_faces"].tolist()
        successes += info["success"]
    params = env.unwrapped._params[0]
    assert params[layout.MASS] == info["mass"] and params[layout.FRICTION] == info["friction"]
    assert successes < 200


def test_dynamics_are_hidden_unless_observed():
    env = gym.make(ENV_ID, mass_range=(1.0, 3.0))
    obs, info = env.reset(seed=0)
    assert obs.shape == (12,) and 1.0 <= info["mass"] <= 3.0
    masses = {env.reset()[1]["mass"] for _ in range(5)}
    assert len(masses) == 5


def test_a_gentle_throw_lands_where_the_parabola_meets_the_floor():
    """Released level at height h with speed v and no spin, restitution 0 and high friction: the
    box lands flat after t = sqrt(2 (h - W/2) / g) at x = v t and stays there."""
    height, speed, g, half_width = 1.0, 1.2, 9.81, 0.1
    env = gym.make(
        ENV_ID,
        release_x_range=(0.0, 0.0),
        release_height_range=(height, height),
        release_angle_range=(0.0, 0.0),
        restitution=0.0,
        friction=1.0,
        gravity=g,
    )
    config = env.unwrapped.config
    low, high = config.launch_angle_range
    action = np.array([2 * speed / config.max_speed - 1, 2 * (0.0 - low) / (high - low) - 1, 0.0])
    env.reset(seed=0)
    _, _, _, _, info = env.step(action)
    flight_time = math.sqrt(2 * (height - half_width) / g)
    assert info["flight_time"] == pytest.approx(flight_time, abs=1e-6)
    assert info["final_x"] == pytest.approx(speed * flight_time, abs=0.02)
    assert info["final_y"] == pytest.approx(half_width, abs=1e-3)
    assert info["at_rest"] and info["face_down"] == 0 and info["n_impacts"] == 1


def test_max_sim_time_ends_a_throw_that_has_not_come_to_rest():
    env = gym.make(ENV_ID, max_sim_time=0.3)
    env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(np.array([1.0, 1.0, 0.0]))  # straight up, 8 m/s
    assert terminated and not truncated and not info["at_rest"] and not info["success"]
    assert info["sim_time"] == pytest.approx(0.3, abs=env.unwrapped.dt) and info["flight_time"] == info["sim_time"]
    assert env.observation_space.contains(obs) and math.isfinite(reward)


def test_a_box_sinking_through_the_floor_is_reported_as_such():
    """The seed scheme with penalty_stiffness=0 lets a box sink: the error says so, not "energy created"."""
    env = gym.make(ENV_ID, solver="seed", penalty_stiffness=0.0)
    env.reset(seed=0)
    with pytest.raises(EnergyGainError, match="sank through the floor") as caught:
        env.step(np.zeros(3))
    assert "created energy" not in str(caught.value) and "penalty_stiffness > 0" in str(caught.value)


def test_the_robust_solvers_errors_speak_of_the_robust_solver():
    """Neither message blames the seed scheme or advises solver='robust' to a robust run."""
    from box_toss_env.physics import NonFiniteStateError

    env = BoxTossEnv()
    sunk, fast = env.observation_space.low.copy(), env.observation_space.high.copy()
    sunk[task_columns.OBS_Y] -= 1.0
    fast[task_columns.OBS_VX] *= 2.0
    messages = [env._bounds_message(sunk), env._bounds_message(fast), str(NonFiniteStateError(0, 3, "robust"))]
    assert "sank through the floor" in messages[0] and "created energy" in messages[1]
    for message in messages:
        assert "solver='robust'" in message and "seed" not in message and "use solver" not in message
    assert "seed scheme" in str(NonFiniteStateError(0, 3, "seed"))


def test_the_seed_solver_is_selectable_and_its_energy_gain_is_reported():
    fine = gym.make(ENV_ID, solver="seed", dt=1 / 1024, max_sim_time=3.0)
    for _, _, (obs, _, _, _, _) in rollout(fine, 0, random_actions(3)):
        assert fine.observation_space.contains(obs)
    coarse = BoxTossEnv(solver="seed", dt=1 / 256, max_sim_time=3.0, max_spin=0.0)
    coarse.reset(seed=1)
    with pytest.raises(EnergyGainError, match="dt"):
        for action in random_actions(20, seed=2):  # the explicit scheme gains energy at this step
            coarse.step(action)
            coarse.reset()


# -- rendering ------------------------------------------------------------------------------------
def box_pixel(env, state):
    camera = env.unwrapped._renderer_for_env().renderer.camera
    return camera.pixel_index(state[:2])


def test_rgb_array_shows_the_box_where_the_state_says():
    env = gym.make(ENV_ID, render_mode="rgb_array", render_width=320, render_height=240)
    env.reset(seed=0)
    for throw in (None, np.array([-0.3, 0.0, 0.2])):  # in the hand, then at rest after the throw
        if throw is not None:
            env.step(throw)
        frame = env.render()
        assert frame.shape == (240, 320, 3) and frame.dtype == np.uint8
        row, column = box_pixel(env, env.unwrapped._state[0])
        assert tuple(frame[row, column]) == Palette().box_fill
    env.close()
    env.close()


def test_rgb_array_list_gives_the_frames_of_the_whole_throw():
    env = gym.make(ENV_ID, render_mode="rgb_array_list", render_fps=25, render_width=160, render_height=120)
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([0.0, 0.0, 0.5]))
    frames = env.render()
    duration = env.unwrapped._throw_trajectory().shape[0] - 1
    assert len(frames) >= 1 + math.floor(duration * env.unwrapped.dt * 25)  # the hand, then 25 per second
    assert all(frame.shape == (120, 160, 3) for frame in frames)
    assert env.render() == []  # frames are returned once
    env.close()
    env.close()


def test_record_throws_writes_a_gif(tmp_path):
    from PIL import Image

    env = gym.make(ENV_ID, render_mode="rgb_array_list", render_fps=20, render_width=160, render_height=120)
    path = record_throws(env, tmp_path / "throws.gif", n_throws=2, seed=0)
    with Image.open(path) as gif:
        assert gif.size == (160, 120) and gif.n_frames > 10
    with pytest.raises(ValueError, match="rgb_array_list"):
        record_throws(gym.make(ENV_ID, render_mode="rgb_array"), tmp_path / "x.gif")


def test_human_mode_plays_headless():
    env = gym.make(ENV_ID, render_mode="human", render_fps=50, max_sim_time=0.4, render_width=160, render_height=120)
    env.reset(seed=0)
    env.step(np.array([-0.5, 0.0, 0.0]))
    assert env.render() is None
    env.close()
    env.close()


def test_missing_pygame_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "pygame", None)  # `import pygame` now raises ImportError
    env = gym.make(ENV_ID, render_mode="rgb_array")
    env.reset(seed=0)
    with pytest.raises(DependencyNotInstalled, match=r"box_toss_env\[render\]"):
        env.render()


def test_close_twice_without_rendering():
    env = gym.make(ENV_ID)
    env.close()
    env.close()
