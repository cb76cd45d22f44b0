"""The benchmark's page (``docs/agents/benchmark.md``), its figures and the README's benchmark section, written from the
stored runs (``agents.benchmark_store``) by ``python -m agents.benchmark --readme``.

Every figure is drawn here: the performance profiles and the aggregate IQMs of each tier (``profiles.png``,
``aggregates.png``), and each variant's learning curves per tier (``curves_<env id>[_raw].png``), redrawn only when
every stored training of the figure has its run folder here (a figure drawn from fewer runs would lose the others).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from agents import benchmark_hidden as hidden
from agents import benchmark_report as tables
from agents import benchmark_stats as stats
from agents import benchmark_store as store_module
from agents import report
from agents.benchmark_goal import GOAL_SECTION
from agents.benchmark_tiers import STACK, TIERS, Tier, run_dir
from agents.doc_sections import read_section, replace_section
from agents.evaluation import STACK_TEST_EPISODES, TEST_TARGETS
from box_toss_env.files import save_figure, write_atomic

DOCS = store_module.DOCS
PAGE = DOCS / "benchmark.md"
COLORS = {"random": "0.6", "prior": "0.3", "PPO": "C0", "SAC": "C1", "TD3": "C2", "RecurrentPPO": "C3", "blind": "C4"}

INTRO = (
    "Every agent is scored on the same {targets:,} test targets per variant (seeds 10000...; `BoxToss-Stack-v0`: "
    "{episodes} test episodes of 4 throws, success the whole hand stacked on the target); success is a throw at rest "
    "within the tolerance on a target face. A cell is the interquartile mean (IQM) of its seeds' success with its 95%"
    " stratified-bootstrap confidence interval and, in brackets, the number of seeds, all by "
    "[rliable](https://github.com/google-research/rliable) (with 3 seeds the IQM is their mean). The planned seeds "
    "are 5 for PPO on every variant of the headline tier and for every algorithm on "
    "ThisSideUp, ShortEnd and the stack, 3 elsewhere; a cell with fewer says so (`3 of 5`: the seeds this 2-core "
    "machine had time for), and `-` is a cell not trained. "
    "*random*: uniform env actions; *prior*: the tier's PPO recipe untrained, its mean action (what training starts "
    "from, with the recipe's `initial_mean`); the ceiling: the oracle whose search grew until its success stopped "
    "rising (the stack's: its planner). The aggregate row pools every variant's runs, success divided by the ceiling "
    "(runs per variant: as many as the variant with the fewest). Trainings: `python -m agents.train` with each tier's"
    " recipe on this 2-core machine shared with other work; budgets and wall times per variant are in the sections "
    "below, with the trials (`--trial`: the recipe with other settings) beside the recipe's rows."
)


def tier_section(store: dict[str, Any], tier: Tier, level: str = "###") -> list[str]:
    """A tier's table, its probability of improvement and its held-out table."""
    lines = [f"{level} {tier.title}", "", f"Acting in {tier.meaning}.", "", *tables.tier_table(store, tier), ""]
    if repeated := tables.repeated_line(tier):
        lines += [repeated, ""]
    if line := tables.improvement_line(store, tier):
        lines += [line, ""]
    if tier.headline and (goals := tables.goals_line(store, tier)):
        lines += [goals, ""]
    heldout = tables.heldout_table(store, tier)
    if heldout:
        lines += [
            f'Held-out split ({tier.title.split(":")[0].split(" (")[0].lower()}): trained with `split="train"`, '
            'scored on the train and on the test split (`split="test"`, ranges partly outside training\'s):',
            "",
            *heldout,
            "",
        ]
    return lines


