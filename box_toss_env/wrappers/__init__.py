"""Wrappers and adapters around BoxToss's vector envs: the adapter to Stable-Baselines3's VecEnv
(``sb3_adapter``), next-step autoreset for RLlib (``next_step``), observation normalisation for same-step vector
envs (``normalize``), ballistic throw commands for vector envs (``ballistic``), and Gymnasium's ``RecordVideo``
keeping every frame of a throw (``record_video.RecordThrowVideo``). The native vector env itself is
``box_toss_env.envs.box_toss_vector``.
"""

from box_toss_env.wrappers.record_video import RecordThrowVideo

__all__ = ["RecordThrowVideo"]
