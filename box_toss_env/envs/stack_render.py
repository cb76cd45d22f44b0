"""What a frame of ``BoxToss-Stack-v0`` shows: every box thrown and the one in the hand, the target's bracket, a
line at the stack's height over it, the throw count, height and score top-left and, after the last throw or a
fall, the result top-right (``rendering.SceneRenderer.render_rgb``'s arguments)."""

from __future__ import annotations

from typing import Any

import numpy as np

from box_toss_env.envs import stack_task
from box_toss_env.physics import layout


def drawn_scene(env) -> dict[str, Any]:
    """``SceneRenderer.render_rgb``'s keyword arguments for the state of ``env`` (a ``stack.BoxTossStackEnv``)."""
    config, batch, task = env.config, env._batch, env.task
    k, n = env.thrown, config.n_boxes
    states, half = batch.state[0, :k], batch.params[0, :k, layout.HALF_LENGTH : layout.HALF_WIDTH + 1]
    if k < n and not env._needs_reset:  # the box in the hand, at its release pose
        release = task.hands(batch.episodes)[0, k, stack_task.E_RELEASE_X :]
        states = np.vstack((states, [*release, 0.0, 0.0, 0.0]))
        half = np.vstack((half, batch.params[0, k, layout.HALF_LENGTH : layout.HALF_WIDTH + 1]))
    radius, target_x, height = config.target_radius, env.target_x, float(batch.memory[0, 0])
    result: tuple[str, ...] = ()
    success = None
    last = env._last_info
    if env._needs_reset and last is not None:
        success = bool(last["success"])
        result = (
            f"success: {'yes' if success else 'no'}",
            f"stack height: {height:.2f} m",
            "the stack fell" if last["fell"] else f"{last['stack_size']} boxes on it",
        )
    return dict(
        position=states[:, :2],
        angle=states[:, 2],
        half_extents=half,
        target_x=target_x,
        target_tolerance_m=radius,
        target_label="stack here",
        text_lines=(f"throw {k} of {n}, stack height {height:.2f} m", f"score {env._score:+.2f}"),
        result_lines=result,
        result_success=success,
        trace=np.array([[target_x - radius, height], [target_x + radius, height]]) if height > 0 else None,
        camera=camera(config, states, half, env.render_size),
    )


def camera(config: stack_task.StackConfig, states: np.ndarray, half: np.ndarray, size: tuple[int, int]):
    """The home view (hand, targets, the tallest stack the hand can make), widened to hold every box."""
    from box_toss_env.rendering import Camera, bounds_of_boxes, box_vertices

    x_min = min(config.release_x_range[0], config.target_x_range[0]) - 0.6
    x_max = max(config.release_x_range[1], config.target_x_range[1]) + 1.0
    y_max = max(config.release_height_range[1], config.n_boxes * config.box_width_range[1]) + 0.6
    if len(states):
        bounds = bounds_of_boxes(box_vertices(states[:, :2], states[:, 2], half))
        x_min, x_max = min(x_min, bounds[:, 0].min() - 0.2), max(x_max, bounds[:, 1].max() + 0.2)
        y_max = max(y_max, bounds[:, 3].max() + 0.2)
    width, height = size
    return Camera.from_view(
        x_min, x_max, 0.0, y_max, width, height, padding_px=(8, 8, min(40, height / 5), min(30, height / 6))
    )
