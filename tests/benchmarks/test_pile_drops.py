"""The dropped-pile benchmark runs on tiny piles, reports every size and checks its options (no timing asserted)."""

import pytest

from benchmarks import pile_drops


def test_pile_drops_reports_each_size_over_its_seeds(capsys):
    pile_drops.main(["--sizes", "2,4", "--seeds", "2", "--duration", "0.3"])
    lines = capsys.readouterr().out.splitlines()
    rows = [line.split("|")[1:-1] for line in lines if line.startswith("| ") and line[2].isdigit()]
    assert [(int(r[0]), int(r[1])) for r in rows] == [(2, 2), (4, 2)]
    for row in rows:
        deepest_mean, deepest_max = (float(x) for x in row[2].split("/"))
        assert 0.0 <= deepest_mean <= deepest_max < 1.0  # mm: two or four boxes dropped side by side


def test_a_pile_drop_gives_its_cost_its_deepest_penetration_and_when_it_slept():
    cost, deepest, asleep = pile_drops.drop(3, 1, 2.0)
    assert cost > 0.0 and 0.0 <= deepest < 1e-3 and 0.0 < asleep <= 2.0


def test_layers_drop_the_engine_benchmarks_wide_pile(capsys):
    pile_drops.main(["--sizes", "6", "--seeds", "1", "--duration", "0.3", "--layers", "2"])
    out = capsys.readouterr().out
    assert "2 rows wide" in out and "--layers 2" in out


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (["--seeds", "0"], "--seeds"),
        (["--duration", "0"], "--duration"),
        (["--sizes", "0,16"], "--sizes"),
        (["--layers", "0"], "--layers"),
    ],
)
def test_bad_options_are_refused_naming_them(argv, named, capsys):
    with pytest.raises(SystemExit):
        pile_drops.parse(argv)
    assert named in capsys.readouterr().err
