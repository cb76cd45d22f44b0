"""The native batched BoxToss seen with Gymnasium's default autoreset, ``AutoresetMode.NEXT_STEP``.

The native env resets every env in the step its throw ends (``SAME_STEP``: the observation returned
is the next episode's first one, the landing is in ``info["final_obs"]``). Libraries written for
``NEXT_STEP`` (RLlib's env runners, Gymnasium's ``SyncVectorEnv`` default) expect instead the landing
observation from the step that ends an episode, and the next episode's first observation from the
following ``step``, whose actions are ignored. Every BoxToss episode is one throw that ends every env
at once, so this adapter alternates exactly:

    step 1, 3, 5 ...  throws all boxes (one engine call)   obs = landings,      terminated all True
    step 2, 4, 6 ...  no simulation: the reset step         obs = next episodes, reward 0, terminated all False

and returns what a ``SyncVectorEnv`` of single BoxToss envs (``NEXT_STEP``) returns for the same seeds
and actions (``tests/wrappers/test_next_step.py``), at the native env's speed.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv, VectorWrapper


class NextStepAutoreset(VectorWrapper):
    """``NEXT_STEP`` autoreset over a vector env that resets every env in the step it ends."""

    def __init__(self, env: VectorEnv):
        mode = env.metadata.get("autoreset_mode")
        if mode != AutoresetMode.SAME_STEP:
            raise ValueError(f"env must reset in the step it ends (autoreset_mode SAME_STEP), got {mode!r}")
        super().__init__(env)
        self.metadata = {**env.metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
        self._next: tuple[np.ndarray, dict[str, Any]] | None = None  # the episodes started in the last step

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        self._next = None
        return self.env.reset(seed=seed, options=options)  # type: ignore[arg-type]  # a list of seeds too

    def step(self, actions):
        n = self.num_envs
        if self._next is not None:  # the reset step: the episodes the last step started
            observations, info = self._next
            self._next = None
            return observations, np.zeros(n), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool), info
        observations, reward, terminated, truncated, info = self.env.step(actions)
        if not np.all(terminated | truncated):
            raise RuntimeError("NextStepAutoreset needs every env to end in every step (one-throw episodes)")
        reset_info = {
            key: value
            for key, value in info.items()
            if key not in ("final_obs", "_final_obs", "final_info", "_final_info")
        }
        self._next = (observations, reset_info)
        return info["final_obs"], reward, terminated, truncated, info["final_info"]
