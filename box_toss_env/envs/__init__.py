"""The BoxToss Gymnasium environments.

- ``box_toss.BoxTossEnv``: ``BoxToss-v0``, one throw per episode;
- ``functional.BoxTossFunctional``: the throw itself, batch-first (the functional API), which the single env,
  the batched env and the oracle all run;
- ``arguments``: every keyword argument of the env, declared once;
- ``task``: the task logic as batch-first numpy functions, which the throw is made of;
- ``render``: frames, playback and ``record_throws`` (GIF or video of whole throws).

Importing this package does not import pygame (rendering imports it on the first draw).
"""

from box_toss_env.envs.box_toss import BoxTossEnv
from box_toss_env.envs.box_toss_vector import BoxTossVectorEnv
from box_toss_env.envs.functional import BoxTossFunctional, ThrowBatch
from box_toss_env.envs.render import record_throws

__all__ = ["BoxTossEnv", "BoxTossFunctional", "BoxTossVectorEnv", "ThrowBatch", "record_throws"]
