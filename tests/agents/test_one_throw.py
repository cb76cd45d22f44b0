"""One throw, written once: the single env, the vector env and the oracle throw with the same
``envs.functional.BoxTossFunctional`` and give identical throws."""

import gymnasium as gym
import numpy as np
import pytest

import box_toss_env  # noqa: F401  (registers BoxToss-v0)
from agents.oracle import ThrowSimulator, episodes_from_infos
from box_toss_env.envs.functional import BoxTossFunctional

N = 4
VARIANTS = [("BoxToss-Mixed-v0", {"mass_range": (1.0, 3.0), "observe_dynamics": True}), ("BoxToss-OnBox-v0", {})]


def actions(n: int = N) -> np.ndarray:
    return np.random.default_rng(7).uniform(-1, 1, (n, 3))


@pytest.mark.parametrize(("env_id", "kwargs"), VARIANTS)
def test_single_env_vector_env_and_oracle_throw_identically_with_the_one_core(env_id, kwargs):
    """The same episodes and actions through the three front doors: the same final states, rewards and
    info, bit for bit; each of them runs the same ``BoxTossFunctional``."""
    vector = gym.make_vec(env_id, num_envs=N, vectorization_mode="vector_entry_point", **kwargs).unwrapped
    _, reset_info = vector.reset(seed=3)
    infos = [{key: value[i] for key, value in reset_info.items() if not key.startswith("_")} for i in range(N)]
    _, vector_reward, _, _, vector_info = vector.step(actions())
    singles = [gym.make(env_id, **kwargs) for _ in range(N)]
    for i, env in enumerate(singles):
        env.reset(seed=3 + i)
        obs, reward, *_, info = env.step(actions()[i])
        np.testing.assert_array_equal(obs, vector_info["final_obs"][i])
        assert reward == vector_reward[i]
        assert info == {key: vector_info["final_info"][key][i].item() for key in info}
    oracle = ThrowSimulator(singles[0])
    oracle_reward, oracle_success, _ = oracle.rewards(episodes_from_infos(infos), actions())
    np.testing.assert_array_equal(oracle_reward, vector_reward)
    np.testing.assert_array_equal(oracle_success, vector_info["final_info"]["success"])
    assert all(type(front.core) is BoxTossFunctional for front in (vector, oracle, *(e.unwrapped for e in singles)))
