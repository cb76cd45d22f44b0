"""``BoxToss-Stack-v0``: throw a hand of boxes, one per step, into the tallest stable stack on a target."""

from __future__ import annotations

from typing import Any, cast

from box_toss_env.envs import stack_render
from box_toss_env.envs.multi_throw_env import MultiThrowEnv, document_arguments
from box_toss_env.envs.stack_task import STACK_ARGUMENTS, StackTask


class BoxTossStackEnv(MultiThrowEnv):
    r"""Throw a hand of boxes, one per step, so that they come to rest stacked on a target spot.

    ## Description

    At reset the thrower holds a hand of ``n_boxes`` boxes (4 by default), each with its own length,
    width and mass, and its own release pose, drawn per episode; a target x on the floor is drawn too.
    Each ``step`` throws the next box of the hand (the action is a throw, as in ``BoxToss-v0``). Everything
    thrown stays in the scene: the boxes thrown so far are one scene of colliding boxes
    (``Scene(boxes_collide=True)``, the engine's box-box contact), simulated after each throw until every
    body rests (the engine's ``until_rest``: islands of touching boxes fall asleep once still) or for
    ``max_sim_time``. The pile asleep at the end of a throw stays asleep in the next until the thrown box
    reaches it (the engine's warm start, carried from throw to throw). A throw may land on the stack, bounce
    off it, or knock it over.

    The goal is the tallest stable stack on the target. Height is what a thrower can control only by
    placing each box on what the last ones built (a box beside the stack adds nothing), and a bad throw is
    punished by the physics itself: it knocks boxes off and ends the episode. Pure height rewards a single
    box stood on its end; the success criterion asks for the whole hand instead:

    **Success**: after the last throw every box rests on the target (its centre within ``target_radius``
    of the target x), nothing fell, and the stack is at least ``success_fraction`` (0.9) of the sum of the
    boxes' widths high (their thin sides stacked: the hand lying flat one on another).

    ## Action Space

    ``Box(-1, 1, (3,), float32)``, the throw of the box in the hand, as ``BoxToss-v0``'s: each component
    mapped linearly onto its range (values outside [-1, 1] clipped; NaN, inf or a wrong shape raise
    ``ValueError``).

    | Num | Action                                | Min (at -1)               | Max (at +1)               | Unit  |
    |-----|---------------------------------------|---------------------------|---------------------------|-------|
    | 0   | launch speed                          | 0                         | ``max_speed`` (8)         | m/s   |
    | 1   | launch direction above the horizontal | ``launch_angle_range[0]`` | ``launch_angle_range[1]`` | rad   |
    | 2   | spin, counter-clockwise positive      | -``max_spin`` (-20)       | ``max_spin`` (20)         | rad/s |

    ## Observation Space

    ``Box(low, high, (11 n + 12,), float32)`` with n = ``n_boxes`` (56 by default): 11 columns per box of
    the hand, in throwing order, then 12 for the hand, the goal and the progress
    (``stack_task.observation_names`` names them all).

    | Num         | Observation                            | Min                     | Max                    | Unit  |
    |-------------|----------------------------------------|-------------------------|------------------------|-------|
    | 11 j + 0, 1 | box j's centre x, y (0 until thrown)   | release x min - R, -r   | release x max + R, Y   | m     |
    | 11 j + 2, 3 | cos, sin of its angle (0 until thrown) | -1                      | 1                      |       |
    | 11 j + 4, 5 | its velocity x, y (0 until thrown)     | -V                      | V                      | m/s   |
    | 11 j + 6    | its spin (0 until thrown)              | -W                      | W                      | rad/s |
    | 11 j + 7, 8 | its length, width (always)             | ``box_*_range[0]``      | ``box_*_range[1]``     | m     |
    | 11 j + 9    | its mass (always)                      | ``mass_range[0]``       | ``mass_range[1]``      | kg    |
    | 11 j + 10   | 1 once thrown, 0 before (the mask)     | 0                       | 1                      |       |
    | 11 n + 0, 1 | the box in the hand: release x, y      | min(x lo, 0), 0         | ``release_*_range[1]`` | m     |
    | 11 n + 2, 3 | its release cos, sin                   | -1                      | 1                      |       |
    | 11 n + 4-6  | its length, width [m], mass [kg]       | 0                       | the ranges' highs      |       |
    | 11 n + 7    | 1 while a box is in the hand           | 0                       | 1                      |       |
    | 11 n + 8    | target x                               | ``target_x_range[0]``   | ``target_x_range[1]``  | m     |
    | 11 n + 9    | target radius                          | ``target_radius``       | ``target_radius``      | m     |
    | 11 n + 10   | the stack's height                     | 0                       | Y + r                  | m     |
    | 11 n + 11   | boxes left in the hand                 | 0                       | n                      |       |

    Columns 11 n + 0 to 11 n + 6 are 0 after the last throw (their bounds include 0).

    The bounds follow from energy: a throw gives a box of mass m at most m e, e = max_speed^2 / 2 +
    (I/m)_max max_spin^2 / 2 + g y_release_max, contacts take energy away, so the scene never holds more
    than E = n m_max e; V = 2 sqrt(2 E / m_min), W = 2 sqrt(2 E / I_min), Y = 2 E / (m_min g) + r, R = V n T
    (T the simulated time of one throw, ``max_sim_time`` in whole steps; r the largest corner radius). A
    throw that ends outside them raises ``EnergyGainError``; nothing is clipped.

    ## Rewards

    Per throw, from the scene once it rests (``stack_task.score_throws``; H is the stack's height, the
    highest corner of the boxes whose centre lies within ``target_radius`` of the target x):

        reward          = reward_height + reward_distance + reward_fall + reward_success
        reward_height   = height_weight * (H_after - H_before)                 (height_weight = 5 per m)
        reward_distance = -distance_weight * max(|x - target_x| - target_radius, 0)  (distance_weight = 0.5 per m)
        reward_fall     = -fall_penalty * fell                                 (fall_penalty = 1)
        reward_success  = success_bonus * success                              (success_bonus = 1, last throw only)

    x is where the thrown box's centre ended. The height terms sum over an episode to height_weight times the
    final height (a potential difference): a box knocked off takes back what it brought. The four terms are
    in ``info`` under their names and ``reward`` is exactly their sum.

    ## Starting State

    The hand is drawn uniformly, box by box: length in ``box_length_range`` ((0.3, 0.5) m), width in
    ``box_width_range`` ((0.15, 0.25) m), mass in ``mass_range`` ((1, 3) kg), release x in
    ``release_x_range`` ((-0.1, 0.1) m), height in ``release_height_range`` ((1.2, 1.6) m) and angle in
    ``release_angle_range`` ((-0.3, 0.3) rad); the target x uniformly in ``target_x_range`` ((1.5, 3) m). The
    scene is empty. All draws come from ``self.np_random``, one call per reset.

    ## Episode End

    The episode terminates (``terminated=True``) when the last box of the hand has been thrown and the
    scene simulated to rest (or to ``max_sim_time``), or earlier when the stack fell: a box that was on the
    target before the throw is no longer on it, or its top came down by more than ``fall_tolerance``
    (5 cm). ``truncated`` is always False: an episode lasts at most ``n_boxes`` steps, and its end is the
    task's, not a time limit (no ``TimeLimit`` is registered). ``step`` after the end raises
    ``gymnasium.error.ResetNeeded``.

    ``info`` after ``reset``: ``target_x``, ``box_lengths``, ``box_widths``, ``box_masses`` (n,) arrays.
    After ``step``: the four reward terms, ``stack_height`` [m], ``stack_size`` (boxes on the target),
    ``fell``, ``at_rest`` (every body fell asleep before ``max_sim_time``), ``success``, ``distance`` (of
    the thrown box's centre from the target x) [m], ``final_x``, ``final_y``, ``final_angle`` of the thrown
    box, ``thrown`` (boxes thrown so far), ``sim_time`` [s] and ``n_steps`` (time steps of this throw).

    ## Arguments

    ``gymnasium.make("BoxToss-Stack-v0", **kwargs)``, each argument validated when the env is made (a
    ``TypeError`` or ``ValueError`` naming it); the table is made from their one declaration
    (``stack_task.STACK_ARGUMENTS``):

    ARGUMENTS_TABLE

    and ``render_mode``: None, "human" or "rgb_array" (Gymnasium's argument, first).

    Rendering (the ``render`` extra): ``"rgb_array"`` returns an (H, W, 3) uint8 frame of the scene: every
    box thrown and the one in the hand, the target's bracket (``target_radius`` wide), a line at the stack's
    height over it, and the throw count, height and score (the return so far) written top-left; after the
    last throw or a fall, the result top-right. ``"human"`` shows the same in a window after each step.

    The env is the multi-throw core (``multi_throw.MultiThrowFunctional`` with ``stack_task.StackTask``) over a
    batch of one. Batching: ``gymnasium.make_vec("BoxToss-Stack-v0", num_envs=n)`` gives the native batched env
    (``stack_vector.BoxTossStackVectorEnv``, the same core over n envs): one compiled call per scene size present
    in the batch, every env bit for bit this env seeded alike, same-step autoreset. ``vectorization_mode="sync"``
    gives Gymnasium's ``SyncVectorEnv`` of single envs (SB3: ``DummyVecEnv``). ``try_throws`` simulates many
    candidate throws onto copies of the current scene in one compiled call (the planner's search,
    ``agents.stack_planner``).

    ## Version History

    * v0: initial version.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 2}
    task_class = StackTask
    window_title = "BoxToss-Stack"

    def __init__(self, render_mode: str | None = None, **kwargs: Any):
        super().__init__(render_mode, **kwargs)
        self.task = cast(StackTask, self.core.task)

    @property
    def target_x(self) -> float:
        """This episode's target x [m]."""
        return float(self.task.targets(self._batch.episodes)[0])

    def drawn_scene(self) -> dict[str, Any]:
        return stack_render.drawn_scene(self)


document_arguments(BoxTossStackEnv, STACK_ARGUMENTS)
