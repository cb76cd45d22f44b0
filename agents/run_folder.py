"""A run folder as a small database that never loses a row: safe names, atomic files, appended logs.

- A run's folder is made with ``os.mkdir`` (atomic): two runs started in the same second without a
  name get ``NAME`` and ``NAME-2``, never one folder between them.
- Names and tags are single path components, so nothing is written outside the runs folder.
- Every file is written whole or not at all (``box_toss_env.files``): into a temporary file in the
  same folder, then ``os.replace`` (a kill leaves the old file or the new one, never half of one).
- Logs (``logs/progress.csv``, ``evaluations.csv``) are appended a flushed line at a time; on resume
  the rows after the checkpoint are dropped explicitly (``truncate_csv``), so the log continues
  exactly where the checkpoint was, without a duplicate. A line cut by a kill is dropped with them.
"""

from __future__ import annotations

import csv
import fcntl
import io
import os
import shutil
import time
from pathlib import Path
from typing import Any

from stable_baselines3.common.logger import KVWriter

from agents.command_line import InputError
from box_toss_env.files import (  # noqa: F401  (write_atomic: re-exported)
    DamagedFileError,
    atomic_path,
    file_action,
    write_atomic,
)


class RunFolderError(InputError):
    """A run folder, name or file that cannot be used; the message names it."""


# -- names ---------------------------------------------------------------------------------------
def check_component(value: str, option: str) -> str:
    """``value`` if it is a single path component (a folder name, not a path), else a RunFolderError."""
    if (
        not isinstance(value, str)
        or value in ("", ".", "..")
        or "/" in value
        or "\0" in value
        or (os.altsep and os.altsep in value)
        or os.sep in value
    ):
        raise RunFolderError(f"{option} must be a single folder name (no '/', not '.' or '..'), got {value!r}")
    return value


def check_runs_dir(runs: Path) -> Path:
    """``runs`` made if absent; a RunFolderError if it (or a parent) is a file, an OSError naming it if the
    file system refuses to make it."""
    if is_file_on_the_way(runs):
        raise RunFolderError(f"--runs-dir {runs} is a file, not a folder (or lies under one)")
    with file_action("make the runs folder", runs):
        runs.mkdir(parents=True, exist_ok=True)
    return runs


def is_file_on_the_way(path: Path) -> bool:
    """Whether ``path`` or one of its parents is a file (so that no folder can be made there)."""
    return any(part.exists() and not part.is_dir() for part in (path, *path.parents))


def claim_folder(runs: Path, base: str) -> Path:
    """A new folder ``runs/base`` (or ``base-2``, ``base-3``, ...), made atomically: no two callers
    ever get the same one."""
    check_runs_dir(runs)
    for n in range(1, 10_000):
        path = runs / (base if n == 1 else f"{base}-{n}")
        try:
            with file_action("make the run folder", path):
                os.mkdir(path)
        except FileExistsError:
            continue
        return path
    raise RunFolderError(f"{runs} has 10,000 folders named {base}-N; choose a --name")


LOCK = ".lock"
_held: dict[Path, Any] = {}  # the locks this process holds, kept open for its lifetime


def lock_run(run_dir: Path, user: str = "training") -> None:
    """Hold ``run_dir/.lock`` (an advisory lock, released when the process ends, kill -9 included);
    a RunFolderError if another process holds it (a ``user`` of that folder is going on: a training of a run,
    an evaluation into a results folder)."""
    run_dir = Path(run_dir)
    if run_dir.resolve() in _held:
        return
    with file_action("lock the folder (open its lock file)", run_dir / LOCK):
        handle = open(run_dir / LOCK, "a")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.close()
        raise RunFolderError(f"{run_dir} is in use by another {user} (it holds {run_dir / LOCK})") from None
    _held[run_dir.resolve()] = handle


def unlock_run(run_dir: Path) -> None:
    handle = _held.pop(Path(run_dir).resolve(), None)
    if handle is not None:
        handle.close()


def timestamp() -> str:
    return time.strftime("%Y%m%d-%H%M%S")


# -- atomic files (``box_toss_env.files``) -----------------------------------------------------
def copy_atomic(source: str | Path, destination: str | Path) -> None:
    """``destination`` replaced whole by the current content of ``source``: a hard link to it where the
    file system allows (no bytes copied; ``source`` is itself only ever replaced, never written in place,
    so the link keeps today's content), a copy otherwise."""
    destination = Path(destination)
    with atomic_path(destination) as temp:
        try:
            os.unlink(temp)
            os.link(source, temp)
        except OSError:
            shutil.copyfile(source, temp)


