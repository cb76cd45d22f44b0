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
            assert any(s.startswith(f"{substeps} substeps, {hertz:g} Hz,") for s in settings)
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
