"""The commands' front: option types that check as they parse, and every error as one line.

Everything here is light (argparse, pathlib): a command parses its options, and answers ``--help``, before torch
or Stable-Baselines3 is imported.

- ``OneLineParser``: argparse's errors in one line (``box-toss train: error: argument --seed: ...``), exit 2.
- ``Integer``, ``SEED``, ``folder``, ``single_name``: argparse ``type=`` callables that refuse a wrong type, a value
  out of range or an empty value with the option's allowed range; their bounds are attributes, which the fault
  tests (tests/test_fault_options.py) read to make the values out of range.
- ``one_line_errors``: a command's body under it ends, on a refused option or configuration, a damaged file
  or a file-system error, with one line naming the option, file or path (no traceback) and a non-zero exit.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

MAX_SEED = 2**32 - 1
"""The largest seed: numpy's legacy seeding (``np.random.seed``, which SB3's ``set_random_seed`` calls) takes
seeds in [0, 2**32 - 1]; every seed option and every seed a command derives (first seed + count) stays in it."""
RUNS = Path("runs")  # the run folders' folder, relative to where the command runs
INPUT_ERROR, FILE_ERROR = 2, 1  # exit statuses: a refused option or configuration; a damaged file or OS error


class InputError(ValueError):
    """A refused option, configuration or name (``ConfigError``, ``RunFolderError`` and ``SchemaError`` are
    these); the message names it and what is allowed."""


class OneLineParser(argparse.ArgumentParser):
    """A parser whose errors are one line, exit code 2 (argparse would print the whole usage first)."""

    def error(self, message: str):
        self.exit(INPUT_ERROR, f"{self.prog}: error: {message} (see --help)\n")


class Integer:
    """An argparse type: an integer in [low, high] (``high`` None: no upper bound)."""

    def __init__(self, low: int, high: int | None = None):
        self.low, self.high = low, high
        self.__name__ = "integer"

    @property
    def allowed(self) -> str:
        return f"an integer >= {self.low}" + (f" and <= {self.high}" if self.high is not None else "")

    def __call__(self, text: str) -> int:
        try:
            value = int(text.strip())
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {self.allowed}, got {text!r}") from None
        if value < self.low or (self.high is not None and value > self.high):
            raise argparse.ArgumentTypeError(f"must be {self.allowed}, got {value}")
        return value


SEED = Integer(0, MAX_SEED)
COUNT = Integer(1)


def folder(text: str) -> Path:
    """An argparse type: a folder's path, not empty."""
    if not text.strip():
        raise argparse.ArgumentTypeError("must be a folder's path, got ''")
    return Path(text)


def json_file(text: str) -> Path:
    """An argparse type: the path of a JSON file (``.json``), not a folder."""
    path = Path(text)
    if not text.strip() or path.suffix != ".json" or path.is_dir():
        raise argparse.ArgumentTypeError(f"must be the path of a .json file, got {text!r}")
    return path


def single_name(text: str) -> str:
    """An argparse type: a single folder name (a run's ``--name``, an evaluation's ``--tag``)."""
    if text in ("", ".", "..") or "/" in text or "\0" in text:
        raise argparse.ArgumentTypeError(f"must be a single folder name (no '/', not '.' or '..'), got {text!r}")
    return text


def check_seed_range(option: str, first: int, count: int) -> None:
    """A ValueError if the seeds ``first`` .. ``first + count - 1`` (what ``option`` makes) pass ``MAX_SEED``."""
    if first + count - 1 > MAX_SEED:
        raise ValueError(
            f"{option} {first} with {count:,} seeds reaches {first + count - 1}, above the largest seed {MAX_SEED}"
        )


class CommandError(Exception):
    """A refusal a command reports as one line (``message``) with exit status ``status``."""

    def __init__(self, message: str, status: int = INPUT_ERROR):
        super().__init__(message)
        self.status = status


@contextlib.contextmanager
def one_line_errors(prog: str, hint: str | Callable[[], str] = "") -> Iterator[None]:
    """Run a command's body: a refused configuration or option (``InputError``: ``ConfigError``,
    ``RunFolderError``), a damaged file (``DamagedFileError``) or a file-system error (``OSError``,
    said as a sentence by ``box_toss_env.files.describe_os_error``) ends the command with one line on stderr naming
    what is wrong, and exit status 2 (input) or 1 (a file or the file system); ``hint`` is added to the line of a
    file-system error (e.g. how to resume the run)."""
    from box_toss_env.files import DamagedFileError, describe_os_error

    try:
        yield
    except CommandError as error:
        _exit(prog, str(error), error.status)
    except DamagedFileError as error:
        _exit(prog, str(error), FILE_ERROR)
    except OSError as error:
        advice = hint() if callable(hint) else hint
        _exit(prog, describe_os_error(error) + (f"; {advice}" if advice else ""), FILE_ERROR)
    except InputError as error:
        _exit(prog, str(error), INPUT_ERROR)


def _exit(prog: str, message: str, status: int) -> None:
    line = " ".join(message.split())  # one line, whatever the message held
    print(f"{prog}: {line}", file=sys.stderr)
    raise SystemExit(status)
