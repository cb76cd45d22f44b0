"""The pile section of the engine benchmark runs on a tiny pile and reports every method (no timing asserted)."""

import math

from benchmarks import engine


def test_a_pile_is_bricks_that_collide_and_never_sleep():
    scene = engine.pile(10)
    assert scene.n_bodies == 10 and scene.boxes_collide
    assert scene.sleep_time >= engine.NEVER_SLEEP
    heights = sorted({round(box.position[1], 6) for box in scene.boxes})
    assert len(heights) == 3  # rows of ceil(sqrt(10)) = 4


def test_pile_costs_runs_every_method_on_a_tiny_pile():
    rows = engine.pile_costs(sizes=(1, 2), duration=0.05, repeats=1)
    methods = {method for method, *_ in rows}
    assert {"robust", "seed"} <= methods
    for method, n, ns, note in rows:
        assert n in (1, 2)
        assert (ns > 0) if not math.isnan(ns) else note, (method, n)
    if engine.engine_has_box_contact():
        assert all(not math.isnan(ns) for method, _, ns, _ in rows if method == "robust")
    lines = engine.pile_lines(rows)
    assert lines[0].split() == ["method", "1", "box", "2", "boxes"]
