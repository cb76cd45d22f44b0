"""The throw written once (``envs.functional``): the core alone throws as the env does, whatever the batch;
every argument is declared once (``envs.arguments``). tests/agents/test_one_throw.py has the oracle."""

import inspect
from pathlib import Path

import numpy as np
import pytest

import box_toss_env  # noqa: F401  (registers BoxToss-v0)
from box_toss_env.envs import task_config
from box_toss_env.envs.arguments import ENV_ARGUMENTS, ENV_DEFAULTS, arguments_table
from box_toss_env.envs.box_toss import BoxTossEnv
from box_toss_env.envs.box_toss_vector import BoxTossVectorEnv
from box_toss_env.envs.functional import BoxTossFunctional, first_of


def actions(n: int) -> np.ndarray:
    return np.random.default_rng(7).uniform(-1, 1, (n, 3))


def test_the_core_alone_throws_as_the_env_does():
    core = BoxTossFunctional(target_face="long_side")
    batch = core.initial(np.random.default_rng(5), core.empty(1))
    env = BoxTossEnv(target_face="long_side")
    obs, reset_info = env.reset(seed=5)
    np.testing.assert_array_equal(core.observation(batch)[0], obs)
    assert first_of(core.reset_info(batch)).keys() == reset_info.keys()
    core.transition(batch, actions(1), core.make_simulator())
    reward, info = core.score(batch)
    _, env_reward, terminated, _, env_info = env.step(actions(1)[0])
    assert (float(reward[0]), first_of(info)) == (env_reward, env_info)
    np.testing.assert_array_equal(core.terminal(batch), [terminated])
    rewards, terms = core.reward(batch)
    assert rewards[0] == sum(value[0] for value in terms.values()) == env_reward


def test_a_batch_result_does_not_depend_on_the_batch_size():
    core = BoxTossFunctional()
    big = core.initial(np.random.default_rng(1), core.empty(8))
    small = core.for_episodes(task_config.Episodes(big.episodes.data[5:6].copy()))
    simulator = core.make_simulator(parallel=True)
    core.transition(big, actions(8), simulator)
    core.transition(small, actions(8)[5:6], simulator)
    np.testing.assert_array_equal(big.thrown_state[5], small.thrown_state[0])


def test_every_argument_is_declared_once_and_read_from_the_declaration():
    signature = inspect.signature(BoxTossEnv)
    assert list(signature.parameters) == ["render_mode", *ENV_DEFAULTS]
    assert all(signature.parameters[a.name].default == a.default for a in ENV_ARGUMENTS)
    assert arguments_table() in inspect.cleandoc(BoxTossEnv.__doc__)
    assert all(
        task_config.ENV_RANGES[name] is a.allowed
        for name, a in ((a.name, a) for a in ENV_ARGUMENTS)
        if name in task_config.ENV_RANGES
    )
    with pytest.raises(TypeError, match="unexpected keyword argument 'box_lenght'"):
        BoxTossEnv(box_lenght=0.3)
    with pytest.raises(TypeError, match="unexpected keyword argument 'render_fps'"):
        BoxTossFunctional(render_fps=30)  # rendering is the env's, not the throw's
    assert BoxTossVectorEnv(2, box_length=0.3).config.half_length == 0.15


def test_the_example_of_the_functional_page_runs():
    text = (Path(__file__).parents[2] / "docs" / "functional.md").read_text()
    example = text.split("```python\n")[1].split("```")[0]
    namespace = {}
    exec(compile(example, "docs/functional.md", "exec"), namespace)  # noqa: S102  (our own page)
    assert namespace["reward"].shape == (256,) and set(namespace["info"]) >= {"success", "distance"}
