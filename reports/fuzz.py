"""Property-based fuzz (hypothesis) of the engine and the env over their declared ranges.

Three fuzzes, each a strategy of examples and a check returning what an example violated ([] if nothing):

1. ``engine``: robust-solver scenes drawn over the robust solver's declared range (``DECLARED``, the same as
   the stability report's): the run is finite, no corner sinks below 5% of the box's smaller side, no
   recorded step gains energy (beyond rounding and m g times the deepest penetration, the potential
   energy of pushing it out), and the box either lies still on a face or ran the whole duration;
2. ``env_declared``: BoxToss-v0 made with arguments inside that declared range, one throw each with the
   robust solver: no exception at all (``EnergyGainError`` included), a finite observation inside the
   observation space, penetration below 5% of the smaller side;
3. ``env_accepted``: BoxToss-v0 made with arguments drawn anywhere in the ranges the env accepts
   (``task_config.ENV_RANGES``, docs/ranges.md), both solvers: making the env, resetting and throwing raise
   nothing but the documented ``EnergyGainError`` and ``NonFiniteStateError``, and what is returned is
   finite and inside the observation space.

Two profiles: ``REDUCED`` (a few seconds, run by the tests in CI) and ``FULL`` (run by
``python -m reports.stability``). Both draw with a fixed seed, so a profile always draws the same examples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from box_toss_env.envs import task_columns, task_config
from box_toss_env.physics import Box, NonFiniteStateError, Scene, simulate

PENETRATION_SHARE = 0.05  # of the box's smaller side
ENERGY_ROUNDING = 1e-9  # a step may gain this share of the starting energy (rounding)
GRAVITY = 9.81  # [m/s^2] of the engine scenes (the env's default)
FUZZ_SEED = 13  # hypothesis's seed: every run of a profile draws the same examples


@dataclass(frozen=True)
class Profile:
    """How much each fuzz draws and how long each example runs."""

    name: str
    examples: int  # per fuzz
    engine_duration: float  # [s] simulated per engine example
    env_max_sim_time: float  # [s] the most an env example's throw is simulated
    env_max_steps: int  # the most time steps of an env example (max_sim_time / dt)


REDUCED = Profile("reduced", examples=40, engine_duration=1.0, env_max_sim_time=2.0, env_max_steps=20_000)
FULL = Profile("full", examples=1000, engine_duration=5.0, env_max_sim_time=10.0, env_max_steps=400_000)

DECLARED = {
    "dt": (2.0**-14, 2.0**-5),  # [s]
    "penalty_stiffness": (1e2, 1e9),  # [N/m]
    "speed": (0.0, 200.0),  # [m/s] at the first impact, at most
    "spin": (0.0, 600.0),  # [rad/s]
    "aspect": (1.0, 200.0),  # length / width
    "mass": (1e-3, 1e3),  # [kg]
    "restitution": (0.0, 1.0),
    "friction": (0.0, 1.5),
    "distance": (0.0, 1e5),  # [m] from the origin
    "length": (0.02, 5.0),  # [m] of the longer side (the declared range names none; these are the fuzz's)
}
"""The robust solver's declared range (``reports.stability.DECLARED_RANGE``) as numbers."""


def log_uniform(st, low: float, high: float):
    """low * (high / low)^u, u uniform in [0, 1] (exactly low and high at the ends)."""
    return st.floats(0.0, 1.0).map(lambda u: min(max(low * (high / low) ** u, low), high))


# -- 1. the engine ---------------------------------------------------------------------------------------------
def engine_strategy():
    from hypothesis import strategies as st

    return st.fixed_dictionaries(
        {
            "length": log_uniform(st, *DECLARED["length"]),
            "aspect": log_uniform(st, *DECLARED["aspect"]),
            "mass": log_uniform(st, *DECLARED["mass"]),
            "height": st.floats(0.0, 3.0),  # [m] of the centre above the corner radius
            "x": st.floats(-DECLARED["distance"][1], DECLARED["distance"][1]),
            "angle": st.floats(-math.pi, math.pi),
            "speed": st.floats(*DECLARED["speed"]),
            "direction": st.floats(-math.pi, math.pi),
            "spin": st.floats(-DECLARED["spin"][1], DECLARED["spin"][1]),
            "restitution": st.floats(*DECLARED["restitution"]),
            "friction": st.floats(*DECLARED["friction"]),
            "penalty_stiffness": log_uniform(st, *DECLARED["penalty_stiffness"]),
            "dt": log_uniform(st, *DECLARED["dt"]),
        }
    )


