"""Files written whole or not at all: the one atomic-write helper of the repository.

A writer (matplotlib's ``savefig``, Pillow, imageio, pygame, ``np.save``, SB3's ``model.save``, or plain
bytes) writes into a temporary file in the destination's folder; the file is flushed to disk and then
renamed over the destination (``os.replace``, atomic on one file system). A kill or an error in the
middle leaves the previous file as it was (or no file), never half of one; the temporary file is
removed on an error (a ``kill -9`` leaves it, named ``.<name>.<random>.tmp<suffix>``, and a later command that
owns the folder removes it: ``remove_stale_temporaries``).

What the file system refuses (a full disk, a read-only folder, a missing permission or path) is an ``OSError``
carrying the path and the action (``file_action``); ``describe_os_error`` says it as one sentence. A file that
reads but is damaged (cut, empty, of another kind) is a ``DamagedFileError`` naming the file and what is wrong.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, BinaryIO


class DamagedFileError(ValueError):
    """A file that exists but cannot be used (cut by a kill, emptied, malformed, another kind of file); the
    message names the file and what is wrong with it."""


REASONS = {
    errno.ENOSPC: "the disk is full (no space left on device)",
    errno.EDQUOT: "the disk quota is used up",
    errno.EFBIG: "the file would pass the size limit (file too large)",
    errno.EROFS: "the file system is read-only",
    errno.EACCES: "permission denied",
    errno.EPERM: "the operation is not permitted",
    errno.ENOENT: "no such file or folder",
    errno.ENOTDIR: "a part of the path is a file, not a folder",
    errno.EISDIR: "it is a folder, not a file",
    errno.EEXIST: "it exists already",
}


def describe_os_error(error: OSError) -> str:
    """``error`` as one sentence naming the action and the path: ``cannot write runs/a/model.zip: the disk is
    full (no space left on device)``."""
    reason = REASONS.get(error.errno or -1) or (error.strerror or str(error) or type(error).__name__).lower()
    action = getattr(error, "action", None)
    path = error.filename
    if path is None:
        return f"{action or 'file-system error'}: {reason}" if action else f"file-system error: {reason}"
    return f"cannot {action or 'use'} {os.fsdecode(path)}: {reason}"


@contextlib.contextmanager
def file_action(action: str, path: str | Path) -> Iterator[None]:
    """Any ``OSError`` in the block re-raised naming ``action`` ("write", "make the folder", ...) and ``path``
    (where the error does not name a path of its own, or names a temporary file standing for ``path``)."""
    try:
        yield
    except OSError as error:
        if getattr(error, "action", None):
            raise
        named = error.filename is not None and not is_temporary(Path(os.fsdecode(error.filename)))
        described = OSError(error.errno, error.strerror or str(error), error.filename if named else str(path))
        described.action = action  # type: ignore[attr-defined]
        raise described from error


TEMPORARY = re.compile(r"^\..+\.[a-z0-9_]{8}\.tmp[^/]*$")
"""The name ``atomic_path`` gives a temporary file: ``.<name>.<8 random characters>.tmp<suffix>``."""


def is_temporary(path: Path) -> bool:
    """Whether ``path`` is named as ``atomic_path``'s temporary files are."""
    return bool(TEMPORARY.match(path.name))


def remove_stale_temporaries(folder: str | Path) -> list[Path]:
    """Remove the temporary files that interrupted atomic writes left in ``folder`` (not in its subfolders);
    returns them. Only a command that owns ``folder`` (holds its lock) may call it: another's write in progress
    has a temporary file too."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    removed = []
    for path in folder.iterdir():
        if is_temporary(path) and path.is_file():
            with contextlib.suppress(FileNotFoundError), file_action("remove the leftover", path):
                path.unlink()
            removed.append(path)
    return removed


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
    with file_action("write", path):
        handle, temp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{suffix}", dir=path.parent)
        os.close(handle)
        os.chmod(temp, FILE_MODE)
    try:
        with file_action("write", path):
            yield Path(temp)
            with open(temp, "rb+") as file:
                os.fsync(file.fileno())
            os.replace(temp, path)
    finally:
        with contextlib.suppress(OSError):  # a read-only folder: nothing was made
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
