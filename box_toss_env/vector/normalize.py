"""The former path of ``box_toss_env.wrappers.normalize``: importing it gives that very module."""

import sys

from box_toss_env.wrappers import normalize

sys.modules[__name__] = normalize
