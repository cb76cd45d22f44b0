"""Wrappers and adapters around BoxToss's vector envs: the adapter to Stable-Baselines3's VecEnv
(``sb3_adapter``), next-step autoreset for RLlib (``next_step``), observation normalisation for same-step vector
envs (``normalize``), and ballistic throw commands for vector envs (``ballistic``). The native vector env itself
is ``box_toss_env.envs.box_toss_vector``.
"""
