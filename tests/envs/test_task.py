"""The batch-first task functions: a batch of n is n batches of one, and each piece against its formula."""

import math
from pathlib import Path

import numpy as np
import pytest

from box_toss_env.envs import task, task_columns, task_config
from box_toss_env.envs.box_toss import BoxTossEnv
from box_toss_env.physics import face_down, layout

CONFIG = BoxTossEnv(
    target_face="mixed",
    mass_range=(1.0, 3.0),
    friction_range=(0.2, 0.9),
    restitution_range=(0.0, 0.6),
    observe_dynamics=True,
).config


def sample(n, seed=0, config=CONFIG):
    return task.sample_episodes(np.random.default_rng(seed), config, task_config.Episodes.empty(n))


def test_a_batch_is_the_rows_computed_one_by_one():
    n = 16
    episodes = sample(n)
    actions = np.random.default_rng(1).uniform(-1.0, 1.0, (n, 3))
    states = task.write_initial_states(np.zeros((n, 6)), episodes, task.actions_to_throws(actions, CONFIG))
    states[:, layout.ANGLE] += np.linspace(-7.0, 7.0, n)  # final poses at many angles
    at_rest = np.arange(n) % 3 != 0
    obs = task.observe(states, episodes, CONFIG)
    reward, terms, success, distance, error = task.reward_terms(states, at_rest, episodes, CONFIG)
    for i in range(n):
        one = task_config.Episodes(episodes.data[i : i + 1].copy())
        state = task.write_initial_states(np.zeros((1, 6)), one, task.actions_to_throws(actions[i : i + 1], CONFIG))
        state[:, layout.ANGLE] = states[i, layout.ANGLE]
        np.testing.assert_array_equal(state[0], states[i])
        np.testing.assert_array_equal(task.observe(state, one, CONFIG)[0], obs[i])
        r, t, s, d, e = task.reward_terms(state, at_rest[i : i + 1], one, CONFIG)
        assert (r[0], s[0], d[0], e[0]) == (reward[i], success[i], distance[i], error[i])
        assert {k: v[0] for k, v in t.items()} == {k: v[i] for k, v in terms.items()}


def test_sampling_stays_in_the_ranges_and_covers_them():
    episodes = sample(4000)
    data = episodes.data
    for column, (low, high) in (
        (task_columns.EP_RELEASE_X, CONFIG.release_x_range),
        (task_columns.EP_RELEASE_Y, CONFIG.release_height_range),
        (task_columns.EP_RELEASE_ANGLE, CONFIG.release_angle_range),
        (task_columns.EP_TARGET_X, CONFIG.target_x_range),
        (task_columns.EP_MASS, CONFIG.mass_range),
        (task_columns.EP_FRICTION, CONFIG.friction_range),
        (task_columns.EP_RESTITUTION, CONFIG.restitution_range),
    ):
        assert low <= data[:, column].min() < low + 0.01 * (high - low)
        assert high - 0.01 * (high - low) < data[:, column].max() <= high
    kinds = {task.describe_target_faces(mask) for mask in episodes.target_faces}
    assert kinds == {"any face", "a long side", "a short end", "face 0", "face 1", "face 2", "face 3"}


@pytest.mark.parametrize(
    ("kind", "masks"),
    [
        ("any", {(1, 1, 1, 1)}),
        ("long_side", {(1, 0, 1, 0)}),
        ("short_end", {(0, 1, 0, 1)}),
        ("exact", {(1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)}),
    ],
)
def test_target_kinds(kind, masks):
    config = BoxTossEnv(target_face=kind).config
    drawn = {tuple(int(v) for v in mask) for mask in sample(200, config=config).target_faces}
    assert drawn == masks


