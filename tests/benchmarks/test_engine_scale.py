"""The engine comparison's harness on tiny cases: every engine at its defaults from its own start, interleaved timed
repeats, budget cuts reported, goals and losses said, nothing written unless asked (no timing asserted)."""

import hashlib
import inspect
import math

import numpy as np
import pytest

from benchmarks import engine_scale, scale_report, suite_runs
from benchmarks.other_scenes import available_scene_engines
from benchmarks.scene_suite import Case, Plan, Segment, suite
from box_toss_env.physics import scenes, simulate


def small_pile(n: int = 3, window: float = 0.1) -> Case:
    plans = (
        Plan(True, (Segment(window, "drop"), Segment(window), Segment(window, "rest"))),
        Plan(False, (Segment(window), Segment(window, "awake"))),
    )
    return Case(f"pile {n}", "pile", lambda: scenes.pile(n), plans)


def test_ours_runs_at_simulates_default_and_its_runs_carry_on_as_one():
    """Ours as a user gets it: sleeping exactly as a plain ``simulate`` call (its signature's default), and a run
    advanced one step a call is the run of one call (the observed run measures the timed one) up to rounding: the
    engine's run boundaries round its state in the last bit (a pile of 4 split at step 2 is 6e-17 m off at step 3,
    and a pile's chaos grows it), so the test holds 10 steps to 1e-12."""
    assert suite_runs.until_rest_default() is inspect.signature(simulate).parameters["until_rest"].default
    scene = scenes.pile(4)
    one, steps = suite_runs.OurWorld(scene, True), suite_runs.OurWorld(scene, True)
    assert one.until_rest is suite_runs.until_rest_default()
    one.advance(10)
    for _ in range(10):
        steps.advance(1)
    np.testing.assert_allclose(one.state, steps.state, rtol=0, atol=1e-12)
    awake = suite_runs.OurWorld(scene, False)
    assert awake.scene.sleep_time == suite_runs.NEVER_SLEEP and not awake.until_rest
    assert suite_runs.OurWorld(scene, True).scene is scene  # nothing changed from the scene as built


def test_a_new_default_of_simulate_is_measured(monkeypatch):
    def later(scene, *, steps=None, duration=None, until_rest=True, record=False, threads=None, sleep=False): ...

    def awake(scene, *, steps=None, duration=None, until_rest=False, record=False, threads=None, sleep=False): ...

    monkeypatch.setattr(simulate, "__signature__", inspect.signature(later), raising=False)
    assert suite_runs.until_rest_default() is True and suite_runs.sleep_default() is False
    world = suite_runs.OurWorld(scenes.pile(2), True)
    assert world.until_rest is True and world.sleep is True  # until_rest sleeps
    monkeypatch.setattr(simulate, "__signature__", inspect.signature(awake), raising=False)
    assert suite_runs.OurWorld(scenes.pile(2), True).sleep is False
    monkeypatch.undo()
    assert suite_runs.OurWorld(scenes.pile(2), True).sleep is True  # simulate's default today
    assert suite_runs.OurWorld(scenes.pile(2), False).sleep is False  # sleeping off


def test_snapshot_restore_and_reset():
    world = suite_runs.OurWorld(scenes.pile(3), True)
    world.advance(10)
    saved = world.snapshot()
    world.advance(10)
    ahead = world.state.copy()
    world.restore(saved)
    world.advance(10)
    np.testing.assert_array_equal(world.state, ahead)
    world.reset()
    np.testing.assert_array_equal(world.state, scenes.pile(3).initial_state())


def test_every_engine_measures_every_window_and_the_repeats_interleave():
    engines = [suite_runs.OURS, *available_scene_engines()]
    windows, order = suite_runs.run_case(small_pile(), engines, repeats=2, budget=5.0)
    assert {(w.engine, w.label) for w in windows} == {(e, m) for e in engines for m in ("drop", "rest", "awake")}
    for w in windows:
        assert w.steps == w.wanted == round(0.1 / w.dt), w
        assert len(w.seconds) == 2 and math.isfinite(w.us_per_body_second) and w.us_per_body_second > 0, w
        assert w.quality.samples == w.steps and 0 <= w.quality.penetration < 0.05, w
    assert {w.dt for w in windows if w.engine != suite_runs.OURS} == {1 / 60}  # each engine at its own step
    per_round = len(order) // 2
    assert order[:per_round] == order[per_round:]  # ABAB: every window once, then every window again
    assert len({engine for engine, _ in order[: len(engines) * 3]}) == len(engines)


def test_each_engine_starts_from_the_scene_and_settles_its_own_pile(monkeypatch):
    """No engine is given a state another engine made: every world is built from the scene's own start."""
    engines = available_scene_engines()
    built = []

    def make_world(engine, scene, sleep, layout=None, **options):
        built.append((engine, options))
        return real(engine, scene, sleep, layout, **options)

    real = suite_runs.make_world
    monkeypatch.setattr(suite_runs, "make_world", make_world)
    windows, _ = suite_runs.run_case(small_pile(), engines, 1, 5.0)
    assert {engine for engine, _ in built} == set(engines)
    assert all("state" not in options for _, options in built)
    assert all(w.steps for w in windows)


def test_the_budget_cuts_a_window_and_says_so():
    windows, _ = suite_runs.run_case(small_pile(window=0.5), [suite_runs.OURS], 1, budget=1e-9)
    drop = next(w for w in windows if w.label == "drop")
    assert drop.steps == 1 < drop.wanted and drop.cut and drop.seconds
    rest = next(w for w in windows if w.label == "rest")
    assert rest.steps == 0 and "budget cut" in rest.note  # never reached: the window before it was cut
    assert any("budget cut" in line for line in scale_report.notes(windows))
    assert "(1/128 steps)" in scale_report.cost_cell(drop)