def append_line(path: str | Path, line: str) -> None:
    """One line appended to ``path`` and flushed to disk (a kill leaves it whole or cut, never reordered)."""
    with file_action("append to", path), open(path, "a", newline="") as file:
        file.write(line if line.endswith("\n") else line + "\n")
        file.flush()
        os.fsync(file.fileno())


def csv_line(values: list[Any]) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(values)
    return buffer.getvalue()


# -- appended CSV logs ---------------------------------------------------------------------------
def read_csv(path: str | Path) -> tuple[list[str], list[dict[str, str]]]:
    """(columns, complete rows) of a CSV log; a last line cut by a kill is left out."""
    path = Path(path)
    if not path.exists():
        return [], []
    with file_action("read", path):
        data = path.read_bytes()
    try:
        text = data.decode()
    except UnicodeDecodeError:
        raise DamagedFileError(f"{path} is damaged: it is not text (UTF-8)") from None
    if text and not text.endswith("\n"):  # a line cut by a kill
        text = text[: text.rfind("\n") + 1]
    reader = csv.reader(io.StringIO(text))
    columns = next(reader, [])
    rows = [dict(zip(columns, values, strict=True)) for values in reader if len(values) == len(columns)]
    return columns, rows


def truncate_csv(path: str | Path, column: str, last: int, *, dry_run: bool = False) -> tuple[int, int]:
    """Drop the rows of the CSV log at ``path`` whose ``column`` is above ``last`` (and a cut line):
    the log then ends where the checkpoint at ``last`` steps was. Returns (rows kept, rows dropped); with
    ``dry_run`` nothing is written (the log is only checked: a DamagedFileError names a row that is not a number)."""
    path = Path(path)
    columns, rows = read_csv(path)
    if not columns:
        return 0, 0
    if column not in columns:
        raise DamagedFileError(f"{path} is damaged: its header {columns} has no {column}")
    valued = [row for row in rows if row.get(column) not in (None, "")]
    kept = [row for row, value in zip(valued, number_column(path, valued, column), strict=True) if value <= last]
    dropped = len(path.read_text().splitlines()) - 1 - len(kept)
    if dropped and not dry_run:
        write_atomic(path, "".join([csv_line(columns)] + [csv_line([row[c] for c in columns]) for row in kept]))
    return len(kept), dropped


def number_column(path: Path, rows: list[dict[str, str]], column: str) -> list[float]:
    """The values of ``column`` in a CSV log's ``rows``, as numbers (a DamagedFileError naming the file and
    the row of one that is not)."""
    values = []
    for i, row in enumerate(rows):
        try:
            values.append(float(row[column]))
        except (KeyError, TypeError, ValueError):
            raise DamagedFileError(
                f"{path} is damaged: row {i + 2} has {row.get(column)!r} for {column}, not a number"
            ) from None
    return values


class AppendingCSVOutput(KVWriter):
    """SB3's logger output to ``progress.csv``, appended a flushed row at a time (SB3's own CSV output
    opens the file with "w", so a resumed run emptied its log). A key not seen before widens the
    header: the file is then rewritten whole, atomically."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.columns, _ = read_csv(self.path)

    def write(self, key_values: dict[str, Any], key_excluded: dict[str, Any], step: int = 0) -> None:
        values = {
            key: value
            for key, value in key_values.items()
            if not (key_excluded.get(key) and "csv" in key_excluded[key])
        }
        new = [key for key in values if key not in self.columns]
        if new or not self.path.exists():
            _, rows = read_csv(self.path)
            self.columns = self.columns + sorted(new)
            write_atomic(
                self.path,
                "".join([csv_line(self.columns)] + [csv_line([row.get(c, "") for c in self.columns]) for row in rows]),
            )
        append_line(self.path, csv_line([plain(values.get(column, "")) for column in self.columns]))

    def close(self) -> None:
        pass


def plain(value: Any) -> Any:
    """A logged value as SB3's CSV output writes it (tensors and arrays as numbers)."""
    if hasattr(value, "item") and getattr(value, "size", 1) == 1:
        return value.item()
    return value
