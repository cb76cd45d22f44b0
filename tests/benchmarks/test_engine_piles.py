"""The pile section of the engine benchmark runs on a tiny pile and reports every method (no timing asserted)."""

import math

from benchmarks import engine


def test_a_pile_is_the_named_pile_never_put_to_sleep():
    scene = engine.pile(10)
    assert scene.n_bodies == 10 and scene.boxes_collide
    assert scene.sleep_time >= engine.NEVER_SLEEP


def test_pile_costs_runs_every_method_on_a_tiny_pile():
    rows = engine.pile_costs(sizes=(1, 2), duration=0.05, repeats=1)
    methods = {method for method, *_ in rows}
    assert {"robust", "seed"} <= methods
    for method, n, ns, note in rows:
        assert n in (1, 2)
        assert (ns > 0) if not math.isnan(ns) else note, (method, n)
    assert all(not math.isnan(ns) for method, _, ns, _ in rows if method == "robust")
    lines = engine.pile_lines(rows)
    assert lines[0].split() == ["method", "1", "box", "2", "boxes"]