def engine_scene(example: dict, solver: str = "robust") -> Scene:
    """The scene of an engine example. The release speed is chosen so that the box reaches the floor no faster
    than ``speed`` (the declared impact speed), whatever its height."""
    width = example["length"] / example["aspect"]
    radius = 0.5 * math.hypot(example["length"], width)
    fall = math.sqrt(2.0 * GRAVITY * (example["height"] + radius))
    launch = math.sqrt(max(example["speed"] ** 2 - fall**2, 0.0))
    box = Box(
        length=example["length"],
        width=width,
        mass=example["mass"],
        position=(example["x"], radius + example["height"]),
        angle=example["angle"],
        velocity=(launch * math.cos(example["direction"]), launch * math.sin(example["direction"])),
        spin=example["spin"],
    )
    return Scene(
        boxes=(box,),
        dt=example["dt"],
        gravity=-GRAVITY,
        restitution=example["restitution"],
        friction=example["friction"],
        penalty_stiffness=example["penalty_stiffness"],
        solver=solver,
    )


def check_engine(example: dict, duration: float, solver: str = "robust") -> list[str]:
    """What ``solver``'s run of ``example`` violates ([] if nothing)."""
    scene = engine_scene(example, solver)
    box = scene.boxes[0]
    try:
        result = simulate(scene, duration=duration, until_rest=True, record=True)
    except NonFiniteStateError as error:
        return [f"non-finite: {error}"]
    states = result.trajectory.state[:, 0]
    if not np.isfinite(states).all():
        return ["non-finite state"]
    problems = []
    angle = states[:, 2]
    lowest = states[:, 1] - 0.5 * box.length * np.abs(np.sin(angle)) - 0.5 * box.width * np.abs(np.cos(angle))
    depth = max(float(-lowest.min()), float(result.max_penetration[0]), 0.0)
    if depth >= PENETRATION_SHARE * min(box.length, box.width):
        problems.append(f"penetration {depth:.3g} m >= {PENETRATION_SHARE:g} of the smaller side")
    speed_squared = states[:, 3] ** 2 + states[:, 4] ** 2
    energy = (
        0.5 * box.mass * speed_squared + 0.5 * box.inertia * states[:, 5] ** 2 - box.mass * scene.gravity * states[:, 1]
    )
    # a step may gain rounding, and the potential energy of pushing out what penetrated (less than m g depth)
    gain = float(np.diff(energy).max(initial=0.0))
    if gain > ENERGY_ROUNDING * energy[0] + box.mass * GRAVITY * depth:
        step = int(np.diff(energy).argmax())
        problems.append(f"step {step} gains {gain / energy[0]:.3g} of the starting energy (penetration {depth:.3g} m)")
    if result.at_rest[0]:
        x, y, a, vx, vy, w = states[-1]
        flat = abs(math.remainder(a, 0.5 * math.pi)) <= 2e-3
        on_floor = abs(lowest[-1]) <= 1e-3 * (box.length + box.width)
        if not (flat and on_floor and vx == vy == w == 0.0):
            problems.append(f"asleep but not lying still on a face: {states[-1]}")
    elif result.end_time[0] < duration - 1e-9:
        problems.append(f"stopped at {result.end_time[0]:g} s, neither at rest nor at the end")
    return problems


