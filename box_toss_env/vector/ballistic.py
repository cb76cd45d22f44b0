"""The former path of ``box_toss_env.wrappers.ballistic``: importing it gives that very module."""

import sys

from box_toss_env.wrappers import ballistic

sys.modules[__name__] = ballistic
