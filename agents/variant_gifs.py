"""One short GIF per registered BoxToss variant, each a good throw planned by the oracle (the docs' variant figures).

    python -m agents.variant_gifs --write-docs    # every registered BoxToss-* id into docs/figures/, and the section
    python -m agents.variant_gifs --envs BoxToss-ShortEnd-v0 --out /tmp/gifs

For each variant the oracle (``agents.oracle``, at the ceiling's third search budget) plans the throw at the first
test target (seed 10000 on) that no earlier variant's figure showed; if it does not succeed there, the next seed
is tried (``--tries``). The throw is
recorded as ``record_throws`` does (the box in the hand, the whole throw with its path, its result held for a
second), small (360 x 240 at 20 fps), and written atomically (a temporary file in the same folder, then
``os.replace``) into ``--out`` (default: ``variant_gifs/`` where the command runs). With ``--write-docs`` they go to
docs/figures/ and the section ``variant-gifs`` of docs/environment.md is rewritten: one figure per variant with the
seed and the throw's result (the repository's files change only when asked).
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np

import box_toss_env  # noqa: F401  (registers the variants)
from agents.ceiling import BUDGETS
from agents.doc_sections import DOCS, replace_section
from agents.evaluation import TEST_FIRST_SEED
from agents.oracle import OraclePlanner, ThrowSimulator, episodes_from_infos
from box_toss_env.rendering.video import write_gif

GIF_ENV_KWARGS: dict[str, Any] = {"render_width": 360, "render_height": 240, "render_fps": 20}
PLANNER_BUDGET = BUDGETS[2]  # 512 uniform candidates, then 16 rounds of 64
OUT = DOCS / "figures"
MAX_BYTES = 300_000


SEQUENTIAL = ("BoxToss-Stack-v0", "BoxToss-HiddenPhysics-v0")
"""Ids whose episodes are several throws (docs/stack.md, docs/hidden_physics.md): no one-throw GIF."""


def pixel_ids() -> list[str]:
    """The pixel-observation ids (``BoxToss-*-Pixels-v0``): their throws are their state variant's, whose GIF shows
    them."""
    return [env_id for env_id in gym.registry if env_id.startswith("BoxToss-") and env_id.endswith("-Pixels-v0")]


def variant_ids() -> list[str]:
    """Every registered one-throw BoxToss id observing the state, in registration order."""
    left_out = {*SEQUENTIAL, *pixel_ids()}
    return [env_id for env_id in gym.registry if env_id.startswith("BoxToss-") and env_id not in left_out]


def throw_env(env: gym.Env) -> gym.Env:
    """The ``BoxTossEnv`` that throws for ``env`` (a goal env holds one; the oracle plans on it)."""
    return getattr(env.unwrapped, "throw_env", env.unwrapped)


def episode_key(info: dict[str, Any]) -> tuple:
    """What a reset drew that a figure shows: the release pose, the target x and faces, the base box."""
    keys = ("release_x", "release_y", "release_angle", "target_x", "base_length", "base_height")
    return tuple(round(float(info[key]), 9) for key in keys if key in info) + tuple(info["target_faces"].tolist())


def good_throw(
    env_id: str, first_seed: int = TEST_FIRST_SEED, tries: int = 8, threads: int | None = None, shown: set | None = None
) -> tuple[int, np.ndarray]:
    """(seed, action): the oracle's throw at the first of ``tries`` seeds from ``first_seed`` where it succeeds
    (the last one tried if none does). Seeds whose episode is in ``shown`` (``episode_key``; another variant's
    figure) are skipped, and the chosen one is added to it."""
    env = gym.make(env_id)
    planner = OraclePlanner(PLANNER_BUDGET)
    simulator = ThrowSimulator(throw_env(env), threads)
    shown = set() if shown is None else shown
    seed, tried = first_seed - 1, 0
    while tried < tries:
        seed += 1
        _, info = env.reset(seed=seed)
        if episode_key(info) in shown:
            continue
        tried += 1
        key = episode_key(info)
        action = planner.plan(simulator, episodes_from_infos([info]))[0]
        env.reset(seed=seed)
        info = env.step(action.astype(np.float32))[4]
        if info["success"]:
            break
    shown.add(key)
    env.close()
    return seed, action.astype(np.float32)


def write_atomically(frames: list[np.ndarray], path: Path, fps: float) -> Path:
    """``write_gif`` into a temporary file beside ``path``, then ``os.replace`` it onto ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".gif", dir=path.parent)
    os.close(handle)
    try:
        write_gif(frames, temporary, fps)
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise
    return path


