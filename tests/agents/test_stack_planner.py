"""The ceiling planner of BoxToss-Stack-v0: it builds a whole stack with its default budget, it leaves the env's
scene as it was while it searches, and its command aims at the stack's top."""

import gymnasium as gym
import numpy as np

import box_toss_env  # noqa: F401  (registers the ids)
from agents.stack_planner import (
    BUDGETS,
    StackPlanner,
    StackPlannerSettings,
    budget_table,
    command_actions,
    run_episodes,
)
from box_toss_env.envs import stack_task


def test_the_planner_stacks_a_hand_of_three():
    result = run_episodes(2, StackPlannerSettings(), first_seed=10_000, env_kwargs={"n_boxes": 3})
    assert result["success_rate"] == 1.0 and result["fall_rate"] == 0.0
    assert result["mean_height"] >= 0.9 * 3 * 0.15
    assert 0 < result["simulated_per_throw"] <= 64 + 3 * 32
    table = budget_table([{"name": "default", "first_seed": 10_000, **result}])
    assert "| default (64, 32, 6, 3) | 2 (10000...) | 100.0% |" in table


def test_planning_leaves_the_scene_and_the_throw_made_is_the_one_scored():
    env = gym.make("BoxToss-Stack-v0", n_boxes=2)
    observation, _ = env.reset(seed=3)
    planner = StackPlanner(StackPlannerSettings(initial=8, population=4, elite=2, iterations=1))
    observation, *_ = env.step(planner.plan(env, observation))
    scene = env.unwrapped.scene[0].copy()
    action = planner.plan(env, observation)
    np.testing.assert_array_equal(env.unwrapped.scene[0], scene)
    expected = env.unwrapped.try_throws(action[None]).reward[0]
    _, reward, *_ = env.step(action)
    assert reward == expected
    assert planner.simulated >= 2 * 8


def test_the_command_touches_down_on_the_stack_top():
    """The command's throw passes through the touchdown point: the centre at the target x, the stack's height plus
    the half width (lying flat), after the flight time."""
    env = gym.make("BoxToss-Stack-v0", max_spin=20.0)
    observation, _ = env.reset(seed=0)
    observation = observation.copy()
    tail = stack_task.BODY_SIZE * 4
    observation[tail + stack_task.G_HEIGHT] = 0.4
    settings = StackPlannerSettings()
    action = command_actions(observation, np.array([[0.0, 0.0, 0.0]]), env.unwrapped.config, settings)
    release = np.array([observation[tail + stack_task.H_X], observation[tail + stack_task.H_Y], 0.0])
    state = stack_task.thrown_states(release, action, env.unwrapped.config)[0]
    flight_time = 0.5 * sum(settings.flight_time_range)
    x = observation[tail + stack_task.H_X] + state[3] * flight_time
    y = observation[tail + stack_task.H_Y] + state[4] * flight_time - 0.5 * 9.81 * flight_time**2
    assert abs(x - observation[tail + stack_task.G_TARGET_X]) < 1e-5
    assert abs(y - (0.4 + 0.5 * observation[tail + stack_task.H_WIDTH])) < 1e-5
    assert set(BUDGETS) == {"small", "default", "large"}


def test_a_zoo_run_folder_is_evaluated_with_its_normalisation(tmp_path):
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from agents.stack_planner import play_episodes, zoo_policy
    from box_toss_env.envs.stack_commands import StackCommands

    venv = VecNormalize(DummyVecEnv([lambda: StackCommands(gym.make("BoxToss-Stack-v0"))]), norm_reward=False)
    model = PPO("MlpPolicy", venv, n_steps=8, batch_size=8, n_epochs=1, seed=0)
    model.learn(8)
    model.save(tmp_path / "BoxToss-Stack-v0.zip")
    (tmp_path / "BoxToss-Stack-v0").mkdir()
    venv.save(str(tmp_path / "BoxToss-Stack-v0" / "vecnormalize.pkl"))
    result = play_episodes(2, zoo_policy(tmp_path))
    assert result["episodes"] == 2 and 2 <= result["throws"] <= 8 and 0.0 <= result["success_rate"] <= 1.0


def test_saved_rows_make_one_table_ordered_by_budget(tmp_path):
    from agents.stack_planner import save_row, saved_rows

    path = tmp_path / "rows.json"
    row = {
        "episodes": 3,
        "first_seed": 5,
        "success_rate": 0.5,
        "mean_height": 0.4,
        "fall_rate": 0.0,
        "simulated_per_throw": 10.0,
        "seconds": 1.0,
    }
    save_row({**row, "name": "large", "budget": {"initial": 1, "population": 2, "elite": 3, "iterations": 4}}, path)
    save_row({**row, "name": "small", "budget": {"initial": 5, "population": 6, "elite": 7, "iterations": 8}}, path)
    rows = save_row(
        {
            **row,
            "name": "small",
            "success_rate": 1.0,
            "budget": {"initial": 5, "population": 6, "elite": 7, "iterations": 8},
        },
        path,
    )
    assert [r["name"] for r in rows] == ["small", "large"] and saved_rows(path) == rows
    table = budget_table(rows).splitlines()
    assert table[-2].startswith("| small (5, 6, 7, 8) | 3 (5...) | 100.0% |") and table[-1].startswith("| large")
