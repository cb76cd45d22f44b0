"""The benchmark's tables, from the stored runs (``agents.benchmark_store``) alone: one table per tier (headline
first) with random actions, the prior (the untrained policy), each algorithm and the ceiling, every cell an IQM of
the seeds' success with its 95% stratified-bootstrap interval and its number of seeds (``agents.benchmark_stats``);
the aggregate over variants and the probability of improvement; the held-out split's train and test success; and,
per variant, the details (distances, face accuracy, budgets, breakdowns by target face and distance, the oracle's
sweep, the learning curves).
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from agents import benchmark_stats as stats
from agents import benchmark_store as store_module
from agents import ceiling
from agents.benchmark_tiers import PLANNED_CEILINGS, RANDOM_SEEDS, SAME_TASK, STACK, TIERS, Tier, same_as_headline
from agents.report import format_seconds

RANDOM, PRIOR = "random", "prior"
FACE_KINDS = ("any face", "a long side", "a short end", "face 0", "face 1", "face 2", "face 3")
TEST_TAG = "split=test"
"""The evaluation tag of a held-out run's test-split scores (its ``default`` tag is its own train split)."""


def label(agent: str) -> str:
    """A column's or row's name: random, prior, PPO, or a trial's ``PPO, name``."""
    algo, _, trial = agent.partition(":")
    name = {RANDOM: "random", PRIOR: "prior"}.get(algo, algo.upper())
    return f"{name}, {trial}" if trial else name


def agents_of(tier: Tier) -> list[str]:
    """The columns of a tier's table: random actions, the prior, the tier's algorithms."""
    return [RANDOM, PRIOR, *tier.algos]


def cell_tier(tier: Tier, agent: str) -> str | None:
    """The tier a cell's records are stored under: random actions are the same in every tier (None)."""
    return None if agent == RANDOM else tier.name


def scores(store: dict[str, Any], env_id: str, tier: Tier, agent: str, split=None, tag="default") -> list[float]:
    """The success rates of one cell's seeds (in seed order)."""
    found = store_module.records(store, env_id, cell_tier(tier, agent), agent, split)
    return [value for r in found if (value := store_module.success(r, tag)) is not None]


def ceiling_rate(store: dict[str, Any], env_id: str, tag: str = "default") -> float | None:
    """The ceiling's success on ``env_id``: a planner's measured rows (``PLANNED_CEILINGS``: the stack's), else the
    oracle sweep's last budget under ``tag`` (``default``, ``split=train`` or ``split=test``)."""
    if env_id in PLANNED_CEILINGS:
        path = PLANNED_CEILINGS[env_id]
        rows = json.loads(path.read_text()) if path.exists() else []
        return None if not rows or tag != "default" else float(rows[-1]["success_rate"])
    sweep = store["ceilings"].get(SAME_TASK.get(env_id, env_id), {}).get(tag)
    return None if not sweep else float(ceiling.ceiling_of(sweep)["success_rate"])


def estimate(values: list[float]) -> stats.Estimate | None:
    return stats.iqm(np.array(values)) if values else None


def cell_text(value: stats.Estimate | None, planned: int | None = None) -> str:
    """An estimate's cell; with fewer runs than the ``planned`` seeds, the count says so: ``(3 of 5)``."""
    if value is None:
        return "-"
    short = planned is not None and value.runs < planned
    count = f"{value.runs} of {planned}" if short else f"{value.runs}"
    return f"{value.value:.1%} [{100 * value.low:.1f}, {100 * value.high:.1f}] ({count})"


def planned_seeds(tier: Tier, env_id: str, agent: str) -> int:
    """How many seeds the plan gives a cell (``Tier.default_seeds``; random actions ``RANDOM_SEEDS``, the prior its
    algorithm's)."""
    if agent == RANDOM:
        return len(RANDOM_SEEDS)
    return len(tier.default_seeds(env_id, tier.prior_algo if agent == PRIOR else agent))


def normalised(store: dict[str, Any], tier: Tier, agent: str) -> tuple[list[str], np.ndarray | None]:
    """The variants with a ceiling and a run of ``agent``, and the runs x variants matrix of its success divided by
    the ceiling (the first seeds of each, as many as the variant with the fewest)."""
    variants, columns = [], []
    for env_id in tier.variants:
        top = ceiling_rate(store, env_id)
        values = scores(store, env_id, tier, agent)
        if top and values:
            variants.append(env_id)
            columns.append([value / top for value in values])
    return variants, stats.rectangular(columns)