def test_a_scene_an_engine_cannot_build_is_reported_not_dropped():
    pytest.importorskip("Box2D")
    thin = next(c for c in suite() if c.name == "thin 100")
    case = Case("thin", "pile", lambda: thin.scene.replace(boxes=thin.scene.boxes[:2]), small_pile().plans)
    windows, _ = suite_runs.run_case(case, ["box2d"], 1, 1.0)
    assert windows and all(w.steps == 0 and "b2_polygonRadius" in w.note for w in windows)


def window(engine: str, us: float, label: str = "drop", case: str = "pile 100") -> suite_runs.Window:
    w = suite_runs.Window(case, engine, label, 100, 1 / 60, 60, steps=60, seconds=[us * 100 * 1e-6])
    return w


def test_where_ours_loses_the_tables_say_so():
    windows = [window(suite_runs.OURS, 30.0), window("box2d3", 20.0), window(suite_runs.OURS_TUNED, 10.0)]
    windows += [window(suite_runs.OURS, 10.0, "awake"), window("box2d3", 20.0, "awake")]
    table = "\n".join(scale_report.cost_table(windows))
    assert "ours loses, 1.5x" in table and "ours wins, 0.50x" in table
    assert "ours, tuned (beside, not instead)" in table.splitlines()[0]
    cases = {"pile 100": Case("pile 100", "pile", lambda: scenes.pile(2), ())}
    goals = "\n".join(scale_report.goals_table(windows, cases))
    assert "no (1.5x)" in goals
    assert scale_report.losses(windows) == (1, 2)
    for w in windows:
        w.case = "pile 1000"
    summary = scale_report.readme_summary(windows, "header.", "")
    assert "| pile 1000, dropped | 30.0 | 20.0 | ours loses, 1.5x |" in summary
    assert "kept awake" not in summary  # the README's rows alone
    assert "in 1 of the 2 windows" in summary


def fingerprint(paths) -> dict:
    return {p: hashlib.sha256(p.read_bytes()).hexdigest() if p.exists() else None for p in paths}


def test_the_command_changes_no_file_unless_asked(tmp_path, capsys):
    from agents.doc_sections import README

    tracked = [engine_scale.DOCS_PAGE, engine_scale.FIGURE, README]
    before = fingerprint(tracked)
    argv = ["--quick", "--cases", "heavy 1000:1", "--engines", "ours", "--repeats", "1", "--no-onbox"]
    engine_scale.main([*argv, "--json", str(tmp_path / "windows.json")])
    assert fingerprint(tracked) == before
    assert "heavy 1000:1" in capsys.readouterr().out and (tmp_path / "windows.json").stat().st_size > 0


def test_write_docs_writes_the_page_the_figure_and_the_readme_between_markers(tmp_path, monkeypatch):
    import agents.doc_sections

    page, readme, figure = tmp_path / "page.md", tmp_path / "README.md", tmp_path / "figure.png"
    page.write_text("head\n<!-- engine-scale:start -->\nold\n<!-- engine-scale:end -->\ntail\n")
    readme.write_text("top\n<!-- engine-scale-summary:start -->\nold\n<!-- engine-scale-summary:end -->\nend\n")
    monkeypatch.setattr(engine_scale, "DOCS_PAGE", page)
    monkeypatch.setattr(engine_scale, "FIGURE", figure)
    monkeypatch.setattr(agents.doc_sections, "README", readme)
    engine_scale.main(["--quick", "--cases", "heavy 1000:1", "--repeats", "1", "--no-onbox", "--write-docs"])
    text = page.read_text()
    assert text.startswith("head\n<!-- engine-scale:start -->\n") and text.endswith("<!-- engine-scale:end -->\ntail\n")
    assert "### Method (written by the command)" in text and "heavy 1000:1" in text and "\nold\n" not in text
    assert "Box2D v3" in readme.read_text() and readme.read_text().startswith("top\n")
    assert figure.stat().st_size > 0


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--budget", "0"], "--budget"),
        (["--cases", "pile 7"], "unknown ['pile 7']"),
        (["--engines", "bullet"], "--engines"),
        (["--repeats", "0"], "--repeats"),
    ],
)
def test_bad_options_name_themselves(argv, message, capsys):
    with pytest.raises(SystemExit):
        engine_scale.main(argv)
    assert message in capsys.readouterr().err


def test_pile_case_stays_at_the_scene_defaults():
    kind, scene = engine_scale.pile_case(100)
    assert kind == "pile" and scene == scenes.pile(100)


def test_the_python_loop_that_steps_the_other_engines_is_measured_and_said():
    from benchmarks.suite_runs import loop_overhead

    overhead = loop_overhead(steps=2000, repeats=1)
    assert 0.0 < overhead["loop"] < overhead.get("box2d3 empty", math.inf)
    dropped = suite_runs.Window("pile 16", "box2d3", "drop", 16, 1 / 60, 120, steps=120, seconds=[0.004])
    resting = suite_runs.Window("pile 16", "box2d3", "rest", 16, 1 / 60, 120, steps=120, seconds=[0.001])
    line = "\n".join(scale_report.loop_note({"loop": 0.03, "box2d3 empty": 0.4}, [dropped, resting]))
    # 0.4 us of a 0.004 s / 120 steps = 33.3 us step: 1%; at rest 0.4 of 8.3 us: 5%
    assert "0.030 us a step" in line and "up to 1% of Box2D v3's step (pile 16, dropped" in line
    assert "is 5-5% of its step" in line
    assert scale_report.loop_note({}, [dropped]) == []
