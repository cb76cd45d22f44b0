"""Gymnasium's ``RecordVideo`` for whole throws: every frame of a throw, not one frame per step.

A BoxToss episode is one step. ``gymnasium.wrappers.RecordVideo`` takes one frame after ``reset`` and one
after each ``step``: on an env made with ``render_mode="rgb_array"`` that is the box in the hand and the
landing, and on ``"rgb_array_list"`` it keeps the last of the frames ``render()`` returns, so a video holds
two frames an episode either way (``tests/rendering/test_record_video.py`` checks this against Gymnasium's
own wrapper).

``RecordThrowVideo`` is that wrapper, with its triggers, file names, ``video_length`` and moviepy writer,
keeping every frame an ``"rgb_array_list"`` env draws: the box in the hand, the whole throw at the env's
``render_fps`` and its result held for a second. It needs the ``render`` extra (pygame-ce draws the frames,
moviepy writes the video)::

    env = RecordThrowVideo(gym.make("BoxToss-v0", render_mode="rgb_array_list"), "videos")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()  # videos/rl-video-episode-0.mp4: every frame of the throw
"""

from __future__ import annotations

from collections.abc import Callable

import gymnasium as gym
from gymnasium.wrappers import RecordVideo


class RecordThrowVideo(RecordVideo):
    """``gymnasium.wrappers.RecordVideo`` keeping every frame of each throw (module docstring).

    The arguments are ``RecordVideo``'s; ``env`` must have been made with ``render_mode="rgb_array_list"``
    (only then are the throws' trajectories recorded), else a ``ValueError`` says so.
    """

    def __init__(
        self,
        env: gym.Env,
        video_folder: str,
        episode_trigger: Callable[[int], bool] | None = None,
        step_trigger: Callable[[int], bool] | None = None,
        video_length: int = 0,
        name_prefix: str = "rl-video",
        fps: int | None = None,
        disable_logger: bool = True,
    ):
        if env.render_mode != "rgb_array_list":
            raise ValueError(
                'RecordThrowVideo needs an env made with render_mode="rgb_array_list" (every frame of a throw), '
                f"got render_mode={env.render_mode!r}; for one frame per step use gymnasium.wrappers.RecordVideo"
            )
        super().__init__(
            env,
            video_folder,
            episode_trigger=episode_trigger,
            step_trigger=step_trigger,
            video_length=video_length,
            name_prefix=name_prefix,
            fps=fps,
            disable_logger=disable_logger,
        )

    def _capture_frame(self) -> None:
        """Every frame the env drew since the last ``render()`` call, where ``RecordVideo`` keeps the last one
        (the frames are kept for a later ``render()`` call too, as ``RecordVideo`` keeps them)."""
        assert self.recording, "Cannot capture a frame, recording wasn't started."
        frames = self.env.render()
        assert isinstance(frames, list)  # render_mode="rgb_array_list", checked when the wrapper was made
        self.render_history += frames
        self.recorded_frames += frames