def aggregate_row(store: dict[str, Any], tier: Tier) -> str:
    """The table's last row: per agent the IQM of success / ceiling pooled over the variants it has runs on
    (how many, and runs per variant, in brackets)."""
    cells = []
    for agent in agents_of(tier):
        variants, matrix = normalised(store, tier, agent)
        if matrix is None:
            cells.append("-")
            continue
        value = stats.iqm(matrix)
        cells.append(
            f"{value.value:.1%} [{100 * value.low:.1f}, {100 * value.high:.1f}] ({len(variants)} x {value.runs})"
        )
    return "| **all variants** (success / ceiling) | " + " | ".join(cells) + " | 100% |"


def repeats_headline(tier: Tier, env_id: str, agent: str) -> bool:
    """Whether a cell of ``tier`` is the headline tier's trainings again (``same_as_headline``; the prior: its
    algorithm's recipe)."""
    if agent == RANDOM:
        return False
    return same_as_headline(tier, tier.prior_algo if agent == PRIOR else agent, env_id)


def repeated_cells(tier: Tier) -> str:
    """The agents and variants whose cells of ``tier`` repeat the headline tier's trainings, "" where none do."""
    found = {
        label(agent): [env_id for env_id in tier.variants if repeats_headline(tier, env_id, agent)]
        for agent in agents_of(tier)
    }
    return "; ".join(f"{name} on {', '.join(f'`{env_id}`' for env_id in envs)}" for name, envs in found.items() if envs)


def repeated_line(tier: Tier) -> str:
    """What the table's ``= raw`` cells mean, naming them; "" where the tier has none."""
    name = TIERS[0].name
    if not (cells := repeated_cells(tier)):
        return ""
    return (
        f"`= {name}`: {cells}: the recipe (`agents/hyperparams/<algo>.yml`) has no `env_wrapper` there, so the cell "
        f"is the {name} tier's trainings again, seed for seed (the same scores), not a run in this tier's commands."
    )


def tier_table(store: dict[str, Any], tier: Tier) -> list[str]:
    """One tier's table: a row per variant, a column per agent and the ceiling, then the aggregate; a cell that
    repeats the headline tier's trainings (``repeats_headline``) is marked ``= raw``."""
    agents = agents_of(tier)
    lines = [
        "| variant | " + " | ".join(label(agent) for agent in agents) + " | ceiling |",
        "|---|" + "---:|" * (len(agents) + 1),
    ]
    for env_id in tier.variants:
        cells = [
            cell_text(estimate(scores(store, env_id, tier, agent)), planned_seeds(tier, env_id, agent))
            for agent in agents
        ]
        cells = [
            f"{cell} = {TIERS[0].name}" if cell != "-" and repeats_headline(tier, env_id, agent) else cell
            for cell, agent in zip(cells, agents, strict=True)
        ]
        if all(cell == "-" for cell in cells[2:]):
            continue
        top = ceiling_rate(store, env_id)
        lines.append(f"| {env_id} | " + " | ".join(cells) + f" | {'-' if top is None else f'{top:.1%}'} |")
    lines.append(aggregate_row(store, tier))
    return lines


def aggregate_text(store: dict[str, Any], tier: Tier) -> str:
    """One sentence of a tier: each algorithm's IQM of success / ceiling over the variants, and the probability
    that the first beats the others."""
    parts = []
    for agent in tier.algos:
        variants, matrix = normalised(store, tier, agent)
        if matrix is not None:
            value = stats.iqm(matrix)
            parts.append(f"{label(agent)} {value.value:.1%} [{100 * value.low:.1f}, {100 * value.high:.1f}]")
    improvement = improvement_line(store, tier).split(": ", 1)[-1].rstrip(".")
    text = "IQM of success / ceiling " + ", ".join(parts) if parts else "no runs"
    return text + (f"; {improvement}." if improvement else ".")


RAW_GOALS = ("BoxToss-ThisSideUp-v0", "BoxToss-ShortEnd-v0", "BoxToss-Mixed-v0")
GOAL_SHARE = 0.9


def goals_line(store: dict[str, Any], tier: Tier) -> str:
    """The headline tier's goals: per variant of ``RAW_GOALS``, the best agent or trial (by the IQM of its seeds)
    as a share of the ceiling, against ``GOAL_SHARE``."""
    parts = []
    for env_id in RAW_GOALS:
        top = ceiling_rate(store, env_id)
        candidates = [
            (estimate(scores(store, env_id, tier, agent)), agent)
            for agent in [*tier.algos, *trials(store, env_id, tier)]
        ]
        found = [(value, agent) for value, agent in candidates if value is not None]
        if not top or not found:
            continue
        value, agent = max(found, key=lambda item: item[0].value)
        share = value.value / top
        verdict = "reached" if share >= GOAL_SHARE else "missed"
        parts.append(f"{env_id} {share:.0%} ({label(agent)}, {value.runs} seed{'s' * (value.runs > 1)}; {verdict})")
    if not parts:
        return ""
    return f"Goals of this tier (the best agent at {GOAL_SHARE:.0%} of the ceiling or more): " + "; ".join(parts) + "."


