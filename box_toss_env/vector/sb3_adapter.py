"""The former path of ``box_toss_env.wrappers.sb3_adapter``: importing it gives that very module."""

import sys

from box_toss_env.wrappers import sb3_adapter

sys.modules[__name__] = sb3_adapter
