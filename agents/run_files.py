"""Every file the tools read from a run folder, validated as it is read.

A file cut by a kill or a full disk, emptied, edited into something else or of another kind is a
``DamagedFileError`` whose one line names the file and what is wrong with it, raised before the command writes
anything: a command reads (and checks) all its input first. What the file system refuses (a missing permission)
is an ``OSError`` naming the file and the action (``box_toss_env.files.file_action``).

- ``config.yml``: ``read_run_config`` (a mapping with the run's algorithm, env id, seed and hyperparameters, which
  must pass ``agents.config.check_config``, or a baseline's settings);
- ``model.zip`` and the checkpoints' models: ``check_model_file`` (a whole zip archive, every member's checksum
  right, SB3's ``data`` and ``policy.pth`` in it; returns the steps it was trained for);
- ``vecnormalize.pkl`` and the checkpoints' statistics: ``read_normalizer`` (SB3's pickled ``VecNormalize`` of
  the env's observation shape); a replay buffer: ``check_replay_buffer``;
- ``timing.json``, ``results.json``: ``read_json``; the CSV logs: ``agents.run_folder.read_csv`` and
  ``number_column``.
"""

from __future__ import annotations

import json
import pickle
import zipfile
import zlib
from pathlib import Path
from typing import Any

import yaml

from agents import algorithms
from agents.command_line import MAX_SEED
from agents.config import ConfigError, check_config
from agents.run_folder import RunFolderError, number_column  # noqa: F401  (number_column: re-exported)
from box_toss_env.files import DamagedFileError, file_action

BASELINES = ("random", "oracle", "constant")
MODEL_MEMBERS = ("data", "policy.pth")  # what SB3's save writes and its load needs


def one_line(text: str) -> str:
    return " ".join(text.split())


def read_text(path: Path) -> str:
    """``path``'s text (an OSError naming it if it cannot be read; a DamagedFileError if it is not text)."""
    with file_action("read", path):
        data = path.read_bytes()
    try:
        return data.decode()
    except UnicodeDecodeError:
        raise DamagedFileError(f"{path} is damaged: it is not text (UTF-8)") from None


def read_yaml(path: Path) -> Any:
    """``path`` read as YAML; empty or malformed is a DamagedFileError."""
    text = read_text(path)
    if not text.strip():
        raise DamagedFileError(f"{path} is empty (cut by a kill or a full disk, or emptied)")
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(error, "problem", None) or one_line(str(error))
        raise DamagedFileError(f"{path} is damaged: not valid YAML{where} ({problem})") from None


def read_json(path: Path) -> Any:
    """``path`` read as JSON; empty or malformed is a DamagedFileError."""
    text = read_text(path)
    if not text.strip():
        raise DamagedFileError(f"{path} is empty (cut by a kill or a full disk, or emptied)")
    try:
        return json.loads(text)
    except ValueError as error:
        raise DamagedFileError(f"{path} is damaged: not valid JSON ({error})") from None


def read_json_mapping(path: Path, keys: tuple[str, ...] = ()) -> dict[str, Any]:
    """``read_json`` of a file that must hold a mapping with ``keys``."""
    data = read_json(path)
    if not isinstance(data, dict):
        raise DamagedFileError(f"{path} is damaged: it holds a {type(data).__name__}, not a mapping")
    missing = [key for key in keys if key not in data]
    if missing:
        raise DamagedFileError(f"{path} is damaged: it has no {', '.join(missing)}")
    return data


# -- config.yml --------------------------------------------------------------------------------------
def read_run_config(run_dir: Path) -> dict[str, Any]:
    """A run folder's ``config.yml``, checked: a mapping naming the algorithm (one of the algorithms, with a seed
    and hyperparameters that pass ``check_config``, or a baseline) and a registered env id."""
    path = Path(run_dir) / "config.yml"
    if Path(run_dir).is_file():
        raise RunFolderError(f"{run_dir} is a file, not a run folder: give the folder that holds it")
    if not path.is_file():
        raise RunFolderError(f"{run_dir} is not a run folder (no config.yml)")
    config = read_yaml(path)
    if not isinstance(config, dict):
        raise DamagedFileError(f"{path} is damaged: it holds a {type(config).__name__}, not a run's configuration")
    algo, env_id = config.get("algo"), config.get("env_id")
    if algo not in (*algorithms.ALGORITHMS, *BASELINES):
        raise DamagedFileError(
            f"{path} is damaged: algo is {algo!r}, not one of {[*algorithms.ALGORITHMS, *BASELINES]}"
        )
    if not isinstance(env_id, str) or not env_id:
        raise DamagedFileError(f"{path} is damaged: env_id is {env_id!r}, not an env id")
    if not isinstance(config.get("env_kwargs", {}) or {}, dict):
        raise DamagedFileError(f"{path} is damaged: env_kwargs is {config['env_kwargs']!r}, not a mapping")
    if algo in BASELINES:
        if not isinstance(config.get("baseline", {}) or {}, dict):
            raise DamagedFileError(f"{path} is damaged: baseline is {config['baseline']!r}, not a mapping")
        return config
    check_trained_config(path, config, algo)
    return config


