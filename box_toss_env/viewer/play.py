"""Play mode's model: throw BoxToss's box by hand, with no window (the env does the physics and scoring).

The user drags: the drag's direction and length give the launch velocity (``THROW_GAIN`` metres
per second for each metre dragged), a key or the wheel sets the spin. ``throw_to_action`` turns
that into the env's normalised action, the inverse of ``task.actions_to_throws`` (the env has no
inverse of its own), clipping it into the action space: a throw backwards is thrown at the nearest
launch direction the env allows. ``env.step(action)`` then simulates and scores the throw exactly
as it would an agent's; with ``render_mode="rgb_array_list"`` the env also draws the throw's
frames, which the front end plays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from box_toss_env.envs import task, task_config

THROW_GAIN = 4.0
"""Launch speed per metre of drag [1/s]: a 1 m drag throws at 4 m/s (the default max_speed, 8 m/s,
is a 2 m drag)."""
SPIN_STEPS = 10
"""The spin keys and the wheel move the spin in steps of max_spin / SPIN_STEPS."""
PREVIEW_POINTS = 40


def wrap_angle(angle: float) -> float:
    """``angle`` wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def clip_launch_angle(theta: float, low: float, high: float) -> float:
    """``theta`` [rad] if it lies in [low, high] (up to whole turns), else the nearer bound (by turning)."""
    for candidate in (theta, theta - 2.0 * math.pi, theta + 2.0 * math.pi):
        if low <= candidate <= high:
            return candidate
    return low if abs(wrap_angle(theta - low)) <= abs(wrap_angle(theta - high)) else high


def throw_to_action(velocity, spin: float, config: task_config.TaskConfig) -> tuple[np.ndarray, bool]:
    """The action in [-1, 1]^3 that throws at ``velocity`` (vx, vy) [m/s] spinning at ``spin`` [rad/s],
    and whether it had to be clipped into the action space.

    speed = |v|, launch angle = atan2(vy, vx) (clipped to ``launch_angle_range``), then the env's own
    inverse mapping ``task.throws_to_actions``.
    """
    vx, vy = (float(v) for v in velocity)
    speed = math.hypot(vx, vy)
    low, high = config.launch_angle_range
    theta = math.atan2(vy, vx) if speed > 0.0 else 0.5 * (low + high)
    clipped_theta = clip_launch_angle(theta, low, high)
    action = task.throws_to_actions(np.array([[speed, clipped_theta, float(spin)]]), config)[0]
    clipped = bool(np.any(np.abs(action) > 1.0 + 1e-12) or clipped_theta != theta)
    return np.clip(action, -1.0, 1.0), clipped


@dataclass
class ThrowResult:
    """One throw and how the env scored it."""

    action: np.ndarray  # (3,) in [-1, 1]
    throw: np.ndarray  # (3,) speed [m/s], launch angle [rad], spin [rad/s] the env threw with
    clipped: bool
    reward: float
    terms: dict[str, float]  # the reward's named terms (task.REWARD_TERMS), from info
    info: dict[str, Any]
    frames: list[np.ndarray] = field(default_factory=list)  # the env's frames of the throw, if recorded


