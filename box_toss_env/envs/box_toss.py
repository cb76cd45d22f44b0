"""``BoxToss-v0``: throw a box so that it comes to rest at a target, on a chosen face."""

from __future__ import annotations

import dataclasses
import inspect
import math
import textwrap
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from box_toss_env.envs import task, task_columns, task_config
from box_toss_env.envs.arguments import CORE_ARGUMENTS, ENV_ARGUMENTS, arguments_table, with_defaults
from box_toss_env.envs.functional import BoxTossFunctional, first_of
from box_toss_env.envs.pixels import OBSERVATION_MODES, PixelRenderer
from box_toss_env.envs.random_streams import check_seed
from box_toss_env.physics import Simulator, layout
from box_toss_env.physics.grouped import GroupedSimulator
from box_toss_env.physics.validation import check_choice, check_integer

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
        raise TypeError(
            f"render_mode must be None or one of {RENDER_MODES}, got {type(render_mode).__name__} {render_mode!r}"
        )


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

    With a drawn box size (``box_length_range``, ``box_width_range``) the box's length and width [m] follow the
    dynamics' columns (or the target faces', without ``observe_dynamics``), bounded by their ranges; the energy
    bounds then take the largest box's I/m, the spin's the smallest box's.

    ``observation_mode="pixels"`` (the ``BoxToss-*-Pixels-v0`` ids) observes instead an image of the scene,
    ``Box(0, 255, (height, width, 3), uint8)`` at ``pixel_size`` ((96, 40) by default): the thrown box in red, the
    target in green (a band of full height whose edges are the target x -+ ``position_tolerance``, and a strip along
    each face of the box that may end down), other boxes (the base) in blue, antialiased, in a view fixed by the
    task's ranges (``envs.pixels``). Before the throw it shows the box in the hand, after it where the box came to
    rest; the bounds are still checked on the state.

    ## Held-out split

    ``split="train"`` or ``"test"`` draws, per episode, the box's length and width, its mass, friction and
    restitution and the target x from the split's ranges (``envs.arguments.SPLITS``), all observed; the test ranges
    reach past the training ones. It sets those arguments (and ``observe_dynamics=True``), which must then be left
    at their defaults. ``python -m agents.benchmark --heldout`` trains on the train split and scores on both.

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
    ``box_toss_env.envs.functional.EnergyGainError`` if the final state leaves the observation bounds,
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
    a ``ValueError`` names one outside its allowed range, and an unknown name is a ``TypeError``. The table is
    generated from the one declaration of the arguments (``envs.arguments.ENV_ARGUMENTS``), which the
    validation reads too; the rules that tie arguments together are in docs/ranges.md.

    ARGUMENTS_TABLE

    and ``render_mode``: None, "human", "rgb_array" or "rgb_array_list" (Gymnasium's argument, first).

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
    result held for a second). For videos of whole throws, wrap the env in
    ``box_toss_env.wrappers.RecordThrowVideo`` (Gymnasium's ``RecordVideo`` keeping every frame; the plain
    ``RecordVideo`` keeps one frame per step, two a throw) or write them to a GIF or MP4 with
    ``box_toss_env.envs.record_throws``. A throw that
    leaves the home view (release points and targets) is zoomed out to keep the box in frame: one camera
    fitted to the whole throw in recordings, a following camera in the window (``envs.render``). Only
    the last two modes record trajectories, so training without them pays nothing for rendering.

    ## Version History

    * v0: initial version (``box_toss_env`` 0.1.0; the changelog lists what changed since).
    """

    metadata = {"render_modes": RenderModes(RENDER_MODES), "render_fps": 30}

    def __init__(self, render_mode: str | None = None, **kwargs: Any):
        check_render_mode_type(render_mode)
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode must be None or one of {RENDER_MODES}, got {render_mode!r}")
        self.render_mode = render_mode
        args = with_defaults(kwargs, owner=type(self).__name__)
        # the throw itself, batch-first (a batch of one here): the one copy of the task and of the step
        self.core = BoxTossFunctional(**{name: args[name] for name in CORE_ARGUMENTS})
        self.config = config = self.core.config
        self.solver, self.dt, self.max_steps, self.flags = (
            self.core.solver,
            self.core.dt,
            self.core.max_steps,
            self.core.flags,
        )
        self._settings = self.core.settings
        self.render_fps = task_config.ENV_RANGES["render_fps"].check("render_fps", args["render_fps"])
        self.render_size = (
            _check_pixels("render_width", args["render_width"]),
            _check_pixels("render_height", args["render_height"]),
        )
        self.metadata = {**self.metadata, "render_fps": self.render_fps}

        self.action_space = spaces.Box(-1.0, 1.0, shape=(task_columns.ACTION_SIZE,), dtype=np.float32)
        self.pixels = pixel_renderer(config, args["observation_mode"], args["pixel_size"])
        self.observation_space = (
            spaces.Box(self.core.observation_low, self.core.observation_high, dtype=np.float32)
            if self.pixels is None
            else spaces.Box(0, 255, self.pixels.shape, dtype=np.uint8)
        )

        # per-episode arrays, allocated once: a throw only writes its six initial numbers. The engine's
        # arrays hold the thrown box in row 0 and, with base_box, the base box in row 1
        self._batch = self.core.empty(1)
        self._episodes, self._params, self._state, self._stats = (
            self._batch.episodes,
            self._batch.params,
            self._batch.state,
            self._batch.stats,
        )
        self._records = render_mode in ("human", "rgb_array_list")
        bodies = config.bodies_per_env
        self._trajectory = np.zeros((self.max_steps + 1, bodies, layout.STATE_SIZE)) if self._records else None
        self._events = np.zeros((bodies, layout.MAX_EVENTS, layout.EVENT_SIZE)) if self._records else None
        self._needs_reset = True
        self._renderer = None
        # "rgb_array_list" draws when render() asks: the hand and the throw not returned yet, and the result
        self._hand_unseen = self._throw_unseen = False
        self._outcome = None
        self._simulator: Simulator | GroupedSimulator | None = None  # built at the first throw: nothing compiled before

    @property
    def engine_settings(self) -> np.ndarray:
        """The engine's settings array for this env's throws (dt, gravity, sleep, ...; see
        ``physics.layout``), for running the same throws on the engine directly (a copy)."""
        return self._settings.copy()

    def _build_simulator(self) -> Simulator | GroupedSimulator:
        self._simulator = self.core.make_simulator(record=self._records, start_interpreted=True)
        return self._simulator

    # -- the Gymnasium API ------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Draw a release pose, a target and the dynamics; the box is at rest in the hand.
        ``options`` is unused. ``seed`` is None or any integer >= 0 (``np.int64`` too), never a bool."""
        super().reset(seed=check_seed(seed))
        self.core.initial(self.np_random, self._batch)
        self._needs_reset = False
        self._hand_unseen, self._throw_unseen, self._outcome = self.render_mode == "rgb_array_list", False, None
        if self.render_mode == "human":
            self.render()
        return self._seen(self._observe())[0], first_of(self.core.reset_info(self._batch))

    def _observe(self) -> np.ndarray:
        """The state observation (1, obs) of the batch of one; ``_seen`` makes it what the agent observes."""
        return self.core.observation(self._batch)

    def _seen(self, state: np.ndarray) -> np.ndarray:
        """What the agent observes: the state observation, or with ``observation_mode="pixels"`` the image
        (``envs.pixels``) of the scene as it is now, (1, ...)."""
        return state if self.pixels is None else self.pixels.draw(self._batch)

    def step(self, action):
        """Throw the box with ``action`` and simulate until it rests (or ``max_sim_time``)."""
        if self._needs_reset:
            raise ResetNeeded("each BoxToss episode is a single throw: call reset() before step()")
        core, batch = self.core, self._batch
        core.launch(batch, core.check_actions(action, self.action_space.shape))
        self._needs_reset = True
        core.simulate(batch, self._simulator or self._build_simulator(), self._trajectory, self._events)
        core.check_finite(batch)  # raises NonFiniteStateError
        reward, info = core.score(batch)
        reward, info = float(reward[0]), first_of(info)
        if self.render_mode is not None:
            from box_toss_env.envs.render import ThrowOutcome

            self._outcome = ThrowOutcome.from_step(reward, info, self._episodes.target_faces[0])
            self._throw_unseen = self.render_mode == "rgb_array_list"
            if self.render_mode == "human":
                self.render()
        observation = self._observe()
        core.check_bounds(observation)  # raises EnergyGainError
        return self._seen(observation)[0], reward, True, False, info

    def _bounds_message(self, observation: np.ndarray) -> str:
        """What the throw that ended in ``observation`` (outside the bounds) did, for the solver that ran."""
        return self.core.bounds_message(observation)

    def landing_reward(
        self, final_state: np.ndarray, at_rest: bool, base_state: np.ndarray | None = None
    ) -> tuple[float, dict[str, float]]:
        """The reward of the current episode's throw ending in ``final_state`` (x, y, angle, vx, vy,
        spin) and its named terms (see Rewards); ``step`` returns exactly this. With a base box,
        ``base_state`` is where the base ended (default: where it stands at reset)."""
        batch = dataclasses.replace(self._batch, state=np.zeros_like(self._state))
        batch.thrown_state[:] = np.asarray(final_state, dtype=np.float64).reshape(1, layout.STATE_SIZE)
        base = batch.base_state
        if base is not None and base_state is None:
            task.write_base_states(base, self._episodes)  # where the base stands at reset
        elif base is not None:
            base[:] = np.asarray(base_state, dtype=np.float64).reshape(1, layout.STATE_SIZE)
        reward, terms, *_ = self.core.landing(batch, np.array([at_rest]))
        return float(reward[0]), {name: float(value[0]) for name, value in terms.items()}

    # -- rendering --------------------------------------------------------------------------------
    def render(self):
        """See the class docstring: a frame ("rgb_array"), the frames since the last call
        ("rgb_array_list"), or the window ("human", playing a throw that just happened)."""
        if self.render_mode is None:
            gym.logger.warn(
                "render() was called without a render_mode; make the env with "
                'gymnasium.make("BoxToss-v0", render_mode="rgb_array") (or "human", "rgb_array_list")'
            )
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
        return self._renderer_for_env().frame(
            self._drawn_state(), float(episodes.target_x[0]), episodes.target_faces[0], caption, self._outcome
        )

    def _unseen_frames(self) -> list[np.ndarray]:
        """ "rgb_array_list": the frames since the last call, drawn now. A throw is drawn whole, with one
        camera fitted to it (from the hand on, unless the hand was returned already) and its result."""
        hand, throw = self._hand_unseen, self._throw_unseen
        self._hand_unseen = self._throw_unseen = False
        if throw:
            return self._renderer_for_env().throw_frames(
                self._throw_trajectory(),
                self.dt,
                float(self._episodes.target_x[0]),
                self._episodes.target_faces[0],
                self._outcome,
                skip_first=not hand,
            )
        return [self._draw_state("in the hand")] if hand else []

    def _renderer_for_env(self):
        if self._renderer is None:
            from box_toss_env.envs.render import ThrowRenderer

            self._renderer = ThrowRenderer(self.config, *self.render_size, fps=self.render_fps)
        if self.config.base_box:  # this episode's base box is drawn too
            self._renderer.other_boxes = 0.5 * self._episodes.base_size[:1]
        if self.config.draws_box_size:  # this episode's box
            self._renderer.half_extents = task.box_half_sizes(self._episodes, self.config)[0].copy()
        return self._renderer

    def _drawn_state(self) -> np.ndarray:
        """The state drawn: the thrown box's (6,), with a base box both boxes' (2, 6)."""
        return self._state if self.config.base_box else self._state[0]

    def _throw_trajectory(self) -> np.ndarray:
        """(T, 6) states of the last throw on the grid t = k dt, up to where it ended (the engine
        writes rows up to the step where the box fell asleep; later rows are left unwritten); with a base
        box (T, 2, 6), the thrown box first."""
        recorded = int(self._stats[0, layout.N_RECORDED])
        assert self._trajectory is not None  # recorded: the env draws
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


