"""Every file the repository writes (figures, GIFs, videos, screenshots, tables, pages) is written whole or
not at all, through one helper (``box_toss_env.files``): a write that fails half way leaves the previous
file as it was, and no temporary file."""

import ast
import os
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from box_toss_env.files import atomic_path, save_figure, write_atomic

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
FRAMES = [np.full((16, 24, 3), shade, dtype=np.uint8) for shade in (0, 80, 160, 240)]


class Broken(Exception):
    """The write failing half way (a full disk, a bug in a writer, a KeyboardInterrupt)."""


def leaves_the_old_file(path: Path, old: bytes) -> None:
    assert path.read_bytes() == old
    assert sorted(os.listdir(path.parent)) == [path.name]  # no temporary file left


def test_a_write_that_fails_half_way_leaves_the_previous_file(tmp_path):
    path = tmp_path / "table.csv"
    write_atomic(path, "a,b\n1,2\n")

    def half(file):
        file.write(b"a,b\n3,")
        raise Broken

    with pytest.raises(Broken):
        write_atomic(path, half)
    leaves_the_old_file(path, b"a,b\n1,2\n")
    write_atomic(path, b"a,b\n3,4\n")
    assert path.read_bytes() == b"a,b\n3,4\n" and os.stat(path).st_mode & 0o777 == 0o666 & ~current_umask()


def current_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_a_figure_that_fails_while_being_written_leaves_the_previous_one(tmp_path, suffix):
    path = tmp_path / f"curves{suffix}"
    figure, axes = plt.subplots()
    axes.plot([0, 1], [0, 1])
    save_figure(figure, path, dpi=50)
    old = path.read_bytes()
    assert old.startswith(b"\x89PNG" if suffix == ".png" else b"<?xml")

    class FailingArtist(matplotlib.artist.Artist):
        def draw(self, renderer):  # drawn after the SVG header is written: the file is half written
            raise Broken

    axes.add_artist(FailingArtist())
    with pytest.raises(Broken):
        save_figure(figure, path, dpi=50)
    plt.close(figure)
    leaves_the_old_file(path, old)


@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_a_video_that_fails_while_being_written_leaves_the_previous_one(tmp_path, monkeypatch, suffix):
    from box_toss_env.rendering import video

    path = tmp_path / f"throw{suffix}"
    video.write_video(FRAMES, path, fps=10)
    old = path.read_bytes()
    assert len(old) > 100
    if suffix == ".gif":
        from PIL import Image

        real_save = Image.Image.save

        def half_save(self, fp, *args, **kwargs):
            real_save(self, fp, *args, **kwargs)
            Path(fp).write_bytes(Path(fp).read_bytes()[:50])  # then the disk is full
            raise Broken

        monkeypatch.setattr(Image.Image, "save", half_save)
    else:
        real_pad = np.pad
        calls = []

        def failing_pad(*args, **kwargs):  # the third frame fails after two were encoded
            calls.append(1)
            if len(calls) == 3:
                raise Broken
            return real_pad(*args, **kwargs)

        monkeypatch.setattr(video.np, "pad", failing_pad)
    with pytest.raises(Broken):
        video.write_video(FRAMES, path, fps=10)
    leaves_the_old_file(path, old)


def test_a_kept_suffix_lets_writers_choose_their_format_and_add_nothing(tmp_path):
    path = tmp_path / "states.npy"
    with atomic_path(path) as temp:
        assert temp.suffix == ".npy" and temp.parent == tmp_path
        np.save(temp, np.arange(3))
    np.testing.assert_array_equal(np.load(path), np.arange(3))
    assert sorted(os.listdir(tmp_path)) == ["states.npy"]


# the calls that write a file in place; each must write into ``atomic_path``'s temporary path
IN_PLACE_WRITERS = {"savefig", "write_text", "write_bytes", "imwrite", "mimsave", "mimwrite"}


def test_no_package_writes_a_file_in_place():
    """Figures, pages, tables and data go through ``box_toss_env.files`` (``save_figure``, ``write_atomic``,
    ``atomic_path``), never ``savefig`` / ``write_text`` / ``write_bytes`` / imageio on the destination."""
    found = []
    for package in ("box_toss_env", "agents", "benchmarks", "reports"):
        for path in (REPO / package).rglob("*.py"):
            if path == REPO / "box_toss_env" / "files.py":
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                if (
                    isinstance(node, ast.Call)
                    and isinstance(node.func, ast.Attribute)
                    and node.func.attr in IN_PLACE_WRITERS
                ):
                    found.append(f"{path.relative_to(REPO)}:{node.lineno} {node.func.attr}")
    assert found == []
