"""The pile section of the engine benchmark runs on tiny piles and reports every method (no timing asserted)."""

import math

import numpy as np
import pytest

from benchmarks import engine
from benchmarks.other_scenes import SCENE_ENGINE_MODULES, SCENE_ENGINES, simulate_scene
from box_toss_env.physics import scenes, simulate


def test_pile_comparison_runs_every_method_on_tiny_piles():
    rows = engine.pile_comparison(sizes=(1, 2), steps=4, settle=0.1, repeats=1)
    methods = {method for method, *_ in rows}
    assert {"robust", "seed", "robust, sleeping"} <= methods
    for method, n, ns, note in rows:
        assert n in (1, 2)
        assert (ns > 0) if not math.isnan(ns) else note, (method, n)
    assert all(not math.isnan(ns) for method, _, ns, _ in rows if method == "robust")
    lines = engine.pile_lines(rows)
    assert lines[0].split() == ["method", "1", "box", "2", "boxes"]


@pytest.mark.parametrize("name", list(SCENE_ENGINES))
def test_other_engines_start_from_the_settled_pile(name):
    pytest.importorskip(SCENE_ENGINE_MODULES[name])
    scene = scenes.pile(3)
    settled = simulate(scene, duration=0.2).final_state
    run = simulate_scene(name, scene, 0, state=settled)
    np.testing.assert_allclose(run.final_state, settled, atol=1e-6)  # Box2D is float32
