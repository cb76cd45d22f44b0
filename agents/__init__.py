"""Agents for BoxToss: PPO, SAC and TD3 on Stable-Baselines3, headless evaluation, baselines, the ceiling.

Installed with the package (``box-toss train``, ``evaluate`` and ``main`` run these from any folder):

    python -m agents.main                       # short PPO run on BoxToss-ThisSideUp-v0, then the success table
    python -m agents.train --algo sac --env BoxToss-ShortEnd-v0   # agents/hyperparams/sac.yml (RL Zoo format)
    python -m agents.evaluate runs/NAME         # evaluate a run on the fixed target set
    python -m agents.baselines oracle           # random actions or the simulator-planning oracle, as a run
    python -m agents.benchmark                  # every variant x algorithm x seed against the ceiling
    python -m agents.tune --env BoxToss-ShortEnd-v0   # Optuna (TPE) on Ray Tune, ASHA pruning (tune extra)
    python -m agents.rllib_ppo                  # RLlib's PPO on the native batched env (rllib extra)

Modules import one way (``tests/agents/test_layers.py``): algorithms, command_line, targets -> schema, run_folder,
envs -> config -> run_files -> checkpoints, policies, oracle, search_space -> evaluation -> training, ceiling ->
report, tuning, sweep_report -> the commands (train, evaluate, baselines, tune, rllib_ppo, benchmark, main), which
import the rest after parsing their options (``--help`` loads no torch).
Needs the ``train`` extra (``pip install -e ".[train]"``).
"""
