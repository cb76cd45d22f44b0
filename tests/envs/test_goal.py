"""BoxToss-Goal-v0: env checkers, compute_reward against the step's reward and BoxToss-v0's, seeding, HER
training, the SAC recipe through our config and through RL Zoo."""

import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import box_toss_env  # noqa: F401
from box_toss_env.envs import goal
from box_toss_env.envs.ballistic import ballistic_actions

REPO = Path(__file__).resolve().parents[2]


def make(**kwargs):
    return gymnasium.make("BoxToss-Goal-v0", **kwargs)


def test_env_checkers_pass_without_warnings():
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(make().unwrapped)
        sb3_check_env(make().unwrapped)
        check_env(make(target_face="mixed", observe_dynamics=True, mass_range=(1.0, 3.0)).unwrapped)


def test_spaces_are_not_changed_by_stepping():
    env = make().unwrapped
    spaces = (env.observation_space, env.throw_env.observation_space)
    env.reset(seed=0)
    obs, *_ = env.step(env.action_space.sample())
    assert (env.observation_space, env.throw_env.observation_space) == spaces
    assert isinstance(env.observation_space, gymnasium.spaces.Dict)
    assert obs in env.observation_space


@pytest.mark.parametrize("target_face", ["any", "mixed"])
def test_step_reward_is_compute_reward_and_box_toss_reward(target_face):
    """Over 150 throws (half of them the ballistic prior's, which often succeed, half random): the goal env sees
    the same episodes as BoxToss-v0 from the same seed; its reward is exactly compute_reward of its goals, batched
    or not, and BoxToss-v0's reward up to float32 rounding of the goals, with the same success."""
    env, flat = make(target_face=target_face), gymnasium.make("BoxToss-v0", target_face=target_face)
    rng = np.random.default_rng(0)
    rewards, achieved, desired, successes = [], [], [], []
    for seed in range(150):
        obs, _ = env.reset(seed=seed)
        flat_obs, _ = flat.reset(seed=seed)
        np.testing.assert_array_equal(obs["observation"], flat_obs)
        assert obs["achieved_goal"][goal.GOAL_AT_REST] == 0.0  # in the hand
        if seed % 2:
            action = rng.uniform(-1, 1, 3).astype(np.float32)
        else:
            action = ballistic_actions(flat_obs[None], np.zeros((1, 3)), env.unwrapped.config)[0][0].astype(np.float32)
        obs, reward, terminated, truncated, info = env.step(action)
        _, flat_reward, *_, flat_info = flat.step(action)
        assert terminated and not truncated
        assert reward == float(env.unwrapped.compute_reward(obs["achieved_goal"], obs["desired_goal"], info))
        assert reward == pytest.approx(flat_reward, abs=1e-5)
        assert info["is_success"] == flat_info["success"]
        rewards.append(reward)
        achieved.append(obs["achieved_goal"])
        desired.append(obs["desired_goal"])
        successes.append(info["is_success"])
    assert 20 <= sum(successes) <= 140  # both outcomes are exercised
    achieved, desired = np.array(achieved), np.array(desired)
    np.testing.assert_array_equal(env.unwrapped.compute_reward(achieved, desired, [{}] * len(rewards)), rewards)
    np.testing.assert_array_equal(
        env.unwrapped.compute_reward(achieved.reshape(15, 10, 7), desired.reshape(15, 10, 7), None).ravel(), rewards
    )
    # relabelled as HER does: each landing is a success for its own achieved goal when it came to rest
    relabelled = env.unwrapped.compute_success(achieved, achieved)
    np.testing.assert_array_equal(relabelled, achieved[:, goal.GOAL_AT_REST] > 0.5)
    assert env.unwrapped.compute_terminated(achieved, desired, None).all()
    assert not env.unwrapped.compute_truncated(achieved, desired, None).any()


def test_goal_columns():
    goals = goal.achieved_goals(
        np.array([1.0, 2.0, 3.0]), np.array([0.1, -np.pi / 2 - 0.2, 3.0]), np.array([1.0, 0.0, 1.0])
    )
    np.testing.assert_allclose(goals[:, goal.GOAL_TILT], [0.1, -0.2, 3.0 - np.pi], rtol=1e-6)
    np.testing.assert_array_equal(np.argmax(goals[:, goal.GOAL_FACES], axis=1), [0, 1, 2])
    np.testing.assert_array_equal(goals[:, goal.GOAL_AT_REST], [1.0, 0.0, 1.0])


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
    env = make()
    first = env.reset(seed=3)[0]["desired_goal"]
    assert not np.array_equal(env.reset(seed=4)[0]["desired_goal"], first)


