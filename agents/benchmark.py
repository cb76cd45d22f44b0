"""The BoxToss benchmark: every variant, tier and algorithm over several seeds, against the ceiling, reported as
researchers report it (rliable's IQM with stratified-bootstrap 95% intervals, performance profiles, the
probability of improvement), with a held-out split of each variant.

    python -m agents.benchmark                           # everything (days on 2 cores): runs/benchmark/, docs/agents/
    python -m agents.benchmark --report-only --readme    # the page, the figures and the README from the stored runs
    python -m agents.benchmark --envs BoxToss-ShortEnd-v0 --tiers raw --algos ppo --seeds 0 1 2 3 4
    python -m agents.benchmark --envs BoxToss-v0 --tiers assisted --heldout --algos ppo   # the held-out split
    python -m agents.benchmark --envs BoxToss-Stack-v0 --set n_timesteps=16384           # a shorter budget
    python -m agents.benchmark --envs BoxToss-Goal-v0 --seeds 0 --readme                 # HER on the goal env
    python -m agents.benchmark --envs BoxToss-HiddenPhysics-v0 --tiers hidden-physics    # its ceiling and baselines

Tiers (``agents.benchmark_tiers``, headline first): ``raw``, the env's own actions, and ``assisted``, the recipes'
ballistic or stack commands; then ``hidden-physics`` (``agents.benchmark_hidden``), several throws of a box whose
dynamics are unseen, whose ceiling and baselines ``agents.hidden_physics_tier`` measures and stores.
Without ``--seeds`` each tier trains its default seeds (five for PPO on every variant of
the headline tier and for every algorithm on ThisSideUp, ShortEnd and the stack; three elsewhere). Each training is
``python -m agents.train`` with the tier's recipe, in ``runs/benchmark/<env id>/[raw/]<algo>-seed<k>``; a finished
run is kept and a killed one resumed, and every run is added to ``docs/agents/benchmark_runs.json`` as soon as it is
scored (``agents.benchmark_store``), so the tables grow run by run and a session may stop between any two. Beside
the algorithms: random actions (``random-seed<k>``, uniform env actions, the same in every tier) and the prior
(``prior-seed<k>``: the tier's PPO recipe untrained, its mean action, as training starts from it, including the
recipe's ``initial_mean``). The ceiling is ``agents.ceiling.sweep`` (the oracle at growing budgets; the stack's is
``agents.stack_planner``'s measured rows). ``--heldout`` trains on each variant's train split (``split="train"``,
``envs.arguments``) in ``<tier folder>/heldout/`` and scores on both splits' test targets.

``--readme`` writes ``docs/agents/benchmark.md`` (a table per tier, the held-out tables, per variant the details),
``docs/agents/profiles.png`` and ``aggregates.png`` (performance profiles and aggregate IQMs per tier) and the README's
benchmark section, headline tier first.
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path
from typing import Any, cast

import gymnasium as gym

from agents import benchmark_goal, benchmark_hidden, benchmark_page, ceiling, report, train
from agents import benchmark_store as store_module
from agents import config as configuration
from agents.algorithms import ALGORITHMS
from agents.benchmark_goal import GOAL_AGENTS, GOAL_ENV, GOAL_SECTION, goal_hyperparams
from agents.benchmark_tiers import (
    PLANNED_CEILINGS,
    RANDOM_SEEDS,
    SAME_TASK,
    TIER_NAMES,
    TIERS,
    VARIANTS,
    Tier,
    run_dir,
    tier_named,
)
from agents.command_line import SEED, OneLineParser, folder, json_file, one_line_errors
from agents.envs import make_training_env, normalizer_of
from agents.evaluation import (
    evaluate,
    evaluate_run,
    evaluate_stack,
    is_stack,
    make_baseline_run,
    stack_scores,
    summarize,
)
from agents.policies import TrainedPolicy
from agents.run_folder import is_file_on_the_way, read_csv
from agents.training import RUNS, latest_checkpoint, new_model, read_timing
from box_toss_env.files import write_atomic

ROOT = RUNS / "benchmark"
DOCS = report.DOCS
TRIAL_NAME = re.compile(r"[a-z0-9][a-z0-9-]*")
ALL_TIERS = (*TIER_NAMES, benchmark_hidden.NAME)
"""``--tiers``' choices: the SB3 tiers (``agents.benchmark_tiers``) and the hidden-physics tier (``benchmark_hidden``:
its own episodes, ceiling and baselines, trained by ``agents.hidden_physics_tier``)."""
TEST_SPLIT = {"split": "test"}
SPLIT_TAGS = {"split=train": {"split": "train"}, "split=test": TEST_SPLIT}


# -- training --------------------------------------------------------------------------------------
def settings(tier: Tier, overrides: list[str], split: str | None) -> list[str]:
    """The ``--set`` overrides of a training: the tier's, the command's, and the train split's env kwarg."""
    return [*tier.overrides, *overrides, *([f"env_kwargs.split={split}"] if split else [])]


