"""The oracle's simulator on BoxToss-OnBox-v0: each planned throw is the env's own (base box included)."""

import gymnasium as gym
import numpy as np

import box_toss_env  # noqa: F401  (registers the ids)
from agents.evaluation import draw_targets, throw
from agents.oracle import OraclePlanner, OracleSettings, ThrowSimulator, episodes_from_infos
from box_toss_env.physics.grouped import GroupedSimulator


def test_the_oracles_simulated_throws_are_the_envs_throws():
    env = gym.make("BoxToss-OnBox-v0")
    seeds = np.arange(10_000, 10_006)
    _, infos = draw_targets(env, seeds)
    actions = np.random.default_rng(0).uniform(-1, 1, (len(seeds), 3))
    simulator = ThrowSimulator(env)
    assert isinstance(simulator.simulator, GroupedSimulator)
    reward, success, _ = simulator.rewards(episodes_from_infos(infos), actions)
    thrown = throw(env, seeds, actions, infos)
    np.testing.assert_array_equal(reward, thrown.reward)
    np.testing.assert_array_equal(success, thrown.success)


def test_a_small_search_finds_throws_onto_the_base():
    env = gym.make("BoxToss-OnBox-v0")
    seeds = np.arange(10_000, 10_004)
    observations, infos = draw_targets(env, seeds)
    planner = OraclePlanner(OracleSettings(initial=64, population=16, elite=4, iterations=4))
    thrown = throw(env, seeds, planner.act(observations, infos, env), infos)
    assert thrown.success.sum() >= 2
