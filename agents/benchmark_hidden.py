"""The hidden-physics tier in the benchmark's tables (``BoxToss-HiddenPhysics-v0``: several throws of one box whose
mass, friction and restitution are never observed).

Its runs are not SB3 recipes of ``agents.benchmark_tiers``: ``agents.hidden_physics_tier`` measures its ceiling (the
oracle told the true dynamics), its references (random actions, the oracle told the middle dynamics) and trains its
two baselines (RecurrentPPO, PPO on stacked observations), keeping them in ``docs/agents/hidden_physics.json``. This
module reads them through ``hidden_physics_tier.benchmark_rows`` and reports them as every other tier is reported:
each agent's success over its seeds as rliable's IQM with its 95% stratified-bootstrap interval and the seed count,
its share of the ceiling, the gap between the best baseline and the ceiling, and the runs x 1 matrices of success /
ceiling the performance profiles and the aggregate figure draw.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from agents import benchmark_stats as stats
from agents import hidden_physics_tier

NAME = "hidden-physics"
"""The tier's name for ``python -m agents.benchmark --tiers``."""
ENV_ID = hidden_physics_tier.ENV_ID
TITLE = "Hidden physics: several throws, the dynamics unseen"
MEANING = (
    "the env's own actions on `BoxToss-HiddenPhysics-v0`: up to 5 throws of the same box at the same target, its "
    "mass, friction and restitution drawn wide and never observed, each landing observed; success is the pose reached "
    "within the throws ([its page](../hidden_physics.md))"
)
PANEL_NAMES = {
    "RecurrentPPO (LSTM policy)": "RecurrentPPO",
    "PPO, stacked observations": "PPO stacked",
    "oracle told the middle dynamics": "blind planner",
    "random": "random",
}
"""The agents the profiles and aggregates draw (not the ceiling's rows), under a short name."""


def rows(path: Path = hidden_physics_tier.RESULTS) -> dict[str, Any]:
    """The tier's stored rows (``hidden_physics_tier.benchmark_rows``)."""
    return hidden_physics_tier.benchmark_rows(path)


def baselines(found: dict[str, Any]) -> dict[str, stats.Estimate]:
    """Each trained baseline's IQM of success over its seeds."""
    return {name: stats.iqm(np.array(a["success"])) for name, a in found["agents"].items() if a["kind"] == "baseline"}


def table(found: dict[str, Any]) -> list[str]:
    """A row per agent: its kind, success IQM [95% CI] (seeds), first-throw success and throws an episode (means over
    seeds), and its share of the ceiling."""
    top = found["ceiling"]
    lines = [
        "| agent | kind | success | first-throw success | throws an episode | share of the ceiling |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for name, agent in found["agents"].items():
        value = stats.iqm(np.array(agent["success"]))
        share = "-" if not top else f"{value.value / top:.0%}"
        lines.append(
            f"| {name} | {agent['kind']} | {value.percent()} | {np.mean(agent['first_throw_success']):.1%} | "
            f"{np.mean(agent['mean_throws']):.2f} | {share} |"
        )
    return lines


def gap_line(found: dict[str, Any]) -> str:
    """The best baseline against the ceiling, in points and as a share ("" before both are measured)."""
    top, trained = found["ceiling"], baselines(found)
    if not top or not trained:
        return ""
    name, best = max(trained.items(), key=lambda item: item[1].value)
    return (
        f"Gap: the best baseline, {name}, reaches {best.percent()} against the ceiling's {top:.1%}: "
        f"{100 * (top - best.value):.1f} points below it ({best.value / top:.0%} of the ceiling; its interval's top "
        f"{100 * (top - best.high):.1f} points below)."
    )


def matrices(found: dict[str, Any]) -> dict[str, np.ndarray]:
    """Per drawn agent, its seeds' success / ceiling as a runs x 1 matrix (nothing without a ceiling)."""
    top = found["ceiling"]
    if not top:
        return {}
    return {
        f"{PANEL_NAMES[name]} ({len(agent['success'])} seed{'s' * (len(agent['success']) > 1)})": np.array(
            agent["success"]
        )[:, None]
        / top
        for name, agent in found["agents"].items()
        if name in PANEL_NAMES
    }


def section(found: dict[str, Any], level: str = "###") -> list[str]:
    """The tier's part of the benchmark page: what it is, its table, the gap and the commands that measured it."""
    if not found["agents"]:
        return []
    lines = [f"{level} {TITLE}", "", f"Acting in {MEANING}.", "", *table(found), ""]
    if gap := gap_line(found):
        lines += [gap, ""]
    return lines + [
        f"On the same {found['episodes']} test episodes (seeds {found['first_seed']}...); measured by "
        "`python -m agents.hidden_physics_tier ceiling` and `train` (or `python -m agents.benchmark --tiers "
        f"{NAME}`), the baselines' budgets and training times on the task's page.",
        "",
    ]


def summary_line(found: dict[str, Any]) -> str:
    """The README's line of the tier: its gap, or "" before it is measured."""
    gap = gap_line(found)
    return f"**{TITLE}** (`{ENV_ID}`): {gap[len('Gap: ') :]}" if gap else ""


def train(seeds: list[int]) -> None:
    """The tier's references and ceiling if not stored yet, then its baselines' ``seeds`` (a run stored is kept)."""
    if not rows()["agents"].get("random"):
        hidden_physics_tier.main(["ceiling"])
    hidden_physics_tier.main(["train", "--seeds", *map(str, seeds)])
