"""Benchmarks and precision comparisons for box_toss_env (not installed with the package)."""
