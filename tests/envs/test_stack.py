"""BoxToss-Stack-v0: a hand of boxes thrown one per step onto a persistent scene. Registration and both
checkers, determinism, candidate throws on copies of the scene equal to the throw made, the physics of
stacking (a box lobbed onto the stack stays there; one thrown into it knocks boxes off and ends the
episode), the episode's end, the observation's mask, rendering, bad arguments and a PPO smoke run."""

import math
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.error import ResetNeeded

import box_toss_env  # noqa: F401  (registers the ids)
from box_toss_env.envs import stack_task
from box_toss_env.envs.stack import BoxTossStackEnv
from box_toss_env.envs.stack_commands import StackCommands, command_actions
from box_toss_env.physics import layout

ENV_ID = "BoxToss-Stack-v0"
LOB = np.array([[0.6, 0.0, 0.0]])
"""A command by hand (``envs.stack_commands``): a lob of 1.08 s touching down flat on the stack's top, at the
target x."""


def lob(env, observation) -> np.ndarray:
    return command_actions(observation, LOB, env.unwrapped.config)[0].astype(np.float32)


def test_registered_with_its_spaces():
    env = gym.make(ENV_ID)
    assert isinstance(env.unwrapped, BoxTossStackEnv)
    assert env.unwrapped.flags.boxes_collide
    assert env.observation_space.shape == (stack_task.BODY_SIZE * 4 + stack_task.TAIL_SIZE,)
    assert env.action_space.shape == (3,)
    assert np.all(np.isfinite(env.observation_space.low)) and np.all(np.isfinite(env.observation_space.high))
    assert gym.make(ENV_ID, n_boxes=7).observation_space.shape == (stack_task.BODY_SIZE * 7 + stack_task.TAIL_SIZE,)
    assert len(stack_task.observation_names(env.unwrapped.config)) == env.observation_space.shape[0]


@pytest.mark.parametrize("kwargs", [{}, {"n_boxes": 2, "mass_range": (2.0, 2.0), "box_length_range": (0.4, 0.4)}])
def test_gymnasium_check_env_without_warnings(kwargs):
    from gymnasium.utils.env_checker import check_env

    env = gym.make(ENV_ID, **kwargs)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)


def test_sb3_check_env_without_warnings():
    from stable_baselines3.common.env_checker import check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make(ENV_ID).unwrapped, warn=True)


def rollout(seed: int, actions: np.ndarray, **kwargs):
    env = gym.make(ENV_ID, **kwargs)
    observations, rewards, infos = [env.reset(seed=seed)[0]], [], []
    for action in actions:
        observation, reward, terminated, truncated, info = env.step(action)
        observations.append(observation)
        rewards.append(reward)
        infos.append(info)
        if terminated:
            break
    return observations, rewards, infos


def test_deterministic_under_seeds_bit_for_bit():
    actions = np.random.default_rng(3).uniform(-1, 1, (4, 3)).astype(np.float32)
    first, second = rollout(11, actions), rollout(11, actions)
    for a, b in zip(first[0], second[0], strict=True):
        assert a.tobytes() == b.tobytes()
    assert first[1] == second[1] and first[2] == second[2]
    other = rollout(12, actions)
    assert other[0][0].tobytes() != first[0][0].tobytes()


def test_reward_is_the_sum_of_its_terms_and_the_episode_ends_after_the_hand():
    env = gym.make(ENV_ID)
    observation, _ = env.reset(seed=5)
    for k in range(4):
        observation, reward, terminated, truncated, info = env.step(lob(env, observation))
        assert reward == sum(info[name] for name in stack_task.REWARD_TERMS)
        assert not truncated and info["thrown"] == k + 1
        assert observation[stack_task.BODY_SIZE * k + stack_task.B_THROWN] == 1.0
        assert observation[stack_task.BODY_SIZE * 4 + stack_task.G_LEFT] == 3 - k
        if terminated:
            break
    assert terminated and k == 3 and not info["fell"]
    tail = observation[stack_task.BODY_SIZE * 4 :]
    assert tail[stack_task.H_IN_HAND] == 0.0 and np.all(tail[: stack_task.H_IN_HAND] == 0.0)
    with pytest.raises(ResetNeeded):
        env.step(env.action_space.sample())


