"""Agents for BoxToss: PPO, SAC and TD3 on Stable-Baselines3, headless evaluation, baselines, the ceiling.

Run from the repository root (this folder is not installed with the package):

    python -m agents.main                       # short PPO run on BoxToss-ThisSideUp-v0, then the success table
    python -m agents.train --algo sac --env BoxToss-ShortEnd-v0   # agents/hyperparams/sac.yml (RL Zoo format)
    python -m agents.evaluate runs/NAME         # evaluate a run on the fixed target set
    python -m agents.baselines oracle           # random actions or the simulator-planning oracle, as a run
    python -m agents.benchmark                  # every variant x algorithm x seed against the ceiling

Modules import one way (``tests/agents/test_layers.py``): algorithms, config, envs -> policies, oracle ->
evaluation -> training, ceiling -> report -> the commands (train, evaluate, baselines, benchmark, main).
Needs the ``train`` extra (``pip install -e ".[train]"``).
"""
