"""Every option is checked before anything is made: one line naming the option (or key), exit status 2, no folder,
no traceback. Both sides are generated, not listed: the configuration's bad values from its schema
(``agents.schema``, itself derived from the signatures of SB3's PPO, SAC and TD3, their policies, buffers, the
optimiser and VecNormalize), the command lines' from each command's parser (each option's type names its range), so
a new key or option gets its tests.

For every configuration key and every command-line option: a value of the wrong type, one out of its range and an
empty one.
"""

from __future__ import annotations

import argparse
import inspect
import math
import os
from pathlib import Path

import pytest

from agents import algorithms, benchmark, evaluate, main, schema, train
from agents.command_line import MAX_SEED, Integer, folder, json_file, single_name
from agents.config import ConfigError, check_config, load_hyperparams
from agents.evaluation import make_baseline_run


# -- the configuration -------------------------------------------------------------------------------------------
def bad_values(rule: schema.Rule) -> list[tuple[str, object]]:
    """(what is wrong, value) for values ``rule`` refuses: the wrong type, out of its range, empty."""
    forms, b = rule.forms, rule.bounds
    values: list[tuple[str, object]] = [("empty", "")]
    if not forms & {"str", "class", "schedule"}:
        values.append(("wrong type", "abc"))
    elif not forms & {"int", "float", "bool"}:
        values.append(("wrong type", 1.5))
    if "bool" in forms:
        values += [("a typo", "Flase"), ("YAML 1.1's yes", "yes")]
        if not forms & {"int", "float"}:
            values.append(("an integer", 1))
    if forms & {"int", "float"}:
        if b.low is not None:
            values.append(("below the range", b.low if b.above else b.low - 1))
        if b.high is not None:
            values.append(("above the range", b.high + 1))
        if "float" in forms:
            values.append(("not finite", math.nan))
        else:
            values.append(("not an integer", (b.low or 0) + 1.5))
    if "str" in forms and (b.choices or b.prefixes):
        values.append(("not a choice", "not-a-choice"))
    if "class" in forms:
        values.append(("no such class", "nn.NotAThing"))
    if "schedule" in forms:
        values += [("a malformed schedule", "lin_abc"), ("a negative schedule", "lin_-1")]
    if "sequence" in forms and rule.items:
        label, item = next((label, item) for label, item in bad_values(rule.items[0]) if label != "empty")
        values.append((f"an item {label}", [item] * (rule.length or 1)))
    return values


def nested_rules(algo: str) -> dict[str, tuple[schema.Rule, str]]:
    """Every key a configuration of ``algo`` may set, dotted into its mappings (the policy's kwargs, the optimiser's,
    VecNormalize's; the replay buffer's for HER), with the recipe to set it in."""
    rules = {key: (rule, "BoxToss-v0") for key, rule in schema.algorithm_rules(algo).items()}
    policy = algorithms.algorithm_class(algo).policy_aliases["MlpPolicy"]
    inner, _ = schema.signature_rules(policy, schema.SUPPLIED["policy_kwargs"])
    rules |= {f"policy_kwargs.{key}": (rule, "BoxToss-v0") for key, rule in inner.items()}
    adam = inspect.signature(policy.__init__).parameters["optimizer_class"].default
    inner, _ = schema.signature_rules(adam, schema.SUPPLIED["optimizer_kwargs"])
    rules |= {f"policy_kwargs.optimizer_kwargs.{key}": (rule, "BoxToss-v0") for key, rule in inner.items()}
    rules |= {
        f"normalize.{key}": (rule, "BoxToss-v0") for key, rule in schema.algorithm_rules(algo)["normalize"].keys.items()
    }
    if algorithms.is_off_policy(algo):
        from stable_baselines3 import HerReplayBuffer

        inner, _ = schema.signature_rules(HerReplayBuffer, schema.SUPPLIED["replay_buffer_kwargs"])
        rules |= {f"replay_buffer_kwargs.{key}": (rule, "BoxToss-Goal-v0") for key, rule in inner.items()}
    return rules


def config_cases():
    for algo in sorted(algorithms.ALGORITHMS):
        for key, (rule, env_id) in nested_rules(algo).items():
            for label, value in bad_values(rule):
                yield pytest.param(algo, env_id, key, value, id=f"{algo}-{key}-{label}")


def set_key(config: dict, key: str, value: object) -> None:
    *parents, last = key.split(".")
    node = config
    for part in parents:
        if not isinstance(node.get(part), dict):
            node[part] = {}
        node = node[part]
    node[last] = value


@pytest.mark.parametrize("algo, env_id, key, value", list(config_cases()))
def test_every_configuration_key_refuses_the_wrong_type_a_value_out_of_range_and_an_empty_value(
    algo, env_id, key, value
):
    config = load_hyperparams(algo, env_id)
    set_key(config, key, value)
    with pytest.raises(ConfigError) as refused:
        check_config(config, algo)
    message = str(refused.value)
    assert key in message and "\n" not in message, message


