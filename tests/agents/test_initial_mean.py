"""The recipe option ``initial_mean``: where an untrained policy throws (a constant action, or the ballistic
command's throw fitted by regression), checked before anything is made."""

import json

import numpy as np
import pytest
import torch

from agents import config as configuration
from agents import initial_mean, training
from agents.envs import make_training_env, normalizer_of
from agents.policies import TrainedPolicy

ENV = "BoxToss-ThisSideUp-v0"


@pytest.fixture(autouse=True)
def one_torch_thread():
    """As training runs (project.yml's torch_threads): several threads on a loaded 2-core machine are far slower."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def recipe(algo: str, option) -> dict:
    config = configuration.load_hyperparams(algo, ENV)
    config.pop("env_wrapper", None)
    config.update(initial_mean=option, n_envs=4, env_kwargs={})
    config.setdefault("policy_kwargs", {})["net_arch"] = [32, 32]
    return config


def untrained(algo: str, option, seed: int = 0, run_dir=None):
    config = recipe(algo, option)
    venv = make_training_env(ENV, 4, seed=seed, env_kwargs={}, vec_env_kwargs={"threads": 1}, normalize=True)
    model = training.new_model(venv, config, ENV, seed, algo, run_dir)
    return model, venv, config


@pytest.mark.parametrize("bad", [[0.1, 0.2], [0, 0, 2.0], "ballistics", {"ballistic": [0, 0]}, [True, 0, 0]])
def test_a_bad_option_is_refused_naming_what_is_accepted(bad):
    config = {**recipe("ppo", None), "initial_mean": bad}
    with pytest.raises(configuration.ConfigError, match="initial_mean must be a list of 3 numbers in"):
        configuration.check_config(config, "ppo")


def test_a_ballistic_start_needs_the_envs_own_actions():
    config = {**configuration.load_hyperparams("ppo", ENV), "initial_mean": "ballistic"}  # the ballistic wrapper
    with pytest.raises(configuration.ConfigError, match="a ballistic start is a throw in the env's own actions"):
        configuration.check_config(config, "ppo")
    configuration.check_config({**config, "env_wrapper": None}, "ppo")


@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_a_constant_start_is_the_mean_for_every_observation(algo):
    model, venv, _ = untrained(algo, [0.3, -0.2, 0.25])
    observations = np.random.default_rng(0).normal(size=(64, venv.observation_space.shape[0])).astype(np.float32)
    actions, _ = model.predict(observations, deterministic=True)
    np.testing.assert_allclose(actions, np.tile([0.3, -0.2, 0.25], (64, 1)), atol=0.05)


def test_a_ballistic_start_is_fitted_to_the_commands_throw(monkeypatch, tmp_path):
    monkeypatch.setattr(initial_mean, "SAMPLES", 1024)
    monkeypatch.setattr(initial_mean, "FIT_STEPS", 600)
    torch.manual_seed(0)
    plain, plain_venv, config = untrained("ppo", None)
    model, venv, _ = untrained("ppo", "ballistic", run_dir=tmp_path)
    held_out = initial_mean.first_observations(ENV, config, seed=123, n=256)
    targets = initial_mean.ballistic_targets(ENV, config, held_out, [0.0, 0.0, 0.0])

    def error(model, venv) -> float:
        actions = TrainedPolicy(model, normalizer_of(venv)).act(held_out.astype(np.float32), [], None)
        return float(np.abs(np.clip(actions, -1, 1) - targets).mean())

    assert error(model, venv) < 0.25 * error(plain, plain_venv)  # the start moved onto the command's throws
    assert normalizer_of(venv).obs_rms.count > 1000  # the statistics start from the fit's observations
    assert np.allclose(model.policy.log_std.detach().numpy(), config["policy_kwargs"]["log_std_init"])
    fitted = json.loads((tmp_path / "initial_mean.json").read_text())
    assert fitted["value_explained_variance"] > 0.005  # an untouched critic explains none of them (V = 0)
