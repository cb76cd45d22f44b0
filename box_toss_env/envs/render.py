"""Drawing BoxToss episodes with ``box_toss_env.rendering`` (pygame-ce, imported on the first draw).

``ThrowRenderer`` turns engine states into frames, a window, or the frames of a whole throw;
``record_throws`` writes GIFs or videos of whole throws (opt-in: only an env made with
``render_mode="rgb_array_list"`` records its trajectories, so training pays nothing for it).

Framing. The *home view* holds the release points and the targets (from the task's ranges), the floor and
some sky; frames of throws that stay in it line up across episodes. A throw that leaves it is shown
zoomed out just enough: recorded throws with one camera fitted to the whole trajectory (``plan_throw``),
a throw played in the window with a camera that follows the box and eases in and out
(``follow=True``, see ``rendering.follow_bounds``). Either way every corner of the box is inside every
frame, the target stays in view, and bands are kept free for the caption (top) and the floor's metre
labels (bottom). The last frames of a throw, held for ``result_hold_s``, say how it ended.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from box_toss_env.envs import task, task_config
from box_toss_env.physics import layout

VIEW_MARGIN_M = 0.6
"""Free space behind the release points and in front of the targets in the home view [m]."""
VIEW_OVERSHOOT_M = 1.0
"""Extra space beyond the farthest target, where long throws come to rest [m]."""
VIEW_HEADROOM_M = 1.0
"""Space above the highest release point [m]."""
BOX_MARGIN_M = 0.25
"""Free space around the box's corners when a view is widened to hold it [m]."""
TEXT_BAND_PX = 40
"""Band at the top kept free of the world's boxes, for the two caption lines [px] (at most a fifth of
the image)."""
GROUND_BAND_PX = 30
"""Band below the floor line kept in every view, for the metre labels [px] (at most a sixth)."""
SIDE_PADDING_PX = 8
"""Bands left and right kept free, so the box never touches the image's edge [px] (at most 1/20)."""
FLOOR_DIP_M = 0.01
"""A box this far below the floor still counts as inside the home view (resting boxes penetrate it by
millimetres, drawn in the ground band) [m]."""
FOLLOW_WINDOW_S = 0.5
"""A following camera looks this far ahead and behind, and eases its zoom over as long [s]."""
RESULT_HOLD_S = 1.0
"""The final pose with the result is held this long at the end of a throw's frames [s]."""


def frame_rows(n_rows: int, dt: float, fps: float) -> np.ndarray:
    """Rows of a trajectory on the grid t = k dt to show at ``fps``: one per 1 / fps seconds from
    t = 0, the last row always included (the pose the throw ended in)."""
    duration = (n_rows - 1) * dt
    times = np.arange(int(np.floor(duration * fps + 1e-9)) + 1) / fps
    rows = np.minimum(np.rint(times / dt).astype(np.int64), n_rows - 1)
    if rows[-1] != n_rows - 1:
        rows = np.append(rows, n_rows - 1)
    return rows


@dataclass(frozen=True)
class ThrowOutcome:
    """How a throw ended, as the last frames of the throw write it."""

    success: bool
    distance: float
    """|x - target_x| where the box ended [m]."""
    face_down: int
    on_target_face: bool
    reward: float
    at_rest: bool

    @classmethod
    def from_step(cls, reward: float, info: dict, target_faces: np.ndarray) -> ThrowOutcome:
        """From what ``BoxTossEnv.step`` returned and the episode's (4,) target-face mask."""
        face = int(info["face_down"])
        return cls(
            success=bool(info["success"]),
            distance=float(info["distance"]),
            face_down=face,
            on_target_face=bool(target_faces[face] > 0.0),
            reward=float(reward),
            at_rest=bool(info["at_rest"]),
        )

    def lines(self) -> tuple[str, ...]:
        """The headline (success yes / no), then distance, face down and reward."""
        from box_toss_env.rendering import FACE_COLOUR_NAMES

        face = f"face down: {self.face_down} ({FACE_COLOUR_NAMES[self.face_down]})"
        return (
            f"success: {'yes' if self.success else 'no'}",
            f"distance to target: {self.distance:.2f} m",
            face + ("" if self.on_target_face else ", not a target face"),
            f"reward: {self.reward:+.2f}",
            *(() if self.at_rest else ("still moving at max_sim_time",)),
        )


