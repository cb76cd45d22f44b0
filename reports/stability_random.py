"""The stability report's random scenes (hypothesis): random single-box scenes inside the declared range,
the failures shrunk to their smallest."""

from __future__ import annotations

import math

from box_toss_env.physics import Box, Scene

from .cases import dt_of
from .stability_checks import SOLVERS, Check, Row, run_scene
from .stability_rows import energy_check

# -- random scenes (hypothesis) ---------------------------------------------------------------------------------
RANDOM_FIELDS = (
    "length",
    "aspect",
    "log_mass",
    "height",
    "angle",
    "vx",
    "vy",
    "spin",
    "restitution",
    "friction",
    "log_stiffness",
    "dt_exponent",
)
KNOWN_EXAMPLES = ((1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 5),)
"""Examples always run (hypothesis ``@example``): the smallest robust failure found so far, kept as a regression."""


def random_strategy():
    from hypothesis import strategies as st

    return st.tuples(
        st.floats(0.05, 2.0),
        st.floats(1.0, 200.0),
        st.floats(-3.0, 3.0),
        st.floats(0.0, 3.0),
        st.floats(-math.pi, math.pi),
        st.floats(-50.0, 50.0),
        st.floats(-50.0, 50.0),
        st.floats(-200.0, 200.0),
        st.floats(0.0, 1.0),
        st.floats(0.0, 1.5),
        st.floats(2.0, 9.0),
        st.integers(5, 14),
    )


def random_scene(example, solver: str) -> Scene:
    """A box of length L and width L / aspect, mass 10^log_mass, its centre ``height`` above the corner radius
    (so it starts clear of the floor at any angle), thrown anywhere, on any material."""
    length, aspect, log_mass, height, angle, vx, vy, spin, restitution, friction, log_k, exponent = example
    width = length / aspect
    box = Box(
        length=length,
        width=width,
        mass=10.0**log_mass,
        position=(0.0, 0.5 * math.hypot(length, width) + height),
        angle=angle,
        velocity=(vx, vy),
        spin=spin,
    )
    return Scene(
        boxes=(box,),
        restitution=restitution,
        friction=friction,
        penalty_stiffness=10.0**log_k,
        dt=dt_of(int(exponent)),
        solver=solver,
    )


def random_check(example, solver: str) -> Check:
    point = {"example": "(" + ", ".join(f"{v:.4g}" for v in example) + ")"}
    return energy_check(run_scene(random_scene(example, solver), 2.0), point, solver)


def random_examples(count: int) -> list[tuple]:
    """``count`` examples drawn by hypothesis (derandomized, so the report is reproducible), after the known ones."""
    from hypothesis import HealthCheck, Phase, example, given, settings

    drawn = []

    def keep(example):
        drawn.append(example)

    body = given(random_strategy())(keep)
    for known in KNOWN_EXAMPLES:
        body = example(known)(body)
    settings(
        max_examples=count,
        derandomize=True,
        database=None,
        deadline=None,
        phases=[Phase.explicit, Phase.generate],
        suppress_health_check=list(HealthCheck),
    )(body)()
    return drawn


def shrink_failure(solver: str, max_examples: int) -> tuple | None:
    """The smallest example hypothesis finds on which ``solver`` fails, or None."""
    from hypothesis import HealthCheck, find, settings
    from hypothesis.errors import NoSuchExample

    try:
        return find(
            random_strategy(),
            lambda example: not random_check(example, solver).passed,
            settings=settings(
                max_examples=max_examples,
                derandomize=True,
                database=None,
                deadline=None,
                suppress_health_check=list(HealthCheck),
            ),
        )
    except NoSuchExample:
        return None


def random_scenes(count: int, shrink: bool) -> Row:
    checks = [random_check(example, solver) for example in random_examples(count) for solver in SOLVERS]
    row = Row(
        "random_scenes",
        "Random scenes (hypothesis)",
        "finite; energy never rises above its start without input (allowance: rounding and m g times the "
        "deepest penetration); 2 s each",
        f"{count} drawn examples plus {len(KNOWN_EXAMPLES)} kept one(s): length 0.05 to 2 m, aspect 1 to 200, "
        "mass 1e-3 to 1e3 kg, any angle, |v| components up to 50 m/s, spin up to 200 rad/s, e 0 to 1, "
        "mu 0 to 1.5, k 1e2 to 1e9 N/m, dt 2^-14 to 2^-5 s",
        checks,
    )
    row.smallest_failure = shrink_failure("robust", 500) if shrink and not row.passed("robust") else None
    return row