def recipe(tier: Tier, algo: str, env_id: str, overrides: list[str], split: str | None = None) -> dict[str, Any]:
    """The checked configuration ``algo`` trains on ``env_id`` in ``tier`` (a ConfigError names what is wrong)."""
    config = configuration.apply_overrides(
        configuration.load_hyperparams(algo, env_id, tier.hyperparams(algo, env_id)),
        settings(tier, overrides, split),
        algo,
    )
    config.setdefault("env_kwargs", {})
    configuration.check_config(config, algo)
    return config


def stem(algo: str, trial: str | None) -> str:
    """The run folder's name before ``-seed<k>``: the algorithm, and a trial's name after it."""
    return algo if trial is None else f"{algo}-{trial}"


def agent_name(algo: str, trial: str | None) -> str:
    """A record's agent: the algorithm, or ``algo:trial`` for a trial of other settings (``--trial``)."""
    return algo if trial is None else f"{algo}:{trial}"


def ensure_trained(
    root: Path,
    env_id: str,
    tier: Tier,
    algo: str,
    seed: int,
    overrides: list[str],
    split: str | None = None,
    trial: str | None = None,
) -> Path:
    """The run of ``algo`` on ``env_id`` with ``seed`` in ``tier`` (on the train split with ``split``; a ``trial`` of
    the ``overrides`` in its own folder), trained or resumed unless it has results; a run on the train split is also
    scored on the test split."""
    path = run_dir(root, env_id, tier, f"{stem(algo, trial)}-seed{seed}", split)
    if report.read_results(path) is None:
        if (path / "config.yml").exists() and latest_checkpoint(path, algo) is not None:
            train.main(["--resume", str(path), "--no-progress"])
        else:
            args = ["--algo", algo, "--env", env_id, "--seed", str(seed), "--no-progress", "--runs-dir"]
            args += [str(path.parent), "--name", path.name, "--hyperparams", str(tier.hyperparams(algo, env_id))]
            extra = settings(tier, overrides, split)
            train.main(args + (["--set", *extra] if extra else []))
    if split is not None and report.read_results(path, "split=test") is None:
        evaluate_run(path, env_kwargs=TEST_SPLIT, quiet=True)
    return path


def training_return(path: Path) -> float | None:
    """The mean episode return of the last rollouts while training (SB3's ``rollout/ep_rew_mean``), or None."""
    rows = read_csv(path / "logs" / "progress.csv")[1] if (path / "logs" / "progress.csv").exists() else []
    values = [row.get("rollout/ep_rew_mean") for row in rows if row.get("rollout/ep_rew_mean")]
    return float(cast(str, values[-1])) if values else None


def training_record(path: Path, env_id: str, tier: Tier, agent: str, seed: int, split=None) -> dict[str, Any] | None:
    """The store's record of a finished training run (None if it has no results yet); a trial's keeps the command
    that trained it."""
    results = {tag: r for tag in ("default", "split=test") if (r := report.read_results(path, tag)) is not None}
    if "default" not in results or (split is not None and "split=test" not in results):
        return None
    record = store_module.make_record(
        env_id,
        tier.name,
        agent,
        seed,
        results,
        split=split,
        timing=read_timing(path),
        training_return=training_return(path),
    )
    if ":" in agent and (path / "command.txt").exists():
        record["command"] = (path / "command.txt").read_text().splitlines()[0]
    return record