# -- 2. and 3. the env -----------------------------------------------------------------------------------------
def env_declared_strategy(profile: Profile):
    """BoxToss-v0 keyword arguments inside the robust solver's declared range, a seed and an action."""
    from hypothesis import strategies as st

    def kwargs(d):
        width = d["length"] / d["aspect"]
        radius = 0.5 * math.hypot(d["length"], width)
        return {
            "box_length": d["length"],
            "box_width": width,
            "mass": d["mass"],
            "friction": d["friction"],
            "restitution": d["restitution"],
            "penalty_stiffness": d["penalty_stiffness"],
            "dt": d["dt"],
            "release_height_range": (radius + 0.01, radius + 0.01 + d["height"]),
            "release_x_range": (d["x"], d["x"]),
            "target_x_range": (d["x"], d["x"] + 4.0),
            "max_speed": d["max_speed"],
            "max_spin": d["max_spin"],
            "solver": "robust",
            "max_sim_time": min(profile.env_max_sim_time, profile.env_max_steps * d["dt"]),
        }

    return st.tuples(
        st.fixed_dictionaries(
            {
                "length": log_uniform(st, *DECLARED["length"]),
                "aspect": log_uniform(st, *DECLARED["aspect"]),
                "mass": log_uniform(st, *DECLARED["mass"]),
                "friction": st.floats(*DECLARED["friction"]),
                "restitution": st.floats(*DECLARED["restitution"]),
                "penalty_stiffness": log_uniform(st, *DECLARED["penalty_stiffness"]),
                "dt": log_uniform(st, *DECLARED["dt"]),
                "height": st.floats(0.0, 3.0),
                "x": st.floats(-996.0, 996.0),
                "max_speed": st.floats(1.0, 150.0),
                "max_spin": st.floats(0.0, DECLARED["spin"][1]),
            }
        ).map(kwargs),
        st.integers(0, 2**31 - 1),
        st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
    )


def env_accepted_strategy(profile: Profile):
    """BoxToss-v0 keyword arguments anywhere in ``task_config.ENV_RANGES`` (the step count capped by the profile), a
    solver, a seed and an action."""
    from hypothesis import strategies as st

    ranges = task_config.ENV_RANGES

    def positive(name, low=None):
        allowed = ranges[name]
        return log_uniform(st, low if low is not None else max(allowed.low, 1e-300), allowed.high)

    def pair(name, low, high):
        return st.tuples(st.floats(low, high), st.floats(low, high)).map(lambda p: (min(p), max(p)))

    def kwargs(d):
        radius = 0.5 * math.hypot(d["box_length"], d["box_width"])
        low_height = min(radius * (1.0 + d["clearance"]), ranges["release_height_range"].high)
        if low_height <= radius:  # a box too big to be released under the highest allowed height
            low_height = math.nextafter(radius, math.inf)
        d = dict(d)
        d["release_height_range"] = (
            low_height,
            min(low_height * (1.0 + d.pop("height_span")), ranges["release_height_range"].high),
        )
        d.pop("clearance")
        d["max_sim_time"] = min(d["max_sim_time"], profile.env_max_steps * d["dt"])
        return d

    return st.tuples(
        st.fixed_dictionaries(
            {
                "box_length": positive("box_length"),
                "box_width": positive("box_width"),
                "mass": positive("mass"),
                "friction": st.floats(ranges["friction"].low, ranges["friction"].high),
                "restitution": st.floats(0.0, 1.0),
                "penalty_stiffness": st.one_of(st.just(0.0), log_uniform(st, 1e-3, 1e15)),
                "gravity": positive("gravity"),
                "release_x_range": pair(
                    "release_x_range", ranges["release_x_range"].low, ranges["release_x_range"].high
                ),
                "release_angle_range": pair("release_angle_range", -math.pi, math.pi),
                "target_x_range": pair("target_x_range", ranges["target_x_range"].low, ranges["target_x_range"].high),
                "launch_angle_range": pair("launch_angle_range", -math.pi, math.pi),
                "max_speed": positive("max_speed", 1e-3),
                "max_spin": st.floats(0.0, ranges["max_spin"].high),
                "dt": positive("dt"),
                "max_sim_time": positive("max_sim_time", 1e-3),
                "clearance": st.floats(1e-6, 10.0),
                "height_span": st.floats(0.0, 10.0),
                "target_face": st.sampled_from(task_columns.TARGET_FACE_KINDS),
                "solver": st.sampled_from(("robust", "seed")),
            }
        ).map(kwargs),
        st.integers(0, 2**31 - 1),
        st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
    )


def throw_once(kwargs: dict, seed: int, action) -> tuple[object, object, dict]:
    """(env, the step's result, the reset's observation) of one throw; exceptions propagate."""
    import gymnasium as gym

    import box_toss_env  # noqa: F401  (registers the ids)

    env = gym.make("BoxToss-v0", **kwargs).unwrapped
    observation, _ = env.reset(seed=seed)
    return env, env.step(np.asarray(action, dtype=np.float32)), observation


