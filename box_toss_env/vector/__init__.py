"""Batched BoxToss: the native vector env, and the adapter to Stable-Baselines3's VecEnv."""