# -- baselines and the ceiling ---------------------------------------------------------------------
def ensure_random(root: Path, env_id: str, seed: int) -> dict[str, Any]:
    """Uniform env actions (``RandomPolicy(seed)``) on the test targets: the same in every tier."""
    path = root / env_id / f"random-seed{seed}"
    if report.read_results(path) is None:
        command = f"python -m agents.baselines random --env {env_id} --set seed={seed}"
        make_baseline_run("random", path, env_id, settings={"seed": seed}, command=command)
        evaluate_run(path, quiet=True)
    results = cast(dict[str, Any], report.read_results(path))
    return store_module.make_record(env_id, None, "random", seed, {"default": results})


def prior_results(env_id: str, tier: Tier, seed: int, overrides: list[str]) -> dict[str, Any]:
    """The tier's prior recipe untrained (``training.new_model``: seeded, its ``initial_mean`` applied) after one
    reset of its training env (the observation statistics training starts with), scored deterministically."""
    import torch

    config = recipe(tier, tier.prior_algo, env_id, overrides)
    torch.set_num_threads(int(config.get("torch_threads", 1)))
    venv = make_training_env(
        env_id,
        config["n_envs"],
        seed=seed,
        env_kwargs=config["env_kwargs"],
        vec_env_kwargs=config.get("vec_env_kwargs"),
        normalize=config.get("normalize", True),
        env_wrapper=config.get("env_wrapper"),
    )
    model = new_model(venv, config, env_id, seed, tier.prior_algo)
    venv.reset()
    policy = TrainedPolicy(model, normalizer_of(venv), config.get("env_wrapper"))
    venv.close()
    if is_stack(env_id):
        return stack_scores(evaluate_stack(policy, env_id, config["env_kwargs"])[0])
    throws, _ = evaluate(policy, env_id, config["env_kwargs"])
    target_range = gym.make(env_id, **config["env_kwargs"]).unwrapped.config.target_x_range  # type: ignore[attr-defined]
    return summarize(throws, target_range)


def ensure_prior(root: Path, env_id: str, tier: Tier, seed: int, overrides: list[str]) -> dict[str, Any]:
    """The prior's scores (``prior_results``), kept in ``prior-seed<k>/results.json``."""
    path = run_dir(root, env_id, tier, f"prior-seed{seed}") / "results.json"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(path, json.dumps(prior_results(env_id, tier, seed, overrides), indent=1))
    results = json.loads(path.read_text())
    return store_module.make_record(env_id, tier.name, "prior", seed, {"default": results})


def ensure_ceiling(store: dict[str, Any], root: Path, env_id: str, tag: str = "default") -> None:
    """The variant's oracle sweep under ``tag`` (``default`` or a split's), run if the store lacks it; each finished
    budget is kept in ``<root>/<env id>/ceiling-<tag>.partial.json``, so a killed sweep resumes at its budget."""
    if env_id in PLANNED_CEILINGS or env_id in SAME_TASK or store["ceilings"].get(env_id, {}).get(tag):
        return
    partial = root / env_id / f"ceiling-{tag}.partial.json"
    done = json.loads(partial.read_text()) if partial.exists() else []
    print(f"{env_id} ({tag}): the oracle at {len(ceiling.BUDGETS)} search budgets on {ceiling.CEILING_TARGETS} targets")
    partial.parent.mkdir(parents=True, exist_ok=True)
    rows = ceiling.sweep(
        env_id,
        SPLIT_TAGS.get(tag),
        done=done,
        on_row=lambda rows: write_atomic(partial, json.dumps(rows, indent=1)),
    )
    store["ceilings"].setdefault(env_id, {})[tag] = rows
    partial.unlink(missing_ok=True)


# -- the command -----------------------------------------------------------------------------------
def planned_seeds(args: argparse.Namespace, tier: Tier, env_id: str, algo: str) -> tuple[int, ...]:
    return tuple(args.seeds) if args.seeds is not None else tier.default_seeds(env_id, algo)


def sb3_tiers(args: argparse.Namespace) -> list[Tier]:
    """The ``--tiers`` trained with SB3 recipes (all but the hidden-physics tier)."""
    return [tier_named(name) for name in args.tiers if name != benchmark_hidden.NAME]


