"""A run's checkpoints: where they are, which is newest, which are intact, and where a resume starts.

``checkpoints/<algo>_<steps>_steps.zip`` is a checkpoint's model, beside it its VecNormalize statistics
(``<algo>_vecnormalize_<steps>_steps.pkl``), its replay buffer (``<algo>_replay_buffer_<steps>_steps.pkl``,
off-policy algorithms) and the run's best model as it was then (``best_snapshot``). A run trained before
checkpoints were written at its end may have only ``model.zip`` (and ``vecnormalize.pkl``).

A resume starts from the newest checkpoint if every file of it is intact (``resume_point``: the model a whole
SB3 archive of its step count, the statistics and the replay buffer unpickling to what they should be). If it is
not, nothing is touched: the command stops with one line naming the damaged file and the newest intact checkpoint,
which ``--from-steps STEPS`` resumes from; the damaged newer checkpoint's files are then set aside (renamed
``*.damaged``, never deleted) so that no later resume mistakes them for the newest.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.run_files import check_model_file, check_replay_buffer, read_normalizer
from box_toss_env.files import DamagedFileError, file_action

BEST_FILES = ("best_model.zip", "best_vecnormalize.pkl")
DAMAGED = ".damaged"


class ResumeError(DamagedFileError):
    """No checkpoint to resume from as asked; the message says which one could be."""


@dataclass(frozen=True)
class Checkpoint:
    """The files of one checkpoint: its model, statistics and replay buffer (which may not exist)."""

    model: Path
    statistics: Path
    replay_buffer: Path
    steps: int

    def files(self, algo: str) -> list[Path]:
        """Every file of the checkpoint that exists, the best model's snapshots too."""
        folder = self.model.parent
        snapshots = [best_snapshot(folder.parent, algo, self.steps, name) for name in BEST_FILES]
        paths = [self.model, self.statistics, self.replay_buffer]
        return [path for path in paths + (snapshots if folder.name == "checkpoints" else []) if path.exists()]


def best_snapshot(run_dir: Path, algo: str, steps: int, name: str) -> Path:
    """Where the checkpoint at ``steps`` keeps the run's ``name`` (one of ``BEST_FILES``) as it was then:
    ``checkpoints/<algo>_best_model_<steps>_steps.zip``, ``..._best_vecnormalize_<steps>_steps.pkl``."""
    stem, suffix = name.rsplit(".", 1)
    return run_dir / "checkpoints" / f"{algo}_{stem}_{steps}_steps.{suffix}"


def model_timesteps(path: Path) -> int | None:
    """The env steps a saved SB3 model was trained for (None if the file is missing or damaged)."""
    try:
        return check_model_file(path)
    except (DamagedFileError, OSError):
        return None


def checkpoints_of(run_dir: Path, algo: str) -> list[Checkpoint]:
    """Every checkpoint of a run, newest first; a run without any in ``checkpoints/`` (trained before they were
    written at the end of a training) has ``model.zip`` for one, if it reads."""
    found = []
    for path in (run_dir / "checkpoints").glob(f"{algo}_*_steps.zip"):
        match = re.fullmatch(rf"{algo}_(\d+)_steps\.zip", path.name)
        if match:
            steps = int(match.group(1))
            stats = path.with_name(f"{algo}_vecnormalize_{steps}_steps.pkl")
            buffer = path.with_name(f"{algo}_replay_buffer_{steps}_steps.pkl")
            found.append((steps, 1, Checkpoint(path, stats, buffer, steps)))
    final = run_dir / "model.zip"
    if not found and final.exists() and (trained := model_timesteps(final)) is not None:
        found.append((trained, 0, Checkpoint(final, run_dir / "vecnormalize.pkl", run_dir / "no_buffer", trained)))
    return [checkpoint for *_, checkpoint in sorted(found, key=lambda item: item[:2], reverse=True)]


def latest_checkpoint(run_dir: Path, algo: str) -> tuple[Path, Path | None, int] | None:
    """(model, vecnormalize or None, timesteps) of the newest checkpoint of a run (or None), intact or not."""
    found = checkpoints_of(run_dir, algo)
    if not found:
        return None
    newest = found[0]
    return newest.model, (newest.statistics if newest.statistics.exists() else None), newest.steps


def damage(checkpoint: Checkpoint, normalized: bool, observation_shape: tuple[int, ...] | None) -> str | None:
    """What is wrong with a checkpoint's files (None if every one is intact)."""
    try:
        steps = check_model_file(checkpoint.model)
        if steps != checkpoint.steps:
            return f"{checkpoint.model} holds a model of {steps} steps, not {checkpoint.steps}"
        if normalized and not checkpoint.statistics.exists():
            return f"{checkpoint.statistics} is missing (the observation statistics of {checkpoint.model.name})"
        if checkpoint.statistics.exists():
            read_normalizer(checkpoint.statistics, observation_shape)
        if checkpoint.replay_buffer.exists():
            check_replay_buffer(checkpoint.replay_buffer)
    except DamagedFileError as error:
        return str(error)
    return None


def resume_point(
    run_dir: Path,
    algo: str,
    config: dict[str, Any],
    from_steps: int | None = None,
    observation_shape: tuple[int, ...] | None = None,
) -> tuple[Checkpoint, list[Checkpoint]]:
    """The checkpoint a resume of ``run_dir`` starts from (the newest, or the one at ``from_steps``), every file
    of it checked, and the damaged checkpoints newer than it (``set_aside`` then). A ``ResumeError`` naming the
    damaged file and the newest intact checkpoint if the newest is damaged, or if ``from_steps`` names none."""
    normalized = bool(config.get("normalize", True))
    found = checkpoints_of(run_dir, algo)
    if not found:
        raise ResumeError(
            f"--resume {run_dir}: no checkpoint to resume from (no {run_dir}/checkpoints/"
            f"{algo}_<steps>_steps.zip nor {run_dir}/model.zip); train it afresh"
        )
    asked = found[0] if from_steps is None else next((c for c in found if c.steps == from_steps), None)
    if asked is None:
        steps = sorted({c.steps for c in found})
        raise ResumeError(f"--from-steps {from_steps}: {run_dir} has no checkpoint at it; it has {steps}")
    chosen = asked
    newer = [c for c in found if c.steps > chosen.steps]
    for checkpoint in newer:
        if damage(checkpoint, normalized, observation_shape) is None:
            raise ResumeError(
                f"--from-steps {from_steps}: the checkpoint at {checkpoint.steps} steps is newer and intact; "
                "resume from it (drop --from-steps)"
            )
    problem = damage(chosen, normalized, observation_shape)
    if problem is not None:
        older = next(
            (c for c in found if c.steps < chosen.steps and not damage(c, normalized, observation_shape)), None
        )
        offer = (
            f"the newest intact checkpoint is at {older.steps} steps: resume from it with "
            f"--resume {run_dir} --from-steps {older.steps}"
            if older is not None
            else "no older checkpoint is intact: train the run afresh"
        )
        raise ResumeError(f"--resume {run_dir}: {problem}; {offer}")
    return chosen, newer


def set_aside(checkpoints: list[Checkpoint], algo: str) -> list[Path]:
    """The files of damaged ``checkpoints`` renamed ``<name>.damaged`` (kept, never deleted, and no longer
    taken for checkpoints); returns their new paths."""
    moved = []
    for checkpoint in checkpoints:
        for path in checkpoint.files(algo):
            target = path.with_name(path.name + DAMAGED)
            with file_action("set aside", path):
                os.replace(path, target)
            moved.append(target)
    return moved
