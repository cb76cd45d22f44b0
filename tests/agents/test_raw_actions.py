"""agents.raw_actions: where the throws that succeed lie in the env's own actions."""

import numpy as np
import pytest

from agents import raw_actions


def test_by_face_gives_each_target_face_the_range_of_its_solutions_in_env_actions():
    rows = raw_actions.by_face("BoxToss-ThisSideUp-v0", n_targets=12, draws=2)
    assert [row["face"] for row in rows] == [0, 1, 2, 3]
    assert sum(row["targets"] for row in rows) == 12
    for row in rows:
        assert 0 <= row["solved"] <= row["targets"]
        if row["solved"]:
            low, high = np.array(row["low"]), np.array(row["high"])
            assert np.all(-1.0 <= low) and np.all(low <= high) and np.all(high <= 1.0)
            assert 0.0 <= row["noisy"] <= 1.0
    text = raw_actions.face_table("BoxToss-ThisSideUp-v0", rows, 0.01, "the command")
    assert "first 12 of BoxToss-ThisSideUp-v0's test targets" in text and text.count("| face ") == 4


def test_by_face_takes_one_variant_whose_targets_name_one_face(capsys):
    with pytest.raises(SystemExit):
        raw_actions.main(["--by-face", "--envs", "BoxToss-v0"])
    assert "--by-face" in capsys.readouterr().err