class PlayController:
    """Aim, throw and score on a BoxToss env.

    ``env`` is made with ``gymnasium.make("BoxToss-v0", render_mode="rgb_array_list")`` for frames
    (or ``render_mode=None`` for the logic alone). Episodes are reset with explicit seeds drawn from
    ``seed``, so ``retry`` throws again at the same target from the same hand pose.
    """

    def __init__(self, env, seed: int | None = None):
        self.env = env
        self.config: task_config.TaskConfig = env.unwrapped.config
        self._seeds = np.random.default_rng(seed)
        self.episode_seed = 0
        self.info: dict[str, Any] = {}
        self.hand_frames: list[np.ndarray] = []
        self.spin = 0.0
        self.drag_start: np.ndarray | None = None
        self.drag_end: np.ndarray | None = None
        self.result: ThrowResult | None = None
        self.new_target()

    # -- episodes -------------------------------------------------------------------------------------
    def new_target(self) -> None:
        """A new episode: a new hand pose and target."""
        self.episode_seed = int(self._seeds.integers(2**31))
        self._reset()

    def retry(self) -> None:
        """The same episode again (same hand pose and target), to throw once more."""
        self._reset()

    def _reset(self) -> None:
        _, self.info = self.env.reset(seed=self.episode_seed)
        self.hand_frames = self._frames()
        self.drag_start = self.drag_end = None
        self.result = None

    def _frames(self) -> list[np.ndarray]:
        return list(self.env.render()) if self.env.render_mode == "rgb_array_list" else []

    @property
    def release(self) -> np.ndarray:
        """(x, y, angle) of the box in the hand [m, m, rad]."""
        return np.array([self.info["release_x"], self.info["release_y"], self.info["release_angle"]])

    @property
    def target_x(self) -> float:
        return float(self.info["target_x"])

    @property
    def target_label(self) -> str:
        return task.describe_target_faces(np.asarray(self.info["target_faces"], dtype=np.float64))

    @property
    def thrown(self) -> bool:
        return self.result is not None

    # -- aiming ---------------------------------------------------------------------------------------------
    def begin_drag(self, point) -> None:
        """Press at a world point [m]; a new drag after a throw starts over on the same target."""
        if self.thrown:
            self.retry()
        self.drag_start = np.asarray(point, dtype=np.float64).copy()
        self.drag_end = self.drag_start.copy()

    def drag_to(self, point) -> None:
        if self.drag_start is not None:
            self.drag_end = np.asarray(point, dtype=np.float64).copy()

    def cancel_drag(self) -> None:
        self.drag_start = self.drag_end = None

    @property
    def aiming(self) -> bool:
        return self.drag_start is not None

    def end_drag(self) -> ThrowResult | None:
        """Release: throw with the dragged velocity and the current spin."""
        if self.drag_start is None:
            return None
        velocity = self.velocity
        self.cancel_drag()
        return self.throw(velocity, self.spin)

    @property
    def velocity(self) -> np.ndarray:
        """The launch velocity the drag asks for [m/s] (zero when not dragging)."""
        if self.drag_start is None:
            return np.zeros(2)
        return THROW_GAIN * (self.drag_end - self.drag_start)

    def change_spin(self, steps: int) -> None:
        """Spin up (counter-clockwise, ``steps`` > 0) or down by steps of max_spin / SPIN_STEPS."""
        step = self.config.max_spin / SPIN_STEPS
        self.spin = float(np.clip(self.spin + steps * step, -self.config.max_spin, self.config.max_spin))

    def reset_spin(self) -> None:
        self.spin = 0.0

    def aimed(self) -> tuple[np.ndarray, np.ndarray, bool]:
        """(action, throw, clipped) of the current aim: ``throw`` (speed, angle, spin) is what the env
        will actually throw with (after clipping)."""
        action, clipped = throw_to_action(self.velocity, self.spin, self.config)
        throw = task.actions_to_throws(action[None, :], self.config)[0]
        return action, throw, clipped

    def preview_path(self) -> np.ndarray:
        """(k, 2) ballistic path of the box's centre for the current aim, to the floor [m]."""
        _, (speed, theta, _), _ = self.aimed()
        x, y, _ = self.release
        vx, vy, g = speed * math.cos(theta), speed * math.sin(theta), self.config.gravity
        landing_time = (vy + math.sqrt(vy * vy + 2.0 * g * y)) / g
        t = np.linspace(0.0, landing_time, PREVIEW_POINTS)
        return np.column_stack([x + vx * t, y + vy * t - 0.5 * g * t * t])

    # -- throwing -------------------------------------------------------------------------------------------
    def throw(self, velocity, spin: float) -> ThrowResult:
        """Throw at ``velocity`` (vx, vy) [m/s] with ``spin`` [rad/s] through ``env.step`` and keep the result."""
        if self.thrown:
            self.retry()
        action, clipped = throw_to_action(velocity, spin, self.config)
        _, reward, _, _, info = self.env.step(action.astype(np.float32))
        throw = task.actions_to_throws(action.astype(np.float32).astype(np.float64)[None, :], self.config)[0]
        self.result = ThrowResult(
            action=action,
            throw=throw,
            clipped=clipped,
            reward=float(reward),
            terms={name: float(info[name]) for name in task.REWARD_TERMS},
            info=info,
            frames=self._frames(),
        )
        return self.result