def test_the_mask_hides_boxes_not_thrown_yet():
    env = gym.make(ENV_ID)
    observation, info = env.reset(seed=2)
    bodies = observation[: stack_task.BODY_SIZE * 4].reshape(4, stack_task.BODY_SIZE)
    assert np.all(bodies[:, : stack_task.B_LENGTH] == 0.0) and np.all(bodies[:, stack_task.B_THROWN] == 0.0)
    np.testing.assert_array_equal(bodies[:, stack_task.B_LENGTH], info["box_lengths"].astype(np.float32))
    observation, *_ = env.step(lob(env, observation))
    bodies = observation[: stack_task.BODY_SIZE * 4].reshape(4, stack_task.BODY_SIZE)
    assert bodies[0, stack_task.B_THROWN] == 1.0 and bodies[0, stack_task.B_Y] > 0.0
    assert np.all(bodies[1:, : stack_task.B_LENGTH] == 0.0) and np.all(bodies[1:, stack_task.B_THROWN] == 0.0)


@pytest.mark.parametrize("seed", [0, 5, 9])  # (the lob stands the first box on its end for seeds 1 and 3)
def test_a_box_lobbed_onto_the_stack_stays_on_it(seed):
    """Two lobs flat onto the target: the second box rests on the first, which did not move."""
    env = gym.make(ENV_ID)
    observation, info = env.reset(seed=seed)
    widths = info["box_widths"]
    observation, reward, _, _, first = env.step(lob(env, observation))
    assert first["stack_size"] == 1 and abs(first["stack_height"] - widths[0]) < 0.005
    assert reward == pytest.approx(5.0 * first["stack_height"])
    base = env.unwrapped.scene[0][0].copy()
    observation, reward, terminated, _, second = env.step(lob(env, observation))
    state = env.unwrapped.scene[0]
    assert not terminated and not second["fell"] and second["at_rest"] and second["stack_size"] == 2
    assert abs(second["stack_height"] - widths[:2].sum()) < 0.01  # lying flat on the first box
    assert abs(state[1, 0] - state[0, 0]) < 0.5 * info["box_lengths"][0]  # its centre over the lower box's top
    assert np.abs(state[0, :3] - base[:3]).max() < 0.005  # the box below stayed where it was
    assert reward == pytest.approx(5.0 * widths[1], abs=0.05)


def test_the_stack_sleeps_through_a_throw_that_does_not_reach_it():
    """The pile asleep at the end of a throw stays asleep in the next (the warm start carried from throw to throw):
    a box thrown away from it costs the stack no step and leaves it bit for bit where it was."""
    env = gym.make(ENV_ID)
    observation, _ = env.reset(seed=0)
    for _ in range(2):
        observation, *_ = env.step(lob(env, observation))
    unwrapped = env.unwrapped
    stack = unwrapped.scene[0].copy()
    away = stack_task.actions_of_throws(np.array([3.0]), np.array([math.pi - 0.5]), np.array([0.0]), unwrapped.config)
    _, _, _, _, info = env.step(away[0])
    assert info["at_rest"] and not info["fell"]
    stats = unwrapped._batch.stats[0]
    assert not stats[:2, layout.N_STEPS].any() and stats[2, layout.N_STEPS] > 0
    assert unwrapped.scene[0][:2].tobytes() == stack.tobytes()


def test_a_box_that_knocks_the_stack_over_ends_the_episode():
    env = gym.make(ENV_ID)
    observation, _ = env.reset(seed=0)
    for _ in range(2):
        observation, *_ = env.step(lob(env, observation))
    unwrapped = env.unwrapped
    height = observation[stack_task.BODY_SIZE * 4 + stack_task.G_HEIGHT]
    # a fast, nearly flat throw straight at the stack's top box: 8 m/s, aimed a little below its top
    hand = unwrapped.core.task.hands(unwrapped._batch.episodes)[0, 2]
    dx = unwrapped.target_x - hand[stack_task.E_RELEASE_X]
    direction = math.atan2(height - 0.1 - hand[stack_task.E_RELEASE_Y], dx)
    action = stack_task.actions_of_throws(np.array([8.0]), np.array([direction]), np.array([0.0]), unwrapped.config)[0]
    observation, reward, terminated, truncated, info = env.step(action)
    assert info["fell"] and terminated and not truncated
    assert info["reward_fall"] == -1.0 and info["stack_height"] < height - 0.05
    assert reward == sum(info[name] for name in stack_task.REWARD_TERMS)
    with pytest.raises(ResetNeeded):
        env.step(action)


