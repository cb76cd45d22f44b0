"""The error-against-cost comparison: every point a setting a user can pick, Box2D v3's contact stiffness turned with
its substeps, each setting from its own start, the front marked (no timing asserted)."""

import dataclasses
import math

import pytest

from benchmarks import pile_pareto, suite_runs
from benchmarks.other_scenes import Box2D3Settings, available_scene_engines
from box_toss_env.physics import Scene, scenes


def test_our_points_are_public_scene_settings_turned_one_at_a_time():
    fields = {f.name for f in dataclasses.fields(Scene)}
    defaults = scenes.pile(1)
    ours = pile_pareto.our_variants(defaults, quick=False)
    assert sum(v.default for v in ours) == 1 and ours[0].setting == "defaults"
    assert set(pile_pareto.OUR_KNOBS) <= fields and set(suite_runs.OUR_TUNED) <= fields
    case = pile_pareto.cases(0.1, pile=2)[0]
    for variant in ours[1:]:
        world = variant.build(case, False)
        changed = {name for name in fields if getattr(world.scene, name) != getattr(case.scene, name)}
        assert changed - {"sleep_time"}, variant.setting  # something a user set, and what it says
        if variant.name != "ours: tuned":
            assert len(changed - {"sleep_time"}) == 1, variant.setting


def test_box2d3_turns_its_contact_stiffness_with_its_substeps():
    variants = pile_pareto.box2d3_variants(quick=False)
    settings = {v.setting for v in variants}
    assert len(settings) == len(variants)
    for substeps in pile_pareto.BOX2D3_SUBSTEP_COUNTS:
        for hertz in pile_pareto.BOX2D3_HERTZ:
            assert any(s.startswith(f"{substeps} substeps, {hertz:g} Hz") for s in settings)
    assert "1 substeps, 30 Hz (acts as 7.5), damping 10" in "\n".join(settings)
    assert any("damping 2," in s for s in settings) and any("push 10 m/s" in s for s in settings)
    defaults = [v for v in variants if v.default]
    assert len(defaults) == 1 and defaults[0].setting.startswith("4 substeps, 30 Hz, damping 10, push 3 m/s")
    assert Box2D3Settings(4, 30.0).contact() == Box2D3Settings().contact()


def window(cost: float, depth: float) -> suite_runs.Window:
    w = suite_runs.Window("pile", "x", "drop", 1, 1.0, 1, steps=1, seconds=[cost * 1e-6])
    w.quality.penetration = depth
    return w


def test_the_front_holds_the_settings_nothing_beats():
    a, b, c = window(10, 1e-3), window(20, 1e-4), window(30, 1e-3)
    others = [a, b, c]
    assert pile_pareto.on_front(a, others) and pile_pareto.on_front(b, others) and not pile_pareto.on_front(c, others)
    exact = [window(10, 1e-12), window(20, 1e-13)]  # rounding: the cheaper one alone
    assert pile_pareto.on_front(exact[0], exact) and not pile_pareto.on_front(exact[1], exact)


def test_quick_rows_cover_every_engine_with_finite_figures(tmp_path):
    rows = pile_pareto.pareto_rows(quick=True, budget=0.5, repeats=1, pile=3, rows=3)
    engines = {v.engine for v, _, _ in rows}
    assert engines == {suite_runs.OURS, *available_scene_engines()}
    assert {w.case for _, w, _ in rows} == {"pile 3", "pyramid 6"}
    for variant, w, _ in rows:
        assert math.isfinite(w.us_per_body_second) and w.us_per_body_second > 0, variant.name
        assert w.quality.samples == w.steps, variant.name
    assert any(front for _, _, front in rows)
    lines = pile_pareto.table(rows)
    assert len(lines) == 2 + len(rows) and "(default)" in "\n".join(lines)
    pile_pareto.plot(rows, path=tmp_path / "pareto.png")
    assert (tmp_path / "pareto.png").stat().st_size > 0


def test_the_command_writes_nothing_unless_asked(monkeypatch, capsys):
    monkeypatch.setattr(pile_pareto, "pareto_rows", lambda *a, **k: [])
    written = []
    monkeypatch.setattr(pile_pareto.engine_scale, "write_docs", lambda *a, **k: written.append(a))
    monkeypatch.setattr(pile_pareto, "plot", lambda *a, **k: written.append(a))
    pile_pareto.main(["--quick"])
    assert written == []
    pile_pareto.main(["--quick", "--write-docs"])
    assert len(written) == 2
    with pytest.raises(SystemExit):
        pile_pareto.main(["--budget", "0"])
    assert "--budget" in capsys.readouterr().err


@pytest.mark.parametrize("substeps", [1, 4])
def test_box2d3_stiffens_its_contacts_up_to_an_eighth_of_the_substep_rate(substeps):
    """What the pareto's labels say: a 200 kg box on another sinks as deep for every contact hertz from the cap up,
    and deeper below it."""
    pytest.importorskip("pyb2d3")
    import numpy as np

    from benchmarks.other_scenes import make_world
    from box_toss_env.physics import Box

    boxes = tuple(Box(length=0.4, width=0.2, mass=200.0, position=(0.0, y)) for y in (0.1, 0.3))
    scene = Scene(boxes=boxes, dt=1 / 60, boxes_collide=True)
    cap = pile_pareto.BOX2D3_HERTZ_CAP * substeps * 60
    sink = {}
    for hertz in (0.9 * cap, cap, 2 * cap):
        world = make_world("box2d3", scene, settings=Box2D3Settings(substeps, hertz))
        world.advance(120)
        out = np.empty((2, 6))
        world.read_states(out)
        sink[hertz] = 0.3 - out[1, 1]
    assert sink[0.9 * cap] > sink[cap] * 1.01 and sink[2 * cap] == pytest.approx(sink[cap], rel=1e-6)
