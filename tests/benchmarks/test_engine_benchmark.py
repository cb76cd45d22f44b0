"""benchmarks.engine's pile measurement: what it returns (a figure and what it was measured on), not how fast."""

import numpy as np

from benchmarks.engine import PILE_SIZES, pile_cost


def test_pile_cost_returns_a_figure_and_the_settled_pile():
    row = pile_cost(3, settle=0.25, steps=4, repeats=1)
    assert PILE_SIZES == (1, 10, 100)
    assert row["n"] == 3 and row["solver"] == "robust" and row["steps"] == 4 and row["dt"] == 1 / 256
    assert row["ns_per_body_step"] > 0
    assert row["settled_state"].shape == (3, 6) and np.all(np.isfinite(row["settled_state"]))
