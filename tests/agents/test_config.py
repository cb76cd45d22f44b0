"""Hyperparameter files (RL Zoo's format plus project.yml) and command-line overrides."""

import pytest
import torch
import yaml

from agents import algorithms, config

VARIANTS = (
    "BoxToss-v0",
    "BoxToss-LongSide-v0",
    "BoxToss-ShortEnd-v0",
    "BoxToss-ThisSideUp-v0",
    "BoxToss-Mixed-v0",
    "BoxToss-OnBox-v0",
)


@pytest.mark.parametrize("algo", sorted(algorithms.ALGORITHMS))
def test_every_algorithm_has_valid_hyperparameters_for_every_variant(algo):
    for env_id in VARIANTS:
        hyperparams = config.load_hyperparams(algo, env_id)
        config.check_config(hyperparams, algo)
        kwargs = config.algorithm_kwargs(hyperparams, algo)
        assert set(kwargs) <= algorithms.constructor_keys(algo) | {"action_noise"}  # set from noise_type
        if algo == "ppo":
            assert hyperparams["n_steps"] * hyperparams["n_envs"] % hyperparams["batch_size"] == 0


def test_zoo_expressions_are_read_and_written_back():
    hyperparams = config.load_hyperparams("ppo", "BoxToss-ShortEnd-v0")
    assert hyperparams["policy_kwargs"] == {"net_arch": [128, 128], "activation_fn": "nn.Tanh", "log_std_init": -1.0}
    assert hyperparams["env_wrapper"] == "box_toss_env.envs.ballistic.BallisticThrows"
    assert hyperparams["normalize"] == {"norm_obs": True, "norm_reward": False}
    assert hyperparams["torch_threads"] == 1  # from project.yml
    entry = config.zoo_entry(hyperparams)
    assert "torch_threads" not in entry and entry["policy_kwargs"].startswith("dict(")
    assert config.read_zoo_entry(yaml.safe_load(yaml.safe_dump(entry)), "round trip") == {
        key: value for key, value in hyperparams.items() if key not in config.PROJECT_KEYS
    }
    kwargs = config.algorithm_kwargs(hyperparams, "ppo")
    assert kwargs["policy_kwargs"]["activation_fn"] is torch.nn.Tanh


def test_expressions_are_never_evaluated():
    for text in ("__import__('os').system('echo hi')", "dict(a=open('x'))", "nn.Tanh()", "lambda: 1"):
        with pytest.raises(config.ConfigError, match="policy_kwargs"):
            config.read_expression(text, "policy_kwargs")


def test_overrides_reach_into_dicts_and_read_values_as_yaml():
    base = config.load_hyperparams("ppo", "BoxToss-v0")
    changed = config.apply_overrides(
        base,
        [
            "n_timesteps=1e3",
            "learning_rate=1e-3",
            "policy_kwargs.net_arch=[8, 8]",
            "env_kwargs.target_face=exact",
            "normalize=false",
        ],
    )
    assert changed["n_timesteps"] == 1000 and isinstance(changed["n_timesteps"], int)
    assert changed["learning_rate"] == pytest.approx(1e-3)
    assert changed["policy_kwargs"]["net_arch"] == [8, 8]
    assert changed["policy_kwargs"]["log_std_init"] == base["policy_kwargs"]["log_std_init"]  # siblings kept
    assert changed["env_kwargs"] == {"target_face": "exact"}
    assert changed["normalize"] is False
    assert base["policy_kwargs"]["net_arch"] != [8, 8]  # the original is untouched


@pytest.mark.parametrize(
    "algo, override, message",
    [
        ("ppo", "n_timestep=5", "unknown hyperparameter 'n_timestep'"),
        ("ppo", "buffer_size=5", "unknown hyperparameter 'buffer_size'"),  # SAC's, not PPO's
        ("ppo", "n_timesteps", "key=value"),
        ("sac", "=5", "key=value"),
    ],
)
def test_bad_overrides_name_the_problem(algo, override, message):
    with pytest.raises(config.ConfigError, match=message):
        config.apply_overrides({}, [override], algo)
    assert config.apply_overrides({}, ["buffer_size=5"], "sac") == {"buffer_size": 5}


def test_linear_schedule():
    kwargs = config.algorithm_kwargs(
        {**config.load_hyperparams("ppo", "BoxToss-v0"), "learning_rate": "lin_0.001"}, "ppo"
    )
    assert kwargs["learning_rate"](1.0) == pytest.approx(1e-3)
    assert kwargs["learning_rate"](0.25) == pytest.approx(2.5e-4)
    assert kwargs["learning_rate"](-0.01) == 0.0  # the last rollout may overshoot the budget
    with pytest.raises(config.ConfigError, match="lin_<number>"):
        config.check_config({**config.load_hyperparams("ppo", "BoxToss-v0"), "learning_rate": "cosine_1e-3"})


