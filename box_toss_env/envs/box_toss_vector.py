"""The ``vector_entry_point`` of ``BoxToss-v0``: for now N ``BoxTossEnv`` stepped in turn.

A native batched env (all N throws in one engine call, reusing ``task``'s batch-first functions)
replaces this class in a later version without changing how it is made::

    envs = gymnasium.make_vec("BoxToss-v0", num_envs=8)  # vectorization_mode="vector_entry_point"

Episodes are one step long, so sub-envs reset in the same step as they end
(``AutoresetMode.SAME_STEP``: the returned observation is the next episode's first one, and the
final observation and info are in ``info["final_obs"]`` and ``info["final_info"]``); with
Gymnasium's default ``NEXT_STEP`` every other step of a vector env would be an empty reset step.
"""

from __future__ import annotations

import functools

from gymnasium.vector import AutoresetMode, SyncVectorEnv

from box_toss_env.envs.box_toss import BoxTossEnv


class BoxTossVectorEnv(SyncVectorEnv):
    """``num_envs`` copies of ``BoxTossEnv(**kwargs)`` in one process, resetting on the step they end."""

    def __init__(self, num_envs: int = 1, **kwargs):
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        super().__init__([functools.partial(BoxTossEnv, **kwargs) for _ in range(num_envs)],
                         autoreset_mode=AutoresetMode.SAME_STEP)