@dataclass(frozen=True)
class PlannedFrame:
    """One frame of a throw before it is drawn: which state, seen by which camera, with which caption."""

    row: int
    """The trajectory row drawn."""
    camera: object  # rendering.Camera (imported lazily with the rest of rendering)
    caption: str
    shows_result: bool


class ThrowRenderer:
    """Frames of one BoxToss env: floor with metre labels, target flag, the box with its coloured faces,
    a caption, the result of a throw, and optionally the path the box took (``trace``).

    ``home_camera`` shows the home view (see the module docstring); the box in the hand and frames whose
    box lies in the home view use it. pygame is imported on the first draw; a missing ``render`` extra
    raises ``gymnasium.error.DependencyNotInstalled`` naming it.
    """

    def __init__(
        self,
        config: task_config.TaskConfig,
        width_px: int,
        height_px: int,
        fps: float,
        *,
        trace: bool = False,
        result_hold_s: float = RESULT_HOLD_S,
    ):
        from box_toss_env.rendering import SceneRenderer

        self.width_px, self.height_px = int(width_px), int(height_px)
        side = min(SIDE_PADDING_PX, self.width_px / 20)
        self.padding_px = (side, side, min(TEXT_BAND_PX, self.height_px / 5), min(GROUND_BAND_PX, self.height_px / 6))
        x_min = min(config.release_x_range[0], config.target_x_range[0]) - VIEW_MARGIN_M
        x_max = max(config.release_x_range[1], config.target_x_range[1]) + VIEW_MARGIN_M + VIEW_OVERSHOOT_M
        self.home_bounds = np.array([x_min, x_max, 0.0, config.release_height_range[1] + VIEW_HEADROOM_M])
        """(x_min, x_max, y_min, y_max) of the home view [m]."""
        self.home_camera = self.camera_for(self.home_bounds)
        self.renderer = SceneRenderer(width_px, height_px, camera=self.home_camera)
        self.half_extents = np.array([config.half_length, config.half_width])
        self.other_boxes: np.ndarray | None = None
        """(m, 2) half extents of the boxes drawn besides the thrown one (a base box, set per episode by the env),
        whose states follow the thrown box's in the states given: (1 + m, 6), trajectories (T, 1 + m, 6)."""
        self.tolerance = config.position_tolerance
        self.fps = fps
        self.trace = trace
        self.result_hold_s = float(result_hold_s)

    # -- framing ------------------------------------------------------------------------------------
    def camera_for(self, bounds: np.ndarray):
        """The camera showing ``bounds`` (x_min, x_max, y_min, y_max) [m] within the padded image, its
        bottom on the ground band: room to spare goes to the sky, not underground."""
        from box_toss_env.rendering import Camera

        x_min, x_max, y_min, y_max = (float(b) for b in bounds)
        camera = Camera.from_view(x_min, x_max, y_min, y_max, self.width_px, self.height_px, padding_px=self.padding_px)
        _, _, top, bottom = self.padding_px
        y_max = max(y_max, y_min + (self.height_px - top - bottom) / camera.pixels_per_metre)
        return Camera.from_view(x_min, x_max, y_min, y_max, self.width_px, self.height_px, padding_px=self.padding_px)

    def box_bounds(self, states: np.ndarray) -> np.ndarray:
        """(n, 4) bounds of the box in engine states (n, 6), widened by ``BOX_MARGIN_M`` except below (the
        ground band lies there already, and a box on the floor would otherwise always widen the view) [m]."""
        from box_toss_env.rendering import bounds_of_boxes, box_vertices

        states = np.asarray(states, dtype=np.float64).reshape(-1, layout.STATE_SIZE)
        corners = box_vertices(
            states[:, layout.X : layout.Y + 1],
            states[:, layout.ANGLE],
            np.broadcast_to(self.half_extents, (len(states), 2)),
        )
        return bounds_of_boxes(corners) + np.array([-BOX_MARGIN_M, BOX_MARGIN_M, 0.0, BOX_MARGIN_M])

    def fitted_camera(self, states: np.ndarray):
        """The home view, widened to hold the box in every one of the engine states (n, 6)."""
        from box_toss_env.rendering import union_bounds

        bounds = self.box_bounds(states)
        return self.camera_for(union_bounds(self.home_bounds, bounds.min(axis=0), bounds.max(axis=0)))

    def plan_throw(
        self, trajectory: np.ndarray, dt: float, *, follow: bool = False, skip_first: bool = False
    ) -> list[PlannedFrame]:
        """The frames of a recorded throw (T, 6) on the grid t = k dt, at ``self.fps``, then the final pose
        held ``result_hold_s``; the last frame of the throw and the held ones show the result.

        One camera fitted to the whole trajectory, or with ``follow`` one per frame following the box
        (``rendering.follow_bounds`` over ``FOLLOW_WINDOW_S``). ``skip_first`` leaves out t = 0 (the pose
        in the hand, when it was drawn already).
        """
        from box_toss_env.rendering import follow_bounds, union_bounds

        trajectory = thrown_trajectory(trajectory)
        rows = frame_rows(trajectory.shape[0], dt, self.fps)
        if follow:
            held = union_bounds(self.box_bounds(trajectory[rows]), self.home_bounds)
            cameras = [self.camera_for(b) for b in follow_bounds(held, round(FOLLOW_WINDOW_S * self.fps))]
        else:
            cameras = [self.fitted_camera(trajectory)] * len(rows)
        planned = [
            PlannedFrame(int(row), camera, f"t = {row * dt:.2f} s", index == len(rows) - 1)
            for index, (row, camera) in enumerate(zip(rows, cameras, strict=True))
        ]
        planned += [planned[-1]] * int(round(self.result_hold_s * self.fps))
        return planned[1:] if skip_first else planned

    # -- drawing --------------------------------------------------------------------------------------
    def _scene(
        self,
        state: np.ndarray,
        target_x: float,
        target_faces: np.ndarray,
        caption: str,
        camera,
        outcome: ThrowOutcome | None = None,
        trace: np.ndarray | None = None,
    ) -> dict:
        faces = np.flatnonzero(target_faces > 0.0)
        states = np.asarray(state, dtype=np.float64).reshape(-1, layout.STATE_SIZE)  # the thrown box first
        half_extents = self.half_extents
        if len(states) != 1:
            assert self.other_boxes is not None  # set with the other boxes' states
            half_extents = np.vstack((self.half_extents, self.other_boxes))
        return dict(
            position=states[:, layout.X : layout.Y + 1],
            angle=states[:, layout.ANGLE],
            half_extents=half_extents,
            target_x=target_x,
            target_face=int(faces[0]) if faces.size == 1 else None,
            target_tolerance_m=self.tolerance,
            target_label=f"{task.describe_target_faces(target_faces)} down",
            text_lines=(f"target: {task.describe_target_faces(target_faces)} down at x = {target_x:.2f} m", caption),
            result_lines=outcome.lines() if outcome is not None else (),
            result_success=outcome.success if outcome is not None else None,
            trace=trace,
            camera=camera,
        )

    def _planned_scene(
        self,
        trajectory: np.ndarray,
        planned: PlannedFrame,
        target_x: float,
        target_faces: np.ndarray,
        outcome: ThrowOutcome | None,
    ) -> dict:
        shows_result = planned.shows_result and outcome is not None
        caption = planned.caption + (", at rest" if shows_result and outcome is not None and outcome.at_rest else "")
        trace = thrown_trajectory(trajectory)[: planned.row + 1, layout.X : layout.Y + 1] if self.trace else None
        return self._scene(
            trajectory[planned.row],
            target_x,
            target_faces,
            caption,
            planned.camera,
            outcome if shows_result else None,
            trace,
        )

    def camera_for_state(self, state: np.ndarray):
        """The home camera, or if the box of the engine state (6,) is not inside the home view, the home
        view widened to hold it (of states (1 + m, 6), the thrown box's: the first)."""
        bounds = self.box_bounds(state)[0]
        home = self.home_bounds
        # a box resting on the floor dips into it by up to a few millimetres: the ground band holds that
        inside = (
            bounds[0] >= home[0]
            and bounds[1] <= home[1]
            and bounds[2] >= home[2] - FLOOR_DIP_M
            and bounds[3] <= home[3]
        )
        return self.home_camera if inside else self.fitted_camera(state)

    def frame(
        self,
        state: np.ndarray,
        target_x: float,
        target_faces: np.ndarray,
        caption: str = "",
        outcome: ThrowOutcome | None = None,
    ) -> np.ndarray:
        """An (H, W, 3) uint8 frame of one engine state (6,), with the result if ``outcome`` is given."""
        return self.renderer.render_rgb(
            **self._scene(state, target_x, target_faces, caption, self.camera_for_state(state), outcome)
        )

    def throw_frames(
        self,
        trajectory: np.ndarray,
        dt: float,
        target_x: float,
        target_faces: np.ndarray,
        outcome: ThrowOutcome | None = None,
        skip_first: bool = False,
    ) -> list[np.ndarray]:
        """Frames of a recorded throw (T, 6) on the grid t = k dt, at ``self.fps``, as ``plan_throw`` lays
        them out (one camera fitted to the whole throw); the last ones show ``outcome`` if given."""
        return [
            self.renderer.render_rgb(**self._planned_scene(trajectory, planned, target_x, target_faces, outcome))
            for planned in self.plan_throw(trajectory, dt, skip_first=skip_first)
        ]

    def play(
        self,
        trajectory: np.ndarray,
        dt: float,
        target_x: float,
        target_faces: np.ndarray,
        outcome: ThrowOutcome | None = None,
    ) -> None:
        """Show a recorded throw (T, 6) in the window in real time (at ``self.fps``), the camera following
        the box, then hold the result."""
        for planned in self.plan_throw(trajectory, dt, follow=True):
            scene = self._planned_scene(trajectory, planned, target_x, target_faces, outcome)
            if not self.renderer.show(**scene, fps=self.fps):
                self.close()  # the user closed the window
                return

    def show(self, state: np.ndarray, target_x: float, target_faces: np.ndarray, caption: str = "") -> None:
        """Show one engine state (6,) in the window."""
        scene = self._scene(state, target_x, target_faces, caption, self.camera_for_state(state))
        if not self.renderer.show(**scene, fps=self.fps):
            self.close()

    def close(self) -> None:
        self.renderer.close()


