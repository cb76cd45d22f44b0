"""agents.variant_gifs: one small GIF per registered variant, an oracle throw that succeeds, written atomically;
the docs show every registered variant's GIF."""

import re

import gymnasium as gym
import numpy as np
import pytest

from agents import variant_gifs
from agents.doc_sections import DOCS

pytest.importorskip("pygame")
PIL = pytest.importorskip("PIL.Image")


def test_records_a_successful_small_gif_atomically(tmp_path):
    shown = set()
    row = variant_gifs.record_variant("BoxToss-ShortEnd-v0", tmp_path, tries=3, shown=shown)
    assert row["success"] and row["path"] == tmp_path / "variant_BoxToss-ShortEnd-v0.gif"
    assert [path.name for path in tmp_path.iterdir()] == [row["path"].name]  # no temporary file left
    assert row["bytes"] == row["path"].stat().st_size < variant_gifs.MAX_BYTES
    with PIL.open(row["path"]) as image:
        assert image.n_frames > 10 and image.size == (360, 240)
        image.seek(image.n_frames - 1)
        assert np.asarray(image.convert("RGB")).std() > 0
    assert len(shown) == 1
    # the same episode is not shown twice: another variant drawing it moves on to the next seed
    assert variant_gifs.good_throw("BoxToss-ShortEnd-v0", row["seed"], tries=1, shown=shown)[0] > row["seed"]


def test_an_interrupted_write_leaves_the_old_file(tmp_path):
    path = tmp_path / "a.gif"
    path.write_bytes(b"old")
    with pytest.raises(ValueError):
        variant_gifs.write_atomically([np.zeros((4, 4), dtype=np.uint8)], path, 20)  # not (H, W, 3)
    assert path.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["a.gif"]


def test_goal_variant_plans_on_its_throw_env():
    env = gym.make("BoxToss-Goal-v0")
    assert type(variant_gifs.throw_env(env)).__name__ == "BoxTossEnv"


def test_docs_show_every_registered_one_throw_variant_with_a_small_gif():
    page = (DOCS / "environment.md").read_text()
    section = page.split("<!-- variant-gifs:start -->")[1].split("<!-- variant-gifs:end -->")[0]
    linked = re.findall(r"\]\(figures/variant_(.+?)\.gif\)", section)
    assert linked == variant_gifs.variant_ids()
    assert set(variant_gifs.variant_ids()) | set(variant_gifs.SEQUENTIAL) | set(variant_gifs.pixel_ids()) == {
        env_id for env_id in gym.registry if env_id.startswith("BoxToss-")
    }
    for env_id in linked:
        path = DOCS / "figures" / f"variant_{env_id}.gif"
        assert path.stat().st_size < variant_gifs.MAX_BYTES
    assert "no success" not in section
