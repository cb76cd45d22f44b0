"""RLlib's PPO trains on BoxToss for an iteration, on the native batched env and on RLlib's default
vectorisation, with env_config reaching the env. RLlib pins its own gymnasium, so these tests run in
the ``rllib`` extra's environment (``.ci/run`` makes one); elsewhere they are skipped."""

import gymnasium as gym
import pytest

pytest.importorskip("ray.rllib")

import ray  # noqa: E402

from agents.rllib_envs import make_env, register_rllib_envs  # noqa: E402
from agents.rllib_ppo import SUCCESS, MaskedAdvantagePPOLearner, evaluate, iterations_of, make_config, recipe, summary  # noqa: E402
from box_toss_env.envs.ballistic import BallisticThrows  # noqa: E402
from box_toss_env.wrappers.ballistic import BallisticThrowsVector  # noqa: E402
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
    assert isinstance(make_env("BoxToss-ShortEnd-v0", {"ballistic": True}), BallisticThrows)
    commands = make_env("BoxToss-ShortEnd-v0", {"num_envs": 4, "ballistic": True})
    assert isinstance(commands, NextStepAutoreset) and isinstance(commands.env, BallisticThrowsVector)


def test_the_settings_are_sb3s_recipe():
    position, pose = recipe("BoxToss-v0"), recipe("BoxToss-ShortEnd-v0")
    assert position == {
        "n_throws": 300_000,
        "train_batch_size": 2048,
        "minibatch_size": 128,
        "num_epochs": 10,
        "lr": 5e-4,
        "lr_decays": True,
        "gamma": 0.0,
        "lambda_": 1.0,
        "clip_param": 0.2,
        "entropy_coeff": 0.0,
        "vf_loss_coeff": 0.5,
        "grad_clip": 0.5,
        "hiddens": [128, 128],
        "activation": "tanh",
        "log_std_init": -2.5,
        "ballistic": False,
    }
    assert pose["ballistic"] and pose["log_std_init"] == -1.0 and pose["n_throws"] == 600_000
    config = make_config("BoxToss-v0")
    assert config.lr == [[0, 5e-4], [300_000, 0.0]] and not config.use_kl_loss and config.grad_clip == 0.5
    assert config.minibatch_size == 256  # rows: SB3's 128 throws and RLlib's artificial timestep of each
    assert config.learner_class is MaskedAdvantagePPOLearner
    assert iterations_of(config, "BoxToss-v0") == 147
    assert make_config("BoxToss-ShortEnd-v0").env_config["ballistic"] is True
    with pytest.raises(ValueError, match="unknown settings"):
        make_config("BoxToss-v0", learning_rate=1e-3)


@pytest.mark.parametrize("vectorize", ["native", "sync"])
def test_rllib_ppo_trains_an_iteration(local_ray, vectorize):
    config = make_config(
        "BoxToss-LongSide-v0",
        {"max_spin": 10.0},
        num_envs=16,
        vectorize=vectorize,
        train_batch_size=256,
        minibatch_size=64,
        num_epochs=1,
    )
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


def test_the_module_starts_from_the_recipes_std_with_separate_networks(local_ray):
    config = make_config("BoxToss-v0", num_envs=16, train_batch_size=256, minibatch_size=64, num_epochs=1)
    algo = config.build_algo()
    try:
        module = algo.get_module()
        assert module.pi.log_std.detach().tolist() == [-2.5] * 3  # RLlib's default would start at 0 (std 1)
        assert not module.model_config["vf_share_layers"]
        result = evaluate(algo, 32)
        assert result["episodes"] >= 32 and 0.0 <= result["success"] <= 1.0
    finally:
        algo.stop()


def test_the_learner_standardises_the_advantages_over_the_real_timesteps(monkeypatch):
    """RLlib's standardisation includes the artificial (loss-masked) timestep of every episode; ours does not."""
    import torch
    from ray.rllib.algorithms.ppo.torch.ppo_torch_learner import PPOTorchLearner
    from ray.rllib.core.columns import Columns
    from ray.rllib.evaluation.postprocessing import Postprocessing

    seen = {}
    monkeypatch.setattr(PPOTorchLearner, "compute_loss_for_module", lambda self, **kwargs: seen.update(kwargs))
    batch = {
        Postprocessing.ADVANTAGES: torch.tensor([1.0, 3.0, 100.0, -50.0]),
        Columns.LOSS_MASK: torch.tensor([True, True, False, False]),
    }
    learner = object.__new__(MaskedAdvantagePPOLearner)  # no setup: only the loss is called
    learner.compute_loss_for_module(module_id="p", config=None, batch=batch, fwd_out={})
    torch.testing.assert_close(seen["batch"][Postprocessing.ADVANTAGES][:2], torch.tensor([-0.5, 0.5]) * 2**0.5)