def summary(store: dict[str, Any], hidden_rows: dict[str, Any]) -> str:
    """The README's section (the README stays a front page): the headline tier's table, then a line per other
    tier (its aggregates and probabilities of improvement), the hidden-physics tier's gap (``hidden_rows``:
    ``benchmark_hidden.rows()``) and the held-out split of each tier that has one, a line each; the rest is on
    the page."""
    headline, others = TIERS[0], TIERS[1:]
    lines = [
        "### Benchmark: every variant, tier and algorithm against the ceiling",
        "",
        "`python -m agents.benchmark` (then `--report-only --readme`): success on the test targets, IQM [95% "
        "stratified-bootstrap CI] (seeds) by rliable; every tier's table, the held-out split, performance profiles, "
        "budgets, breakdowns and learning curves in [docs/agents/benchmark.md](docs/agents/benchmark.md). "
        f"**{headline.title}**: {headline.meaning}.",
        "",
        *tables.tier_table(store, headline),
        "",
    ]
    if line := tables.improvement_line(store, headline):
        lines += [f"- {line}"]
    for tier in others:
        repeated = tables.repeated_cells(tier)
        also = f" ({repeated}: the {headline.name} tier's trainings, the recipe has no wrapper)" if repeated else ""
        lines += [f"- **{tier.title}**, over every variant{also}: {tables.aggregate_text(store, tier)}"]
    if line := hidden.summary_line(hidden_rows):
        lines += [f"- {line}"]
    heldout = [f"{tier.title.lower()}: {text}" for tier in TIERS if (text := heldout_text(store, tier))]
    if heldout:
        lines += ['- **Held-out split** (trained on `split="train"`), ' + "; ".join(heldout) + "."]
    return "\n".join(lines).rstrip() + "\n"


def heldout_text(store: dict[str, Any], tier: Tier) -> str:
    """The held-out table's rows of ``tier`` in a sentence: per variant and agent, train and test success, the gap."""
    parts = []
    for row in tables.heldout_table(store, tier)[2:]:
        env_id, agent, train, test, gap = (cell.strip() for cell in row.strip("|").split("|")[:5])
        parts.append(f"{env_id} {agent}: train split {train}, test split {test}, gap {gap}")
    return "; ".join(parts)


def panels(
    store: dict[str, Any], hidden_rows: dict[str, Any]
) -> tuple[dict[str, dict[str, Any]], dict[str, dict[str, stats.Estimate]]]:
    """Per tier (the hidden-physics tier's from ``hidden_rows`` last): each agent's runs x variants matrix of
    normalised scores, and its aggregate IQM."""
    profiles, aggregates = {}, {}
    for tier in TIERS:
        matrices = {}
        for agent in tables.agents_of(tier):
            variants, matrix = tables.normalised(store, tier, agent)
            if matrix is not None:
                matrices[f"{tables.label(agent)} ({len(variants)} of {len(tier.variants)})"] = matrix
        profiles[tier.title] = matrices
        aggregates[tier.title] = {name: stats.iqm(matrix) for name, matrix in matrices.items()}
    if hidden_matrices := hidden.matrices(hidden_rows):
        profiles[hidden.TITLE] = hidden_matrices
        aggregates[hidden.TITLE] = {name: stats.iqm(matrix) for name, matrix in hidden_matrices.items()}
    return profiles, aggregates


def plot_curves(store: dict[str, Any], root: Path, env_id: str, tier: Tier, path: Path) -> bool:
    """Validation success against throws and wall time, a line per training run, if every stored training of the
    figure has its run folder in ``root``; returns whether the figure exists."""
    runs = [
        (agent, record["seed"])
        for agent in tier.algos
        for record in store_module.records(store, env_id, tier.name, agent)
    ]
    curves = [
        (agent, report.read_evaluations(run_dir(root, env_id, tier, f"{agent}-seed{seed}"))) for agent, seed in runs
    ]
    if not runs or any(curve is None for _, curve in curves):
        return path.exists()
    plt = report.pyplot()
    fig, (ax_steps, ax_wall) = plt.subplots(1, 2, figsize=(10, 3.6))
    labelled = set()
    for agent, curve in curves:
        assert curve is not None
        name = tables.label(agent)
        kwargs = {"color": COLORS[name.split(",")[0]], "alpha": 0.8, "label": None if name in labelled else name}
        labelled.add(name)
        ax_steps.plot(curve["timesteps"], curve["success_rate"], **kwargs)
        ax_wall.plot(curve["wall_seconds"] / 60, curve["success_rate"], **kwargs)
    top = tables.ceiling_rate(store, env_id)
    for ax in (ax_steps, ax_wall):
        if top is not None:
            ax.axhline(top, color="k", linestyle="--", linewidth=1, label="ceiling" if ax is ax_steps else None)
        ax.grid(alpha=0.3)
    unit = "episodes" if env_id == STACK else "targets"
    ax_steps.set(xlabel="throws (env steps)", ylabel=f"success (validation {unit})", ylim=(0, 1.02))
    ax_wall.set(xlabel="wall time [min]", ylim=(0, 1.02))
    ax_steps.legend(fontsize=8)
    fig.suptitle(f"{env_id}, {tier.title.lower()}: learning curves, one line per training seed")
    fig.tight_layout()
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return True


