"""The native batched BoxToss with Gymnasium's ``AutoresetMode.DISABLED``: no env resets by itself.

In ``DISABLED`` mode the step that ends an episode returns its landing observation, and the user resets
the envs that ended, ``reset(options={"reset_mask": mask})``, before stepping them again (Gymnasium's
``SyncVectorEnv(..., autoreset_mode=AutoresetMode.DISABLED)`` asserts it). The native env draws each env's
next episode in the step that ends the last one (``SAME_STEP``); this wrapper holds those first
observations back until the env is reset, so each env's episodes come from its random stream in the same
order as in a ``SyncVectorEnv`` of single envs with the same seeds (``tests/wrappers/test_vector_conventions.py``),
at the native env's speed. A partial reset takes no seeds: the next episodes were drawn already.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv, VectorWrapper

FINAL_KEYS = ("final_obs", "_final_obs", "final_info", "_final_info")


class DisabledAutoreset(VectorWrapper):
    """``DISABLED`` autoreset over a vector env that resets every env in the step it ends."""

    def __init__(self, env: VectorEnv):
        mode = env.metadata.get("autoreset_mode")
        if mode != AutoresetMode.SAME_STEP:
            raise ValueError(f"env must reset in the step it ends (autoreset_mode SAME_STEP), got {mode!r}")
        super().__init__(env)
        self.metadata = {**env.metadata, "autoreset_mode": AutoresetMode.DISABLED}
        self._pending: tuple[np.ndarray, dict[str, Any]] | None = None  # the episodes drawn in the last step
        self._ended = np.zeros(self.num_envs, dtype=bool)  # envs whose episode ended and that were not reset

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if mask is None:
            self._ended[:] = False
            self._pending = None
            return self.env.reset(seed=seed, options=options or None)  # type: ignore[arg-type]  # a list of seeds too
        mask = check_reset_mask(mask, self.num_envs)
        if seed is not None:
            raise ValueError(
                "seed must be None when options['reset_mask'] is given: the next episodes were drawn "
                "when the last ones ended; reset every env (no reset_mask) to reseed"
            )
        if options:
            raise ValueError(f"options other than reset_mask are not taken with a reset_mask, got {sorted(options)}")
        if np.any(mask & ~self._ended):
            raise ValueError(
                f"reset_mask selects envs whose episode has not ended: {np.flatnonzero(mask & ~self._ended).tolist()}"
            )
        self._ended &= ~mask
        assert self._pending is not None  # drawn when the episodes ended
        observations, info = self._pending
        return observations.copy(), dict(info)

    def step(self, actions):
        if np.any(self._ended):
            raise RuntimeError(
                f"envs {np.flatnonzero(self._ended).tolist()} ended and were not reset: with "
                "autoreset disabled, call reset(options={'reset_mask': mask}) first"
            )
        observations, reward, terminated, truncated, info = self.env.step(actions)
        ended = terminated | truncated
        if not np.all(ended):
            raise RuntimeError("DisabledAutoreset needs every env to end in every step (one-throw episodes)")
        self._ended = ended.copy()
        self._pending = (observations, {key: value for key, value in info.items() if key not in FINAL_KEYS})
        return info["final_obs"], reward, terminated, truncated, info["final_info"]


def check_reset_mask(mask, num_envs: int) -> np.ndarray:
    """``options["reset_mask"]`` as Gymnasium's vector envs take it: a numpy bool array of shape (num_envs,)."""
    if not isinstance(mask, np.ndarray) or mask.dtype != np.bool_ or mask.shape != (num_envs,):
        raise ValueError(f"options['reset_mask'] must be a numpy bool array of shape ({num_envs},), got {mask!r}")
    return mask
