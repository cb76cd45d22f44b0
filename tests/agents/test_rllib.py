"""RLlib's PPO trains on BoxToss for an iteration, on the native batched env and on RLlib's default
vectorisation, with env_config reaching the env. RLlib pins its own gymnasium, so these tests run in
the ``rllib`` extra's environment (``.ci/run`` makes one); elsewhere they are skipped."""

import gymnasium as gym
import pytest

pytest.importorskip("ray.rllib")

import ray  # noqa: E402

from agents.rllib_envs import make_env, register_rllib_envs  # noqa: E402
from agents.rllib_ppo import SUCCESS, make_config, summary  # noqa: E402
from box_toss_env.wrappers.next_step import NextStepAutoreset  # noqa: E402


@pytest.fixture(scope="module")
def local_ray():
    ray.init(address="local", num_cpus=1, include_dashboard=False)
    register_rllib_envs()
    yield
    ray.shutdown()


def test_the_env_creator_honours_env_config():
    single = make_env("BoxToss-v0", {"target_face": "short_end", "max_spin": 10.0})
    assert single.unwrapped.config.target_face == "short_end" and single.unwrapped.config.max_spin == 10.0
    batched = make_env("BoxToss-ShortEnd-v0", {"num_envs": 4, "threads": 1, "max_spin": 10.0})
    assert isinstance(batched, NextStepAutoreset) and batched.num_envs == 4
    assert batched.unwrapped.config.target_face == "short_end" and batched.unwrapped.threads == 1
    with pytest.raises(ValueError, match="max_spin"):
        make_env("BoxToss-v0", {"max_spin": -1.0})


@pytest.mark.parametrize("vectorize", ["native", "sync"])
def test_rllib_ppo_trains_an_iteration(local_ray, vectorize):
    config = make_config("BoxToss-LongSide-v0", {"max_spin": 10.0}, num_envs=16, vectorize=vectorize,
                         train_batch_size=256, minibatch_size=64, num_epochs=1)
    algo = config.build_algo()
    try:
        env = algo.env_runner.env.unwrapped
        if vectorize == "native":
            assert isinstance(algo.env_runner.env.env, NextStepAutoreset)  # under RLlib's DictInfoToList
            assert env.env.config.max_spin == 10.0 and env.env.config.target_face == "long_side"
        else:
            assert isinstance(env, gym.vector.SyncVectorEnv)
            assert env.envs[0].unwrapped.config.max_spin == 10.0
        result = algo.train()
        figures = summary(result)
        assert figures["env_steps"] >= 256 and figures["episode_length"] == 1.0  # one throw per episode
        assert 0.0 <= figures["success"] <= 1.0 and SUCCESS in result["env_runners"]
        assert result["learners"]["default_policy"]["num_module_steps_trained"] > 0
    finally:
        algo.stop()