def improvement_line(store: dict[str, Any], tier: Tier) -> str:
    """The probability that the tier's first algorithm beats each other one, over the variants both have runs on."""
    first, parts = tier.algos[0], []
    for other in tier.algos[1:]:
        columns_x, columns_y, variants = [], [], 0
        for env_id in tier.variants:
            top = ceiling_rate(store, env_id)
            x, y = scores(store, env_id, tier, first), scores(store, env_id, tier, other)
            if top and x and y:
                columns_x.append([v / top for v in x])
                columns_y.append([v / top for v in y])
                variants += 1
        mx, my = stats.rectangular(columns_x), stats.rectangular(columns_y)
        if mx is not None and my is not None:
            value = stats.probability_of_improvement(mx, my)
            where = f"{variants} variant{'s' * (variants > 1)}"
            parts.append(f"P({label(first)} > {label(other)}) = {value.probability()} over {where}")
    if not parts:
        return ""
    return "Probability of improvement (a run of one beats a run of the other on a variant drawn at random): " + (
        "; ".join(parts) + "."
    )


def heldout_table(store: dict[str, Any], tier: Tier) -> list[str]:
    """Per variant and algorithm with runs trained on the train split: success on the train split's and on the
    test split's test targets, the gap (train minus test, per seed), and the ceiling on each split; an agent that
    repeats the headline tier's trainings (``repeats_headline``) is marked ``= raw``."""
    lines = [
        "| variant | agent | train split | test split | gap (train - test) | ceiling: train | ceiling: test |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for env_id in tier.variants:
        for agent in tier.algos:
            found = store_module.records(store, env_id, tier.name, agent, "train")
            pairs = [
                (train_rate, test_rate)
                for r in found
                if (train_rate := store_module.success(r)) is not None
                and (test_rate := store_module.success(r, TEST_TAG)) is not None
            ]
            if not pairs:
                continue
            train, test = [p[0] for p in pairs], [p[1] for p in pairs]
            gap = [a - b for a, b in pairs]
            tops = [ceiling_rate(store, env_id, tag) for tag in ("split=train", TEST_TAG)]
            same = f" = {TIERS[0].name}" if repeats_headline(tier, env_id, agent) else ""
            lines.append(
                f"| {env_id} | {label(agent)}{same} | {cell_text(estimate(train))} | {cell_text(estimate(test))} | "
                f"{cell_text(estimate(gap))} | "
                + " | ".join("-" if top is None else f"{top:.1%}" for top in tops)
                + " |"
            )
    return lines if len(lines) > 2 else []


# -- per variant -----------------------------------------------------------------------------------
def trials(store: dict[str, Any], env_id: str, tier: Tier) -> list[str]:
    """The trials (``algo:name``, ``agents.benchmark --trial``) with runs on ``env_id`` in ``tier``, by name."""
    return sorted(
        {r["agent"] for r in store["runs"] if r["env_id"] == env_id and r["tier"] == tier.name and ":" in r["agent"]}
    )


def detail_rows(store: dict[str, Any], env_id: str, tier: Tier) -> list[tuple[str, list[dict[str, Any]]]]:
    """(label, records) of each agent with runs on ``env_id`` in ``tier``, then of each trial."""
    found = []
    for agent in [*agents_of(tier), *trials(store, env_id, tier)]:
        records = store_module.records(store, env_id, cell_tier(tier, agent), agent)
        if records:
            found.append((label(agent), records))
    return found


def trial_lines(store: dict[str, Any], env_id: str, tier: Tier) -> list[str]:
    """What each trial changed: the command of its first run."""
    lines = []
    for agent in trials(store, env_id, tier):
        record = store_module.records(store, env_id, tier.name, agent)[0]
        if command := record.get("command"):
            lines.append(f"- {label(agent)}: `{command}`")
    return ["Trials (the recipe with other settings, one row each above):", "", *lines] if lines else []


def mean_of(records: list[dict[str, Any]], key: str) -> float:
    values = [r["results"]["default"].get(key) for r in records]
    finite = [v for v in values if v is not None and np.isfinite(v)]
    return float(np.mean(finite)) if finite else float("nan")


def budget(records: list[dict[str, Any]]) -> tuple[str, str]:
    """The mean env steps and wall time of a cell's trainings ("-" for evaluations without training)."""
    timing = [r["timing"] for r in records if r.get("timing")]
    if not timing:
        return "-", "-"
    return f"{int(np.mean([t['timesteps'] for t in timing])):,}", format_seconds(
        float(np.mean([t["wall_seconds"] for t in timing]))
    )


def notes(store: dict[str, Any], env_id: str, tier: Tier) -> list[str]:
    """What a cell's records say of where they come from (``note``), once per note."""
    found: dict[str, str] = {}
    for name, records in detail_rows(store, env_id, tier):
        for r in records:
            if r.get("note"):
                found.setdefault(r["note"], name)
    return [f"{name}: {note}." for note, name in found.items()]


def detail_table(store: dict[str, Any], env_id: str, tier: Tier) -> list[str]:
    """The agents' rows on one variant of a tier (the stack: height and falls instead of distances and faces)."""
    stack = env_id == STACK
    head = (
        "| agent | success | mean final height | stack fell | mean return | return while training | env steps | "
        "wall time |"
        if stack
        else "| agent | success | mean distance | median distance | face accuracy | env steps | wall time |"
    )
    lines = [head, "|---|" + "---:|" * (head.count("|") - 2)]
    for name, records in detail_rows(store, env_id, tier):
        success = cell_text(estimate([store_module.success(r) or 0.0 for r in records]))
        steps, wall = budget(records)
        if stack:
            exploring = [r["training_return"] for r in records if r.get("training_return") is not None]
            middle = (
                f"{mean_of(records, 'mean_height'):.3f} m | {mean_of(records, 'fall_rate'):.1%} | "
                f"{mean_of(records, 'mean_reward'):.2f} | {f'{np.mean(exploring):.2f}' if exploring else '-'}"
            )
        else:
            middle = (
                f"{mean_of(records, 'mean_distance'):.3f} m | {mean_of(records, 'median_distance'):.3f} m | "
                f"{mean_of(records, 'face_accuracy'):.1%}"
            )
        lines.append(f"| {name} | {success} | {middle} | {steps} | {wall} |")
    return lines


def breakdowns(store: dict[str, Any], env_id: str, tier: Tier) -> list[str]:
    """Success by target face kind and by target x, one column per agent (means over seeds)."""
    rows = [
        (name, records)
        for name, records in detail_rows(store, env_id, tier)
        if "by_face" in records[0]["results"]["default"]
    ]
    if not rows:
        return []
    header = "| " + " | ".join(name for name, _ in rows) + " |"
    rule = "|---|" + "---:|" * len(rows)

    def mean_where(records, part: str, field: str, value: str) -> str:
        found = [e["success_rate"] for r in records for e in r["results"]["default"][part] if e[field] == value]
        return f"{np.mean(found):.1%}" if found else "-"

    first = rows[0][1][0]["results"]["default"]
    kinds = [kind for kind in FACE_KINDS if any(e["kind"] == kind for e in first["by_face"])]
    lines = ["Success by target face:", "", "| target face " + header, rule]
    lines += [f"| {k} | " + " | ".join(mean_where(r, "by_face", "kind", k) for _, r in rows) + " |" for k in kinds]
    lines += ["", "Success by target x:", "", "| target x " + header, rule]
    bins = [entry["bin"] for entry in first["by_distance"]]
    lines += [f"| {b} | " + " | ".join(mean_where(r, "by_distance", "bin", b) for _, r in rows) + " |" for b in bins]
    return lines


def sweep_table(sweep: list[dict[str, Any]]) -> list[str]:
    """The oracle's success as its search grows (the ceiling is the last row)."""
    lines = [
        "Oracle success as its search grows (the ceiling is the last row):",
        "",
        "| initial, population x rounds (elite) | throws per target | success | face accuracy | planning |",
        "|---|---:|---:|---:|---:|",
    ]
    for row in sweep:
        b = row["budget"]
        lines.append(
            f"| {b['initial']}, {b['population']} x {b['iterations']} ({b['elite']}) | "
            f"{row['throws_per_target']:,.0f} | {row['success_rate']:.1%} | {row['face_accuracy']:.1%} | "
            f"{format_seconds(row['plan_seconds'])} |"
        )
    return lines


def tiers_in_order() -> tuple[Tier, ...]:
    return TIERS
