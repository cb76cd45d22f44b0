"""``BoxToss-v0``: throw a box so that it comes to rest at a target, on a chosen face."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from box_toss_env.envs import task
from box_toss_env.envs.random_streams import check_seed
from box_toss_env.physics import (
    Box,
    KernelFlags,
    Scene,
    Simulator,
    check_finite_stats,
    face_down,
    layout,
    make_settings,
)
from box_toss_env.physics.ranges import check_step_count
from box_toss_env.physics.validation import check_integer

RENDER_MODES = ("human", "rgb_array", "rgb_array_list")


class RenderModes(list):
    """``metadata["render_modes"]``: a list whose ``in`` test raises a TypeError naming ``render_mode``
    for a value that is neither None nor a string (``gymnasium.make`` tests ``render_mode in
    render_modes`` before it makes the env, and would fail on such a value with an AttributeError)."""

    def __contains__(self, mode) -> bool:
        check_render_mode_type(mode)
        return super().__contains__(mode)


def check_render_mode_type(render_mode) -> None:
    if render_mode is not None and not isinstance(render_mode, str):
        raise TypeError(f"render_mode must be None or one of {RENDER_MODES}, got {type(render_mode).__name__} "
                        f"{render_mode!r}")


class EnergyGainError(FloatingPointError):
    """A throw ended outside the observation bounds: the solver created energy or let the box sink
    through the floor (``solver="seed"`` with a time step too large for the penalty stiffness, or no
    penalty at all). The message says which. Nothing is clipped."""


class BoxTossEnv(gym.Env):
    r"""Throw a 2D box onto a floor so that it comes to rest at a target, with a chosen face down.

    ## Description

    A rigid box (40 x 20 cm, 2 kg by default) is in the thrower's hand, at a release point and angle
    drawn at reset. The agent chooses one throw: the launch speed, its direction and the spin. The
    throw is simulated by BoxToss's engine (``box_toss_env.physics``) until the box lies still on
    the floor: it flies, hits the floor, may bounce, slide and tumble, and comes to rest. The agent is
    rewarded for how close to the target it comes to rest and for ending on one of the target faces.
    Each episode is a single step (a contextual bandit with continuous actions): the observation
    after the reset is the box in the hand and the target, the one after the step the final state.

    The box's faces are told apart (they are coloured in renders): numbered by their outward normal in
    the box's own frame, face 0 is local -y (the bottom at angle 0, drawn with a thick red stripe),
    face 1 is +x, face 2 is +y (the top at angle 0), face 3 is -x. The box's length runs along its
    local x axis, so faces 0 and 2 are its long sides and faces 1 and 3 its short ends. The target
    kind (``target_face``) says which faces may end down: any face, a long side, a short end, one
    exact face drawn per episode ("this side up"), or a mix of these drawn per episode.

    ## Action Space

    ``Box(-1, 1, (3,), float32)``. Each component is mapped linearly onto its range; values outside
    [-1, 1] are clipped to it (a NaN or infinite value, or a wrong shape, raises ``ValueError``).

    | Num | Action                                 | Min (at -1)                  | Max (at +1)                | Unit  |
    |-----|----------------------------------------|------------------------------|----------------------------|-------|
    | 0   | launch speed                           | 0                            | ``max_speed`` (8)          | m/s   |
    | 1   | launch direction above the horizontal  | ``launch_angle_range[0]``    | ``launch_angle_range[1]``  | rad   |
    |     |                                        | (-pi/4)                      | (pi/2)                     |       |
    | 2   | spin, counter-clockwise positive       | -``max_spin`` (-20)          | ``max_spin`` (20)          | rad/s |

    The launch velocity is ``speed * (cos(direction), sin(direction))``; positive x points towards the
    targets.

    ## Observation Space

    ``Box(low, high, (12,), float32)``, or ``(15,)`` with ``observe_dynamics=True``. Before the throw
    it holds the box in the hand (velocities 0), after it the state the throw ended in.

    | Num  | Observation                               | Min                      | Max                       | Unit  |
    |------|-------------------------------------------|--------------------------|---------------------------|-------|
    | 0    | x of the box's centre                     | release x min - R        | release x max + R         | m     |
    | 1    | y of the box's centre (floor at y = 0)    | -corner radius           | 2 e / g + corner radius   | m     |
    | 2    | cos(angle)                                | -1                       | 1                         |       |
    | 3    | sin(angle), angle counter-clockwise       | -1                       | 1                         |       |
    | 4    | x velocity                                | -V                       | V                         | m/s   |
    | 5    | y velocity                                | -V                       | V                         | m/s   |
    | 6    | spin                                      | -V / sqrt(I/m)           | V / sqrt(I/m)             | rad/s |
    | 7    | target x (where the centre should rest)   | ``target_x_range[0]``    | ``target_x_range[1]``     | m     |
    | 8-11 | 1 if face 0, 1, 2, 3 may end down, else 0 | 0                        | 1                         |       |
    | 12   | mass (only with ``observe_dynamics``)     | ``mass_range[0]``        | ``mass_range[1]``         | kg    |
    | 13   | friction coefficient (idem)               | ``friction_range[0]``    | ``friction_range[1]``     |       |
    | 14   | restitution (idem)                        | ``restitution_range[0]`` | ``restitution_range[1]``  |       |

    The bounds follow from energy: a throw has at most
    ``e = max_speed^2 / 2 + (I/m) max_spin^2 / 2 + g * release_height_range[1]`` of energy per unit mass
    (``I/m = (L^2 + W^2) / 12``) and contacts only take energy away, so ``V = 2 sqrt(2 e)`` (twice the
    largest possible speed) and ``R = V * T`` bound what a throw can reach, T being the simulated time
    (``max_sim_time`` rounded up to whole steps) (about 20 m/s, 156 rad/s, 10.6 m and 200 m with the
    defaults). Nothing is clipped: a throw ending outside the bounds raises ``EnergyGainError`` (see
    Episode End). A column whose value is fixed (``target_x_range``, or a dynamics quantity that is not
    drawn) has bounds one float32 step either side of its value, so no bound pair is degenerate.

    ## Rewards

    Computed from the final pose, after the throw (``landing_reward`` returns it with its terms):

        reward = reward_distance + reward_orientation + reward_success
        reward_distance    = -distance_weight * |x - target_x|           (distance_weight = 1 per m)
        reward_orientation = -orientation_weight * orientation_error     (orientation_weight = 0.5 per rad)
        reward_success     = success_bonus * success                     (success_bonus = 1)

    ``orientation_error`` in [0, pi] is how far the box must turn until one of its target faces lies
    flat on the floor, ``min over target faces f of |wrap(angle + f pi/2)|`` (0 when a target face is
    down). ``success`` is True when the box came to rest, ``|x - target_x| <= position_tolerance``
    (0.1 m) and a target face is down. The three terms are in ``info`` under their names, and
    ``reward`` is exactly their sum (in the order above).

    ## Starting State

    The box is at rest in the hand: centre x uniform in ``release_x_range`` ((-0.1, 0.1) m), height
    uniform in ``release_height_range`` ((1.2, 1.6) m), angle uniform in ``release_angle_range``
    ((-0.3, 0.3) rad). The target x is uniform in ``target_x_range`` ((1, 4) m) and the target faces
    follow ``target_face``. With ``mass_range``, ``friction_range`` or ``restitution_range`` given,
    those are drawn uniformly at every reset (domain randomisation). All draws come from
    ``self.np_random`` (one call per reset).

    ## Episode End

    Every episode is one step and ends with ``terminated=True`` (never ``truncated``: the end of a
    throw is the end of the task, not a time limit, so it is not bootstrapped). The throw is simulated
    until the box has lain still on a face for the solver's sleep time (0.1 s below 0.01 m/s), or for
    ``max_sim_time`` (10 s) of simulated time at most; ``info["at_rest"]`` tells which. Calling
    ``step`` again before ``reset`` raises ``gymnasium.error.ResetNeeded``. The explicit seed scheme
    (``solver="seed"``) gains energy when ``dt`` is too large for ``penalty_stiffness`` (at the
    default 1/128 s with 1e5 N/m it does; 1/1024 s is fine): ``step`` then raises
    ``box_toss_env.envs.box_toss.EnergyGainError`` if the final state leaves the observation bounds,
    and the engine's ``NonFiniteStateError`` if it diverges, rather than return such values.

    ``info`` after ``reset``: ``target_x``, ``target_faces`` (4 flags), ``release_x``, ``release_y``,
    ``release_angle``, ``mass``, ``friction``, ``restitution`` (drawn even when hidden from the
    observation). ``info`` after ``step``, all Python scalars: the final pose ``final_x``, ``final_y``
    [m], ``final_angle`` [rad, wrapped to [-pi, pi)], ``face_down`` (0-3), ``at_rest``, ``success``,
    ``distance`` [m], ``orientation_error`` [rad], ``flight_time`` [s] (release to first floor contact;
    the whole simulated time if the box never touched the floor), ``n_impacts``, ``n_steps`` (time
    steps integrated), ``max_penetration`` [m], ``sim_time`` [s] (simulated time to rest or to the
    limit), the three reward terms, and ``target_x``, ``mass``, ``friction``, ``restitution``.

    ## Arguments

    ``gymnasium.make("BoxToss-v0", **kwargs)``; every argument is validated when the env is made: a
    ``TypeError`` names an argument of the wrong type (a string, a bool or a complex number for a number),
    a ``ValueError`` names one outside its allowed range. The ranges are in docs/ranges.md
    (``task.ENV_RANGES``).

    | Argument               | Default           | Meaning                                                         |
    |------------------------|-------------------|-----------------------------------------------------------------|
    | ``box_length``         | 0.4               | box size along its local x [m] (faces 1 and 3 are its ends)     |
    | ``box_width``          | 0.2               | box size along its local y [m]                                  |
    | ``mass``               | 2.0               | box mass [kg]; inertia is that of a uniform box                 |
    | ``friction``           | 0.5               | Coulomb friction coefficient with the floor                     |
    | ``restitution``        | 0.3               | coefficient of restitution with the floor, in [0, 1]            |
    | ``penalty_stiffness``  | 1e5               | stiffness of the penetration correction [N/m]                   |
    | ``gravity``            | 9.81              | gravitational acceleration, pointing down [m/s^2]               |
    | ``release_x_range``    | (-0.1, 0.1)       | release x of the box's centre [m]                               |
    | ``release_height_range`` | (1.2, 1.6)      | release height of the centre [m], above the corner radius       |
    | ``release_angle_range``| (-0.3, 0.3)       | release angle [rad], within [-pi, pi]                           |
    | ``target_x_range``     | (1.0, 4.0)        | target x [m]                                                    |
    | ``target_face``        | "any"             | "any", "long_side", "short_end", "exact" or "mixed"             |
    | ``max_speed``          | 8.0               | launch speed at action[0] = 1 [m/s]                             |
    | ``launch_angle_range`` | (-pi/4, pi/2)     | launch direction at action[1] = -1 and +1 [rad]                 |
    | ``max_spin``           | 20.0              | spin at action[2] = 1 [rad/s]                                   |
    | ``position_tolerance`` | 0.1               | success radius around the target [m]                            |
    | ``distance_weight``    | 1.0               | weight of the distance term [1/m]                               |
    | ``orientation_weight`` | 0.5               | weight of the orientation term [1/rad]                          |
    | ``success_bonus``      | 1.0               | reward added on success                                         |
    | ``mass_range``         | None              | (low, high) [kg]: draw the mass per episode (replaces ``mass``) |
    | ``friction_range``     | None              | (low, high): draw the friction per episode                      |
    | ``restitution_range``  | None              | (low, high) in [0, 1]: draw the restitution per episode         |
    | ``observe_dynamics``   | False             | append mass, friction, restitution to the observation           |
    | ``base_box``           | False             | a base box to come to rest on (see "A base box to land on")      |
    | ``base_length_range``  | None: (0.6, 1.0)  | with ``base_box``: the base box's length, drawn per episode [m]  |
    | ``base_height_range``  | None: (0.2, 0.5)  | with ``base_box``: its height, drawn per episode [m]             |
    | ``base_mass``          | None: 10.0        | with ``base_box``: its mass [kg]                                 |
    | ``solver``             | "robust"          | "robust" (the engine's default) or "seed" (the explicit scheme) |
    | ``dt``                 | 1/128             | solver time step [s] (docs/precision.md: the cheapest accurate one) |
    | ``max_sim_time``       | 10.0              | simulated time after which a throw ends anyway [s]              |
    | ``render_mode``        | None              | None, "human", "rgb_array" or "rgb_array_list"                  |
    | ``render_fps``         | 30                | frame rate of "human" playback and "rgb_array_list" frames      |
    | ``render_width``, ``render_height`` | 600, 400 | frame size [px]                                            |

    Registered variants: ``BoxToss-LongSide-v0`` (``target_face="long_side"``),
    ``BoxToss-ShortEnd-v0`` (``"short_end"``), ``BoxToss-ThisSideUp-v0`` (``"exact"``),
    ``BoxToss-Mixed-v0`` (``"mixed"``) and ``BoxToss-OnBox-v0`` (``base_box=True``); ``BoxToss-Goal-v0`` is
    this task in gymnasium-robotics' goal form (``box_toss_env.envs.goal.BoxTossGoalEnv``, for HER).

    ## A base box to land on (``base_box=True``, ``BoxToss-OnBox-v0``)

    A second box, the base, rests on the floor, level, its centre at the target x; its length and height
    are drawn per episode, uniformly in ``base_length_range`` and ``base_height_range`` (mass
    ``base_mass``; friction, restitution and penalty stiffness those of the thrown box). The thrown box
    must come to rest on the base's top. The two boxes collide (the engine's box-box contact: they are
    one scene of ``Scene(boxes_collide=True)``, stepped by its colliding kernel, and the base can be
    pushed or knocked over). The observation gains six columns after all the others:

    | Num      | Observation                | Min                      | Max                                  | Unit |
    |----------|----------------------------|--------------------------|--------------------------------------|------|
    | k        | x of the base's centre     | target x min - V_b T     | target x max + V_b T                 | m    |
    | k+1      | y of the base's centre     | -base corner radius      | base corner radius + 2 e m / (m_b g) | m    |
    | k+2, k+3 | cos, sin of its angle      | -1                       | 1                                    |      |
    | k+4      | base box length            | ``base_length_range[0]`` | ``base_length_range[1]``             | m    |
    | k+5      | base box height            | ``base_height_range[0]`` | ``base_height_range[1]``             | m    |

    with k = 12 (15 with ``observe_dynamics``), m the largest mass of the thrown box, m_b the base's and
    V_b = 2 sqrt(2 e m / m_b): the base starts at rest in its lowest pose (lying on its long side, which
    is why ``base_height_range[1] <= base_length_range[0]`` is required), so it can take at most the
    energy m e of the throw. Column 7, the target x, is where the base was placed; columns k, k+1 are
    where it is (after the throw, where it ended).

    The target is the centre of the base's top (where the base ended): with dx the thrown box's centre x
    minus the base's centre x and dy the height of the box's lowest point above the base's highest point,

        distance = sqrt(dx^2 + dy^2),    reward_distance = -distance_weight * distance

    (the other terms as above), and success means at rest, ``distance <= position_tolerance``, a target
    face down, and resting on the top: |dy| <= ``task.SUPPORT_TOLERANCE`` (1 cm). A box on the floor beside
    the base is |dy| = the base's height from its target, whatever its x. ``info`` after ``reset`` adds
    ``base_length``, ``base_height``; after ``step``, where the base ended (``base_x``, ``base_y``,
    ``base_angle``), ``height_above_base`` (dy) and ``on_base`` (|dy| within the tolerance and the centre
    over the top face, whatever the target). ``target_x_range`` must leave the base clear of the box in
    the hand (its start at least release x max + the box's corner radius + half the longest base).
    Renders draw the base box too.

    Rendering (needs the ``render`` extra, ``pip install "box_toss_env[render]"``): ``"rgb_array"``
    returns an (H, W, 3) uint8 frame of the current state; ``"human"`` opens a pygame window and plays
    each throw in real time; ``"rgb_array_list"`` records each throw and ``render()`` returns the
    frames since the last call (the box in the hand, then the whole throw at ``render_fps``, then its
    result held for a second), for videos of whole throws (``box_toss_env.envs.record_throws`` writes
    them to a GIF or MP4; Gymnasium's ``RecordVideo`` keeps only one frame per step). A throw that
    leaves the home view (release points and targets) is zoomed out to keep the box in frame: one camera
    fitted to the whole throw in recordings, a following camera in the window (``envs.render``). Only
    the last two modes record trajectories, so training without them pays nothing for rendering.

    ## Version History

    * v0: initial version.
    """

    metadata = {"render_modes": RenderModes(RENDER_MODES), "render_fps": 30}

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        box_length: float = 0.4,
        box_width: float = 0.2,
        mass: float = 2.0,
        friction: float = 0.5,
        restitution: float = 0.3,
        penalty_stiffness: float = 1e5,
        gravity: float = 9.81,
        release_x_range: tuple[float, float] = (-0.1, 0.1),
        release_height_range: tuple[float, float] = (1.2, 1.6),
        release_angle_range: tuple[float, float] = (-0.3, 0.3),
        target_x_range: tuple[float, float] = (1.0, 4.0),
        target_face: str = "any",
        max_speed: float = 8.0,
        launch_angle_range: tuple[float, float] = (-0.25 * math.pi, 0.5 * math.pi),
        max_spin: float = 20.0,
        position_tolerance: float = 0.1,
        distance_weight: float = 1.0,
        orientation_weight: float = 0.5,
        success_bonus: float = 1.0,
        mass_range: tuple[float, float] | None = None,
        friction_range: tuple[float, float] | None = None,
        restitution_range: tuple[float, float] | None = None,
        observe_dynamics: bool = False,
        base_box: bool = False,
        base_length_range: tuple[float, float] | None = None,
        base_height_range: tuple[float, float] | None = None,
        base_mass: float | None = None,
        solver: str = "robust",
        dt: float = 1 / 128,
        max_sim_time: float = 10.0,
        render_fps: float = 30,
        render_width: int = 600,
        render_height: int = 400,
    ):
        check_render_mode_type(render_mode)
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode must be None or one of {RENDER_MODES}, got {render_mode!r}")
        self.render_mode = render_mode
        self.config = task.make_task_config(
            box_length=box_length, box_width=box_width, gravity=gravity, mass=mass, friction=friction,
            restitution=restitution, penalty_stiffness=penalty_stiffness, mass_range=mass_range,
            friction_range=friction_range, restitution_range=restitution_range,
            release_x_range=release_x_range, release_height_range=release_height_range,
            release_angle_range=release_angle_range, target_x_range=target_x_range, target_face=target_face,
            max_speed=max_speed, launch_angle_range=launch_angle_range, max_spin=max_spin,
            position_tolerance=position_tolerance, distance_weight=distance_weight,
            orientation_weight=orientation_weight, success_bonus=success_bonus,
            observe_dynamics=observe_dynamics, max_sim_time=max_sim_time, base_box=base_box,
            base_length_range=base_length_range, base_height_range=base_height_range, base_mass=base_mass)
        config = self.config
        # the engine validates the solver settings (dt, solver, material) and names what is wrong
        scene = Scene(
            boxes=(Box(length=box_length, width=box_width, mass=config.mass_range[1],
                       position=(config.release_x_range[0], config.release_height_range[0])),),
            dt=dt, gravity=-config.gravity, restitution=config.restitution_range[1],
            friction=config.friction_range[1], penalty_stiffness=config.penalty_stiffness, solver=solver)
        self.solver = scene.solver
        self.dt = scene.dt
        self.max_steps = max(1, check_step_count("max_sim_time", config.max_sim_time, scene.dt))
        # with a base box the thrown box and the base are one scene of colliding boxes (the colliding kernel);
        # without one, the floor-only kernel, which compiles no box-box contact at all
        self.flags = KernelFlags(solver=scene.solver, use_impulses=True, use_penalty=scene.has_penalty,
                                 use_friction=config.friction_range[1] > 0.0, record=False, parallel=False,
                                 boxes_collide=config.base_box)
        self._settings = make_settings(scene, self.max_steps, until_rest=True)
        self.render_fps = task.ENV_RANGES["render_fps"].check("render_fps", render_fps)
        self.render_size = (_check_pixels("render_width", render_width),
                            _check_pixels("render_height", render_height))
        self.metadata = {**self.metadata, "render_fps": self.render_fps}

        self.action_space = spaces.Box(-1.0, 1.0, shape=(task.ACTION_SIZE,), dtype=np.float32)
        low, high = task.observation_bounds(config, self.max_steps * self.dt)
        self.observation_space = spaces.Box(low, high, dtype=np.float32)

        # per-episode arrays, allocated once: a throw only writes its six initial numbers. The engine's
        # arrays hold the thrown box in row 0 and, with base_box, the base box in row 1
        bodies = config.bodies_per_env
        self._episodes = task.Episodes.empty(1, config.episode_size)
        self._params = np.zeros((bodies, layout.PARAM_SIZE))
        self._state = np.zeros((bodies, layout.STATE_SIZE))
        self._stats = np.zeros((bodies, layout.STATS_SIZE))
        self._records = render_mode in ("human", "rgb_array_list")
        self._trajectory = np.zeros((self.max_steps + 1, bodies, layout.STATE_SIZE)) if self._records else None
        self._events = np.zeros((bodies, layout.MAX_EVENTS, layout.EVENT_SIZE)) if self._records else None
        self._needs_reset = True
        self._params_stale = True  # body parameters are written at the first reset, then per reset if drawn
        self._renderer = None
        # "rgb_array_list" draws when render() asks: the hand and the throw not returned yet, and the result
        self._hand_unseen = self._throw_unseen = False
        self._outcome = None
        self._simulator = None  # built at the first throw: making an env compiles nothing

    @property
    def engine_settings(self) -> np.ndarray:
        """The engine's settings array for this env's throws (dt, gravity, sleep, ...; see
        ``physics.layout``), for running the same throws on the engine directly (a copy)."""
        return self._settings.copy()

    def _build_simulator(self) -> Simulator:
        self._simulator = Simulator(dataclasses.replace(self.flags, record=self._records), start_interpreted=True)
        return self._simulator

    # -- the Gymnasium API ------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Draw a release pose, a target and the dynamics; the box is at rest in the hand.
        ``options`` is unused. ``seed`` is None or any integer >= 0 (``np.int64`` too), never a bool."""
        super().reset(seed=check_seed(seed))
        episodes = task.sample_episodes(self.np_random, self.config, self._episodes)
        if self._params_stale or self.config.draws_body_params:
            task.write_body_params(self._params, episodes, self.config)
            self._params_stale = False
        task.write_initial_states(self._state[:1], episodes, None)
        if self.config.base_box:
            task.write_base_states(self._state[1:], episodes)
        self._needs_reset = False
        self._hand_unseen, self._throw_unseen, self._outcome = self.render_mode == "rgb_array_list", False, None
        if self.render_mode == "human":
            self.render()
        row = episodes.data[0].tolist()
        info = {
            "target_x": row[task.EP_TARGET_X],
            "target_faces": episodes.data[0, task.EP_TARGET_FACES].astype(np.int8),
            "release_x": row[task.EP_RELEASE_X],
            "release_y": row[task.EP_RELEASE_Y],
            "release_angle": row[task.EP_RELEASE_ANGLE],
            "mass": row[task.EP_MASS],
            "friction": row[task.EP_FRICTION],
            "restitution": row[task.EP_RESTITUTION],
        }
        if self.config.base_box:
            info["base_length"], info["base_height"] = row[task.EP_BASE_LENGTH], row[task.EP_BASE_HEIGHT]
        return self._observe()[0], info

    def _observe(self) -> np.ndarray:
        return task.observe(self._state[:1], self._episodes, self.config, self._state[1:])

    def step(self, action):
        """Throw the box with ``action`` and simulate until it rests (or ``max_sim_time``)."""
        if self._needs_reset:
            raise ResetNeeded("each BoxToss episode is a single throw: call reset() before step()")
        actions = task.check_actions(action, self.action_space.shape)
        task.write_initial_states(self._state[:1], self._episodes, task.actions_to_throws(actions, self.config))
        if self.config.base_box:
            task.write_base_states(self._state[1:], self._episodes)
        self._needs_reset = True
        simulator = self._simulator or self._build_simulator()
        simulator.run(self._state, self._params, self._settings, self._stats, self._trajectory, self._events)
        stats = self._stats[0].tolist()
        if stats[layout.STATUS] != layout.STATUS_OK:
            check_finite_stats(self._stats, self.solver)  # raises NonFiniteStateError
        rest_time, end_time = stats[layout.REST_TIME], stats[layout.END_TIME]
        at_rest = not math.isnan(rest_time)
        reward, terms, success, distance, orientation_error = self._landing(self._state[:1], at_rest, self._state[1:])
        x, y, angle, _, _, _ = self._state[0].tolist()
        episode = self._episodes.data[0].tolist()
        flight_time = stats[layout.FIRST_CONTACT_TIME]
        info = {
            "final_x": x,
            "final_y": y,
            "final_angle": (angle + math.pi) % (2.0 * math.pi) - math.pi,
            "face_down": face_down(angle),
            "at_rest": at_rest,
            "success": bool(success[0]),
            "distance": float(distance[0]),
            "orientation_error": float(orientation_error[0]),
            "flight_time": end_time if math.isnan(flight_time) else flight_time,
            "n_impacts": int(stats[layout.N_IMPACTS]),
            "n_steps": int(stats[layout.N_STEPS]),
            "max_penetration": stats[layout.MAX_PENETRATION],
            "sim_time": end_time,
            **{name: float(value[0]) for name, value in terms.items()},
            "target_x": episode[task.EP_TARGET_X],
            "mass": episode[task.EP_MASS],
            "friction": episode[task.EP_FRICTION],
            "restitution": episode[task.EP_RESTITUTION],
        }
        if self.config.base_box:
            info.update({key: value[0].item() for key, value in
                         base_landing_info(self._state[1:], self._state[:1], self._episodes, self.config).items()})
        if self.render_mode is not None:
            from box_toss_env.envs.render import ThrowOutcome

            self._outcome = ThrowOutcome.from_step(float(reward[0]), info, self._episodes.target_faces[0])
            self._throw_unseen = self.render_mode == "rgb_array_list"
            if self.render_mode == "human":
                self.render()
        observation = self._observe()
        if task.outside_bounds(observation, self.observation_space.low, self.observation_space.high)[0]:
            raise EnergyGainError(self._bounds_message(observation[0]))
        return observation[0], float(reward[0]), True, False, info

    def _bounds_message(self, observation: np.ndarray) -> str:
        """What the throw that ended in ``observation`` (outside the bounds) did, for the solver that ran."""
        space = self.observation_space
        column = int(np.argmax(np.maximum(space.low - observation, observation - space.high)))
        where = (f"the throw ended with {task.observation_names(self.config)[column]} = {observation[column]:g}, "
                 f"outside the "
                 f"observation bounds [{space.low[column]:g}, {space.high[column]:g}]")
        stiffness = self.config.penalty_stiffness
        if column == task.OBS_Y and observation[column] < space.low[column]:
            what = (f"{where}: the box sank through the floor (its centre more than a corner radius below it) "
                    f"with solver={self.solver!r}. ")
            if self.solver == "robust":
                return what + "The robust solver should never let a box through: please report these arguments"
            if stiffness == 0.0:
                return what + ("With penalty_stiffness=0 the seed scheme has nothing that pushes a corner back out "
                               "of the floor: give penalty_stiffness > 0, or use solver='robust'")
            return what + (f"The seed scheme's penalty spring (penalty_stiffness={stiffness:g} N/m) was too soft to "
                           "hold it: use a stiffer one (with a dt small enough for it), or solver='robust'")
        what = f"{where} that energy conservation guarantees: solver={self.solver!r} created energy. "
        if self.solver == "robust":
            return what + "The robust solver should never create energy: please report these arguments"
        return what + (f"The seed scheme's explicit penalty spring gains energy when dt is too large for its "
                       f"stiffness (dt={self.dt:g} s with penalty_stiffness={stiffness:g} N/m): use a smaller dt "
                       "(e.g. 1/1024 s for 1e5 N/m), a softer penalty_stiffness, or solver='robust'")

    def landing_reward(self, final_state: np.ndarray, at_rest: bool, base_state: np.ndarray | None = None
                       ) -> tuple[float, dict[str, float]]:
        """The reward of the current episode's throw ending in ``final_state`` (x, y, angle, vx, vy,
        spin) and its named terms (see Rewards); ``step`` returns exactly this. With a base box,
        ``base_state`` is where the base ended (default: where it stands at reset)."""
        state = np.asarray(final_state, dtype=np.float64).reshape(1, layout.STATE_SIZE)
        base = None
        if self.config.base_box:
            if base_state is None:
                base = task.write_base_states(np.zeros((1, layout.STATE_SIZE)), self._episodes)
            else:
                base = np.asarray(base_state, dtype=np.float64).reshape(1, layout.STATE_SIZE)
        reward, terms, *_ = self._landing(state, at_rest, base)
        return float(reward[0]), {name: float(value[0]) for name, value in terms.items()}

    def _landing(self, states: np.ndarray, at_rest: bool, base_states: np.ndarray | None = None):
        return task.reward_terms(states, np.array([at_rest]), self._episodes, self.config, base_states)

    # -- rendering --------------------------------------------------------------------------------
    def render(self):
        """See the class docstring: a frame ("rgb_array"), the frames since the last call
        ("rgb_array_list"), or the window ("human", playing a throw that just happened)."""
        if self.render_mode is None:
            gym.logger.warn("render() was called without a render_mode; make the env with "
                            'gymnasium.make("BoxToss-v0", render_mode="rgb_array") (or "human", "rgb_array_list")')
            return None
        if self.render_mode == "rgb_array":
            return self._draw_state(self._caption())
        if self.render_mode == "rgb_array_list":
            return self._unseen_frames()
        renderer = self._renderer_for_env()
        target_x, target_faces = float(self._episodes.target_x[0]), self._episodes.target_faces[0]
        if self._needs_reset:  # a throw just happened: play it
            renderer.play(self._throw_trajectory(), self.dt, target_x, target_faces, self._outcome)
        else:
            renderer.show(self._drawn_state(), target_x, target_faces, "in the hand")
        return None

    def _caption(self) -> str:
        if not self._needs_reset:
            return "in the hand"
        at_rest = not math.isnan(self._stats[0, layout.REST_TIME])
        return f"after the throw ({'at rest' if at_rest else 'max_sim_time reached'})"

    def _draw_state(self, caption: str) -> np.ndarray:
        episodes = self._episodes
        return self._renderer_for_env().frame(self._drawn_state(), float(episodes.target_x[0]),
                                              episodes.target_faces[0], caption, self._outcome)

    def _unseen_frames(self) -> list[np.ndarray]:
        """"rgb_array_list": the frames since the last call, drawn now. A throw is drawn whole, with one
        camera fitted to it (from the hand on, unless the hand was returned already) and its result."""
        hand, throw = self._hand_unseen, self._throw_unseen
        self._hand_unseen = self._throw_unseen = False
        if throw:
            return self._renderer_for_env().throw_frames(
                self._throw_trajectory(), self.dt, float(self._episodes.target_x[0]),
                self._episodes.target_faces[0], self._outcome, skip_first=not hand)
        return [self._draw_state("in the hand")] if hand else []

    def _renderer_for_env(self):
        if self._renderer is None:
            from box_toss_env.envs.render import ThrowRenderer

            self._renderer = ThrowRenderer(self.config, *self.render_size, fps=self.render_fps)
        if self.config.base_box:  # this episode's base box is drawn too
            self._renderer.other_boxes = 0.5 * self._episodes.base_size[:1]
        return self._renderer

    def _drawn_state(self) -> np.ndarray:
        """The state drawn: the thrown box's (6,), with a base box both boxes' (2, 6)."""
        return self._state if self.config.base_box else self._state[0]

    def _throw_trajectory(self) -> np.ndarray:
        """(T, 6) states of the last throw on the grid t = k dt, up to where it ended (the engine
        writes rows up to the step where the box fell asleep; later rows are left unwritten); with a base
        box (T, 2, 6), the thrown box first."""
        recorded = int(self._stats[0, layout.N_RECORDED])
        return self._trajectory[:recorded] if self.config.base_box else self._trajectory[:recorded, 0]

    def close(self):
        """Close the window if one is open; safe to call more than once."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # -- pickling (subprocess vector envs): compiled kernels and pygame surfaces are rebuilt -------
    def __getstate__(self):
        state = self.__dict__.copy()
        state["_simulator"] = None
        state["_renderer"] = None
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)


def base_landing_info(base_states: np.ndarray, states: np.ndarray, episodes: task.Episodes,
                      config: task.TaskConfig) -> dict[str, np.ndarray]:
    """The step info of a task with a base box, (n,) arrays: where the base ended (``base_x``, ``base_y``
    [m], ``base_angle`` [rad, wrapped to [-pi, pi)]), the thrown box's lowest point above the base's top
    (``height_above_base`` [m]) and whether it rests on it (``on_base``: within ``task.SUPPORT_TOLERANCE``
    of the top, its centre over the top face)."""
    _, dy = task.landing_offsets(states, episodes, config, base_states)
    top_x, _, half_top = task.base_top(base_states, episodes)
    on_base = (np.abs(dy) <= task.SUPPORT_TOLERANCE) & (np.abs(states[:, layout.X] - top_x) <= half_top)
    return {"base_x": base_states[:, layout.X].copy(), "base_y": base_states[:, layout.Y].copy(),
            "base_angle": task.wrap_angles(base_states[:, layout.ANGLE]), "height_above_base": dy,
            "on_base": on_base}


def _check_pixels(name: str, value) -> int:
    return check_integer(name, value, 16, 8192)
