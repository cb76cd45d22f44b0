"""Every option is checked before anything is made: one line naming the key, the value and what is
allowed, exit code 2, no folder, no traceback. The bad values of the training configuration are
generated from its schema (``agents.config.SCHEMA``), so a new key gets its test."""

import math
import os

import pytest

from agents import algorithms, evaluate, train
from agents.config import SCHEMA, ConfigError, Rule, check_config, load_hyperparams
from agents.evaluation import make_baseline_run
from box_toss_env.viewer import __main__ as viewer


def bad_values(rule: Rule) -> list:
    """Values ``rule`` refuses: its bounds crossed, the wrong type."""
    if rule.kind == "bool":
        return ["maybe", 1]
    if rule.kind == "layers":
        return ["abc", [0], [64, -1]]
    if rule.kind == "mapping":
        return ["abc", [1]]
    values = ["abc", True, math.nan]
    if rule.low is not None:
        values.append(rule.low if rule.above else rule.low - 1)
    if rule.high is not None:
        values.append(rule.high + 1)
    if rule.kind == "int":
        values.append((rule.low or 0) + 1.5)
    return values


def cases():
    for key, rule in SCHEMA.items():
        for name, item in [(key, rule)] + [(f"{key}.{sub}", subrule) for sub, subrule in rule.mapping.items()]:
            for value in bad_values(item):
                yield pytest.param(name, value, id=f"{name}={value!r}")


def algo_of(key: str) -> str:
    top = key.split(".")[0]
    return next((algo for algo in ("ppo", "sac", "td3") if top in algorithms.constructor_keys(algo)), "ppo")


@pytest.mark.parametrize("key, value", list(cases()))
def test_every_key_of_the_schema_refuses_values_out_of_its_range(key, value):
    algo = algo_of(key)
    config = load_hyperparams(algo, "BoxToss-v0")
    node = config
    for part in key.split(".")[:-1]:
        node = node.setdefault(part, {}) if isinstance(node.get(part), dict) or part not in node else node[part]
        if not isinstance(node, dict):
            config[part] = node = {}
    node[key.split(".")[-1]] = value
    with pytest.raises(ConfigError) as error:
        check_config(config, algo)
    message = str(error.value)
    assert key in message and repr(value) in message and "\n" not in message


def test_batch_size_is_bounded_by_the_rollout_on_policy_only():
    """PPO's n_steps is its rollout (a batch must fit in it); SAC's and TD3's is the n-step return's length."""
    ppo = load_hyperparams("ppo", "BoxToss-Stack-v0")
    with pytest.raises(ConfigError, match="batch_size must be <= n_steps x n_envs"):
        check_config({**ppo, "n_steps": 4, "batch_size": 256}, "ppo")
    for algo in ("sac", "td3"):
        check_config({**load_hyperparams(algo, "BoxToss-Stack-v0"), "n_steps": 4, "batch_size": 256}, algo)


def exits_with_one_line(capsys, main, argv, message):
    with pytest.raises(SystemExit) as done:
        main(argv)
    assert done.value.code == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1 and "Traceback" not in err, err


@pytest.mark.parametrize(
    "override, message",
    [
        ("batch_size=0", "batch_size must be an integer >= 2, got 0"),
        ("n_steps=0", "n_steps must be an integer >= 1, got 0"),
        ("policy_kwargs.net_arch=abc", "policy_kwargs.net_arch must be a list of layer sizes"),
        ("checkpoint_freq=abc", "checkpoint_freq must be an integer >= 0, got 'abc'"),
        ("torch_threads=0", "torch_threads must be an integer >= 1, got 0"),
        ("vec_env_kwargs.threads=9", "vec_env_kwargs.threads must be an integer >= 1 and <= "),
        ("eval_targets=0", "eval_targets must be an integer >= 1, got 0"),
        ("eval_freq=-5", "eval_freq must be an integer >= 0, got -5"),
        ("normalize=maybe", "normalize must be true, false or a mapping"),
        ("env_wrapper={box_toss_env.envs.ballistic.BallisticThrows: {turn_range: -1}}", "env_wrapper: "),
        ("env_wrapper={box_toss_env.envs.ballistic.BallisticThrows: {spin: 1}}", "env_wrapper: "),
    ],
)
def test_the_audits_bad_training_options_are_one_line_and_make_nothing(tmp_path, capsys, override, message):
    exits_with_one_line(
        capsys, train.main, ["--runs-dir", str(tmp_path / "runs"), "--no-progress", "--set", override], message
    )
    assert not (tmp_path / "runs").exists()


def test_a_negative_seed_is_refused(tmp_path, capsys):
    exits_with_one_line(
        capsys,
        train.main,
        ["--runs-dir", str(tmp_path / "runs"), "--seed", "-1"],
        "--seed must be an integer >= 0, got -1",
    )
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--targets", "0"], "--targets must be an integer >= 1, got 0"),
        (["--first-seed", "-3"], "--first-seed must be an integer >= 0, got -3"),
        (["--video", "-1"], "--video must be an integer >= 0, got -1"),
        (["--env-kwargs", "mass=-1"], "--env-kwargs: mass"),
        (["--env-kwargs", "nonsense=1"], "--env-kwargs: "),
        (["--env-kwargs", "nonsense"], "key=value"),
        (["--tag", "../../x"], "--tag must be a single folder name"),
    ],
)
def test_bad_evaluation_options_are_one_line_and_make_nothing(tmp_path, capsys, argv, message):
    run_dir = make_baseline_run("random", tmp_path / "random")
    before = sorted(os.listdir(run_dir))
    exits_with_one_line(capsys, evaluate.main, [str(run_dir), *argv], message)
    assert sorted(os.listdir(run_dir)) == before and sorted(os.listdir(tmp_path)) == ["random"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--throw", "1e308,1e308,0"], "the env throws at speeds up to 8 m/s"),
        (["--throw", "0,0,1e308"], "spins up to"),
        (["--throw", "nan,1,0"], "three finite numbers"),
        (["--throw", "1,2"], "three finite numbers"),
        (["--width", "0"], "--width must be an integer in [100, 10000], got 0"),
        (["--height", "-5"], "--height must be an integer in [100, 10000], got -5"),
        (["--seed", "-1"], "--seed must be an integer in [0, inf], got -1"),
    ],
)
def test_bad_viewer_options_are_one_line(tmp_path, capsys, argv, message):
    exits_with_one_line(
        capsys, viewer.main, ["--play", "--frames", "1", "--out", str(tmp_path / "f.png"), *argv], message
    )
    assert not (tmp_path / "f.png").exists()
