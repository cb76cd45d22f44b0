"""The native batched ``BoxToss-Stack-v0``: ``num_envs`` stacking episodes stepped together.

    envs = gymnasium.make_vec("BoxToss-Stack-v0", num_envs=64)                   # this class
    envs = gymnasium.make_vec("BoxToss-Stack-v0", num_envs=64, vectorization_mode="sync")  # single envs

The multi-throw core (``multi_throw.MultiThrowFunctional``) over ``num_envs`` episodes, the single env's core
(``multi_throw_env.MultiThrowVectorEnv`` says how envs are seeded and reset). Each env's scene holds the boxes it
has thrown so far, so the envs of a batch hold scenes of different sizes; a step runs one compiled call per scene
size present (each env's bodies a group of ``physics.grouped``: the single env's colliding kernel on each group
in turn, whole groups per thread), and every env's result is bit for bit the single env's (tested).
"""

from __future__ import annotations

from box_toss_env.envs.multi_throw_env import MultiThrowVectorEnv
from box_toss_env.envs.stack import BoxTossStackEnv


class BoxTossStackVectorEnv(MultiThrowVectorEnv):
    """``num_envs`` BoxToss-Stack envs stepped together; keyword arguments are ``BoxTossStackEnv``'s (and
    ``num_envs``, ``threads``: ``MultiThrowVectorEnv``'s)."""

    env_class = BoxTossStackEnv