@pytest.mark.parametrize(
    "change, message",
    [
        ({"n_envs": 0}, "n_envs"),
        ({"n_timesteps": True}, "n_timesteps"),
        ({"policy": None}, "policy must be"),
        ({"policy_kwargs": {"activation_fn": "sigmoid"}}, "activation_fn"),
        ({"policy_kwargs": {"activation_fn": "nn.NotAThing"}}, "activation_fn"),
        ({"env_wrapper": "gymnasium.wrappers.ClipAction"}, "env_wrapper must be one of"),
        ({"env_wrapper": {"box_toss_env.envs.ballistic.BallisticThrows": [1]}}, "env_wrapper must be one of"),
    ],
)
def test_check_config_names_the_bad_key(change, message):
    good = config.load_hyperparams("ppo", "BoxToss-v0")
    with pytest.raises(config.ConfigError, match=message):
        config.check_config({**good, **change}, "ppo")


def test_a_file_that_is_not_a_mapping_is_one_clear_error(tmp_path):
    (tmp_path / "ppo.yml").write_text("- just\n- a list\n")
    with pytest.raises(config.ConfigError, match="must hold a mapping"):
        config.load_hyperparams("ppo", "BoxToss-v0", tmp_path)
    (tmp_path / "ppo.yml").write_text("BoxToss-v0: [1, 2]\n")
    with pytest.raises(config.ConfigError, match="mapping of hyperparameters"):
        config.load_hyperparams("ppo", "BoxToss-v0", tmp_path)


@pytest.mark.parametrize("algo", sorted(algorithms.ALGORITHMS))
def test_raw_recipes_are_valid_zoo_entries_without_a_wrapper(algo):
    """agents/hyperparams/raw/<algo>.yml (the raw tier's recipes, if the algorithm has any) loads like the main
    files, acts in the env's own actions, and takes its project settings from agents/hyperparams/project.yml."""
    path = config.hyperparams_path(algo, config.RAW_HYPERPARAMS)
    if not path.exists():
        pytest.skip(f"no raw recipes for {algo}")
    for env_id in config.read_mapping(path):
        assert env_id in (*VARIANTS, "BoxToss-Pixels-v0")
        hyperparams = config.load_hyperparams(algo, env_id, config.RAW_HYPERPARAMS)
        config.check_config(hyperparams, algo)
        assert set(config.algorithm_kwargs(hyperparams, algo)) <= algorithms.constructor_keys(algo) | {"action_noise"}
        assert hyperparams.get("env_wrapper") is None
        project = config.load_hyperparams(algo, "BoxToss-v0")  # project.yml's settings are every entry's
        assert hyperparams["torch_threads"] == project["torch_threads"]
        images = env_id.endswith("-Pixels-v0")
        assert (hyperparams["policy"] == "CnnPolicy") == images and (not images or hyperparams["normalize"] is False)


def test_a_folder_without_project_settings_uses_its_parents(tmp_path):
    (tmp_path / "project.yml").write_text("defaults: {eval_freq: 123}\n")
    (tmp_path / "raw").mkdir()
    (tmp_path / "raw" / "ppo.yml").write_text("BoxToss-v0: {n_timesteps: 10}\n")
    assert config.load_hyperparams("ppo", "BoxToss-v0", tmp_path / "raw")["eval_freq"] == 123
    assert config.has_entry("ppo", "BoxToss-v0", tmp_path / "raw")
    assert not config.has_entry("ppo", "BoxToss-OnBox-v0", tmp_path / "raw")
    assert not config.has_entry("sac", "BoxToss-v0", tmp_path / "raw")


def test_a_folders_own_project_settings_add_to_its_parents(tmp_path):
    (tmp_path / "project.yml").write_text("defaults: {eval_freq: 123, torch_threads: 1}\n")
    (tmp_path / "raw").mkdir()
    (tmp_path / "raw" / "ppo.yml").write_text("BoxToss-v0: {n_timesteps: 10}\n")
    (tmp_path / "raw" / "project.yml").write_text("ppo:\n  BoxToss-v0: {eval_freq: 7, initial_mean: ballistic}\n")
    settings = config.load_hyperparams("ppo", "BoxToss-v0", tmp_path / "raw")
    assert (settings["eval_freq"], settings["torch_threads"], settings["initial_mean"]) == (7, 1, "ballistic")


def test_the_pixel_recipe_is_a_cnn_policy_on_unnormalised_images():
    hyperparams = config.load_hyperparams("ppo", "BoxToss-Pixels-v0")
    config.check_config(hyperparams, "ppo")
    assert hyperparams["policy"] == "CnnPolicy" and hyperparams["normalize"] is False
