"""Agents for BoxToss: PPO training on Stable-Baselines3, headless evaluation and baselines.

Run from the repository root (this folder is not installed with the package):

    python -m agents.main                       # short PPO training, then the success table
    python -m agents.train --env BoxToss-v0     # train with agents/hyperparams/ppo.yml
    python -m agents.evaluate runs/NAME         # evaluate a run on the fixed target set
    python -m agents.baselines                  # random actions and the simulator-planning oracle
    python -m agents.report --readme            # the README's results table and figures

Needs the ``train`` extra (``pip install -e ".[train]"``).
"""
