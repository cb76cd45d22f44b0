"""An adapter that lets Stable-Baselines3 train on a Gymnasium ``VectorEnv``.

SB3 has its own ``VecEnv`` interface and does not accept Gymnasium vector envs. This adapter maps
one onto the other, for vector envs that reset in the same step (``AutoresetMode.SAME_STEP``, as
SB3's own vector envs do):

========================================  ==============================================
Gymnasium VectorEnv                       SB3 VecEnv
========================================  ==============================================
``obs, rew, terminated, truncated, info``  ``obs, rew, done = terminated | truncated, infos``
``info`` (dict of arrays, ``_key`` masks)  ``infos`` (list of one dict per env)
``info["final_obs"][i]``                   ``infos[i]["terminal_observation"]``
``info["final_info"]`` for env i           merged into ``infos[i]``
``truncated[i] and not terminated[i]``     ``infos[i]["TimeLimit.truncated"]``
========================================  ==============================================

It works under ``VecMonitor`` and ``VecNormalize`` like any SB3 VecEnv. Needs the ``train`` extra.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, cast

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices


def split_info(info: dict[str, Any], num_envs: int) -> list[dict[str, Any]]:
    """Gymnasium's vector ``info`` (a dict of per-env arrays with ``_key`` masks) as one dict per
    env, keeping only the entries each env actually set. Per-env scalars become Python scalars (as
    a single env returns them), rows of 2-D arrays stay arrays."""
    everywhere_keys, everywhere_columns, partial = [], [], []
    mask_is_full: dict[int, bool] = {}  # vector envs often share one mask array between keys
    for key, value in info.items():
        if key.startswith("_"):
            continue
        if isinstance(value, dict):
            values = split_info(value, num_envs)
        elif isinstance(value, np.ndarray) and value.ndim == 1:
            values = value.tolist()
        else:
            values = list(value)
        mask = info.get(f"_{key}")
        if mask is not None and id(mask) not in mask_is_full:
            mask_is_full[id(mask)] = bool(mask.all())
        if mask is None or mask_is_full[id(mask)]:
            everywhere_keys.append(key)
            everywhere_columns.append(values)
        else:
            partial.append((key, values, np.flatnonzero(mask)))
    per_env = [dict(zip(everywhere_keys, row, strict=True)) for row in zip(*everywhere_columns, strict=True)]
    if not per_env:
        per_env = [{} for _ in range(num_envs)]
    for key, values, envs in partial:
        for i in envs:
            per_env[i][key] = values[i]
    return per_env


class SB3VecEnvAdapter(VecEnv):
    """SB3 ``VecEnv`` view of a Gymnasium ``VectorEnv`` that autoresets in the same step."""

    def __init__(self, vector_env: VectorEnv):
        mode = vector_env.metadata.get("autoreset_mode")
        if mode not in (AutoresetMode.SAME_STEP, "SameStep"):
            raise ValueError(
                f"vector_env must autoreset in the same step (metadata['autoreset_mode'] = AutoresetMode.SAME_STEP), "
                f"got {mode!r}"
            )
        self.vector_env = vector_env
        self._actions: np.ndarray | None = None
        super().__init__(vector_env.num_envs, vector_env.single_observation_space, vector_env.single_action_space)

    def reset(self):
        seeds = None if all(seed is None for seed in self._seeds) else list(self._seeds)
        options = next((options for options in self._options if options), None)
        obs, info = self.vector_env.reset(seed=seeds, options=options)
        self.reset_infos = split_info(info, self.num_envs)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        obs, rewards, terminated, truncated, info = self.vector_env.step(self._actions)
        dones = np.logical_or(terminated, truncated)
        final_obs = info.pop("final_obs", None)
        final_mask = info.pop("_final_obs", dones)
        final_info = info.pop("final_info", None)
        info.pop("_final_info", None)
        infos = split_info(info, self.num_envs)
        ended = split_info(final_info, self.num_envs) if final_info is not None else infos
        for i in np.flatnonzero(final_mask):
            infos[i] = {
                **ended[i],
                "terminal_observation": final_obs[i],
                "TimeLimit.truncated": bool(truncated[i] and not terminated[i]),
            }
        return obs, np.asarray(rewards, dtype=np.float32), dones, infos

    def close(self) -> None:
        self.vector_env.close()

    def _indices(self, indices: VecEnvIndices) -> Sequence[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, int):
            return [indices]
        return cast(Sequence[int], indices)  # SB3 passes a list or a range

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        if hasattr(self.vector_env, "get_attr") and attr_name not in ("render_mode",):
            values = self.vector_env.get_attr(attr_name)
        else:
            values = [getattr(self.vector_env, attr_name)] * self.num_envs
        return [values[i] for i in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        if indices is not None and len(self._indices(indices)) != self.num_envs:
            raise ValueError("set_attr on a subset of a Gymnasium vector env is not supported")
        if hasattr(self.vector_env, "set_attr"):
            self.vector_env.set_attr(attr_name, value)
        else:
            setattr(self.vector_env, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices: VecEnvIndices = None, **method_kwargs) -> list[Any]:
        if hasattr(self.vector_env, "call"):
            results = self.vector_env.call(method_name, *method_args, **method_kwargs)
        else:
            results = [getattr(self.vector_env, method_name)(*method_args, **method_kwargs)] * self.num_envs
        return [results[i] for i in self._indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices: VecEnvIndices = None) -> list[bool]:
        """Gymnasium vector envs do not expose their sub-envs' wrappers: always False."""
        return [False for _ in self._indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        frames = self.vector_env.render()
        return [None] * self.num_envs if frames is None else list(frames)  # type: ignore[arg-type]  # a frame each