def test_candidate_throws_on_copies_of_the_scene_are_the_throw_made():
    env = gym.make(ENV_ID)
    observation, _ = env.reset(seed=7)
    observation, *_ = env.step(lob(env, observation))
    unwrapped = env.unwrapped
    before = unwrapped.scene[0]
    actions = np.random.default_rng(0).uniform(-1, 1, (6, 3))
    actions[2] = lob(env, observation)
    tried_throws = unwrapped.try_throws(actions)
    tried = tried_throws.states
    np.testing.assert_array_equal(unwrapped.scene[0], before)  # the env's own scene is untouched
    for i in (2, 4):
        copy = pickle.loads(pickle.dumps(unwrapped))
        _, reward, _, _, info = copy.step(actions[i])
        assert copy.scene[0].tobytes() == tried[i].tobytes()
        assert reward == tried_throws.reward[i] and info == {key: value[i] for key, value in tried_throws.info.items()}


def test_render_draws_every_box_the_height_and_the_score():
    pytest.importorskip("pygame")
    env = gym.make(ENV_ID, render_mode="rgb_array")
    observation, _ = env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (400, 600, 3) and frame.dtype == np.uint8
    observation, reward, *_ = env.step(lob(env, observation))
    frame = env.render()
    text = env.unwrapped._renderer.drawn_text["lines"]
    assert any("stack height" in line for line in text) and any(f"{reward:+.2f}" in line for line in text)
    assert len(env.unwrapped.drawn_scene()["position"]) == 2  # the box thrown and the one in the hand


@pytest.mark.parametrize(
    "kwargs, error",
    [
        ({"n_boxes": 0}, ValueError),
        ({"n_boxes": 17}, ValueError),
        ({"n_boxes": 2.5}, TypeError),
        ({"box_width_range": (0.2, 0.4), "box_length_range": (0.3, 0.5)}, ValueError),
        ({"target_x_range": (0.2, 1.0)}, ValueError),
        ({"target_radius": 0.0}, ValueError),
        ({"release_height_range": (0.1, 0.2)}, ValueError),
        ({"render_mode": "video"}, ValueError),
        ({"success_fraction": 1.5}, ValueError),
        ({"dt": 0.0}, ValueError),
    ],
)
def test_bad_arguments_are_named(kwargs, error):
    with pytest.raises(error):
        gym.make(ENV_ID, **kwargs)


def test_ppo_smoke():
    from stable_baselines3 import PPO

    model = PPO("MlpPolicy", gym.make(ENV_ID, n_boxes=2), n_steps=16, batch_size=16, n_epochs=1, seed=0)
    model.learn(32)
    action, _ = model.predict(model.get_env().reset(), deterministic=True)
    assert action.shape == (1, 3) and np.all(np.abs(action) <= 1.0)


def test_make_vec_sync_runs_single_envs_with_their_results():
    envs = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync")
    assert isinstance(envs, gym.vector.SyncVectorEnv)
    actions = np.random.default_rng(1).uniform(-1, 1, (3, 2, 3)).astype(np.float32)
    observations, _ = envs.reset(seed=20)
    single = [rollout(20 + i, actions[:, i]) for i in range(2)]
    for i in range(2):
        assert observations[i].tobytes() == single[i][0][0].tobytes()
    _, rewards, _, _, _ = envs.step(actions[0])
    for i in range(2):
        assert rewards[i] == single[i][1][0]


