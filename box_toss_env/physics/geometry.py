"""Box geometry in the plane: where the corners are, and which face is down."""

import math

from .compile.compilation import jit_stage
from .layout import SIGN_X, SIGN_Y


@jit_stage
def vertex_offset(k, cos_a, sin_a, half_length, half_width):
    """World-frame vector r_k = R(alpha) b_k from the centre of mass to corner k.

    b_k = (SIGN_X[k] hx, SIGN_Y[k] hy) and R = [[cos, -sin], [sin, cos]], so the corner's
    world position is b_global = R b_local + x (reference, section 1).
    """
    bx = SIGN_X[k] * half_length
    by = SIGN_Y[k] * half_width
    return cos_a * bx - sin_a * by, sin_a * bx + cos_a * by


@jit_stage
def lowest_pair(height0, height1, height2, height3):
    """Corners (k, j) of the lowest face for corner heights given in corner order: k the lowest,
    j its lower neighbour. The two lowest corners of a rectangle are adjacent, so they bound the
    face that is down; at most these two touch the floor y = 0."""
    heights = (height0, height1, height2, height3)
    lowest = 0
    for k in range(1, 4):
        if heights[k] < heights[lowest]:
            lowest = k
    before = (lowest + 3) % 4
    after = (lowest + 1) % 4
    return lowest, (before if heights[before] < heights[after] else after)


@jit_stage
def lowest_face(cos_a, sin_a, half_length, half_width):
    """``lowest_pair`` of a box at the angle whose cosine and sine are given."""
    return lowest_pair(
        sin_a * SIGN_X[0] * half_length + cos_a * SIGN_Y[0] * half_width,
        sin_a * SIGN_X[1] * half_length + cos_a * SIGN_Y[1] * half_width,
        sin_a * SIGN_X[2] * half_length + cos_a * SIGN_Y[2] * half_width,
        sin_a * SIGN_X[3] * half_length + cos_a * SIGN_Y[3] * half_width,
    )


def face_down(angle: float) -> int:
    """Index of the face that points down for a box at ``angle``: faces are numbered by their
    outward normal in the body frame, 0 = -y, 1 = +x, 2 = +y, 3 = -x."""
    # the outward normal of face f is R(alpha) applied to the body normal at angle -pi/2 + f pi/2;
    # it points down (world angle -pi/2) when alpha + (f - 1) pi/2 = 0 (mod 2 pi)
    return int(round(-angle / (0.5 * math.pi))) % 4
