"""File-system faults for the fault tests, injected without privileges (no mount, no root, no quota).

CI runs unprivileged, where no small tmpfs or loop device can be mounted, and as root a ``chmod`` makes nothing
read-only. Two mechanisms work everywhere:

- ``refuse``: an audit hook (``sys.addaudithook``, PEP 578) that makes the file operations Python performs under a
  folder fail with a chosen ``errno``: every write (an ``open`` for writing, ``os.open`` with write flags, which
  ``tempfile.mkstemp`` uses, ``mkdir``, ``rename``/``replace``, ``remove``, ``link``, ``chmod``) for a read-only
  folder (EROFS) or a full disk (ENOSPC), or every read (EACCES). The operation raises the ``OSError`` the kernel
  would (the hook raises it in place of the call), so the code under test meets the same exception at the same
  call. Python's file operations go through these calls, SB3's, zipfile's, numpy's and matplotlib's included; the
  hook is installed once per process (audit hooks cannot be removed) and does nothing outside ``refuse``.
- ``size_limited``: ``RLIMIT_FSIZE`` for a child process (with ``SIGXFSZ`` ignored): any write past the limit
  fails in the kernel with EFBIG, inside whatever library writes it. This is a real write-time failure, as a
  full disk's ENOSPC is.
"""

from __future__ import annotations

import contextlib
import errno
import fnmatch
import os
import resource
import signal
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC
WRITE_EVENTS = {"os.mkdir", "os.rename", "os.replace", "os.remove", "os.rmdir", "os.link", "os.chmod", "os.truncate"}


@dataclass
class Refusal:
    root: str
    code: int
    reads: bool
    pattern: str


_active: list[Refusal] = []
_installed = False


def _paths(args: tuple) -> list[str]:
    paths = []
    for arg in args[:2]:
        if isinstance(arg, (str, bytes, os.PathLike)):
            paths.append(os.path.abspath(os.fsdecode(arg)))
    return paths


def _hook(event: str, args: tuple) -> None:
    if not _active or (event != "open" and event not in WRITE_EVENTS):
        return
    if event == "open":
        flags = args[2] if len(args) > 2 and isinstance(args[2], int) else 0
        mode = args[1] if len(args) > 1 else None
        writes = bool(flags & WRITE_FLAGS) or (isinstance(mode, str) and any(c in mode for c in "wax+"))
    else:
        writes = True
    for refusal in _active:
        if writes == refusal.reads:
            continue
        for path in _paths(args if event != "open" else args[:1]):
            if (path + os.sep).startswith(refusal.root + os.sep) and fnmatch.fnmatch(path, refusal.pattern):
                raise OSError(refusal.code, os.strerror(refusal.code), path)


@contextlib.contextmanager
def refuse(root: str | Path, code: int = errno.EROFS, *, reads: bool = False, pattern: str = "*") -> Iterator[None]:
    """Within the block, Python's writes (or, with ``reads``, its reads) of paths under ``root`` that match
    ``pattern`` fail with ``OSError(code)``: EROFS a read-only folder, ENOSPC a full disk, EACCES no permission."""
    global _installed
    if not _installed:
        sys.addaudithook(_hook)
        _installed = True
    refusal = Refusal(os.path.abspath(root), code, reads, pattern)
    _active.append(refusal)
    try:
        yield
    finally:
        _active.remove(refusal)


def size_limited(max_bytes: int):
    """A ``preexec_fn`` for ``subprocess``: the child may write no file larger than ``max_bytes`` (EFBIG)."""

    def limit() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # else the kernel kills the writer instead of failing the write
        resource.setrlimit(resource.RLIMIT_FSIZE, (max_bytes, max_bytes))

    return limit


def tree_state(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` with its content (to assert that nothing was created, removed or rewritten)."""
    return {str(path.relative_to(folder)): path.read_bytes() for path in sorted(folder.rglob("*")) if path.is_file()}
