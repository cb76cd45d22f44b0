"""agents.section_merge: a section rebuilt from some algorithms' runs keeps the other agents' rows as written."""

from agents import benchmark, section_merge

OLD = """### BoxToss-ShortEnd-v0

| agent | success | mean distance | median distance | face accuracy | env steps | wall time |
|---|---:|---:|---:|---:|---:|---:|
| random actions | 0.0% | 2.215 m | 1.747 m | 6.4% | - | - |
| PPO (3 seeds) | 98.5% (96.7%-99.6%) | 0.007 m | 0.002 m | 98.5% | 600,064 | 4.1 min |
| SAC (1 seed) | 27.8% | 0.214 m | 0.283 m | 27.8% | 300,000 | 8.6 min |
| ceiling: oracle, 8,192 simulated throws per target, 256 targets | 100.0% | 0.000 m | 0.000 m | 100.0% | - | 2 min |

Success by target face:

| target face | random actions | PPO (3 seeds) | SAC (1 seed) |
|---|---:|---:|---:|
| a short end | 0.0% | 98.5% | 27.8% |

Success by target x:

| target x | random actions | PPO (3 seeds) | SAC (1 seed) |
|---|---:|---:|---:|
| 1.00-1.50 m | 0.0% | 99.0% | 30.0% |
| 1.50-2.00 m | 0.0% | 98.0% | 25.0% |

Oracle success as its search grows (the ceiling is the last row):

| initial, population x rounds (elite) | throws per target | success | face accuracy | planning |
|---|---:|---:|---:|---:|
| 32, 16 x 4 (4) | 89 | 99.2% | 100.0% | 42 s |

![learning curves on BoxToss-ShortEnd-v0](curves_BoxToss-ShortEnd-v0.png)
"""

NEW = """### BoxToss-ShortEnd-v0

| agent | success | mean distance | median distance | face accuracy | env steps | wall time |
|---|---:|---:|---:|---:|---:|---:|
| random actions | 0.0% | 2.215 m | 1.747 m | 6.4% | - | - |
| SAC (3 seeds) | 97.0% (96.0%-98.0%) | 0.010 m | 0.003 m | 97.0% | 300,000 | 3 min |
| TD3 (3 seeds) | 96.0% (95.0%-97.0%) | 0.010 m | 0.003 m | 96.0% | 300,000 | 3 min |

Success by target face:

| target face | random actions | SAC (3 seeds) | TD3 (3 seeds) |
|---|---:|---:|---:|
| a short end | 0.0% | 97.0% | 96.0% |

Success by target x:

| target x | random actions | SAC (3 seeds) | TD3 (3 seeds) |
|---|---:|---:|---:|
| 1.00-1.50 m | 0.0% | 98.0% | 97.0% |
| 1.50-2.00 m | 0.0% | 96.0% | 95.0% |

![learning curves on BoxToss-ShortEnd-v0](curves_BoxToss-ShortEnd-v0.png)
"""


def test_new_rows_replace_their_algorithm_and_the_others_stay():
    merged = "\n".join(section_merge.merge_section(NEW.splitlines(), OLD.splitlines()))
    assert "| SAC (1 seed)" not in merged and "27.8%" not in merged
    assert "| PPO (3 seeds) | 98.5% (96.7%-99.6%) |" in merged
    assert "| SAC (3 seeds) | 97.0% (96.0%-98.0%) |" in merged
    assert merged.index("| PPO (3 seeds) |") < merged.index("| SAC (3 seeds) |") < merged.index("| ceiling: oracle")
    assert "| target face | random actions | PPO (3 seeds) | SAC (3 seeds) | TD3 (3 seeds) |" in merged
    assert "| a short end | 0.0% | 98.5% | 97.0% | 96.0% |" in merged
    assert "| 1.50-2.00 m | 0.0% | 98.0% | 96.0% | 95.0% |" in merged
    assert merged.index("Oracle success") < merged.index("![learning curves")
    assert "| 32, 16 x 4 (4) | 89 | 99.2% |" in merged


def test_a_section_without_a_previous_one_is_unchanged():
    assert section_merge.merge_section(NEW.splitlines(), [""]) == NEW.splitlines()


def test_the_summary_line_takes_missing_cells_from_the_readme():
    old = "| BoxToss-ShortEnd-v0 | 0.0% | 98.5% (96.7%-99.6%) | 27.8% | 90.6% | 100.0% |"
    new = "| BoxToss-ShortEnd-v0 | 0.0% | - | 97.0% (96.0%-98.0%) | - | - |"
    assert section_merge.fill_line(new, old) == (
        "| BoxToss-ShortEnd-v0 | 0.0% | 98.5% (96.7%-99.6%) | 97.0% (96.0%-98.0%) | 90.6% | 100.0% |"
    )


def test_stored_rows_of_other_algorithms_stay(tmp_path):
    row = {"agent": "PPO (3 seeds)", "algo": "ppo", "results": [], "timing": []}
    stored = {"BoxToss-v0": [row]}
    assert benchmark.table_rows(tmp_path, "BoxToss-v0", "commands", ["sac"], [0], stored) == [row]
