"""``BoxToss-HiddenPhysics-v0``: land one box in a pose in as few throws as possible, its physics unseen."""

from __future__ import annotations

from typing import Any, cast

import numpy as np

from box_toss_env.envs import task, task_columns
from box_toss_env.envs.hidden_physics_task import HIDDEN_ARGUMENTS, HiddenPhysicsTask
from box_toss_env.envs.multi_throw_env import MultiThrowEnv, MultiThrowVectorEnv, document_arguments
from box_toss_env.physics import layout


class BoxTossHiddenPhysicsEnv(MultiThrowEnv):
    r"""Throw the same box at the same target until it lands in the pose asked for; its physics is never seen.

    ## Description

    An episode is one ``BoxToss-v0`` episode (a box in the hand at a release pose, a target x, the faces that may
    end down) whose box has a mass, a friction coefficient and a restitution drawn wide per episode and **not
    observed**. Each ``step`` throws the box (the action is ``BoxToss-v0``'s throw) and simulates it until it rests;
    then the box is picked up and held at the same release pose for the next throw.

    The agent sees where each
    throw landed and how it was thrown, and must infer from that what it cannot see: how far this box slides
    (friction), how high it bounces (restitution). Mass changes little in a box-floor throw; it is drawn so that
    nothing about the box is given. A throw is exactly ``BoxToss-v0``'s throw of the same episode and action (the
    same core, engine and score, ``functional.BoxTossFunctional``; tested), so a planner told the dynamics is the
    one-throw oracle: that is the task's ceiling (``agents.hidden_physics_tier``, docs/hidden_physics.md).

    **Success**: a throw comes to rest within ``position_tolerance`` (0.1 m) of the target with a target face
    down (by default a long side: ``target_face="long_side"``), in as few throws as possible: the episode ends at
    the first success, or after ``max_throws`` (5) throws.

    ## Action Space

    ``Box(-1, 1, (3,), float32)``: launch speed, direction and spin, as ``BoxToss-v0``'s (each component mapped
    linearly onto ``[0, max_speed]``, ``launch_angle_range``, ``[-max_spin, max_spin]``; values outside [-1, 1]
    clipped; NaN, inf or a wrong shape raise ``ValueError``).

    ## Observation Space

    ``Box(low, high, (18,), float32)`` (``hidden_physics_task.OBSERVATION_NAMES``):

    | Num   | Observation                                      | Min                    | Max                    |
    |-------|--------------------------------------------------|------------------------|------------------------|
    | 0, 1  | release x, y of the box in the hand [m]          | ``release_*_range[0]`` | ``release_*_range[1]`` |
    | 2, 3  | cos, sin of its release angle                    | -1                     | 1                      |
    | 4     | target x [m]                                     | ``target_x_range[0]``  | ``target_x_range[1]``  |
    | 5-8   | 1 if face 0, 1, 2, 3 may end down                | 0                      | 1                      |
    | 9, 10 | x, y where the last throw ended [m] (0 before)   | ``BoxToss-v0``'s, 0    | ``BoxToss-v0``'s       |
    | 11,12 | cos, sin of its angle there (0 before)           | -1                     | 1                      |
    | 13    | 1 if the last throw came to rest                 | 0                      | 1                      |
    | 14-16 | the last action (0 before)                       | -1                     | 1                      |
    | 17    | throws made                                      | 0                      | ``max_throws``         |

    The landing's bounds are ``BoxToss-v0``'s (from energy: ``task.observation_bounds``); a throw that ends outside
    them raises ``EnergyGainError``. Nothing about the mass, friction or restitution is observed.

    ## Rewards

    Each throw earns ``BoxToss-v0``'s reward of its landing: ``reward_distance + reward_orientation +
    reward_success`` (-1 per m from the target, -0.5 per rad from a target face, +1 on success; ``info`` has the
    terms). Every throw that misses costs what its landing scores, and the episode ends at the first success,
    so fewer throws earn more.

    ## Starting State

    ``BoxToss-v0``'s draws, from ``self.np_random`` (one call per reset): release pose, target x (``target_x_range``,
    (1, 4) m), target faces, and the dynamics: mass in ``mass_range`` ((0.5, 5) kg), friction in ``friction_range``
    ((0.1, 1)), restitution in ``restitution_range`` ((0, 0.6)).

    ## Episode End

    Terminated (``terminated=True``) at the first success or after ``max_throws`` throws: the budget of throws is
    the task's (the throws made are observed), not a time limit, so ``truncated`` is always False. ``step`` after
    the end raises ``gymnasium.error.ResetNeeded``.

    ``info`` after ``reset``: ``BoxToss-v0``'s (``target_x``, ``target_faces``, ``release_x``, ``release_y``,
    ``release_angle``, and the hidden ``mass``, ``friction``, ``restitution``: for analysis and for planners told
    them, never for the policy). After ``step``: ``BoxToss-v0``'s step info of the throw (``final_x``, ``final_y``,
    ``final_angle``, ``face_down``, ``at_rest``, ``success``, ``distance``, ``orientation_error``, the reward terms,
    ...) and ``thrown``, the throws made.

    ## Arguments

    ``gymnasium.make("BoxToss-HiddenPhysics-v0", **kwargs)``, each argument validated when the env is made (a
    ``TypeError`` or ``ValueError`` naming it); ``BoxToss-v0``'s, with other defaults for the target faces and the
    dynamics (``hidden_physics_task.HIDDEN_ARGUMENTS``):

    ARGUMENTS_TABLE

    and ``render_mode``: None, "human" or "rgb_array" (Gymnasium's argument, first). A frame shows the box where
    the last throw left it (in the hand before the first), the target and the throw count.

    Batching: ``gymnasium.make_vec("BoxToss-HiddenPhysics-v0", num_envs=n)`` is the native batched env
    (``BoxTossHiddenPhysicsVectorEnv``): the same multi-throw core over n envs, all throws in one call of the
    engine's floor-only kernel, every env bit for bit this env seeded alike, same-step autoreset.

    ## Version History

    * v0: initial version.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 2}
    task_class = HiddenPhysicsTask
    window_title = "BoxToss-HiddenPhysics"

    def __init__(self, render_mode: str | None = None, **kwargs: Any):
        super().__init__(render_mode, **kwargs)
        self.task = cast(HiddenPhysicsTask, self.core.task)

    def drawn_scene(self) -> dict[str, Any]:
        """The box where the last throw left it (in the hand before the first), the target's bracket and the throw
        count."""
        from box_toss_env.rendering import Camera, bounds_of_boxes, box_vertices

        batch, config, last = self._batch, self.config, self._last_info
        state = batch.state[0, 0].copy()
        if self.thrown == 0:  # in the hand
            state[: layout.ANGLE + 1] = batch.episodes[0, task_columns.EP_RELEASE]
        half = np.array([[config.half_length, config.half_width]])
        bounds = bounds_of_boxes(box_vertices(state[None, :2], state[None, 2], half))[0]
        x_min = min(config.release_x_range[0], config.target_x_range[0], bounds[0]) - 0.6
        x_max = max(config.target_x_range[1], bounds[1]) + 0.6
        y_max = max(config.release_height_range[1], bounds[3]) + 0.8
        result: tuple[str, ...] = ()
        if last is not None:
            result = (f"success: {'yes' if last['success'] else 'no'}",) if self._needs_reset else ()
            result += (f"{last['distance']:.2f} m from the target, face {last['face_down']} down",)
        width, height = self.render_size
        return dict(
            position=state[None, :2],
            angle=state[None, 2],
            half_extents=half,
            target_x=float(batch.episodes[0, task_columns.EP_TARGET_X]),
            target_tolerance_m=config.position_tolerance,
            target_label=task.describe_target_faces(batch.episodes[0, task_columns.EP_TARGET_FACES]),
            text_lines=(f"throw {self.thrown} of {self.task.max_throws}", f"score {self._score:+.2f}"),
            result_lines=result,
            result_success=bool(last["success"]) if last is not None and self._needs_reset else None,
            camera=Camera.from_view(x_min, x_max, 0.0, y_max, width, height, padding_px=(8, 8, 40, 30)),
        )


class BoxTossHiddenPhysicsVectorEnv(MultiThrowVectorEnv):
    """``num_envs`` BoxToss-HiddenPhysics envs stepped together; keyword arguments are
    ``BoxTossHiddenPhysicsEnv``'s (and ``num_envs``, ``threads``: ``MultiThrowVectorEnv``'s)."""

    env_class = BoxTossHiddenPhysicsEnv


document_arguments(BoxTossHiddenPhysicsEnv, HIDDEN_ARGUMENTS)
