"""The test suite runs the compiled engine: an env's first throws on a cold cache would otherwise run
the kernel's interpreted copy while a worker compiles it (``box_toss_env.physics.compile.background_compile``),
which ``tests/physics/test_background_compile.py`` turns on where it tests exactly that."""

import os

os.environ.setdefault("BOX_TOSS_ENV_START_INTERPRETED", "0")
