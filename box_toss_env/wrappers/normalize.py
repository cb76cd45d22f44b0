"""Observation normalisation for vector envs that reset in the same step, such as the native batched
``BoxToss-v0`` (``gymnasium.make_vec("BoxToss-v0", num_envs=N)``).

Gymnasium 1.4's ``gymnasium.wrappers.vector.NormalizeObservation`` accepts only
``AutoresetMode.NEXT_STEP`` (it raises ``Expected env.metadata['autoreset_mode'] to be
AutoresetMode.NEXT_STEP, got AutoresetMode.SAME_STEP``), and ``TransformObservation`` accepts only
``NEXT_STEP``/``DISABLED``. This wrapper is its counterpart for every autoreset mode:

    envs = NormalizeObservation(gymnasium.make_vec("BoxToss-v0", num_envs=64))
    envs.update_running_mean = False   # freeze the statistics, e.g. to evaluate
    pickle.dump(envs.obs_rms, file)    # save them; load with envs.obs_rms = pickle.load(file)

Statistics: Gymnasium's own ``RunningMeanStd`` (parallel mean/variance update). Each ``reset`` and
``step`` updates it with the observations the policy acts on (``obs``), then normalises
``(obs - mean) / sqrt(var + epsilon)``. With ``SAME_STEP`` the observation an episode ended in is
``info["final_obs"]``; it is normalised with the same statistics (those just updated), but does not
update them: it is never acted on, and counting it too would weigh end states like start states.
The inner env's ``info`` is not modified: the wrapper returns a new ``final_obs`` array.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.spaces import Box
from gymnasium.vector import VectorEnv, VectorWrapper
from gymnasium.vector.utils import batch_space
from gymnasium.wrappers.utils import RunningMeanStd


class NormalizeObservation(VectorWrapper):
    """Normalise a vector env's ``Box`` observations to zero mean and unit variance per coordinate,
    ``info["final_obs"]`` included (any autoreset mode).

    Args:
        env: a vector env with a ``Box`` single observation space.
        epsilon: added to the variance under the square root (> 0), so constant coordinates give 0.
        clip: if given, normalised observations are clipped to [-clip, clip] (as SB3's
            ``VecNormalize`` does with ``clip_obs=10``).

    Attributes:
        obs_rms: the running statistics (``mean``, ``var``, ``count``); picklable.
        update_running_mean: False freezes ``obs_rms`` (evaluation).
    """

    def __init__(self, env: VectorEnv, epsilon: float = 1e-8, clip: float | None = None):
        super().__init__(env)
        if not isinstance(env.single_observation_space, Box):
            raise TypeError(f"NormalizeObservation needs a Box observation space, got {env.single_observation_space}")
        if not epsilon > 0:
            raise ValueError(f"epsilon must be > 0, got {epsilon}")
        if clip is not None and not clip > 0:
            raise ValueError(f"clip must be None or > 0, got {clip}")
        shape = env.single_observation_space.shape
        self.single_observation_space = Box(-np.inf, np.inf, shape=shape, dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.obs_rms = RunningMeanStd(shape=shape)  # float64 statistics
        self.epsilon = float(epsilon)
        self.clip = None if clip is None else float(clip)
        self.update_running_mean = True

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        obs, info = self.env.reset(seed=seed, options=options)  # type: ignore[arg-type]  # a list of seeds too
        return self._observe(obs), info

    def step(self, actions):
        obs, reward, terminated, truncated, info = self.env.step(actions)
        obs = self._observe(obs)
        if "final_obs" in info:
            info = {**info, "final_obs": self._normalize_final(info["final_obs"], info.get("_final_obs"))}
        return obs, reward, terminated, truncated, info

    def normalize(self, obs: np.ndarray) -> np.ndarray:
        """``obs`` (a batch or one observation) normalised with the current statistics, which it does
        not update."""
        out = (np.asarray(obs, dtype=np.float64) - self.obs_rms.mean) / np.sqrt(self.obs_rms.var + self.epsilon)
        if self.clip is not None:
            out = np.clip(out, -self.clip, self.clip)
        return out.astype(np.float32)

    def _observe(self, obs: np.ndarray) -> np.ndarray:
        if self.update_running_mean:
            self.obs_rms.update(np.asarray(obs, dtype=np.float64))
        return self.normalize(obs)

    def _normalize_final(self, final_obs, mask) -> np.ndarray:
        """A numeric array (the native env: one row per env) is normalised whole (rows of envs that
        did not end are normalised too, harmlessly); an object array (Gymnasium's ``SyncVectorEnv``:
        ``None`` where no episode ended) entry by entry where ``mask`` is set."""
        if isinstance(final_obs, np.ndarray) and final_obs.dtype != object:
            return self.normalize(final_obs)
        out = np.array(final_obs, dtype=object, copy=True)
        ended = np.ones(len(out), dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        for i in np.flatnonzero(ended):
            out[i] = self.normalize(out[i])
        return out