def test_actions_map_linearly_onto_the_documented_ranges():
    low, high = CONFIG.launch_angle_range
    throws = task.actions_to_throws(np.array([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0], [0.0, 0.0, 0.0]]), CONFIG)
    np.testing.assert_allclose(throws[0], [0.0, low, -CONFIG.max_spin])
    np.testing.assert_allclose(throws[1], [CONFIG.max_speed, high, CONFIG.max_spin])
    np.testing.assert_allclose(throws[2], [0.5 * CONFIG.max_speed, 0.5 * (low + high), 0.0])
    states = task.write_initial_states(np.zeros((3, 6)), sample(3), throws)
    speed = np.hypot(states[:, layout.VX], states[:, layout.VY])
    np.testing.assert_allclose(speed, throws[:, 0])
    np.testing.assert_allclose(np.arctan2(states[1:, layout.VY], states[1:, layout.VX]), throws[1:, 1])


def test_faces_down_agree_with_the_engine():
    angles = np.linspace(-10.0, 10.0, 1001)
    assert task.faces_down(angles).tolist() == [face_down(a) for a in angles]


@pytest.mark.parametrize(
    ("angle", "faces", "error"),
    [
        (0.0, (1, 0, 0, 0), 0.0),  # face 0 flat down
        (-0.5 * math.pi, (0, 1, 0, 0), 0.0),  # turned clockwise a quarter: face 1 (+x) down
        (math.pi, (0, 0, 1, 0), 0.0),  # upside down: face 2 down
        (0.5 * math.pi, (0, 0, 0, 1), 0.0),
        (0.1, (1, 0, 0, 0), 0.1),
        (0.0, (0, 0, 1, 0), math.pi),  # the target face is up
        (0.0, (0, 1, 0, 1), 0.5 * math.pi),  # on a long side, a short end wanted
        (0.3 + 4 * math.pi, (0, 1, 0, 1), 0.5 * math.pi - 0.3),
    ],
)
def test_orientation_error(angle, faces, error):
    value = task.orientation_errors(np.array([angle]), np.array([faces], dtype=float))[0]
    assert value == pytest.approx(error, abs=1e-12)


def test_reward_formula_and_success():
    config = CONFIG
    episodes = sample(4)
    episodes.target_faces[:] = (0.0, 1.0, 0.0, 1.0)  # a short end
    target = episodes.target_x.copy()
    states = np.zeros((4, 6))
    states[:, layout.X] = target + [0.05, 0.05, 0.5, 0.05]
    states[:, layout.ANGLE] = [-0.5 * math.pi, -0.5 * math.pi, 0.5 * math.pi, 0.0]
    at_rest = np.array([True, False, True, True])
    reward, terms, success, distance, error = task.reward_terms(states, at_rest, episodes, config)
    assert success.tolist() == [True, False, False, False]  # not at rest / too far / wrong face
    np.testing.assert_allclose(distance, [0.05, 0.05, 0.5, 0.05])
    np.testing.assert_allclose(error, [0.0, 0.0, 0.0, 0.5 * math.pi], atol=1e-12)
    expected = -config.distance_weight * distance - config.orientation_weight * error + config.success_bonus * success
    np.testing.assert_allclose(reward, expected)
    np.testing.assert_array_equal(reward, sum(terms.values()))


def test_check_actions():
    assert task.check_actions([2.0, -3.0, 0.5], (3,)).tolist() == [[1.0, -1.0, 0.5]]
    with pytest.raises(ValueError, match="finite"):
        task.check_actions([np.nan, 0.0, 0.0], (3,))
    with pytest.raises(ValueError, match=r"shape \(4, 3\)"):
        task.check_actions(np.zeros((3, 3)), (4, 3))


def test_throws_to_actions_inverts_actions_to_throws():
    config = BoxTossEnv().config
    actions = np.random.default_rng(4).uniform(-1, 1, (50, 3))
    np.testing.assert_allclose(
        task.throws_to_actions(task.actions_to_throws(actions, config), config), actions, atol=1e-12
    )


def test_the_ranges_page_lists_the_env_ranges():
    """docs/ranges.md is the one place the ranges are written down; it agrees with the code."""
    text = (Path(__file__).parents[2] / "docs" / "ranges.md").read_text()
    for name, allowed in task_config.ENV_RANGES.items():
        assert f"| `{name}` | {allowed} |" in text, name