def check_options(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Every env id registered, every training's recipe (with the tier's and ``--set`` overrides) valid: a one-line
    error before anything is created or trained."""
    for env_id in args.envs:
        if env_id not in gym.registry:
            parser.error(f"--envs: {env_id!r} is not registered")
    if is_file_on_the_way(args.root):
        parser.error(f"--root {args.root} is a file, not a folder (or lies under one)")
    if args.readme and not DOCS.parent.is_dir():
        parser.error(f"--readme rewrites the repository's pages ({DOCS}): run it in a clone")
    if args.trial is not None and not TRIAL_NAME.fullmatch(args.trial):
        parser.error(f"--trial must be lower-case letters, digits and dashes (a folder name), got {args.trial!r}")
    if args.report_only:
        return
    for text in args.overrides:
        try:
            configuration.parse_override(text)
        except configuration.ConfigError as error:
            parser.error(f"--set: {error}")
    for env_id in args.envs:
        if env_id == GOAL_ENV:  # its agents' settings: GOAL_AGENTS and the goal recipes (goal_hyperparams)
            for agent, (algo, *_) in GOAL_AGENTS.items():
                if algo in args.algos:
                    try:
                        configuration.check_config(goal_hyperparams(agent)[1], algo)
                    except configuration.ConfigError as error:
                        parser.error(f"{agent} on {env_id}: {error}")
            continue
        for tier in sb3_tiers(args):
            algos = [a for a in args.algos if a in tier.algos and tier.has_recipe(a, env_id)]
            for algo in algos + [tier.prior_algo] * (env_id in tier.variants):
                try:
                    recipe(tier, algo, env_id, args.overrides, "train" if args.heldout else None)
                except configuration.ConfigError as error:
                    given = f" with --set {' '.join(args.overrides)}" if args.overrides else ""
                    parser.error(f"{algo} on {env_id} ({tier.name}){given}: {error}")


def record(store: dict[str, Any], entry: dict[str, Any] | None, path: Path) -> None:
    """Add ``entry`` to the store and write it (the partial table grows run by run)."""
    if entry is not None:
        store_module.add(store, entry)
        store_module.save(store, path)


def train_variant(args: argparse.Namespace, store: dict[str, Any], env_id: str) -> None:
    """Everything the options ask for on one variant that the store lacks: random actions, the ceiling, per tier the
    prior and each algorithm's seeds (on the train split with ``--heldout``, and the splits' ceilings). A record in
    the store is never measured again (delete it to measure it anew)."""
    stored = {store_module.key_of(r) for r in store["runs"]}  # measured before: kept, not trained again
    if not args.heldout:
        for seed in RANDOM_SEEDS:
            if (env_id, None, "random", seed, None) not in stored:
                record(store, ensure_random(args.root, env_id, seed), args.store)
    if not args.no_ceiling:
        for tag in ("split=train", "split=test") if args.heldout else ("default",):
            ensure_ceiling(store, args.root, env_id, tag)
            store_module.save(store, args.store)
    split = "train" if args.heldout else None
    for tier in sb3_tiers(args):
        if env_id not in tier.variants or (split and (env_id in PLANNED_CEILINGS or env_id in SAME_TASK)):
            continue
        if not split:
            for seed in planned_seeds(args, tier, env_id, tier.prior_algo):
                if (env_id, tier.name, "prior", seed, None) not in stored:
                    record(store, ensure_prior(args.root, env_id, tier, seed, args.overrides), args.store)
        if args.baselines_only:
            continue
        for algo in [a for a in tier.algos if a in args.algos and tier.has_recipe(a, env_id)]:
            for seed in planned_seeds(args, tier, env_id, algo):
                if (env_id, tier.name, agent_name(algo, args.trial), seed, split) in stored:
                    continue
                path = ensure_trained(args.root, env_id, tier, algo, seed, args.overrides, split, args.trial)
                found = training_record(path, env_id, tier, agent_name(algo, args.trial), seed, split)
                record(store, found, args.store)


def collect(store: dict[str, Any], root: Path, path: Path) -> None:
    """Add the finished runs found in ``root`` that the store lacks (trained by an earlier session or command)."""
    before = len(store["runs"])
    for tier in TIERS:
        for env_id in tier.variants:
            for split in (None, "train"):
                for algo in tier.algos:
                    for found_run in sorted(run_dir(root, env_id, tier, "x", split).parent.glob(f"{algo}-*seed*")):
                        name, _, seed = found_run.name.rpartition("-seed")
                        trial = name[len(algo) + 1 :] or None
                        if not seed.isdigit() or (trial is not None and not TRIAL_NAME.fullmatch(trial)):
                            continue
                        found = training_record(found_run, env_id, tier, agent_name(algo, trial), int(seed), split)
                        if found and store_module.key_of(found) not in {store_module.key_of(r) for r in store["runs"]}:
                            store_module.add(store, found)
    if len(store["runs"]) > before:
        store_module.save(store, path)
        print(f"added {len(store['runs']) - before} finished runs found in {root} to {path}")


def make_parser() -> OneLineParser:
    """The command's options (``check_options`` checks what their types cannot)."""
    p = OneLineParser(prog="python -m agents.benchmark", description=__doc__.split("\n\n")[0])
    variants = [*VARIANTS, *(v for t in TIERS for v in t.variants), benchmark_hidden.ENV_ID, GOAL_ENV]
    p.add_argument("--envs", nargs="+", default=list(dict.fromkeys(variants)), help="registered env ids")
    p.add_argument("--tiers", nargs="+", default=list(ALL_TIERS), choices=ALL_TIERS, help="headline first")
    p.add_argument("--algos", nargs="+", default=sorted(ALGORITHMS), choices=sorted(ALGORITHMS), help="SB3 algorithms")
    p.add_argument(
        "--seeds", nargs="+", type=SEED, default=None, help=f"training seeds, {SEED.allowed} (default: each tier's)"
    )
    p.add_argument("--root", type=folder, default=ROOT, help="folder of the benchmark's runs")
    p.add_argument("--store", type=json_file, default=store_module.STORE, help="the stored runs (a .json file)")
    p.add_argument("--heldout", action="store_true", help="train on the train split, score on train and test")
    p.add_argument(
        "--set",
        nargs="*",
        default=[],
        action="extend",
        metavar="KEY=VALUE",
        dest="overrides",
        help="override the recipes' hyperparameters of every training, e.g. n_timesteps=16384",
    )
    p.add_argument(
        "--trial",
        metavar="NAME",
        help="train the --set overrides as a trial of each algorithm (ppo:NAME, folders ppo-NAME-seed<k>), a row "
        "of its variant's details beside the recipe's",
    )
    p.add_argument("--no-ceiling", action="store_true", help="skip the oracle sweep")
    p.add_argument("--baselines-only", action="store_true", help="random actions, the prior and the ceiling only")
    p.add_argument("--report-only", action="store_true", help="train nothing: tables from the stored runs")
    p.add_argument("--readme", action="store_true", help="write docs/agents/benchmark.md, its figures, the README")
    return p


