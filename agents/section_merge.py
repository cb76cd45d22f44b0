"""A benchmark section rebuilt from some algorithms' runs, merged with the section as the page had it: an algorithm
whose runs are neither in ``--root`` nor in the stored rows keeps its line, its breakdown columns and (without a
ceiling sweep in ``--root``) the ceiling's line and the oracle's table as written.

So that ``python -m agents.benchmark --envs BoxToss-ShortEnd-v0 --algos sac --readme`` on a machine without PPO's
runs replaces SAC's rows and loses neither PPO's nor the ceiling's (``agents.benchmark.document`` calls it).
"""

from __future__ import annotations

ORDER = ("random", "ppo", "sac", "td3", "ceiling")
"""The order of the agents in a table: random actions, the algorithms, the ceiling."""
SWEEP_TITLE = "Oracle success as its search grows"


def agent_kind(label: str) -> str:
    """``random``, an algorithm (``PPO (3 seeds)`` -> ``ppo``) or ``ceiling``, from an agent's label."""
    word = label.strip().split(" ")[0].rstrip(":").lower()
    return {"random": "random", "ceiling": "ceiling"}.get(word, word)


def rank(label: str) -> int:
    kind = agent_kind(label)
    return ORDER.index(kind) if kind in ORDER else len(ORDER)


def cells(line: str) -> list[str]:
    return [cell.strip() for cell in line.strip().strip("|").split("|")]


def row_line(values: list[str]) -> str:
    return "| " + " | ".join(values) + " |"


def tables(lines: list[str]) -> dict[str, tuple[int, int]]:
    """Each markdown table of a section by its first header cell (``agent``, ``target face``, ...): (first line,
    end line) with the header at the first line and the rule after it."""
    found: dict[str, tuple[int, int]] = {}
    k = 0
    while k < len(lines):
        if lines[k].startswith("| ") and k + 1 < len(lines) and lines[k + 1].startswith("|---"):
            end = k + 2
            while end < len(lines) and lines[end].startswith("| "):
                end += 1
            found.setdefault(cells(lines[k])[0], (k, end))
            k = end
        else:
            k += 1
    return found


def merge_main(new: list[str], old: list[str]) -> list[str]:
    """The agents' table: the new lines, with the old lines of the agents it lacks (the ceiling's too)."""
    have = {agent_kind(cells(line)[0]) for line in new}
    kept = [line for line in old if agent_kind(cells(line)[0]) not in have]
    return sorted(new + kept, key=lambda line: rank(cells(line)[0]))


def merge_columns(new: list[str], old: list[str], header_new: list[str], header_old: list[str]) -> list[str]:
    """A breakdown table (one column per agent): the new columns and the old columns of the agents it lacks, by
    row label. Returns the header, the rule and the rows."""
    have = {agent_kind(label) for label in header_new[1:]}
    old_by_row = {cells(line)[0]: cells(line) for line in old}
    columns = [(label, ("new", k)) for k, label in enumerate(header_new[1:], 1)]
    columns += [(label, ("old", k)) for k, label in enumerate(header_old[1:], 1) if agent_kind(label) not in have]
    columns.sort(key=lambda column: rank(column[0]))
    lines = [row_line([header_new[0], *(label for label, _ in columns)]), "|---|" + "---:|" * len(columns)]
    for line in new:
        row = cells(line)
        old_row = old_by_row.get(row[0], [])
        values = [row[k] if side == "new" else (old_row[k] if k < len(old_row) else "-") for _, (side, k) in columns]
        lines.append(row_line([row[0], *values]))
    return lines


def sweep_block(lines: list[str]) -> list[str]:
    """The oracle's table with its title and the blank line after it, or nothing."""
    start = next((k for k, line in enumerate(lines) if line.startswith(SWEEP_TITLE)), None)
    if start is None:
        return []
    spans = tables(lines[start:])
    end = start + max(stop for _, stop in spans.values()) if spans else start + 1
    return lines[start:end] + [""]


def merge_section(new: list[str], old: list[str]) -> list[str]:
    """``new`` (a section's lines from the runs found) with what ``old`` (the page's section) has and it lacks."""
    if not old:
        return new
    merged = list(new)
    old_tables = tables(old)
    for name, (start, end) in sorted(tables(new).items(), key=lambda item: -item[1][0]):
        if name not in old_tables:
            continue
        o_start, o_end = old_tables[name]
        if name == "agent":
            body = merge_main(new[start + 2 : end], old[o_start + 2 : o_end])
            merged[start + 2 : end] = body
        elif name in ("target face", "target x"):
            header_new, header_old = cells(new[start]), cells(old[o_start])
            merged[start:end] = merge_columns(new[start + 2 : end], old[o_start + 2 : o_end], header_new, header_old)
    if not sweep_block(new) and (block := sweep_block(old)):
        figure = next((k for k, line in enumerate(merged) if line.startswith("![")), len(merged))
        merged[figure:figure] = block
    return merged


def fill_line(line: str, old: str | None) -> str:
    """A README summary line with its empty cells (``-``: no runs here) taken from the line as written."""
    if old is None:
        return line
    new_cells, old_cells = cells(line), cells(old)
    if len(new_cells) != len(old_cells):
        return line
    return row_line([o if n == "-" else n for n, o in zip(new_cells, old_cells, strict=True)])