def _check_pixels(name: str, value) -> int:
    return check_integer(name, value, 16, 8192)


def pixel_renderer(config: task.TaskConfig, mode, size) -> PixelRenderer | None:
    """The renderer of ``observation_mode="pixels"`` observations at ``pixel_size`` (None for "state"), both
    checked: a ValueError or TypeError names the argument."""
    mode = check_choice("observation_mode", mode, OBSERVATION_MODES)
    if not isinstance(size, (tuple, list)) or len(size) != 2:
        raise TypeError(f"pixel_size must be a (width, height) pair of integers, got {size!r}")
    width, height = (check_integer(f"pixel_size[{k}]", value, 16, 1024) for k, value in enumerate(size))
    return PixelRenderer(config, width, height) if mode == "pixels" else None


def _document_arguments(env_class: type) -> None:
    """Write the arguments' declaration into the class docstring (its "Arguments" table) and the
    signature of ``__init__`` (what ``help()`` and ``inspect.signature`` show)."""
    if env_class.__doc__:  # None under python -OO
        env_class.__doc__ = env_class.__doc__.replace("    ARGUMENTS_TABLE", textwrap.indent(arguments_table(), "    "))
    parameters = [
        inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD),
        inspect.Parameter("render_mode", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=None),
    ]
    parameters += [inspect.Parameter(a.name, inspect.Parameter.KEYWORD_ONLY, default=a.default) for a in ENV_ARGUMENTS]
    env_class.__init__.__signature__ = inspect.Signature(parameters)  # type: ignore[misc]


_document_arguments(BoxTossEnv)