def variant_section(store: dict[str, Any], root: Path, env_id: str, tier: Tier) -> list[str]:
    """One variant in one tier: the agents' details, the breakdowns, the oracle's sweep (under the headline tier:
    it is the same in every tier) and the learning curves."""
    detail = tables.detail_table(store, env_id, tier)
    if len(detail) <= 2:
        return []
    lines = [f"### {env_id}, {tier.title.lower()}", "", *detail, ""]
    if noted := tables.notes(store, env_id, tier):
        lines += [*noted, ""]
    if tried := tables.trial_lines(store, env_id, tier):
        lines += [*tried, ""]
    if breakdown := tables.breakdowns(store, env_id, tier):
        lines += [*breakdown, ""]
    sweep = store["ceilings"].get(env_id, {}).get("default")
    if sweep and tier.headline:
        lines += [*tables.sweep_table(sweep), ""]
    name = f"curves_{env_id}{'_' + tier.folder if tier.folder else ''}.png"
    if plot_curves(store, root, env_id, tier, DOCS / name):
        lines += [f"![learning curves on {env_id}, {tier.title.lower()}]({name})", ""]
    return lines


def page(store: dict[str, Any], root: Path, goal_text: str, hidden_rows: dict[str, Any]) -> str:
    lines = [
        "# BoxToss benchmark",
        "",
        "Generated by `python -m agents.benchmark --report-only --readme` from the stored runs "
        "(`docs/agents/benchmark_runs.json`).",
        "",
        INTRO.format(targets=TEST_TARGETS, episodes=STACK_TEST_EPISODES),
        "",
        "## The tiers",
        "",
    ]
    for tier in TIERS:
        lines += tier_section(store, tier)
    lines += hidden.section(hidden_rows)
    lines += [
        "## Performance profiles and aggregates",
        "",
        "Per tier, the share of runs (every variant, success / ceiling) scoring above each threshold, with 95% "
        "bands, and each agent's IQM over the variants with its interval; in brackets, on how many of the tier's "
        "variants the agent has runs:",
        "",
        "![performance profiles per tier](profiles.png)",
        "",
        "![aggregate IQM per tier](aggregates.png)",
        "",
        "## Per variant",
        "",
    ]
    for tier in TIERS:
        for env_id in tier.variants:
            lines += variant_section(store, root, env_id, tier)
    return "\n".join(lines) + f"\n<!-- {GOAL_SECTION}:start -->\n{goal_text}\n<!-- {GOAL_SECTION}:end -->\n"


def write(store: dict[str, Any], root: Path, goal_text: str | None, only_goal: bool = False) -> None:
    """The page, the figures and the README's section; ``goal_text`` replaces the goal env's section (None keeps
    it as the page has it); ``only_goal`` writes that section alone."""
    kept = goal_text if goal_text is not None else (read_section(GOAL_SECTION, PAGE) or "")
    if only_goal:
        replace_section(GOAL_SECTION, kept)
        return
    DOCS.mkdir(parents=True, exist_ok=True)
    hidden_rows = hidden.rows()
    profiles, aggregates = panels(store, hidden_rows)
    colors = {name: COLORS[name.split(" ")[0]] for matrices in profiles.values() for name in matrices}
    stats.plot_profiles(profiles, DOCS / "profiles.png", colors)
    stats.plot_aggregates(aggregates, DOCS / "aggregates.png", colors)
    write_atomic(PAGE, page(store, root, kept, hidden_rows))
    report.write_readme(summary(store, hidden_rows), "benchmark")