def record_variant(
    env_id: str,
    out: Path,
    first_seed: int = TEST_FIRST_SEED,
    tries: int = 8,
    threads: int | None = None,
    shown: set | None = None,
) -> dict[str, Any]:
    """Plan a good throw of ``env_id`` (``good_throw``), record it to ``out/variant_<env_id>.gif`` with the path
    the box took; its row (seed, result, size)."""
    seed, action = good_throw(env_id, first_seed, tries, threads, shown)
    env = gym.make(env_id, render_mode="rgb_array_list", **GIF_ENV_KWARGS)
    cast(Any, throw_env(env))._renderer_for_env().trace = True  # as record_throws draws it
    env.reset(seed=seed)
    info = env.step(action)[4]
    frames = cast(list[np.ndarray], env.render())
    env.close()
    path = write_atomically(frames, out / f"variant_{env_id}.gif", GIF_ENV_KWARGS["render_fps"])
    return {
        "env_id": env_id,
        "seed": seed,
        "success": bool(info["success"]),
        "distance": float(info["distance"]),
        "face_down": int(info["face_down"]),
        "frames": len(frames),
        "bytes": path.stat().st_size,
        "path": path,
    }


def docs_section(rows: list[dict[str, Any]]) -> str:
    """The ``variant-gifs`` section: one figure per variant with its seed and result."""
    lines = [
        "Written by `python -m agents.variant_gifs --write-docs` (each variant's throw planned by the oracle at its "
        "third search budget; 360 x 240 at 20 fps):",
        "",
    ]
    for row in rows:
        result = "success" if row["success"] else "no success"
        lines += [
            f"**{row['env_id']}**: seed {row['seed']}, {result}, {row['distance'] * 100:.1f} cm from the "
            f"target, face {row['face_down']} down ({row['frames']} frames, {row['bytes'] / 1000:.0f} kB)",
            "",
            f"![{row['env_id']}: the oracle's throw](docs/figures/{row['path'].name})",
            "",
        ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m agents.variant_gifs", description=__doc__.split("\n\n")[0])
    parser.add_argument("--envs", nargs="+", default=None, help="env ids (default: every registered BoxToss-* id)")
    parser.add_argument("--out", type=Path, default=None, help="folder of the GIFs (default: variant_gifs/)")
    parser.add_argument("--first-seed", type=int, default=TEST_FIRST_SEED, help="first seed tried (>= 0)")
    parser.add_argument("--tries", type=int, default=8, help="seeds tried per variant until a success (>= 1)")
    parser.add_argument("--threads", type=int, default=None, help="engine threads of the oracle (>= 1)")
    parser.add_argument(
        "--write-docs", action="store_true", help=f"write the GIFs into {OUT} and docs/environment.md's section"
    )
    args = parser.parse_args(argv)
    if args.write_docs and args.out is not None:
        parser.error("--write-docs writes the GIFs into the docs' folder: drop --out")
    args.out = OUT if args.write_docs else (args.out or Path("variant_gifs"))
    if args.first_seed < 0 or args.tries < 1 or (args.threads is not None and args.threads < 1):
        parser.error("--first-seed must be >= 0, --tries and --threads >= 1")
    envs = args.envs or variant_ids()
    unknown = [env_id for env_id in envs if env_id not in gym.registry]
    if unknown:
        parser.error(f"unknown env ids {unknown}; registered: {variant_ids()}")
    rows: list[dict[str, Any]] = []
    shown: set[int] = set()
    for env_id in envs:  # each variant's figure shows an episode no earlier one showed
        row = record_variant(env_id, args.out, args.first_seed, args.tries, args.threads, shown)
        rows.append(row)
        print(
            f"{env_id}: seed {row['seed']}, success {row['success']}, {row['frames']} frames, "
            f"{row['bytes']} bytes -> {row['path']}"
        )
        if row["bytes"] > MAX_BYTES:
            print(f"warning: {row['path']} is above {MAX_BYTES} bytes")
    if args.write_docs:
        replace_section("variant-gifs", docs_section(rows))
        print("wrote the variant-gifs section of docs/environment.md")


if __name__ == "__main__":
    main()
