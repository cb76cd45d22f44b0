"""Box corners and the face numbering."""

import numpy as np

from box_toss_env.rendering import FACE_NORMALS_BODY, box_vertices


def test_box_vertices_at_angle_zero():
    corners = box_vertices(np.array([[1.0, 2.0]]), np.array([0.0]), np.array([[0.5, 0.25]]))
    np.testing.assert_allclose(corners[0], [[0.5, 1.75], [1.5, 1.75], [1.5, 2.25], [0.5, 2.25]])


def test_face_k_runs_from_corner_k_to_k_plus_1_along_its_rotated_normal():
    rng = np.random.default_rng(1)
    position = rng.normal(size=(5, 2))
    angle = rng.uniform(-np.pi, np.pi, size=5)
    half_extents = rng.uniform(0.1, 1.0, size=(5, 2))
    corners = box_vertices(position, angle, half_extents)
    for box in range(5):
        cos, sin = np.cos(angle[box]), np.sin(angle[box])
        rotation = np.array([[cos, -sin], [sin, cos]])
        for face in range(4):
            midpoint = 0.5 * (corners[box, face] + corners[box, (face + 1) % 4])
            distance = half_extents[box, 1 if face % 2 == 0 else 0]  # hy for faces 0 and 2, hx for 1 and 3
            expected = position[box] + rotation @ FACE_NORMALS_BODY[face] * distance
            np.testing.assert_allclose(midpoint, expected, atol=1e-12)
