"""Batched BoxToss: the native vector env, the adapter to Stable-Baselines3's VecEnv, observation normalisation
for same-step vector envs, and ballistic throw commands for vector envs."""