def check_trained_config(path: Path, config: dict[str, Any], algo: str) -> None:
    """A trained run's seed (an integer in the seed range) and hyperparameters (``check_config``)."""
    seed = config.get("seed")
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed <= MAX_SEED:
        raise DamagedFileError(f"{path} is damaged: seed is {seed!r}, not an integer in [0, {MAX_SEED}]")
    hyperparams = config.get("hyperparams")
    if not isinstance(hyperparams, dict):
        raise DamagedFileError(f"{path} is damaged: hyperparams is {hyperparams!r}, not a mapping")
    try:
        check_config(hyperparams, algo)
    except ConfigError as error:
        raise DamagedFileError(f"{path} is damaged: hyperparams: {error}") from None


# -- models, statistics, replay buffers ---------------------------------------------------------------
def check_model_file(path: Path) -> int:
    """The env steps the SB3 model saved at ``path`` was trained for, after checking the file: a whole zip
    archive whose every member passes its checksum, with SB3's ``data`` (JSON, ``num_timesteps``) and
    ``policy.pth``. A DamagedFileError naming the file and what is wrong otherwise."""
    cut = "not a whole zip archive (cut by a kill or a full disk?)"
    try:
        with file_action("read", path), zipfile.ZipFile(path) as archive:
            bad = archive.testzip()
            names = set(archive.namelist())
            data = json.loads(archive.read("data")) if "data" in names and bad is None else None
    except (zipfile.BadZipFile, EOFError, zlib.error, ValueError, KeyError) as error:
        reason = cut if not isinstance(error, ValueError) else f"its data is not SB3's ({error})"
        raise DamagedFileError(f"{path} is damaged: {reason}") from None
    if bad is not None:
        raise DamagedFileError(f"{path} is damaged: its member {bad} fails its checksum")
    missing = [name for name in MODEL_MEMBERS if name not in names]
    if missing:
        raise DamagedFileError(f"{path} is damaged: it has no {', '.join(missing)} (not an SB3 model)")
    steps = data.get("num_timesteps") if isinstance(data, dict) else None
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 0:
        raise DamagedFileError(f"{path} is damaged: its data has no step count (num_timesteps)")
    return steps


def read_pickle(path: Path, what: str) -> Any:
    """The object pickled at ``path`` (``what`` it should be, for the message)."""
    with file_action("read", path), open(path, "rb") as file:
        try:
            return pickle.load(file)
        except Exception as error:  # a cut or foreign pickle raises any of a dozen types
            reason = "it is empty" if path.stat().st_size == 0 else f"it does not unpickle ({type(error).__name__})"
            raise DamagedFileError(f"{path} is damaged: {reason}; it should hold {what}") from None


def read_normalizer(path: Path, observation_shape: tuple[int, ...] | None = None):
    """SB3's ``VecNormalize`` statistics pickled at ``path`` (without their env), checked to be of
    ``observation_shape`` if given."""
    from stable_baselines3.common.vec_env import VecNormalize

    statistics = read_pickle(path, "VecNormalize statistics")
    if not isinstance(statistics, VecNormalize):
        raise DamagedFileError(
            f"{path} is damaged: it holds a {type(statistics).__name__}, not VecNormalize statistics"
        )
    shape = getattr(getattr(statistics, "obs_rms", None), "mean", None)
    if observation_shape is not None and getattr(shape, "shape", None) != tuple(observation_shape):
        raise DamagedFileError(
            f"{path} holds statistics of observations of shape {getattr(shape, 'shape', None)}, "
            f"not the env's {tuple(observation_shape)}"
        )
    return statistics


def check_replay_buffer(path: Path) -> None:
    """A DamagedFileError unless ``path`` holds an SB3 replay buffer."""
    from stable_baselines3.common.buffers import ReplayBuffer

    buffer = read_pickle(path, "a replay buffer")
    if not isinstance(buffer, ReplayBuffer):
        raise DamagedFileError(f"{path} is damaged: it holds a {type(buffer).__name__}, not a replay buffer")
