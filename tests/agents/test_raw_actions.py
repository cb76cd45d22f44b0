"""agents.raw_actions: where the throws that succeed lie in the env's own actions."""

import numpy as np
import pytest

from agents import raw_actions
from agents.policies import ConstantPolicy
from box_toss_env.envs import task_columns, task_config


def test_by_face_gives_each_target_face_the_range_of_its_solutions_in_env_actions():
    rows = raw_actions.by_face("BoxToss-ThisSideUp-v0", n_targets=12, draws=2)
    assert [row["face"] for row in rows] == [0, 1, 2, 3]
    assert sum(row["targets"] for row in rows) == 12
    for row in rows:
        assert 0 <= row["solved"] <= row["targets"]
        if row["solved"]:
            low, high = np.array(row["low"]), np.array(row["high"])
            assert np.all(-1.0 <= low) and np.all(low <= high) and np.all(high <= 1.0)
            assert 0.0 <= row["noisy"] <= 1.0
    text = raw_actions.face_table("BoxToss-ThisSideUp-v0", rows, 0.01, "the command")
    assert "first 12 of BoxToss-ThisSideUp-v0's test targets" in text and text.count("| face ") == 4


def test_by_face_takes_one_variant_whose_targets_name_one_face(capsys):
    with pytest.raises(SystemExit):
        raw_actions.main(["--by-face", "--envs", "BoxToss-v0"])
    assert "--by-face" in capsys.readouterr().err


def test_reach_scores_noisy_throws_around_a_policys_long_side_throws_for_each_short_end():
    policy = ConstantPolicy((0.0, 0.0, 0.0))
    result = raw_actions.reach(policy, "BoxToss-ThisSideUp-v0", n_targets=6, draws=3, sigmas=(0.01, 0.3))
    assert [row["face"] for row in result["own"]] == [0, 1, 2, 3]
    assert all(row["spin"] == 0.0 and 0.0 <= row["success"] <= 1.0 for row in result["own"])
    assert len(result["zero"]) == 4 and sum(result["zero"]) == pytest.approx(1.0)
    assert [(row["start"], row["end"]) for row in result["reach"]] == [(0, 1), (0, 3), (2, 1), (2, 3)]
    for row in result["reach"]:
        assert list(row["noisy"]) == ["0.01", "0.3"]
        assert all(0.0 <= row["noisy"][s] <= row["targets"][s] <= 1.0 for s in row["noisy"])
    assert [row["alpha"] for row in result["line"]] == list(raw_actions.LINE_STEPS)
    for row in result["line"]:  # the two long-side throws are the same constant throw: so is every point
        assert row[1] == result["line"][0][1] and row[3]["success"] == result["line"][0][3]["success"]
        assert row["distance"] >= 0.0
    text = raw_actions.reach_table("BoxToss-ThisSideUp-v0", result, 6, 3, "the command")
    assert "first 6 of BoxToss-ThisSideUp-v0's test targets" in text and "| sigma 0.3 |" in text
    assert sum(line.startswith("| face ") for line in text.splitlines()) == 8
    assert sum(line.startswith("| 0.") or line.startswith("| 1.0") for line in text.splitlines()) == 11


def test_with_face_makes_every_target_one_of_the_given_face():
    observations = np.zeros((2, 12), dtype=np.float32)
    observations[:, 8] = 1.0
    episodes = task_config.Episodes(np.zeros((2, task_columns.EPISODE_SIZE)))
    obs, relabelled = raw_actions.with_face(observations, episodes, 3)
    assert obs[:, 8:12].tolist() == [[0, 0, 0, 1]] * 2 and observations[0, 8] == 1.0
    assert relabelled.data[:, task_columns.EP_TARGET_FACES].tolist() == [[0, 0, 0, 1]] * 2


def test_reach_takes_one_variant_whose_targets_name_one_face(capsys):
    with pytest.raises(SystemExit):
        raw_actions.main(["--reach", "runs/none", "--envs", "BoxToss-v0"])
    assert "--reach" in capsys.readouterr().err


def test_course_gives_each_checkpoint_its_spread_and_per_face_throws(tmp_path):
    import gymnasium as gym
    from stable_baselines3 import PPO

    (tmp_path / "checkpoints").mkdir()
    env = gym.make("BoxToss-ThisSideUp-v0")
    PPO("MlpPolicy", env, policy_kwargs={"log_std_init": -2.5}, seed=0).save(tmp_path / "checkpoints" / "ppo_0_steps")
    env.close()
    rows = raw_actions.course(tmp_path, "BoxToss-ThisSideUp-v0", n_targets=4, steps=[0])
    assert [row["steps"] for row in rows] == [0]
    assert rows[0]["std"] == pytest.approx([np.exp(-2.5)] * 3, rel=1e-5)
    assert len(rows[0]["faces"]) == 4
    for face in rows[0]["faces"]:  # an untrained mean is near action 0: face 0 (methodology/raw-actions.md)
        assert abs(face["spin"]) < 0.05 and 0.0 <= face["success"] <= 1.0 and 0.0 <= face["face 0"] <= 1.0
    text = raw_actions.course_table("BoxToss-ThisSideUp-v0", rows, 4, "--steps 0")
    assert "| 0 | 0.082, 0.082, 0.082 |" in text


def test_steps_goes_with_reach(capsys):
    with pytest.raises(SystemExit):
        raw_actions.main(["--steps", "100", "--envs", "BoxToss-ThisSideUp-v0"])
    assert "--steps" in capsys.readouterr().err
