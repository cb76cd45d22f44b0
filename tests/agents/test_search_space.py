"""The declared search spaces: every point is a valid configuration, the files' values are a point,
bad declarations are one clear error, and the objective ranks success before distance."""

import math

import optuna
import pytest

from agents import config as configuration
from agents import search_space
from agents.config import ConfigError
from agents.evaluation import search_objective
from agents.search_space import read_space

VARIANTS = ("BoxToss-v0", "BoxToss-LongSide-v0", "BoxToss-ShortEnd-v0", "BoxToss-ThisSideUp-v0", "BoxToss-Mixed-v0")


def plain(kwargs):
    """Constructor kwargs with schedules and classes as their reprs, to compare configurations."""
    return {key: repr(value) for key, value in kwargs.items()}


@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_sampled_points_are_valid_configurations(algo):
    space = search_space.load_space(algo)
    sampler = optuna.samplers.RandomSampler(seed=0)
    study = optuna.create_study(sampler=sampler)
    for env_id in VARIANTS:
        base = configuration.load_hyperparams(algo, env_id)
        points = [search_space.first_point(space)]
        for _ in range(5):
            trial = study.ask(search_space.optuna_space(space))
            points.append(trial.params)
        for point in points:
            config = search_space.trial_config(base, space, point, algo)
            kwargs = configuration.algorithm_kwargs(config, algo)
            for key, value in point.items():
                node = config
                for part in key.split("."):
                    node = node[part]
                written = space[key].override(key, value).split("=", 1)[1]
                assert node == configuration.read_value(written)  # what the trial trains is what it reports
            assert kwargs["policy"] == "MlpPolicy"


@pytest.mark.parametrize("env_id", VARIANTS)
def test_the_ppo_file_is_a_point_of_the_space_and_the_sweep_starts_there(env_id):
    space = search_space.load_space("ppo")
    base = configuration.load_hyperparams("ppo", env_id)
    point = search_space.current_point(space, base)
    assert point is not None
    again = search_space.trial_config(base, space, point, "ppo")
    assert plain(configuration.algorithm_kwargs(again, "ppo")) == plain(configuration.algorithm_kwargs(base, "ppo"))


def test_a_value_outside_the_space_is_no_start_point():
    space = search_space.load_space("ppo")
    base = configuration.apply_overrides(configuration.load_hyperparams("ppo", "BoxToss-v0"), ["n_epochs=7"])
    assert search_space.current_point(space, base) is None


def test_floats_are_written_with_three_significant_digits():
    dimension = read_space(
        {"learning_rate": {"low": 1e-4, "high": 1e-2, "log": True, "write": "lin_{}"}}, "ppo", "test"
    )["learning_rate"]
    assert dimension.override("learning_rate", 0.000646642271) == "learning_rate=lin_0.000647"
    assert isinstance(dimension.distribution, optuna.distributions.FloatDistribution) and dimension.distribution.log


@pytest.mark.parametrize(
    "entry, message",
    [
        ({"no_such_key": {"low": 0, "high": 1}}, "'no_such_key' is not a hyperparameter"),
        ({"clip_range": {"low": 0.4, "high": 0.1}}, "low must be < high"),
        ({"learning_rate": {"low": 0.0, "high": 1.0, "log": True}}, "a log scale needs low > 0"),
        ({"n_steps": {"choices": []}}, "choices must be a non-empty list"),
        ({"n_steps": {"choices": [16], "low": 1}}, "choices takes no other key"),
        ({"clip_range": {"low": 0.1}}, "must have low and high"),
        ({"clip_range": {"low": 0.1, "high": 0.2, "write": "lin"}}, "write must be a string holding one {}"),
        ({"clip_range": [0.1, 0.2]}, "must be a mapping"),
    ],
)
def test_bad_declarations_name_the_entry(entry, message):
    with pytest.raises(ConfigError, match=message.replace("{", r"\{").replace("}", r"\}")):
        read_space(entry, "ppo", "space.yml: ppo")


def test_a_missing_algorithm_is_named(tmp_path):
    path = tmp_path / "space.yml"
    path.write_text("ppo:\n  clip_range: {low: 0.1, high: 0.3}\n")
    with pytest.raises(ConfigError, match="declares no search space for 'sac'"):
        search_space.load_space("sac", path)


def test_the_objective_ranks_success_first_then_distance():
    targets = 256
    one_target = 1 / targets
    assert search_objective(0.5, 10.0, targets) > search_objective(0.5 - one_target, 0.0, targets)
    assert search_objective(0.5, 0.1, targets) > search_objective(0.5, 0.2, targets)
    assert search_objective(0.5, 50.0, targets) == search_objective(0.5, math.nan, targets)  # both capped at 10 m
    assert search_objective(math.nan, 0.1, targets) == -math.inf
