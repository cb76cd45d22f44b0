"""``BoxToss-Stack-v0``: throw a hand of boxes, one per step, into the tallest stable stack on a target."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from box_toss_env.envs import stack_task, task
from box_toss_env.envs.box_toss import EnergyGainError, check_render_mode_type
from box_toss_env.envs.random_streams import check_seed
from box_toss_env.physics import (
    Box,
    KernelFlags,
    Scene,
    Simulator,
    check_finite_stats,
    layout,
    make_settings,
    warm_start_memory,
)
from box_toss_env.physics.grouped import GroupedSimulator
from box_toss_env.physics.ranges import check_step_count
from box_toss_env.physics.validation import check_integer

RENDER_MODES = ("human", "rgb_array")


class BoxTossStackEnv(gym.Env):
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

    ``gymnasium.make("BoxToss-Stack-v0", **kwargs)``, each argument validated when the env is made
    (a ``TypeError`` or ``ValueError`` naming it):

    | Argument               | Default        | Meaning                                                            |
    |------------------------|----------------|--------------------------------------------------------------------|
    | ``n_boxes``            | 4              | boxes in the hand, thrown one per step, in [1, 16]                 |
    | ``box_length_range``   | (0.3, 0.5)     | each box's length, drawn per episode [m]                           |
    | ``box_width_range``    | (0.15, 0.25)   | each box's width, drawn per episode [m], at most the shortest length |
    | ``mass_range``         | (1.0, 3.0)     | each box's mass, drawn per episode [kg]                            |
    | ``friction``           | 0.5            | Coulomb friction of every box (box-box: the same)                  |
    | ``restitution``        | 0.3            | restitution of every box, in [0, 1]                                |
    | ``penalty_stiffness``  | 1e5            | stiffness of the penetration correction [N/m]                      |
    | ``gravity``            | 9.81           | gravitational acceleration, pointing down [m/s^2]                  |
    | ``release_x_range``    | (-0.1, 0.1)    | release x of each box's centre [m]                                 |
    | ``release_height_range`` | (1.2, 1.6)   | release height [m], above the largest corner radius                |
    | ``release_angle_range``| (-0.3, 0.3)    | release angle [rad]                                                |
    | ``target_x_range``     | (1.5, 3.0)     | target x [m], the target clear of the hand                         |
    | ``target_radius``      | 0.25           | a box is on the target when its centre is this close to it [m]     |
    | ``max_speed``          | 8.0            | launch speed at action[0] = 1 [m/s]                                |
    | ``launch_angle_range`` | (-pi/4, pi/2)  | launch direction at action[1] = -1 and +1 [rad]                    |
    | ``max_spin``           | 20.0           | spin at action[2] = 1 [rad/s]                                      |
    | ``height_weight``      | 5.0            | weight of the height term [1/m]                                    |
    | ``distance_weight``    | 0.5            | weight of the distance term [1/m]                                  |
    | ``fall_penalty``       | 1.0            | reward taken when the stack falls                                  |
    | ``success_bonus``      | 1.0            | reward added on success                                            |
    | ``fall_tolerance``     | 0.05           | a box on the target whose top comes down further has fallen [m]    |
    | ``success_fraction``   | 0.9            | share of the sum of the widths the final stack must reach          |
    | ``dt``                 | 1/128          | solver time step [s]                                               |
    | ``max_sim_time``       | 10.0           | simulated time after which a throw ends anyway [s]                 |
    | ``render_mode``        | None           | None, "human" or "rgb_array"                                       |
    | ``render_width``, ``render_height`` | 600, 400 | frame size [px]                                           |

    Rendering (the ``render`` extra): ``"rgb_array"`` returns an (H, W, 3) uint8 frame of the scene: every
    box thrown and the one in the hand, the target's bracket (``target_radius`` wide), a line at the stack's
    height over it, and the throw count, height and score (the return so far) written top-left; after the
    last throw or a fall, the result top-right. ``"human"`` shows the same in a window after each step.

    Batching: ``gymnasium.make_vec("BoxToss-Stack-v0", num_envs=n)`` gives the native batched env
    (``stack_vector.BoxTossStackVectorEnv``): one compiled call per scene size present in the batch, every env bit
    for bit this env seeded alike, same-step autoreset. ``vectorization_mode="sync"`` gives Gymnasium's
    ``SyncVectorEnv`` of single envs (SB3: ``DummyVecEnv``). ``try_throws`` simulates many candidate throws onto
    copies of the current scene in one compiled call (the planner's search, ``agents.stack_planner``).

    ## Version History

    * v0: initial version.
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 2}

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        n_boxes: int = 4,
        box_length_range: tuple[float, float] = (0.3, 0.5),
        box_width_range: tuple[float, float] = (0.15, 0.25),
        mass_range: tuple[float, float] = (1.0, 3.0),
        friction: float = 0.5,
        restitution: float = 0.3,
        penalty_stiffness: float = 1e5,
        gravity: float = 9.81,
        release_x_range: tuple[float, float] = (-0.1, 0.1),
        release_height_range: tuple[float, float] = (1.2, 1.6),
        release_angle_range: tuple[float, float] = (-0.3, 0.3),
        target_x_range: tuple[float, float] = (1.5, 3.0),
        target_radius: float = 0.25,
        max_speed: float = 8.0,
        launch_angle_range: tuple[float, float] = (-0.25 * math.pi, 0.5 * math.pi),
        max_spin: float = 20.0,
        height_weight: float = 5.0,
        distance_weight: float = 0.5,
        fall_penalty: float = 1.0,
        success_bonus: float = 1.0,
        fall_tolerance: float = 0.05,
        success_fraction: float = 0.9,
        dt: float = 1 / 128,
        max_sim_time: float = 10.0,
        render_width: int = 600,
        render_height: int = 400,
    ):
        check_render_mode_type(render_mode)
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode must be None or one of {RENDER_MODES}, got {render_mode!r}")
        self.render_mode = render_mode
        self.config = config = stack_task.make_stack_config(
            n_boxes=n_boxes,
            box_length_range=box_length_range,
            box_width_range=box_width_range,
            mass_range=mass_range,
            friction=friction,
            restitution=restitution,
            penalty_stiffness=penalty_stiffness,
            gravity=gravity,
            release_x_range=release_x_range,
            release_height_range=release_height_range,
            release_angle_range=release_angle_range,
            target_x_range=target_x_range,
            target_radius=target_radius,
            max_speed=max_speed,
            launch_angle_range=launch_angle_range,
            max_spin=max_spin,
            height_weight=height_weight,
            distance_weight=distance_weight,
            fall_penalty=fall_penalty,
            success_bonus=success_bonus,
            fall_tolerance=fall_tolerance,
            success_fraction=success_fraction,
            max_sim_time=max_sim_time,
        )
        self._configure_engine(config, dt)
        self.render_size = (
            check_integer("render_width", render_width, 16, 8192),
            check_integer("render_height", render_height, 16, 8192),
        )

        self.action_space = spaces.Box(-1.0, 1.0, shape=(task.ACTION_SIZE,), dtype=np.float32)
        low, high = stack_task.observation_bounds(config, self.max_steps * self.dt)
        self.observation_space = spaces.Box(low, high, dtype=np.float32)

        self._clear_episode(config)

    def _configure_engine(self, config, dt: float) -> None:
        """The step, the step budget, the kernel's flags and the engine settings of the colliding scene."""
        # the engine validates its settings (dt, material) and names what is wrong
        scene = Scene(
            boxes=(
                Box(
                    length=config.box_length_range[1],
                    width=config.box_width_range[1],
                    mass=config.mass_range[1],
                    position=(0.0, config.release_height_range[1]),
                ),
            ),
            dt=dt,
            gravity=-config.gravity,
            restitution=config.restitution,
            friction=config.friction,
            penalty_stiffness=config.penalty_stiffness,
            boxes_collide=True,
        )
        self.dt = scene.dt
        self.max_steps = max(1, check_step_count("max_sim_time", config.max_sim_time, scene.dt))
        self.flags = KernelFlags(
            solver="robust",
            use_impulses=True,
            use_penalty=scene.has_penalty,
            use_friction=config.friction > 0.0,
            record=False,
            parallel=False,
            boxes_collide=True,
        )
        self._settings = make_settings(scene, self.max_steps, until_rest=True)

    def _clear_episode(self, config) -> None:
        """The per-episode arrays (the hand, every thrown box's state and stats) and counters, empty."""
        n = config.n_boxes
        self._hand = np.zeros((n, stack_task.EPISODE_COLUMNS))
        self._target_x = 0.0
        self._params = np.zeros((n, layout.PARAM_SIZE))
        self._state = np.zeros((n, layout.STATE_SIZE))  # row j: box j once thrown
        self._stats = np.zeros((n, layout.STATS_SIZE))
        self._warm = warm_start_memory(n)  # what each throw's run ends with (the pile's sleep), the next one's start
        self._thrown = 0
        self._height = 0.0
        self._score = 0.0
        self._last: stack_task.ThrowOutcomes | None = None
        self._needs_reset = True
        self._simulator: Simulator | None = None  # built at the first throw: making an env compiles nothing
        self._renderer = None

    @property
    def engine_settings(self) -> np.ndarray:
        """The engine's settings array of this env's throws (a copy)."""
        return self._settings.copy()

    @property
    def thrown(self) -> int:
        """How many boxes of the hand have been thrown in this episode."""
        return self._thrown

    @property
    def target_x(self) -> float:
        """This episode's target x [m]."""
        return self._target_x

    @property
    def scene(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the engine's state (k, 6) and body parameters (k, 7) of the k boxes thrown so far."""
        k = self._thrown
        return self._state[:k].copy(), self._params[:k].copy()

    # -- the Gymnasium API ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Draw a hand and a target; the scene is empty. ``options`` is unused."""
        super().reset(seed=check_seed(seed))
        self._hand, self._target_x = stack_task.draw_episode(self.np_random, self.config)
        self._params[:] = stack_task.body_params(self._hand, self.config)
        self._state[:] = 0.0
        self._warm[:] = 0.0
        self._thrown, self._height, self._score, self._last = 0, 0.0, 0.0, None
        self._needs_reset = False
        if self.render_mode == "human":
            self.render()
        info = {
            "target_x": self._target_x,
            "box_lengths": self._hand[:, stack_task.E_LENGTH].copy(),
            "box_widths": self._hand[:, stack_task.E_WIDTH].copy(),
            "box_masses": self._hand[:, stack_task.E_MASS].copy(),
        }
        return self._observe(), info

    def _observe(self) -> np.ndarray:
        return stack_task.observe(self._state, self._hand, self._thrown, self._target_x, self._height, self.config)

    def step(self, action):
        """Throw the next box of the hand with ``action``; simulate the scene until everything rests."""
        if self._needs_reset:
            raise ResetNeeded("the episode has ended (or not started): call reset() before step()")
        actions = task.check_actions(action, self.action_space.shape)
        k = self._thrown
        before = self._state[:k].copy()
        self._state[k] = stack_task.thrown_states(self._hand[k, stack_task.E_RELEASE_X :], actions, self.config)[0]
        rows = slice(0, k + 1)
        simulator = self._simulator or self._build_simulator()
        simulator.run(self._state[rows], self._params[rows], self._settings, self._stats[rows], warm_start=self._warm)
        stats = self._stats[rows]
        if np.any(stats[:, layout.STATUS] != layout.STATUS_OK):
            check_finite_stats(stats, "robust")  # raises NonFiniteStateError
        at_rest = np.array([not np.isnan(stats[:, layout.REST_TIME]).any()])
        half = self._params[rows, layout.HALF_LENGTH : layout.HALF_WIDTH + 1]
        outcome = stack_task.score_throws(before, self._state[None, rows], half, at_rest, self._target_x, self.config)
        self._thrown = k + 1
        self._height = float(outcome.height[0])
        reward = float(outcome.reward[0])
        self._score += reward
        terminated = bool(outcome.fell[0]) or self._thrown == self.config.n_boxes
        self._needs_reset = terminated
        self._last = outcome
        observation = self._observe()
        if np.any((observation < self.observation_space.low) | (observation > self.observation_space.high)):
            column = int(
                np.argmax(
                    np.maximum(self.observation_space.low - observation, observation - self.observation_space.high)
                )
            )
            raise EnergyGainError(
                f"the throw ended with {stack_task.observation_names(self.config)[column]} = "
                f"{observation[column]:g}, outside the bounds energy conservation guarantees: "
                "the solver created energy; please report these arguments"
            )
        x, y, angle = self._state[k, :3].tolist()
        info = {
            **{name: float(value[0]) for name, value in outcome.terms.items()},
            "stack_height": self._height,
            "stack_size": int(outcome.on_target[0].sum()),
            "fell": bool(outcome.fell[0]),
            "at_rest": bool(at_rest[0]),
            "success": bool(outcome.success[0]),
            "distance": float(outcome.distance[0]),
            "final_x": x,
            "final_y": y,
            "final_angle": (angle + math.pi) % (2.0 * math.pi) - math.pi,
            "thrown": self._thrown,
            "sim_time": float(stats[0, layout.END_TIME]),
            "n_steps": int(stats[:, layout.N_STEPS].max()),
        }
        if self.render_mode == "human":
            self.render()
        return observation, reward, terminated, False, info

    def _build_simulator(self) -> Simulator:
        self._simulator = Simulator(self.flags, start_interpreted=True)
        return self._simulator

    # -- the planner's search: candidate throws onto copies of the scene -------------------------------------
    def try_throws(self, actions: np.ndarray, threads: int | None = 1) -> stack_task.ThrowOutcomes:
        """What throwing the box in the hand with each of ``actions`` (m, 3) would do, without doing it: m
        copies of the scene, each with one candidate throw, simulated in one call of the engine's colliding
        kernel (``physics.grouped``, whole scenes per thread, each copy's result bit for bit what ``step``
        gives). Returns the outcomes (m,); ``final`` states of the copies are in ``last_tried`` (m, k + 1, 6)."""
        if self._needs_reset:
            raise ResetNeeded("call reset() before try_throws()")
        actions = task.check_actions(actions, np.shape(actions))
        m, k = len(actions), self._thrown
        states = np.empty((m, k + 1, layout.STATE_SIZE))
        states[:, :k] = self._state[:k]
        states[:, k] = stack_task.thrown_states(self._hand[k, stack_task.E_RELEASE_X :], actions, self.config)
        params = np.tile(self._params[: k + 1], (m, 1))
        stats = np.zeros((m * (k + 1), layout.STATS_SIZE))
        flat = states.reshape(m * (k + 1), layout.STATE_SIZE)
        simulator = GroupedSimulator(dataclasses.replace(self.flags, parallel=threads != 1), k + 1, threads=threads)
        simulator.run(flat, params, self._settings, stats, warm_start=np.repeat(self._warm[None], m, axis=0))
        finite = (stats[:, layout.STATUS] == layout.STATUS_OK).reshape(m, k + 1).all(axis=1)
        at_rest = ~np.isnan(stats[:, layout.REST_TIME]).reshape(m, k + 1).any(axis=1)
        half = self._params[: k + 1, layout.HALF_LENGTH : layout.HALF_WIDTH + 1]
        outcomes = stack_task.score_throws(self._state[:k], states, half, at_rest & finite, self._target_x, self.config)
        outcomes.reward = np.where(finite, outcomes.reward, -np.inf)
        self.last_tried = states
        return outcomes

    # -- rendering -------------------------------------------------------------------------------------------
    def render(self):
        """A frame of the scene ("rgb_array") or the window ("human"); see the class docstring."""
        if self.render_mode is None:
            gym.logger.warn('render() was called without a render_mode; make the env with render_mode="rgb_array"')
            return None
        scene = self._drawn_scene()
        renderer = self._renderer_for_env()
        if self.render_mode == "rgb_array":
            return renderer.render_rgb(**scene)
        if not renderer.show(**scene, fps=self.metadata["render_fps"]):
            self.close()
        return None

    def _drawn_scene(self) -> dict:
        """The keyword arguments of ``SceneRenderer.render_rgb``: every box thrown and the one in the hand."""
        k, n = self._thrown, self.config.n_boxes
        states = self._state[:k]
        half = self._params[:k, layout.HALF_LENGTH : layout.HALF_WIDTH + 1]
        if k < n and not self._needs_reset:  # the box in the hand, at its release pose
            hand = self._hand[k]
            states = np.vstack(
                (
                    states,
                    [
                        hand[stack_task.E_RELEASE_X],
                        hand[stack_task.E_RELEASE_Y],
                        hand[stack_task.E_RELEASE_ANGLE],
                        0.0,
                        0.0,
                        0.0,
                    ],
                )
            )
            half = np.vstack((half, self._params[k, layout.HALF_LENGTH : layout.HALF_WIDTH + 1]))
        radius, target_x = self.config.target_radius, self._target_x
        height_line = np.array([[target_x - radius, self._height], [target_x + radius, self._height]])
        result: tuple[str, ...] = ()
        success = None
        if self._needs_reset and self._last is not None:
            success = bool(self._last.success[0])
            result = (
                f"success: {'yes' if success else 'no'}",
                f"stack height: {self._height:.2f} m",
                "the stack fell" if self._last.fell[0] else f"{int(self._last.on_target[0].sum())} boxes on it",
            )
        return dict(
            position=states[:, :2],
            angle=states[:, 2],
            half_extents=half,
            target_x=target_x,
            target_tolerance_m=radius,
            target_label="stack here",
            text_lines=(f"throw {k} of {n}, stack height {self._height:.2f} m", f"score {self._score:+.2f}"),
            result_lines=result,
            result_success=success,
            trace=height_line if self._height > 0 else None,
            camera=self._camera(states, half),
        )

    def _camera(self, states: np.ndarray, half: np.ndarray):
        """The home view (hand, targets, the tallest stack the hand can make), widened to hold every box."""
        from box_toss_env.rendering import Camera, bounds_of_boxes, box_vertices

        config = self.config
        x_min = min(config.release_x_range[0], config.target_x_range[0]) - 0.6
        x_max = max(config.release_x_range[1], config.target_x_range[1]) + 1.0
        y_max = max(config.release_height_range[1], config.n_boxes * config.box_width_range[1]) + 0.6
        if len(states):
            bounds = bounds_of_boxes(box_vertices(states[:, :2], states[:, 2], half))
            x_min, x_max = min(x_min, bounds[:, 0].min() - 0.2), max(x_max, bounds[:, 1].max() + 0.2)
            y_max = max(y_max, bounds[:, 3].max() + 0.2)
        width, height = self.render_size
        return Camera.from_view(
            x_min, x_max, 0.0, y_max, width, height, padding_px=(8, 8, min(40, height / 5), min(30, height / 6))
        )

    def _renderer_for_env(self):
        if self._renderer is None:
            from box_toss_env.rendering import SceneRenderer

            self._renderer = SceneRenderer(*self.render_size, window_title="BoxToss-Stack")
        return self._renderer

    def close(self):
        """Close the window if one is open; safe to call more than once."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_simulator"] = None
        state["_renderer"] = None
        return state