@pytest.mark.parametrize("algo", sorted(algorithms.ALGORITHMS))
def test_the_schema_is_the_algorithms_signature_and_every_number_has_its_range_decided(algo):
    rules = schema.algorithm_rules(algo)
    assert algorithms.constructor_keys(algo) <= set(rules)
    for key, (rule, _) in nested_rules(algo).items():
        name = key.rsplit(".", 1)[-1]
        if rule.forms & {"int", "float"} and "." not in key:
            assert name in schema.RANGES, f"{algo}'s {key} is a number without a decided range (agents.schema.RANGES)"


@pytest.mark.parametrize(
    "override, message",
    [
        ("use_sde=Flase", "use_sde must be true or false, got 'Flase'"),  # a typo was taken as true
        ("normalize_advantage=yes", "normalize_advantage must be true or false, got 'yes'"),
        ("policy_kwargs.ortho_init=0", "policy_kwargs.ortho_init must be true or false, got 0"),
        ("policy_kwargs.activation_fn=nn.Nope", "policy_kwargs.activation_fn must be the name of"),
        ("policy_kwargs.not_a_kwarg=1", "policy_kwargs has no key 'not_a_kwarg'"),
        ("target_kl=0", "target_kl must be a number > 0"),
        ("batch_size=0", "batch_size must be an integer >= 2, got 0"),
        ("vec_env_kwargs.threads=999", "vec_env_kwargs.threads must be an integer >= 1 and <= "),
        ("n_timesteps=", "--set: n_timesteps: an empty value"),
        ("n_timesteps=99999999999999999999", "n_timesteps must be an integer >= 1 and <= 9223372036854775807"),
        # keys that must fit the observations: SB3 checked them only when building the model, in a made folder
        ("policy=CnnPolicy", "policy CnnPolicy does not read BoxToss-v0's flat (Box) observations"),
        ("policy=MultiInputPolicy", "policy MultiInputPolicy does not read BoxToss-v0's flat (Box) observations"),
        ("rollout_buffer_class=DictRolloutBuffer", "rollout_buffer_class DictRolloutBuffer does not take MlpPolicy"),
        ("policy_kwargs.features_extractor_class=NatureCNN", "features_extractor_class NatureCNN does not take"),
        ("policy_kwargs.net_arch={pi: [8], qf: [8]}", "net_arch of ppo takes only the keys ['pi', 'vf']"),
        ("=5", "--set: an override must look like key=value"),
    ],
)
def test_bad_training_options_through_the_command_line_are_one_line_and_make_nothing(
    tmp_path, capsys, override, message
):
    exits_with_one_line(capsys, train.main, ["--runs-dir", str(tmp_path / "runs"), "--set", override], message)
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    "algo, override",
    [
        ("sac", "train_freq=[1, often]"),
        ("td3", "gradient_steps=0"),
        ("sac", "replay_buffer_class=DictReplayBuffer"),  # an assertion in SB3's buffer, after the folder was made
        ("td3", "policy_kwargs.net_arch={pi: [8]}"),  # SB3 asserts a qf key for the critics
    ],
)
def test_the_off_policy_keys_are_checked_too(tmp_path, capsys, algo, override):
    key = override.split("=")[0]
    exits_with_one_line(capsys, train.main, ["--algo", algo, "--runs-dir", str(tmp_path), "--set", override], key)
    assert not os.listdir(tmp_path)


# -- the command lines ------------------------------------------------------------------------------------------
A_FILE = "{a file}"  # replaced by the path of a file in the test's folder


def option_values(action: argparse.Action) -> dict[str, list[str]]:
    """Values ``action`` must refuse, by kind: the wrong type, out of its range, empty (a kind an option cannot
    have, e.g. a wrong type for a path, is left out)."""
    kind = action.type
    values: dict[str, list[str]] = {"empty": [""]}
    if isinstance(kind, Integer):
        values["wrong type"] = ["abc", "1.5"]
        values["out of range"] = [str(kind.low - 1)] + ([str(kind.high + 1)] if kind.high is not None else [])
    elif kind is folder:
        values["out of range"] = [A_FILE]  # a file where a folder must be
    elif kind is json_file:
        values["out of range"] = ["runs.txt", str(Path.cwd())]  # not JSON, a folder
    elif kind is single_name:
        values["out of range"] = ["a/b", ".."]
    elif action.choices:
        values["wrong type"] = ["1.5"]
        values["out of range"] = ["not-a-choice"]
    elif action.dest in ("overrides", "env_kwargs"):
        values["wrong type"] = ["nonsense"]  # not key=value
        values["out of range"] = ["no_such_key=1"]
    else:
        values["out of range"] = ["NoSuchEnv-v0"]  # --env, --envs
    return values


COMMANDS = {
    "train": (train.make_parser, train.main),
    "evaluate": (evaluate.make_parser, evaluate.main),
    "main": (main.make_parser, main.main),
    "benchmark": (benchmark.make_parser, benchmark.main),
}


