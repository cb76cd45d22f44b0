"""The evaluation's numbers, on policies whose outcome is known."""

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3 import PPO

from agents.evaluation import Throws, draw_targets, evaluate, scores, summarize, target_seeds
from agents.oracle import OraclePlanner, OracleSettings, ThrowSimulator, episodes_from_infos
from agents.policies import ConstantPolicy, RandomPolicy, TrainedPolicy
from box_toss_env.envs.ballistic import BallisticThrows

DROP = (-1.0, 0.0, 0.0)  # zero launch speed, no spin: the box falls out of the hand


def test_a_dropped_box_succeeds_exactly_when_its_bottom_face_is_the_target():
    """Dropped from rest at a small angle, the box settles on face 0, right below the hand. With a
    tolerance wider than the range, success is then known from the targets alone: exactly the
    episodes whose one target face ("exact") is face 0."""
    kwargs = {"target_face": "exact", "position_tolerance": 10.0}
    throws, _ = evaluate(ConstantPolicy(DROP), "BoxToss-v0", kwargs, target_seeds(128))
    face_0_targets = throws.target_faces[:, 0] == 1
    assert 0 < face_0_targets.sum() < 128
    assert (throws.face_down == 0).all() and throws.at_rest.all()
    np.testing.assert_array_equal(throws.success, face_0_targets)
    summary = summarize(throws, (1.0, 4.0))
    assert summary["success_rate"] == pytest.approx(face_0_targets.mean())
    assert summary["face_accuracy"] == pytest.approx(face_0_targets.mean())
    by_face = {row["kind"]: row for row in summary["by_face"]}
    assert by_face["face 0"]["success_rate"] == 1.0
    assert all(row["success_rate"] == 0.0 for kind, row in by_face.items() if kind != "face 0")
    assert sum(row["n"] for row in summary["by_face"]) == sum(row["n"] for row in summary["by_distance"]) == 128


def test_a_dropped_box_lands_below_the_hand_and_misses_every_default_target():
    env = gym.make("BoxToss-v0")
    seeds = target_seeds(64)
    _, infos = draw_targets(env, seeds)
    throws, _ = evaluate(ConstantPolicy(DROP), "BoxToss-v0", {}, seeds)
    release_x = np.array([info["release_x"] for info in infos])
    assert np.abs(throws.final_x - release_x).max() < 0.2
    result = scores(throws)
    assert result["success_rate"] == 0.0 and result["face_accuracy"] == 1.0  # any face counts
    assert result["mean_distance"] == pytest.approx(np.abs(throws.final_x - throws.target_x).mean())


def test_scores_on_hand_made_throws():
    throws = Throws(
        seeds=np.arange(4),
        target_x=np.array([1.0, 2.0, 3.0, 4.0]),
        target_faces=np.array([[1, 0, 1, 0]] * 4, dtype=np.int8),
        actions=np.zeros((4, 3)),
        final_x=np.array([1.05, 2.5, np.nan, 3.0]),
        face_down=np.array([0, 1, -1, 2]),
        at_rest=np.array([True, True, False, True]),
        success=np.array([True, False, False, False]),
        reward=np.array([0.95, -0.5, np.nan, -1.0]),
        failure=["", "", "energy gain", ""],
    )
    result = scores(throws)
    assert result["success_rate"] == 0.25
    assert result["mean_distance"] == pytest.approx((0.05 + 0.5 + 1.0) / 3)  # the failed throw is left out
    assert result["median_distance"] == pytest.approx(0.5)
    assert result["face_accuracy"] == 0.5  # faces 0 and 2 are targets; face 1 is not; the failure has none
    assert result["failures"] == 1
    summary = summarize(throws, (1.0, 4.0))
    assert summary["failure_reasons"] == {"energy gain": 1}
    assert [row["n"] for row in summary["by_distance"]] == [1, 0, 1, 0, 1, 1]


def test_throws_the_env_refuses_count_as_failures():
    """The seed scheme at the default step gains energy on hard throws; the env raises and the
    evaluation records a failure instead of stopping."""
    throws, _ = evaluate(ConstantPolicy((1.0, 0.5, 1.0)), "BoxToss-v0", {"solver": "seed"}, target_seeds(16))
    assert "energy gain" in throws.failure
    failed = np.array([reason != "" for reason in throws.failure])
    assert not throws.success[failed].any() and np.isnan(throws.final_x[failed]).all()
    assert scores(throws)["failures"] == failed.sum()


def test_evaluation_is_deterministic_and_the_random_baseline_reproducible():
    first, _ = evaluate(RandomPolicy(seed=3), "BoxToss-v0", {}, target_seeds(32))
    second, _ = evaluate(RandomPolicy(seed=3), "BoxToss-v0", {}, target_seeds(32))
    np.testing.assert_array_equal(first.actions, second.actions)
    np.testing.assert_array_equal(first.final_x, second.final_x)


@pytest.mark.parametrize("kwargs", [{}, {"target_face": "mixed", "restitution_range": (0.1, 0.5)}])
def test_the_planners_batched_throws_are_the_envs_throws(kwargs):
    env = gym.make("BoxToss-v0", **kwargs)
    seeds = target_seeds(24)
    _, infos = draw_targets(env, seeds)
    actions = np.random.default_rng(0).uniform(-1, 1, (len(seeds), 3))
    reward, success, distance = ThrowSimulator(env).rewards(episodes_from_infos(infos), actions)
    for i, seed in enumerate(seeds):
        env.reset(seed=int(seed))
        _, env_reward, _, _, info = env.step(actions[i])
        assert reward[i] == pytest.approx(env_reward, abs=1e-12)
        assert success[i] == info["success"] and distance[i] == pytest.approx(info["distance"], abs=1e-12)


def test_the_oracle_lands_nearly_every_throw():
    planner = OraclePlanner(OracleSettings(initial=128, population=32, iterations=4))
    throws, _ = evaluate(planner, "BoxToss-v0", {}, target_seeds(24))
    assert scores(throws)["success_rate"] >= 0.9
    assert planner.simulated >= 24 * 128


def test_a_policy_trained_in_ballistic_commands_throws_as_the_wrapper_does():
    """TrainedPolicy maps the model's commands to env actions exactly as the training wrapper did."""
    wrapped = BallisticThrows(gym.make("BoxToss-ShortEnd-v0"))
    model = PPO("MlpPolicy", wrapped, seed=0, device="cpu")
    policy = TrainedPolicy(model, env_wrapper="box_toss_env.envs.ballistic.BallisticThrows")
    throws, _ = evaluate(policy, "BoxToss-ShortEnd-v0", seeds=range(8))
    commands, _ = model.predict(np.stack([wrapped.reset(seed=seed)[0] for seed in range(8)]), deterministic=True)
    for seed in range(8):
        wrapped.reset(seed=seed)
        _, _, _, _, info = wrapped.step(commands[seed])
        assert throws.final_x[seed] == info["final_x"]
