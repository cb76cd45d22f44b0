"""The viewer's camera: the world point at the lanes' centre and the zoom (``View``), fitted to a scene."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from box_toss_env.physics import (
    Scene,
    layout,
)
from box_toss_env.rendering import Camera, box_vertices

ZOOM_STEP = 1.15
"""Zoom factor of one wheel click or key press."""
MIN_PIXELS_PER_METRE, MAX_PIXELS_PER_METRE = 0.5, 20000.0


# -- the view ----------------------------------------------------------------------------------------
@dataclass
class View:
    """What the camera looks at: the world point at the centre of each lane [m] and the scale [px/m]."""

    center_x: float
    center_y: float
    pixels_per_metre: float


def view_points(scene: Scene) -> np.ndarray:
    """Points a first view of ``scene`` should show [m]: every box corner, and for a moving box
    the top of its ballistic arc and where that arc meets the floor."""
    state = scene.initial_state()
    params = scene.body_params()
    corners = box_vertices(state[:, :2], state[:, layout.ANGLE], params[:, :2]).reshape(-1, 2)
    points = [corners]
    g = -scene.gravity
    for x, y, _, vx, vy, _ in state:
        if g > 0 and (vx or vy):
            apex_time = max(vy / g, 0.0)
            landing_time = (vy + math.sqrt(vy * vy + 2.0 * g * max(y, 0.0))) / g
            points.append(
                [[x + vx * apex_time, y + vy * apex_time - 0.5 * g * apex_time**2], [x + vx * landing_time, 0.0]]
            )
    return np.concatenate([np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in points])


def fit_view(scene: Scene, width_px: int, height_px: int) -> View:
    points = view_points(scene)
    span = float(np.ptp(points, axis=0).max())
    camera = Camera.fit_points(points, width_px, height_px, margin_m=0.2 + 0.12 * span, min_span_m=2.0)
    return View(camera.center_x, camera.center_y, camera.pixels_per_metre)
