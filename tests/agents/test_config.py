"""Hyperparameter files and command-line overrides."""

import pytest

from agents import config


def test_every_registered_box_toss_env_has_valid_hyperparameters():
    for env_id in ("BoxToss-v0", "BoxToss-LongSide-v0", "BoxToss-ShortEnd-v0", "BoxToss-ThisSideUp-v0"):
        hyperparams = config.load_hyperparams(env_id)
        config.check_config(hyperparams)
        assert hyperparams["n_steps"] * hyperparams["n_envs"] % hyperparams["batch_size"] == 0


def test_overrides_reach_into_dicts_and_read_values_as_yaml():
    base = config.load_hyperparams("BoxToss-v0")
    changed = config.apply_overrides(base, ["n_timesteps=1e3", "learning_rate=1e-3", "policy_kwargs.net_arch=[8, 8]",
                                            "env_kwargs.target_face=exact", "normalize=false"])
    assert changed["n_timesteps"] == 1000 and isinstance(changed["n_timesteps"], int)
    assert changed["learning_rate"] == pytest.approx(1e-3)
    assert changed["policy_kwargs"]["net_arch"] == [8, 8]
    assert changed["policy_kwargs"]["log_std_init"] == base["policy_kwargs"]["log_std_init"]  # siblings kept
    assert changed["env_kwargs"] == {"target_face": "exact"}
    assert changed["normalize"] is False
    assert base["policy_kwargs"]["net_arch"] != [8, 8]  # the original is untouched


@pytest.mark.parametrize("override, message", [
    ("n_timestep=5", "unknown hyperparameter 'n_timestep'"),
    ("n_timesteps", "key=value"),
    ("=5", "key=value"),
])
def test_bad_overrides_name_the_problem(override, message):
    with pytest.raises(ValueError, match=message):
        config.apply_overrides({}, [override])


def test_values_are_never_evaluated_as_code():
    _, value = config.parse_override("policy=__import__('os').system('echo hi')")
    assert value == "__import__('os').system('echo hi')"  # a plain string
    with pytest.raises(Exception, match="could not determine a constructor"):
        config.parse_override("policy=!!python/object/apply:os.system ['echo hi']")


def test_linear_schedule_and_activation_names_become_objects():
    kwargs = config.ppo_kwargs({**config.load_hyperparams("BoxToss-v0"), "learning_rate": "lin_0.001"})
    assert kwargs["learning_rate"](1.0) == pytest.approx(1e-3)
    assert kwargs["learning_rate"](0.25) == pytest.approx(2.5e-4)
    assert kwargs["learning_rate"](-0.01) == 0.0  # the last rollout may overshoot the budget
    assert config.ppo_kwargs(config.load_hyperparams("BoxToss-v0"))["learning_rate"](0.5) > 0
    assert kwargs["policy_kwargs"]["activation_fn"].__name__ == "Tanh"
    with pytest.raises(ValueError, match="lin_<number>"):
        config.ppo_kwargs({"learning_rate": "cosine_1e-3"})


def test_check_config_rejects_bad_budgets_and_activations():
    good = config.load_hyperparams("BoxToss-v0")
    with pytest.raises(ValueError, match="n_envs"):
        config.check_config({**good, "n_envs": 0})
    with pytest.raises(ValueError, match="activation_fn"):
        config.check_config({**good, "policy_kwargs": {"activation_fn": "sigmoid"}})
