"""The multi-throw core (``envs.multi_throw``): the one-throw core's surface, one engine set-up for both cores,
functional use (a copied batch throws again to the same bits), scenes of different sizes in one batch equal to
each env alone, the episode's end, and the checks that name what went wrong."""

import numpy as np
import pytest

from box_toss_env.envs.engine import make_engine
from box_toss_env.envs.functional import BoxTossFunctional, EnergyGainError
from box_toss_env.envs.multi_throw import MultiThrowFunctional
from box_toss_env.envs.stack_task import StackTask


def test_the_surface_of_the_one_throw_core():
    surface = ["empty", "initial", "initial_from_uniforms", "make_simulator", "reset_info", "check_actions"]
    surface += ["launch", "simulate", "transition", "observation", "reward", "terminal", "at_rest", "failed"]
    surface += ["check_finite", "outside_bounds", "check_bounds", "score", "bounds_message"]
    for name in surface:
        assert callable(getattr(BoxTossFunctional, name)) and callable(getattr(MultiThrowFunctional, name)), name


def test_both_cores_take_their_engine_from_make_engine():
    stack = MultiThrowFunctional(StackTask(dt=1 / 256))
    engine = make_engine(stack.task.engine_config)
    assert stack.flags == engine.flags and stack.flags.boxes_collide and stack.dt == 1 / 256
    np.testing.assert_array_equal(stack.settings, engine.settings)
    one = BoxTossFunctional(base_box=True)
    assert one.flags.boxes_collide and not BoxTossFunctional().flags.boxes_collide


def test_a_copied_batch_throws_again_to_the_same_bits_and_each_scene_is_its_own():
    """Envs at different throws of their episodes in one batch: each env's result is what it gives alone."""
    core = MultiThrowFunctional(StackTask(n_boxes=3))
    simulator = core.make_simulator(parallel=True, threads=2)
    batch = core.initial(np.random.default_rng(0), core.empty(4))
    actions = np.random.default_rng(1).uniform(-0.3, 0.3, (2, 4, 3))
    actions[:, :, 0] += 0.4  # lobs, which rarely knock the stack over
    core.transition(batch, actions[0], simulator)
    core.score(batch)
    batch.thrown[2:] = 0  # envs 2 and 3 start their episode again: their scenes empty, sizes now differ
    batch.state[2:] = 0.0
    batch.warm[2:] = 0.0
    kept = batch.copy()
    core.transition(batch, actions[1], simulator)
    reward, info = core.score(batch)
    again = core.transition(kept.copy(), actions[1], simulator)
    assert again.state.tobytes() == batch.state.tobytes()
    for i in range(4):
        alone = kept.repeat(i, 1)
        core.transition(alone, actions[1, i : i + 1], core.make_simulator())
        alone_reward, alone_info = core.score(alone)
        assert alone.state.tobytes() == batch.state[i : i + 1].tobytes()
        assert alone_reward[0] == reward[i] and all(alone_info[k][0] == info[k][i] for k in info)
    assert list(info["thrown"]) == [2, 2, 1, 1]


def test_the_episode_ends_with_the_hand():
    core = MultiThrowFunctional(StackTask(n_boxes=2))
    simulator = core.make_simulator()
    batch = core.initial(np.random.default_rng(3), core.empty(1))
    lob = np.array([[0.3, 0.2, 0.0]])
    for k in range(2):
        core.transition(batch, lob, simulator)
        core.check_finite(batch)
        reward, terms = core.reward(batch)
        assert reward[0] == sum(value[0] for value in terms.values())
        assert core.terminal(batch)[0] == (k == 1) or terms["reward_fall"][0] < 0


def test_observations_outside_the_bounds_are_named():
    core = MultiThrowFunctional(StackTask())
    batch = core.initial(np.random.default_rng(0), core.empty(2))
    observations = core.observation(batch)
    core.check_bounds(observations, name_envs=True)
    observations[1, 1] = 1e9
    with pytest.raises(EnergyGainError, match=r"env 1: the throw ended with box 0 y = 1e\+09"):
        core.check_bounds(observations, name_envs=True)
    with pytest.raises(ValueError, match="action must be finite"):
        core.check_actions(np.full((2, 3), np.nan), (2, 3))
