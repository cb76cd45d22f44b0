"""The columns of the BoxToss task's arrays: the target kinds (which faces may end down), what one episode
draws (``Episodes.data``), the observation and the action, and the observation bounds' energy margin.

Faces are numbered by their outward normal in the body frame: 0 = local -y, 1 = +x, 2 = +y, 3 = -x."""

from __future__ import annotations

import math

import numpy as np

# -- target kinds: which faces may end down ------------------------------------------------------
TARGET_FACE_KINDS = ("any", "long_side", "short_end", "exact", "mixed")
"""Values of ``target_face``. "exact" draws one face per episode ("this side up"); "mixed" draws one
of "any", "long_side", "short_end", "exact" per episode, uniformly."""
FACE_SETS = {
    "any": (1.0, 1.0, 1.0, 1.0),
    "long_side": (1.0, 0.0, 1.0, 0.0),
    "short_end": (0.0, 1.0, 0.0, 1.0),
}
FACE_SET_NAMES = ("any", "long_side", "short_end")
_FACE_SET_TABLE = np.array([FACE_SETS[name] for name in FACE_SET_NAMES])
MIXED_KINDS = ("any", "long_side", "short_end", "exact")  # drawn uniformly by target_face="mixed"
QUARTER_TURN = 0.5 * math.pi

# -- what one episode draws: one row of ``Episodes.data`` per episode ----------------------------
(
    EP_RELEASE_X,
    EP_RELEASE_Y,
    EP_RELEASE_ANGLE,
    EP_TARGET_X,
    EP_FACE_0,
    EP_FACE_1,
    EP_FACE_2,
    EP_FACE_3,
    EP_MASS,
    EP_FRICTION,
    EP_RESTITUTION,
) = range(11)
EPISODE_SIZE = 11
# with base_box: the base box's length and height [m] (its centre x is the target x); a task without a
# base draws EPISODE_SIZE variates per episode, as it always did
EP_BASE_LENGTH, EP_BASE_HEIGHT = 11, 12
EPISODE_SIZE_WITH_BASE = 13
EP_RELEASE = slice(EP_RELEASE_X, EP_RELEASE_ANGLE + 1)  # x [m], y [m], angle [rad] in the hand
EP_TARGET_FACES = slice(EP_FACE_0, EP_FACE_3 + 1)  # 1.0 for each face that may end down
EP_DYNAMICS = slice(EP_MASS, EP_RESTITUTION + 1)  # mass [kg], friction [-], restitution [-]
# the uniform variates: one per column; the face columns' variates pick the target kind and face
U_TARGET_KIND, U_TARGET_FACE = EP_FACE_0, EP_FACE_1

# -- observation columns --------------------------------------------------------------------------
OBS_X, OBS_Y, OBS_COS, OBS_SIN, OBS_VX, OBS_VY, OBS_SPIN, OBS_TARGET_X = range(8)
OBS_TARGET_FACES = slice(8, 12)  # 1.0 where that face may end down
OBS_MASS, OBS_FRICTION, OBS_RESTITUTION = 12, 13, 14  # only with observe_dynamics
OBS_SIZE = 12
OBS_SIZE_WITH_DYNAMICS = 15
# with base_box, six columns after all the others: the base box's pose and size
BASE_OBS_SIZE = 6  # base x [m], base y [m], cos and sin of its angle, its length and height [m]
OBS_BASE_X, OBS_BASE_Y, OBS_BASE_COS, OBS_BASE_SIN, OBS_BASE_LENGTH, OBS_BASE_HEIGHT = range(-6, 0)
# with a drawn box size (box_length_range, box_width_range, split), its length and width [m]: in the observation
# after the dynamics (before a base box's columns), and in the episode's row after all the others
BOX_SIZE_OBS = 2
# the observation's target and dynamics columns are the episode's columns from EP_TARGET_X on
assert OBS_SIZE - OBS_TARGET_X == EP_MASS - EP_TARGET_X

# -- action columns -------------------------------------------------------------------------------
ACT_SPEED, ACT_LAUNCH_ANGLE, ACT_SPIN = 0, 1, 2
ACTION_SIZE = 3

ENERGY_MARGIN = 2.0
"""Observation bounds on speeds and distances are this factor above what the energy of the fastest
throw allows (an exact solver never adds energy; the margin covers the seed scheme's small gains)."""
