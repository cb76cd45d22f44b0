"""The recipe option ``curriculum``: the env's arguments in stages while training, ending on the recipe's env."""

import pytest
import torch

from agents import config as configuration
from agents import curriculum, training
from agents.envs import find_wrapper, make_training_env
from box_toss_env.wrappers.sb3_adapter import SB3VecEnvAdapter

ENV = "BoxToss-ShortEnd-v0"
STAGES = [{"until": 64, "env_kwargs": {"box_length": 0.25}}, {"until": 128, "env_kwargs": {"box_length": 0.3}}]


def recipe(algo: str) -> dict:
    config = configuration.load_hyperparams(algo, ENV)
    small = {
        "n_timesteps": 192,
        "n_envs": 4,
        "env_kwargs": {},
        "curriculum": STAGES,
        "policy_kwargs": {"net_arch": [8]},
    }
    config.update(small)
    config.update({"n_steps": 16, "batch_size": 32, "n_epochs": 1} if algo == "ppo" else {"learning_starts": 16})
    config.pop("env_wrapper", None)
    return config


@pytest.mark.parametrize("algo", ["ppo", "sac"])
def test_training_moves_through_the_stages_to_the_recipes_env(algo):
    torch.set_num_threads(1)
    config = recipe(algo)
    configuration.check_config(config, algo)
    venv = make_training_env(
        ENV, 4, seed=0, env_kwargs=curriculum.env_kwargs_at(config, 0), vec_env_kwargs={"threads": 1}, normalize=True
    )
    model = training.new_model(venv, config, ENV, 0, algo)
    seen = []

    class Watch(curriculum.CurriculumCallback):
        def _on_rollout_start(self) -> None:
            super()._on_rollout_start()
            adapter = find_wrapper(self.model.get_env(), SB3VecEnvAdapter)
            seen.append(2 * adapter.vector_env.unwrapped.config.half_length)

    model.learn(192, callback=Watch(ENV, config, 0))
    assert seen[0] == 0.25 and 0.3 in seen and seen[-1] == 0.4  # the stages, then the recipe's 0.4 m box
    assert seen == sorted(seen)


def test_a_bad_curriculum_is_refused_naming_what_is_accepted():
    config = recipe("ppo")
    for bad in ([{"until": 64}], [{"until": 64, "env_kwargs": {}}, {"until": 32, "env_kwargs": {}}], "box"):
        with pytest.raises(configuration.ConfigError, match="curriculum must be a list"):
            configuration.check_config({**config, "curriculum": bad}, "ppo")
    with pytest.raises(configuration.ConfigError, match="the last stage must end before n_timesteps"):
        configuration.check_config({**config, "curriculum": [{"until": 192, "env_kwargs": {}}]}, "ppo")
    assert curriculum.env_kwargs_at(config, 100) == {"box_length": 0.3}
    assert curriculum.env_kwargs_at(config, 128) == {}
