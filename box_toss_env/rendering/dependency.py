"""Lazy import of pygame, the optional dependency behind the ``render`` extra."""

from __future__ import annotations

import os
from types import ModuleType

from gymnasium.error import DependencyNotInstalled

RENDER_INSTALL_HINT = 'pip install "box_toss_env[render]"'


def import_pygame() -> ModuleType:
    """Return the pygame module, or raise ``DependencyNotInstalled`` naming the ``render`` extra.

    Called inside every function that draws, so that importing ``box_toss_env`` never imports pygame.
    """
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")  # no banner on stdout
    try:
        import pygame
    except ImportError as error:
        raise DependencyNotInstalled(
            f"Rendering needs pygame-ce, which is not installed. Install it with: {RENDER_INSTALL_HINT}"
        ) from error
    return pygame
