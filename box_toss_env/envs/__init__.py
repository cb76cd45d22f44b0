"""The BoxToss Gymnasium environments.

- ``box_toss.BoxTossEnv``: ``BoxToss-v0``, one throw per episode;
- ``task``: the task logic as batch-first numpy functions, shared with the batched env;
- ``render``: frames, playback and ``record_throws`` (GIF or video of whole throws).

Importing this package does not import pygame (rendering imports it on the first draw).
"""

from box_toss_env.envs.box_toss import BoxTossEnv
from box_toss_env.envs.box_toss_vector import BoxTossVectorEnv
from box_toss_env.envs.render import record_throws

__all__ = ["BoxTossEnv", "BoxTossVectorEnv", "record_throws"]