def thrown_trajectory(trajectory: np.ndarray) -> np.ndarray:
    """(T, 6) states of the thrown box in a trajectory (T, 6) or (T, bodies, 6) (the thrown box first)."""
    trajectory = np.asarray(trajectory)
    return trajectory[:, 0] if trajectory.ndim == 3 else trajectory.reshape(-1, layout.STATE_SIZE)


def record_throws(
    env,
    path: str | Path,
    n_throws: int = 1,
    policy: Callable[[np.ndarray], np.ndarray] | None = None,
    seed: int | None = None,
    fps: float | None = None,
    trace: bool = True,
) -> Path:
    """Play ``n_throws`` episodes of ``env`` and write every frame of the throws to ``path``.

    Each throw is framed by a camera fitted to it, ends on its result held for a second, and with
    ``trace`` shows the path the box's centre has taken so far.

    ``env`` must have been made with ``render_mode="rgb_array_list"`` (its trajectories are recorded
    only then). ``policy`` maps an observation to an action (default: random actions from the
    action space, seeded by ``seed``). The file type follows the suffix: ``.gif`` needs Pillow,
    others (``.mp4``) imageio-ffmpeg (see ``box_toss_env.rendering.write_video``). ``fps``
    defaults to the env's ``metadata["render_fps"]``, the rate its frames are drawn at.
    """
    from box_toss_env.rendering import write_video

    if env.render_mode != "rgb_array_list":
        raise ValueError(
            f'record_throws needs an env made with render_mode="rgb_array_list", got render_mode={env.render_mode!r}'
        )
    if policy is None:
        env.action_space.seed(seed)
        policy = lambda observation: env.action_space.sample()  # noqa: E731
    renderer = getattr(env.unwrapped, "throw_env", env.unwrapped)._renderer_for_env()  # a goal env's throws
    frames: list[np.ndarray] = []
    trace_before, renderer.trace = renderer.trace, trace
    try:
        for throw in range(n_throws):
            observation, _ = env.reset(seed=seed if throw == 0 else None)
            env.step(policy(observation))
            frames += env.render()  # the pose in the hand, then the throw, then its result
    finally:
        renderer.trace = trace_before
    return write_video(frames, path, fps if fps is not None else env.metadata["render_fps"])
