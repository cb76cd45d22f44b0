"""Rendering for BoxToss: RGB frames, a pygame window, and GIF/MP4 writers.

Importing this package does not import pygame; it is imported on the first draw and, if missing, raises
``gymnasium.error.DependencyNotInstalled`` naming the extra: ``pip install "box_toss_env[render]"``.
"""

from box_toss_env.rendering.box_corners import CORNER_SIGNS_BODY, FACE_NORMALS_BODY, box_vertices
from box_toss_env.rendering.camera import Camera, bounds_of_boxes, follow_bounds, union_bounds
from box_toss_env.rendering.dependency import RENDER_INSTALL_HINT, import_pygame
from box_toss_env.rendering.renderer import FACE_COLOUR_NAMES, Palette, SceneRenderer, as_box_arrays
from box_toss_env.rendering.video import write_gif, write_video

__all__ = [
    "CORNER_SIGNS_BODY",
    "FACE_COLOUR_NAMES",
    "FACE_NORMALS_BODY",
    "RENDER_INSTALL_HINT",
    "Camera",
    "Palette",
    "SceneRenderer",
    "as_box_arrays",
    "bounds_of_boxes",
    "box_vertices",
    "follow_bounds",
    "import_pygame",
    "union_bounds",
    "write_gif",
    "write_video",
]
