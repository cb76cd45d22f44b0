"""The friction law is one module's (``physics.contact_law``): a frictionless law swapped in there, before anything
compiles, is followed by every solver and every tier of the colliding solver's solve. A box sliding on the floor
(or on a box) keeps its speed under it, closed form, where the Coulomb law stops it."""

import json
import os
import subprocess
import sys

import pytest

from box_toss_env.physics import Box, Scene, simulate
from box_toss_env.physics.tunables import DIRECT_LIMIT, EXACT_MASS_RATIO, JOINT_LIMIT

SPEED = 1.0  # [m/s] of every sliding box
DURATION = 0.1  # [s]: Coulomb friction (mu g = 4.9 m/s^2) takes 0.49 m/s off in it

SOLVERS = {
    # name: (solver, boxes collide, sliding pairs, solver_tolerance, how near the frictionless speeds [m/s], mass of
    # the box under each sliding one [kg])
    "floor robust": ("robust", False, 1, 1e-9, 1e-9, 2.0),
    "floor seed": ("seed", False, 1, 1e-9, 1e-9, 2.0),
    # the seed scheme's box-box penalty forces act along normals a little off the vertical: two frictionless boxes
    # exchange 1.4e-4 m/s of horizontal speed in DURATION (their momentum is kept; the same with friction 0)
    "colliding seed": ("seed", True, 1, 1e-9, 1e-3, 2.0),
    "colliding joint LCP": ("robust", True, 1, 1e-9, 1e-9, 2.0),  # 4 contacts <= JOINT_LIMIT
    "colliding alternation": ("robust", True, 3, 1e-9, 1e-9, 20.0),  # 12 contacts, masses 10:1 (solve.exact_pays)
    # like masses, more contacts than JOINT_LIMIT: the sweeps, which stop short of the exact impulses, and the sliding
    # box loses 4.5e-6 m/s in DURATION (the same, bit for bit, with friction 0 under the Coulomb law)
    "colliding sweeps": ("robust", True, 3, 1e-6, 1e-5, 2.0),
}


def sliding_scene(solver: str, boxes_collide: bool, pairs: int, tolerance: float, lower: float = 2.0) -> Scene:
    """Boxes lying on the floor, sliding at SPEED. Boxes that collide come in pairs a metre apart: a box at rest
    on the floor (``lower`` kg), a box sliding on it."""
    box = dict(length=0.4, width=0.2, mass=2.0)
    if boxes_collide:
        base = dict(length=0.4, width=0.2, mass=lower)
        boxes = tuple(
            b
            for k in range(pairs)
            for b in (Box(**base, position=(k, 0.1)), Box(**box, position=(k, 0.3), velocity=(SPEED, 0.0)))
        )
    else:
        boxes = (Box(**box, position=(0.0, 0.1), velocity=(SPEED, 0.0)),)
    return Scene(
        boxes=boxes,
        friction=0.5,
        restitution=0.3,
        penalty_stiffness=1e5,
        dt=1 / 256 if solver == "robust" else 1 / 1024,
        solver=solver,
        solver_tolerance=tolerance,
        boxes_collide=boxes_collide,
    )


def final_speeds() -> dict[str, list[float]]:
    """Each scene's final horizontal speed of every box."""
    return {
        name: simulate(sliding_scene(*case[:4], lower=case[5]), duration=DURATION).final_state[:, 3].tolist()
        for name, case in SOLVERS.items()
    }


FRICTIONLESS_PROBE = """
import json, sys

import box_toss_env.physics.contact_law as law
from box_toss_env.physics.compile.compilation import jit_stage


@jit_stage(inline="always")
def no_friction(mu):
    return 0.0


# every module that took the law's friction_slope by name takes the frictionless one (nothing is compiled yet)
coulomb, rebound = law.friction_slope, []
for name, module in list(sys.modules.items()):
    if name.startswith("box_toss_env.physics") and getattr(module, "friction_slope", None) is coulomb:
        rebound.append(name)
        module.friction_slope = no_friction
sys.path.insert(0, sys.argv[1])
from test_contact_law import final_speeds

print(json.dumps({"rebound": sorted(rebound), "speeds": final_speeds()}))
"""


@pytest.fixture(scope="module")
def frictionless(tmp_path_factory):
    """The final speeds under a frictionless law, in a fresh process with an empty numba cache (so that every
    stage is compiled with the swapped law)."""
    cache = tmp_path_factory.mktemp("numba_cache")
    out = subprocess.run(
        [sys.executable, "-c", FRICTIONLESS_PROBE, os.path.dirname(__file__)],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_cases_reach_every_tier_of_the_solve():
    assert 4 <= JOINT_LIMIT < 12 <= DIRECT_LIMIT and 1.0 < EXACT_MASS_RATIO < 10.0


def test_coulomb_friction_slows_every_sliding_box():
    for name, speeds in final_speeds().items():
        sliding = speeds[1::2] if SOLVERS[name][1] else speeds
        assert max(sliding) < 0.7 * SPEED, name


def test_every_solver_follows_a_frictionless_law(frictionless):
    # the law is read from contact_law by every solver (the frictionless slope is the only change)
    assert {"contact_law", "colliding.joint_contact_solve", "robust.contact_solver"} <= {
        name.removeprefix("box_toss_env.physics.") for name in frictionless["rebound"]
    }
    assert set(frictionless["speeds"]) == set(SOLVERS)
    off = {}
    for name, speeds in frictionless["speeds"].items():
        _, boxes_collide, pairs, _, near, _ = SOLVERS[name]
        # alone, or on a box at rest: the sliding box keeps SPEED, the box under it is not dragged along
        expected = [0.0, SPEED] * pairs if boxes_collide else [SPEED]
        if speeds != pytest.approx(expected, abs=near):
            off[name] = speeds
    assert off == {}