def base_arguments(command: str, tmp_path: Path, run: Path) -> list[str]:
    """Arguments that are good, beside the bad one (later options override earlier ones)."""
    return {
        "train": ["--runs-dir", str(tmp_path / "runs")],
        "evaluate": [str(run)],
        "main": ["--runs-dir", str(tmp_path / "runs")],
        "benchmark": ["--root", str(tmp_path / "bench"), "--envs", "BoxToss-v0", "--algos", "ppo"],
    }[command]


def cli_cases():
    for command, (make_parser, _) in COMMANDS.items():
        for action in make_parser()._actions:
            if action.nargs == 0 or isinstance(action, argparse._HelpAction):
                continue
            name = action.option_strings[-1] if action.option_strings else action.dest
            for kind, values in option_values(action).items():
                yield pytest.param(command, name, values, id=f"{command}-{name}-{kind}")


@pytest.fixture
def no_work(monkeypatch):
    """Anything past the checks fails the test (a bad value let through would start a training)."""

    def reached(*args, **kwargs):
        raise AssertionError("a bad option got past the checks")

    import agents.evaluation
    import agents.training

    for module, name in (
        (agents.training, "new_run_dir"),
        (train, "prepare_resume"),
        (agents.evaluation, "evaluate_run"),
        (main, "baseline"),
        (benchmark, "collect"),
        (benchmark, "train_variant"),
        (benchmark.benchmark_goal, "goal_document"),
        (benchmark.benchmark_page, "write"),
    ):
        monkeypatch.setattr(module, name, reached)


@pytest.mark.parametrize("command, option, values", list(cli_cases()))
def test_every_option_of_every_command_refuses_the_wrong_type_a_value_out_of_range_and_an_empty_value(
    tmp_path, capsys, monkeypatch, no_work, command, option, values
):
    monkeypatch.chdir(tmp_path)
    make_parser, run = COMMANDS[command]
    action = next(a for a in make_parser()._actions if option in (a.option_strings[-1:] or [a.dest]))
    run_dir = make_baseline_run("random", tmp_path / "run")
    (tmp_path / "a-file").write_text("a file, not a folder\n")
    before = sorted(path.name for path in tmp_path.iterdir())
    held = sorted(os.listdir(run_dir))
    for text in values:
        text = text.replace(A_FILE, str(tmp_path / "a-file"))
        argv = base_arguments(command, tmp_path, run_dir) if action.option_strings else []
        argv += [option, text] if action.option_strings else [text]
        named = text.split("=")[0] if action.dest in ("overrides", "env_kwargs") and "=" in text else option
        exits_with_one_line(capsys, run, argv, named)
        assert sorted(path.name for path in tmp_path.iterdir()) == before and sorted(os.listdir(run_dir)) == held


def test_seeds_stay_in_numpys_range(tmp_path, capsys, no_work):
    """np.random.seed, which SB3 seeds with, takes [0, 2**32 - 1]: a larger seed crashed inside SB3 with a folder
    made; the benchmark's seeds were checked after its random baseline was evaluated."""
    too_large = str(MAX_SEED + 1)
    exits_with_one_line(capsys, train.main, ["--runs-dir", str(tmp_path / "r"), "--seed", too_large], "--seed")
    exits_with_one_line(capsys, benchmark.main, ["--root", str(tmp_path / "b"), "--seeds", "0", too_large], "--seeds")
    run_dir = make_baseline_run("random", tmp_path / "run")
    argv = [str(run_dir), "--first-seed", str(MAX_SEED - 10), "--targets", "20"]
    exits_with_one_line(capsys, evaluate.main, argv, "--first-seed")
    assert sorted(os.listdir(tmp_path)) == ["run"]


def test_main_readme_without_full_makes_nothing(tmp_path, capsys, monkeypatch, no_work):
    monkeypatch.chdir(tmp_path)
    exits_with_one_line(capsys, main.main, ["--readme"], "--readme needs --full")
    assert not os.listdir(tmp_path)


def exits_with_one_line(capsys, command, argv: list[str], message: str) -> None:
    with pytest.raises(SystemExit) as done:
        command(argv)
    assert done.value.code not in (0, None)
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1 and "Traceback" not in err, (argv, err)


def recipes():
    import yaml

    from agents.config import HYPERPARAMS, RAW_HYPERPARAMS

    for directory in (HYPERPARAMS, RAW_HYPERPARAMS):
        for path in sorted(directory.glob("*.yml")):
            if path.stem in algorithms.ALGORITHMS:
                for env_id in yaml.safe_load(path.read_text()):
                    yield pytest.param(path.stem, env_id, directory, id=f"{directory.name}/{path.stem}/{env_id}")


@pytest.mark.parametrize("algo, env_id, directory", list(recipes()))
def test_every_recipe_passes_the_schema(algo, env_id, directory):
    """The schema refuses what SB3 would refuse or misread, and nothing a recipe of ours holds."""
    check_config(load_hyperparams(algo, env_id, directory), algo)
