"""The property-based fuzz of the engine and the env over their declared ranges, reduced profile (a few
seconds; ``python -m reports.stability`` runs the full one)."""

import math

from hypothesis import HealthCheck, given, settings

from reports import fuzz

REDUCED = settings(
    max_examples=fuzz.REDUCED.examples,
    derandomize=True,
    database=None,
    deadline=None,
    suppress_health_check=list(HealthCheck),
)


@REDUCED
@given(fuzz.engine_strategy())
def test_robust_engine_over_its_declared_range(example):
    assert fuzz.check_engine(example, fuzz.REDUCED.engine_duration) == []


@REDUCED
@given(fuzz.env_declared_strategy(fuzz.REDUCED))
def test_env_over_the_declared_range_raises_nothing_and_keeps_boxes_out_of_the_floor(example):
    assert fuzz.check_env_declared(example) == []


@REDUCED
@given(fuzz.env_accepted_strategy(fuzz.REDUCED))
def test_env_over_its_accepted_ranges_raises_only_documented_errors(example):
    assert fuzz.check_env_accepted(example) == []


def test_the_engine_check_catches_what_the_seed_scheme_does_wrong():
    """The same properties flag the seed scheme where it is known to fail (a stiff penalty at a coarse step),
    so a passing fuzz means something."""
    example = {
        "length": 0.4,
        "aspect": 2.0,
        "mass": 2.0,
        "height": 1.0,
        "x": 0.0,
        "angle": 0.3,
        "speed": 5.0,
        "direction": -0.5 * math.pi,
        "spin": 0.0,
        "restitution": 0.3,
        "friction": 0.5,
        "penalty_stiffness": 1e5,
        "dt": 2.0**-5,
    }
    assert fuzz.check_engine(example, 2.0, solver="robust") == []
    problems = fuzz.check_engine(example, 2.0, solver="seed")
    assert problems and any("energy" in p or "non-finite" in p or "penetration" in p for p in problems)


def test_the_env_check_catches_a_box_under_the_floor():
    """A throw of the seed scheme without a penalty sinks: the declared-range check says so."""
    kwargs = {"box_length": 0.4, "box_width": 0.2, "solver": "seed", "penalty_stiffness": 0.0, "dt": 1 / 128}
    problems = fuzz.check_env_declared((kwargs, 0, [0.0, 0.0, 0.0]))
    assert problems and ("EnergyGainError" in problems[0] or "penetration" in problems[0])
