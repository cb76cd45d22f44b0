"""Download the measured square drops into a local folder and check them against the committed checksums.

    python -m reports.reality.download --out data/square-drops
    python -m reports.reality.download --ellipse --out data/ellipse   # data_ellipse.mat, v_models.mat

Each ``traj_N.csv`` (N = 1..500) is read from the repository's raw URL at the pinned commit ``COMMIT`` of
DAIRLab/ImpactModeling (BSD-3-Clause, Copyright (c) 2020, Dynamic Autonomy and Intelligent Robotics Lab;
the licence is saved beside the files as LICENSE) and kept only if its SHA-256 equals the one in
``square_drops.sha256`` (computed from that commit). Files already present with the right checksum are not
downloaded again. The data are not part of this repository: keep them outside it, or in an ignored folder.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import urllib.error
import urllib.request
from pathlib import Path

from box_toss_env.files import write_atomic

REPOSITORY = "DAIRLab/ImpactModeling"
COMMIT = "f6c28898845da6d48efdd6c1c696db2fb3716edf"
FOLDER = "Wang/Wang-Mason%20Square/dice-data-processed"
RAW = f"https://raw.githubusercontent.com/{REPOSITORY}/{COMMIT}"
MANIFEST = Path(__file__).with_name("square_drops.sha256")
# the ellipse impacts (reports.reality.impacts --ellipse): mcubelab/planar-impact-dataset has no licence file, so
# they are only downloaded to a folder the user names (--out), never kept in this repository
ELLIPSE_REPOSITORY = "mcubelab/planar-impact-dataset"
ELLIPSE_COMMIT = "f24a7e3b31ad0b53652d6b2a6b26a702cc4362da"
ELLIPSE_RAW = f"https://raw.githubusercontent.com/{ELLIPSE_REPOSITORY}/{ELLIPSE_COMMIT}/processed_data"
ELLIPSE_FILES = {  # name -> SHA-256 at ELLIPSE_COMMIT
    "data_ellipse.mat": "06ecb1642369b0e013f6f8ba7761797529c3de5e8d70d913722b118572afb169",
    "v_models.mat": "22ebce5783dbb4024e34d2bba05c1c08a30f29cf2473c6dc80a152bd77a677f6",
}


def manifest(path: Path = MANIFEST) -> dict[str, str]:
    """File name -> SHA-256 hex digest, from a ``sha256sum``-format file."""
    entries = {}
    for line in path.read_text().splitlines():
        if line.strip():
            digest, name = line.split()
            entries[name] = digest
    return entries


def sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def verify(folder: Path, expected: dict[str, str] | None = None) -> dict[str, str]:
    """Name -> what is wrong ("missing" or "checksum") for each manifest file not present intact in ``folder``."""
    expected = manifest() if expected is None else expected
    problems = {}
    for name, digest in expected.items():
        path = Path(folder) / name
        if not path.is_file():
            problems[name] = "missing"
        elif sha256(path) != digest:
            problems[name] = "checksum"
    return problems


def download(out: Path, timeout: float = 30.0, ellipse: bool = False) -> dict[str, str]:
    """Download every manifest file not already intact in ``out``; returns the problems left (see ``verify``).
    ``ellipse``: the ellipse impacts' two files (``ELLIPSE_FILES``) instead of the square drops."""
    out.mkdir(parents=True, exist_ok=True)
    expected = ELLIPSE_FILES if ellipse else manifest()
    base = ELLIPSE_RAW if ellipse else f"{RAW}/{FOLDER}"
    for name in verify(out, expected):
        try:
            with urllib.request.urlopen(f"{base}/{name}", timeout=timeout) as response:
                body = response.read()
        except (urllib.error.URLError, TimeoutError) as error:
            print(f"{name}: {error}", file=sys.stderr)
            continue
        if hashlib.sha256(body).hexdigest() == expected[name]:
            write_atomic(out / name, body)
        else:
            print(f"{name}: checksum differs from the pinned one, not saved", file=sys.stderr)
    if ellipse:
        return verify(out, expected)
    if not (out / "LICENSE").exists():
        try:
            with urllib.request.urlopen(f"{RAW}/LICENSE", timeout=timeout) as response:
                write_atomic(out / "LICENSE", response.read())
        except (urllib.error.URLError, TimeoutError) as error:
            print(f"LICENSE: {error}", file=sys.stderr)
    return verify(out, expected)


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line naming the option (no usage block)."""

    def error(self, message):
        raise SystemExit(f"{self.prog}: error: {message}")


def main(argv=None) -> int:
    parser = OneLineParser(prog="python -m reports.reality.download", description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, required=True, help="folder for the traj_N.csv files")
    parser.add_argument("--check", action="store_true", help="only check the files already in --out")
    parser.add_argument(
        "--ellipse",
        action="store_true",
        help="the ellipse impacts (data_ellipse.mat, v_models.mat) instead of the square drops",
    )
    args = parser.parse_args(argv)
    if args.out.exists() and not args.out.is_dir():
        raise SystemExit(f"{parser.prog}: error: --out: {args.out} is not a folder")
    if args.check and not args.out.is_dir():
        raise SystemExit(f"{parser.prog}: error: --out: {args.out} does not exist")
    expected = ELLIPSE_FILES if args.ellipse else manifest()
    problems = verify(args.out, expected) if args.check else download(args.out, ellipse=args.ellipse)
    total = len(expected)
    print(
        f"{args.out}: {total - len(problems)} of {total} files intact"
        + (f"; {len(problems)} missing or wrong, e.g. {next(iter(problems))}" if problems else "")
    )
    return 1 if problems else 0


if __name__ == "__main__":
    raise SystemExit(main())
