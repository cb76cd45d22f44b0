"""Files written whole or not at all: the one atomic-write helper of the repository.

A writer (matplotlib's ``savefig``, Pillow, imageio, pygame, ``np.save``, SB3's ``model.save``, or plain
bytes) writes into a temporary file in the destination's folder; the file is flushed to disk and then
renamed over the destination (``os.replace``, atomic on one file system). A kill or an error in the
middle leaves the previous file as it was (or no file), never half of one; the temporary file is
removed on an error (a ``kill -9`` leaves it, named ``.<name>.<random>.tmp<suffix>``).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, BinaryIO


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


FILE_MODE = 0o666 & ~_umask()  # what open() would have given the file (mkstemp makes it 0o600)


@contextlib.contextmanager
def atomic_path(path: str | Path, suffix: str | None = None) -> Iterator[Path]:
    """A temporary path in ``path``'s folder to write to; it replaces ``path`` when the block ends
    without an error (and is removed otherwise). The temporary name ends with ``suffix`` (by default
    ``path``'s own suffix), for writers that choose the format by the extension or add one."""
    path = Path(path)
    suffix = path.suffix if suffix is None else suffix
    handle, temp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{suffix}", dir=path.parent)
    os.close(handle)
    os.chmod(temp, FILE_MODE)
    try:
        yield Path(temp)
        with open(temp, "rb+") as file:
            os.fsync(file.fileno())
        os.replace(temp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temp)


def write_atomic(path: str | Path, data: str | bytes | Callable[[BinaryIO], Any]) -> None:
    """``path`` replaced whole by ``data`` (text, bytes, or a function writing to a binary file)."""
    with atomic_path(path) as temp, open(temp, "wb") as file:
        if callable(data):
            data(file)
        else:
            file.write(data.encode() if isinstance(data, str) else data)


def save_figure(figure, path: str | Path, **kwargs) -> Path:
    """``figure.savefig(path, **kwargs)`` (a matplotlib figure), written atomically; the format is
    ``path``'s suffix unless ``format`` is given. Returns ``path``."""
    path = Path(path)
    kwargs.setdefault("format", path.suffix.lstrip(".") or None)
    with atomic_path(path) as temp:
        figure.savefig(temp, **kwargs)
    return path