@pytest.mark.parametrize("target_face", ["any", "mixed"])
def test_goal_observations_of_box_toss_observations_are_the_goal_envs(target_face):
    """A goal policy evaluated on BoxToss-v0's targets sees what the goal env's reset gives for the same seed."""
    throw_env, goal_env = gymnasium.make("BoxToss-v0", target_face=target_face), make(target_face=target_face)
    seeds = range(10_000, 10_020)
    flat = np.stack([throw_env.reset(seed=seed)[0] for seed in seeds])
    dicts = [goal_env.reset(seed=seed)[0] for seed in seeds]
    built = goal.goal_observations(flat)
    for key in ("observation", "achieved_goal", "desired_goal"):
        np.testing.assert_allclose(built[key], np.stack([d[key] for d in dicts]), rtol=0, atol=1e-6)


def test_ballistic_commands_around_the_goal_env_are_box_toss_ones():
    from box_toss_env.envs.ballistic import BallisticThrows

    env, flat = BallisticThrows(make()), gymnasium.make("BoxToss-v0")
    command = np.array([0.2, -0.1, 0.3], dtype=np.float32)
    for seed in (5, 6):
        env.reset(seed=seed)
        flat_obs, _ = flat.reset(seed=seed)
        _, reward, *_ = env.step(command)
        actions, _ = ballistic_actions(flat_obs[None], command, flat.unwrapped.config)
        _, flat_reward, *_ = flat.step(actions[0])
        assert reward == pytest.approx(flat_reward, abs=1e-4)


def test_base_box_is_refused():
    with pytest.raises(ValueError, match="base_box"):
        make(base_box=True)


def test_renders_the_throw():
    env = make(render_mode="rgb_array")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.std() > 0


def test_record_throws_records_the_goal_env(tmp_path):
    from box_toss_env.envs import record_throws

    env = make(render_mode="rgb_array_list", render_width=120, render_height=80)
    path = record_throws(env, tmp_path / "goal.gif", n_throws=1, seed=0)
    assert path.stat().st_size > 0


@pytest.mark.parametrize("algo", ["SAC", "TD3"])
def test_her_trains_a_few_hundred_steps(algo):
    import stable_baselines3
    from stable_baselines3 import HerReplayBuffer

    model = getattr(stable_baselines3, algo)(
        "MultiInputPolicy",
        make(),
        replay_buffer_class=HerReplayBuffer,
        replay_buffer_kwargs={"n_sampled_goal": 4, "goal_selection_strategy": "future"},
        learning_starts=50,
        batch_size=32,
        policy_kwargs={"net_arch": [32]},
        seed=0,
        device="cpu",
    )
    model.learn(200)
    buffer = model.replay_buffer
    assert isinstance(buffer, HerReplayBuffer) and buffer.size() == 200
    # relabelled samples get compute_reward's rewards: with goals that are achieved ones, at-rest landings succeed
    samples = buffer.sample(256)
    rewards = make().unwrapped.compute_reward(
        samples.next_observations["achieved_goal"].numpy(), samples.observations["desired_goal"].numpy(), None
    )
    np.testing.assert_allclose(samples.rewards.numpy().ravel(), rewards, rtol=1e-5, atol=1e-5)


def test_sac_recipe_passes_her_through():
    from stable_baselines3 import HerReplayBuffer

    from agents import config

    entry = config.load_hyperparams("sac", "BoxToss-Goal-v0")
    config.check_config(entry, "sac")
    kwargs = config.algorithm_kwargs(entry, "sac")
    assert kwargs["replay_buffer_class"] is HerReplayBuffer
    assert kwargs["replay_buffer_kwargs"]["goal_selection_strategy"] == "future"
    assert kwargs["policy"] == "MultiInputPolicy"


def test_zoo_trains_the_goal_recipe(tmp_path):
    pytest.importorskip("rl_zoo3")
    train = [
        sys.executable,
        "-m",
        "rl_zoo3.train",
        "--algo",
        "sac",
        "--env",
        "BoxToss-Goal-v0",
        "--gym-packages",
        "box_toss_env",
        "--conf-file",
        str(REPO / "agents" / "hyperparams" / "sac.yml"),
        "-n",
        "300",
        "-f",
        str(tmp_path),
        "--eval-freq",
        "-1",
        "--seed",
        "1",
        "-params",
        "learning_starts:64",
        "buffer_size:1000",
    ]
    done = subprocess.run(train, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert (tmp_path / "sac" / "BoxToss-Goal-v0_1" / "BoxToss-Goal-v0.zip").exists()
