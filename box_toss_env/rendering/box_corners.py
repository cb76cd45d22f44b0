"""Box corners and the face numbering shared by the renderer and its tests.

Faces are numbered by their outward normal in the body frame::

    face 0: local -y  (the bottom at angle 0)
    face 1: local +x
    face 2: local +y  (the top at angle 0)
    face 3: local -x

Corners are listed counter-clockwise so that face k is the edge from corner k to corner k+1 (mod 4).
"""

from __future__ import annotations

import numpy as np

FACE_NORMALS_BODY = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
"""(4, 2) outward unit normal of each face in the body frame."""

CORNER_SIGNS_BODY = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
"""(4, 2) corner k of a box is ``CORNER_SIGNS_BODY[k] * half_extents`` in the body frame."""


def box_vertices(position: np.ndarray, angle: np.ndarray, half_extents: np.ndarray) -> np.ndarray:
    """World corners of boxes: ``R(angle) @ (±hx, ±hy) + position``.

    Args:
        position: (n, 2) box centres [m].
        angle: (n,) rotation, counter-clockwise [rad].
        half_extents: (n, 2) half length along local x and half width along local y [m].

    Returns:
        (n, 4, 2) corners [m], counter-clockwise, face k running from corner k to corner k+1.
    """
    position = np.asarray(position, dtype=np.float64)
    angle = np.asarray(angle, dtype=np.float64)
    corners_body = CORNER_SIGNS_BODY[None, :, :] * np.asarray(half_extents, dtype=np.float64)[:, None, :]
    cos, sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
    x_body, y_body = corners_body[..., 0], corners_body[..., 1]
    corners = np.empty_like(corners_body)
    corners[..., 0] = cos * x_body - sin * y_body + position[:, None, 0]
    corners[..., 1] = sin * x_body + cos * y_body + position[:, None, 1]
    return corners
