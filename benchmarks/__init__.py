"""Benchmarks and precision comparisons for box_toss_env (not installed with the package): scripts that
print measured figures (``python -m benchmarks.<name>``).

Timed runs measure the compiled engine: an env's first throws on a cold cache would otherwise run the
kernel's interpreted copy while it compiles (``box_toss_env.physics.compile.background_compile``);
``benchmarks.cold_start`` measures exactly that, with it switched back on in its probes.
"""

import os

os.environ.setdefault("BOX_TOSS_ENV_START_INTERPRETED", "0")
