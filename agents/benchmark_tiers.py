"""The benchmark's tiers, declared once, in the order every table shows them: how the agents act, on which variants,
with which algorithms and seeds, and where their runs live.

- ``raw`` (the headline tier): the env's own actions (launch speed, direction, spin). Each algorithm's recipe is
  ``agents/hyperparams/raw/<algo>.yml``'s entry where it has one, else ``agents/hyperparams/<algo>.yml``'s without
  its ``env_wrapper``. Standing a box on an end here needs a spin right to a hundredth of its range.
- ``assisted``: the recipes as their files say, acting through their ``env_wrapper`` (the ballistic command,
  ``envs.ballistic``, or the stack's throw commands): a controller that already lands a face flat on the target.

A tier of its own episodes and agents (the hidden-physics task of several throws, say) is one more ``Tier`` in
``TIERS``: its variants, its algorithms (names of ``agents.algorithms.ALGORITHMS``, each with a recipe for the
variant in ``agents/hyperparams/<algo>.yml`` or the tier's ``recipes`` folder), its run folder and overrides, and its
variants' ceiling in ``PLANNED_CEILINGS`` where a planner gives it; every table, statistic and figure of
``agents.benchmark`` is made per tier from this list.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from agents import config as configuration

ONE_THROW = (
    "BoxToss-v0",
    "BoxToss-LongSide-v0",
    "BoxToss-ShortEnd-v0",
    "BoxToss-ThisSideUp-v0",
    "BoxToss-Mixed-v0",
    "BoxToss-OnBox-v0",
)
STACK = "BoxToss-Stack-v0"
PIXELS = "BoxToss-Pixels-v0"
VARIANTS = (*ONE_THROW, STACK)
SAME_TASK = {PIXELS: "BoxToss-v0"}
"""Variants that are another's task observed otherwise: their ceiling is that variant's (the oracle plans from the
episode, not from the observation)."""
PLANNED_CEILINGS = {STACK: Path(__file__).resolve().parents[1] / "docs" / "agents" / "stack_ceiling.json"}
"""Variants whose ceiling is a planner's measured rows (a JSON list, the largest budget last, each with its
``success_rate``) rather than the oracle sweep: the stack's (``agents.stack_planner``). A task of several throws of
its own (the hidden-physics tier's, whose ceiling is a planner told the true parameters) adds its file here."""
RANDOM_SEEDS = (0, 1, 2, 3, 4)
"""The seeds of random actions on every variant (the same in every tier)."""
FIVE_SEED_VARIANTS = ("BoxToss-ThisSideUp-v0", "BoxToss-ShortEnd-v0", STACK)
"""Where every algorithm of the headline tier gets five seeds (the rest three, PPO five everywhere)."""


@dataclass(frozen=True)
class Tier:
    """One tier: its name (``--tiers``), title, what it means, its variants and algorithms, the folder of its runs
    under ``<root>/<env id>/`` ("" for the root's own), the ``--set`` overrides of every training, the recipe folder
    tried first (``recipes``, else ``agents/hyperparams/``), the algorithm whose untrained policy is the prior
    column, and whether it is the headline."""

    name: str
    title: str
    meaning: str
    variants: tuple[str, ...] = VARIANTS
    algos: tuple[str, ...] = ("ppo", "sac", "td3")
    folder: str = ""
    overrides: tuple[str, ...] = ()
    recipes: Path | None = None
    prior_algo: str = "ppo"
    headline: bool = False

    def hyperparams(self, algo: str, env_id: str) -> Path:
        """The folder of the recipe ``algo`` trains on ``env_id`` in this tier."""
        own = self.recipes is not None and configuration.has_entry(algo, env_id, self.recipes)
        return self.recipes if own and self.recipes is not None else configuration.HYPERPARAMS

    def has_recipe(self, algo: str, env_id: str) -> bool:
        """Whether ``algo`` has a recipe for ``env_id`` in this tier (``BoxToss-Pixels-v0``: the raw tier's alone):
        the others are not in the tier's plan for the variant."""
        return configuration.has_entry(algo, env_id, self.hyperparams(algo, env_id))

    def default_seeds(self, env_id: str, algo: str) -> tuple[int, ...]:
        """The seeds ``python -m agents.benchmark`` trains without ``--seeds``: five for the headline algorithm on
        every variant of the headline tier and for every algorithm on ``FIVE_SEED_VARIANTS``, three elsewhere."""
        headline = self.headline and algo == self.prior_algo
        five = headline or env_id in FIVE_SEED_VARIANTS
        return tuple(range(5 if five else 3))


RAW = Tier(
    name="raw",
    title="Raw actions (headline)",
    meaning="the env's own actions: launch speed, direction and spin (`BoxToss-Pixels-v0`: `BoxToss-v0` observed as "
    "an image, SB3's CnnPolicy)",
    variants=(*ONE_THROW, PIXELS, STACK),
    folder="raw",
    overrides=("env_wrapper=null",),
    recipes=configuration.RAW_HYPERPARAMS,
    headline=True,
)
ASSISTED = Tier(
    name="assisted",
    title="Assisted: ballistic commands",
    meaning="the recipe's env_wrapper: the ballistic command (flight time, landing offset, lean from a throw that "
    "lands a target face flat on the target) or the stack's throw commands",
)
TIERS: tuple[Tier, ...] = (RAW, ASSISTED)
"""Every tier, headline first: the order of the tables, the README and the figures."""
TIER_NAMES = tuple(tier.name for tier in TIERS)


def recipe_of(tier: Tier, algo: str, env_id: str) -> dict:
    """``algo``'s recipe on ``env_id`` in ``tier`` with the tier's overrides (no ``--set``), an ``env_wrapper`` of
    None dropped (the raw tier's ``env_wrapper=null`` is a recipe without one)."""
    config = configuration.apply_overrides(
        configuration.load_hyperparams(algo, env_id, tier.hyperparams(algo, env_id)), list(tier.overrides), algo
    )
    if config.get("env_wrapper") is None:
        config.pop("env_wrapper", None)
    return config


def same_as_headline(tier: Tier, algo: str, env_id: str) -> bool:
    """Whether ``algo`` trains on ``env_id`` in ``tier`` exactly as in the headline tier: a recipe of another tier
    with no ``env_wrapper`` (``ppo.yml``'s BoxToss-v0 and BoxToss-LongSide-v0 entries act in the env's own actions),
    so its cell repeats the headline tier's trainings seed for seed."""
    headline = TIERS[0]
    if tier.headline or env_id not in headline.variants or not headline.has_recipe(algo, env_id):
        return False
    if not tier.has_recipe(algo, env_id):
        return False
    return recipe_of(tier, algo, env_id) == recipe_of(headline, algo, env_id)


def tier_named(name: str) -> Tier:
    """The tier called ``name`` (a ValueError naming the tiers otherwise)."""
    for tier in TIERS:
        if tier.name == name:
            return tier
    raise ValueError(f"tier must be one of {TIER_NAMES}, got {name!r}")


SPLIT_FOLDER = "heldout"
"""Runs trained on a variant's train split (``split="train"``) live in ``<tier folder>/heldout/``."""


def run_dir(root: Path, env_id: str, tier: Tier, name: str, split: str | None = None) -> Path:
    """The folder of run ``name`` (``ppo-seed0``, ``random-seed0``, ``prior-seed0``) of ``tier`` on ``env_id``."""
    folder = root / env_id
    if tier.folder:
        folder = folder / tier.folder
    if split is not None:
        folder = folder / SPLIT_FOLDER
    return folder / name
