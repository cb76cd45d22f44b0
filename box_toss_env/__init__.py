"""BoxToss: throw a 2D rigid box onto a floor and be rewarded for how it lands.

Importing the package registers ``BoxToss-v0`` with Gymnasium; the physics engine lives in
``box_toss_env.physics``.
"""

__version__ = "0.1.0"