def returned_problems(env, step, reset_observation) -> list[str]:
    """What is wrong with what reset and step returned: non-finite values, or observations outside the space."""
    observation, reward, terminated, truncated, info = step
    problems = []
    for name, obs in (("reset", reset_observation), ("step", observation)):
        if not np.isfinite(obs).all():
            problems.append(f"{name} observation not finite: {obs}")
        elif not env.observation_space.contains(obs):
            problems.append(f"{name} observation outside the observation space: {obs}")
    if not math.isfinite(reward):
        problems.append(f"reward {reward}")
    for key, value in info.items():
        if isinstance(value, float) and not math.isfinite(value):
            problems.append(f"info[{key!r}] = {value}")
    if not terminated or truncated:
        problems.append("a throw did not terminate")
    return problems


def check_env_declared(example) -> list[str]:
    """What a robust throw with arguments inside the declared range violates ([] if nothing)."""
    kwargs, seed, action = example
    try:
        env, step, reset_observation = throw_once(kwargs, seed, action)
    except Exception as error:  # noqa: BLE001  (any exception is the finding)
        return [f"{type(error).__name__}: {error}"]
    problems = returned_problems(env, step, reset_observation)
    depth = step[4]["max_penetration"]
    if depth >= PENETRATION_SHARE * min(kwargs["box_length"], kwargs["box_width"]):
        problems.append(f"penetration {depth:.3g} m >= {PENETRATION_SHARE:g} of the smaller side")
    return problems


def accepted_throw_outcome(example) -> tuple[list[str], str]:
    """(what a throw with arguments anywhere in the accepted ranges violates, the name of the documented error it
    raised or ""): an exception other than the documented EnergyGainError and NonFiniteStateError, or a
    returned value that is not finite or outside the observation space, is a violation."""
    from box_toss_env.envs.functional import EnergyGainError

    kwargs, seed, action = example
    try:
        env, step, reset_observation = throw_once(kwargs, seed, action)
    except (EnergyGainError, NonFiniteStateError) as error:
        return [], type(error).__name__
    except Exception as error:  # noqa: BLE001  (any other exception is the finding)
        return [f"{type(error).__name__}: {error}"], ""
    return returned_problems(env, step, reset_observation), ""


def check_env_accepted(example) -> list[str]:
    """What a throw with arguments anywhere in the accepted ranges violates ([] if nothing)."""
    return accepted_throw_outcome(example)[0]


# -- running a fuzz ---------------------------------------------------------------------------------------------
@dataclass
class FuzzResult:
    name: str
    examples: int
    failures: list[tuple[object, list[str]]] = field(default_factory=list)  # (example, what it violated)
    documented_errors: dict = field(default_factory=dict)  # env_accepted: (solver, error name) -> throws

    @property
    def passed(self) -> bool:
        return not self.failures


FUZZES = ("engine", "env_declared", "env_accepted")


def strategy_and_check(name: str, profile: Profile):
    if name == "engine":
        return engine_strategy(), lambda example: check_engine(example, profile.engine_duration)
    if name == "env_declared":
        return env_declared_strategy(profile), check_env_declared
    if name == "env_accepted":
        return env_accepted_strategy(profile), check_env_accepted
    raise ValueError(f"fuzz must be one of {FUZZES}, got {name!r}")


def draw_examples(strategy, count: int) -> list:
    """``count`` examples of ``strategy``, drawn with ``FUZZ_SEED`` (the same ones every run)."""
    from hypothesis import HealthCheck, Phase, given, seed, settings

    drawn = []

    def keep(example):
        drawn.append(example)

    # a fixed seed, not derandomize=True: a derandomized run draws differently after other hypothesis runs in
    # the same process (measured), a seeded one does not
    seed(FUZZ_SEED)(
        settings(
            max_examples=count,
            database=None,
            deadline=None,
            phases=[Phase.generate],
            suppress_health_check=list(HealthCheck),
        )(given(strategy)(keep))
    )()
    return drawn


def run_fuzz(name: str, profile: Profile) -> FuzzResult:
    """Every example of one fuzz under ``profile``, with what each failing one violated."""
    strategy, check = strategy_and_check(name, profile)
    examples = draw_examples(strategy, profile.examples)
    result = FuzzResult(name, len(examples))
    for example in examples:
        if name == "env_accepted":
            problems, error = accepted_throw_outcome(example)
            if error:
                key = (example[0]["solver"], error)
                result.documented_errors[key] = result.documented_errors.get(key, 0) + 1
        else:
            problems = check(example)
        if problems:
            result.failures.append((example, problems))
    return result