def main(argv: list[str] | None = None) -> None:
    """The command; a damaged run file or a file-system error ends it in one line (``one_line_errors``)."""
    with one_line_errors("python -m agents.benchmark"):
        run(argv)


def run(argv: list[str] | None = None) -> None:
    command = make_parser()
    args = command.parse_args(argv)
    check_options(command, args)
    variants = [env_id for env_id in args.envs if env_id not in (GOAL_ENV, benchmark_hidden.ENV_ID)]
    goal = GOAL_ENV in args.envs
    hidden = benchmark_hidden.NAME in args.tiers and benchmark_hidden.ENV_ID in args.envs
    store = store_module.load(args.store)
    collect(store, args.root, args.store)
    if not args.report_only:
        for env_id in variants:
            train_variant(args, store, env_id)
        if hidden:
            benchmark_hidden.train(args.seeds if args.seeds is not None else [0, 1, 2])
        if goal:
            benchmark_goal.ensure_goal_random(args.root)
            for seed in args.seeds if args.seeds is not None else (0, 1, 2):
                for agent, (algo, *_) in benchmark_goal.GOAL_AGENTS.items():
                    if algo in args.algos:
                        benchmark_goal.ensure_goal_trained(args.root, agent, seed)
    goal_text = benchmark_goal.goal_document(args.root, args.algos, args.seeds or [0, 1, 2]) if goal else ""
    if variants:
        print(benchmark_page.summary(store, benchmark_hidden.rows()))
    if goal_text:
        print(goal_text)
    if args.readme:
        benchmark_page.write(store, args.root, goal_text or None, only_goal=not variants)


__all__ = ["GOAL_SECTION", "TIERS", "main"]

if __name__ == "__main__":
    main()
