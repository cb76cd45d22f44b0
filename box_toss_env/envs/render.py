"""Drawing BoxToss episodes with ``box_toss_env.rendering`` (pygame-ce, imported on the first draw).

``ThrowRenderer`` turns engine states into frames, a window, or the frames of a whole throw;
``record_throws`` writes GIFs or videos of whole throws (opt-in: only an env made with
``render_mode="rgb_array_list"`` records its trajectories, so training pays nothing for it).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from box_toss_env.envs import task
from box_toss_env.physics import layout

VIEW_MARGIN_M = 0.6
"""Free space behind the release points and in front of the targets in the view [m]."""
VIEW_OVERSHOOT_M = 1.0
"""Extra space beyond the farthest target, where long throws come to rest [m]."""
VIEW_HEADROOM_M = 1.0
"""Space above the highest release point [m]."""


def frame_rows(n_rows: int, dt: float, fps: float) -> np.ndarray:
    """Rows of a trajectory on the grid t = k dt to show at ``fps``: one per 1 / fps seconds from
    t = 0, the last row always included (the pose the throw ended in)."""
    duration = (n_rows - 1) * dt
    times = np.arange(int(np.floor(duration * fps + 1e-9)) + 1) / fps
    rows = np.minimum(np.rint(times / dt).astype(np.int64), n_rows - 1)
    if rows[-1] != n_rows - 1:
        rows = np.append(rows, n_rows - 1)
    return rows


class ThrowRenderer:
    """Frames of one BoxToss env: floor, target flag, the box with its coloured faces, a caption.

    The camera is fixed by the task's ranges (release points and targets in view), so frames of
    different episodes line up. pygame is imported on the first draw; a missing ``render`` extra
    raises ``gymnasium.error.DependencyNotInstalled`` naming it.
    """

    def __init__(self, config: task.TaskConfig, width_px: int, height_px: int, fps: float):
        from box_toss_env.rendering import Camera, SceneRenderer

        x_min = min(config.release_x_range[0], config.target_x_range[0]) - VIEW_MARGIN_M
        x_max = max(config.release_x_range[1], config.target_x_range[1]) + VIEW_MARGIN_M + VIEW_OVERSHOOT_M
        y_max = config.release_height_range[1] + VIEW_HEADROOM_M
        camera = Camera.from_view(x_min, x_max, -0.3, y_max, width_px, height_px)
        self.renderer = SceneRenderer(width_px, height_px, camera=camera)
        self.half_extents = np.array([config.half_length, config.half_width])
        self.tolerance = config.position_tolerance
        self.fps = fps

    def _scene(self, state: np.ndarray, target_x: float, target_faces: np.ndarray, caption: str) -> dict:
        faces = np.flatnonzero(target_faces > 0.0)
        return dict(
            position=state[layout.X:layout.Y + 1],
            angle=state[layout.ANGLE],
            half_extents=self.half_extents,
            target_x=target_x,
            target_face=int(faces[0]) if faces.size == 1 else None,
            target_tolerance_m=self.tolerance,
            target_label=f"{task.describe_target_faces(target_faces)} down",
            text_lines=(f"target: {task.describe_target_faces(target_faces)} down at x = {target_x:.2f} m",
                        caption),
        )

    def frame(self, state: np.ndarray, target_x: float, target_faces: np.ndarray, caption: str = "") -> np.ndarray:
        """An (H, W, 3) uint8 frame of one engine state (6,)."""
        return self.renderer.render_rgb(**self._scene(state, target_x, target_faces, caption))

    def throw_frames(self, trajectory: np.ndarray, dt: float, target_x: float, target_faces: np.ndarray,
                     skip_first: bool = False) -> list[np.ndarray]:
        """Frames of a recorded throw (T, 6) on the grid t = k dt, at ``self.fps``."""
        rows = frame_rows(trajectory.shape[0], dt, self.fps)
        if skip_first:
            rows = rows[1:]
        return [self.frame(trajectory[row], target_x, target_faces, f"t = {row * dt:.2f} s") for row in rows]

    def play(self, trajectory: np.ndarray, dt: float, target_x: float, target_faces: np.ndarray) -> None:
        """Show a recorded throw (T, 6) in the window in real time (at ``self.fps``)."""
        for row in frame_rows(trajectory.shape[0], dt, self.fps):
            scene = self._scene(trajectory[row], target_x, target_faces, f"t = {row * dt:.2f} s")
            if not self.renderer.show(**scene, fps=self.fps):
                self.close()  # the user closed the window
                return

    def show(self, state: np.ndarray, target_x: float, target_faces: np.ndarray, caption: str = "") -> None:
        """Show one engine state (6,) in the window."""
        if not self.renderer.show(**self._scene(state, target_x, target_faces, caption), fps=self.fps):
            self.close()

    def close(self) -> None:
        self.renderer.close()


def record_throws(env, path: str | Path, n_throws: int = 1,
                  policy: Callable[[np.ndarray], np.ndarray] | None = None, seed: int | None = None,
                  fps: float | None = None) -> Path:
    """Play ``n_throws`` episodes of ``env`` and write every frame of the throws to ``path``.

    ``env`` must have been made with ``render_mode="rgb_array_list"`` (its trajectories are recorded
    only then). ``policy`` maps an observation to an action (default: random actions from the
    action space, seeded by ``seed``). The file type follows the suffix: ``.gif`` needs Pillow,
    others (``.mp4``) imageio-ffmpeg (see ``box_toss_env.rendering.write_video``). ``fps``
    defaults to the env's ``metadata["render_fps"]``, the rate its frames are drawn at.
    """
    from box_toss_env.rendering import write_video

    if env.render_mode != "rgb_array_list":
        raise ValueError(f'record_throws needs an env made with render_mode="rgb_array_list", '
                         f"got render_mode={env.render_mode!r}")
    if policy is None:
        env.action_space.seed(seed)
        policy = lambda observation: env.action_space.sample()  # noqa: E731
    frames: list[np.ndarray] = []
    for throw in range(n_throws):
        observation, _ = env.reset(seed=seed if throw == 0 else None)
        env.step(policy(observation))
        frames += env.render()  # the pose in the hand, then the throw
    return write_video(frames, path, fps if fps is not None else env.metadata["render_fps"])