def single_episodes(seed: int, policy, n_steps: int, **kwargs):
    """(observation, reward, terminated, info) after each of ``n_steps`` steps of one env seeded ``seed``, with the
    vector env's same-step autoreset: after an episode ends, the next one starts at once (the reset's observation
    returned, the ended one's kept as ``final``)."""
    env = gym.make(ENV_ID, **kwargs)
    observation, _ = env.reset(seed=seed)
    rows = []
    for step in range(n_steps):
        observation, reward, terminated, _, info = env.step(policy(env, observation, step))
        final = observation
        if terminated:
            observation, _ = env.reset()
        rows.append((observation, reward, terminated, info, final))
    return rows


@pytest.mark.parametrize("threads", [1, 2])
def test_the_native_batch_is_the_single_envs_bit_for_bit(threads):
    """Envs at different throws of their episodes (scenes of different sizes), episodes ending at different steps
    (lobs build stacks, random throws knock them over): every env's observation, reward, termination and info are
    the single env's seeded alike, bit for bit, whatever the thread count."""
    from box_toss_env.envs.stack_vector import BoxTossStackVectorEnv

    n, n_steps = 4, 7
    rng = np.random.default_rng(8)
    random_actions = rng.uniform(-1, 1, (n_steps, n, 3)).astype(np.float32)
    lobbing = rng.random((n_steps, n)) < 0.7

    def policy(i):
        return lambda env, observation, step: lob(env, observation) if lobbing[step, i] else random_actions[step, i]

    envs = gym.make_vec(ENV_ID, num_envs=n, threads=threads)
    assert isinstance(envs, BoxTossStackVectorEnv)
    observations, _ = envs.reset(seed=30)
    singles = [single_episodes(30 + i, policy(i), n_steps) for i in range(n)]
    ended = 0
    for step in range(n_steps):
        actions = np.stack(
            [lob(envs.env, observations[i]) if lobbing[step, i] else random_actions[step, i] for i in range(n)]
        )
        observations, rewards, terminated, truncated, info = envs.step(actions)
        assert not truncated.any()
        for i in range(n):
            observation, reward, done, single_info, final = singles[i][step]
            assert observations[i].tobytes() == observation.tobytes()
            assert rewards[i] == reward and terminated[i] == done
            source = info["final_info"] if done else info
            for key, value in single_info.items():
                assert source[key][i] == value, key
            if done:
                assert info["final_obs"][i].tobytes() == final.tobytes()
                ended += 1
    assert ended >= 2


def test_stack_commands_act_through_the_command_map():
    """The wrapper throws what ``command_actions`` maps its command to; its observations and rewards are the env's."""
    wrapped = StackCommands(gym.make(ENV_ID))
    env = gym.make(ENV_ID)
    observation, _ = wrapped.reset(seed=4)
    assert observation.tobytes() == env.reset(seed=4)[0].tobytes()
    for _ in range(2):
        expected = env.step(lob(env, observation))
        observation, reward, terminated, _, info = wrapped.step(LOB[0])
        assert observation.tobytes() == expected[0].tobytes() and reward == expected[1]
    assert info["stack_size"] == 2 and not info["fell"]


def test_sb3_trains_on_the_native_batch():
    """SB3 through the batched env's adapter: a hand of two ends every episode at the second step, with its
    terminal observation, and PPO learns on it."""
    from stable_baselines3 import PPO

    from box_toss_env.wrappers.sb3_adapter import SB3VecEnvAdapter

    adapter = SB3VecEnvAdapter(gym.make_vec(ENV_ID, num_envs=4, n_boxes=2))
    adapter.reset()
    actions = np.random.default_rng(0).uniform(-1, 1, (2, 4, 3)).astype(np.float32)
    _, _, dones, _ = adapter.step(actions[0])
    assert not dones.any()  # nothing stood on the target before the first throw, so nothing could fall
    observations, _, dones, infos = adapter.step(actions[1])
    assert dones.all() and all(info["terminal_observation"].shape == observations[0].shape for info in infos)
    tail = stack_task.BODY_SIZE * 2
    assert np.all(observations[:, tail + stack_task.G_LEFT] == 2)  # the next episodes' hands, full
    model = PPO("MlpPolicy", adapter, n_steps=16, batch_size=32, n_epochs=1, seed=0)
    model.learn(64)
    assert model.num_timesteps == 64
