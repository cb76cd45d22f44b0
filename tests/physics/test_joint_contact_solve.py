"""The joint normal-and-friction solve (``joint_contact_solve``): on random small contact sets between two boxes
and the floor, the impulses it returns meet every condition of the 2D Coulomb contact LCP, and they are the
impulses the alternation of exact normal solves and friction sweeps converges to."""

import numba
import numpy as np
import pytest

from box_toss_env.physics.colliding.narrowphase import (
    BODY1,
    BODY2,
    CONTACT_COLUMNS,
    FRICTION,
    FRICTION_IMPULSE,
    ID_COLUMNS,
    IMPULSE,
    NORMAL_MASS,
    NX,
    NY,
    R1X,
    R1Y,
    R2X,
    R2Y,
    TANGENT_MASS,
    TARGET,
)
from box_toss_env.physics.colliding.normal_lcp import delassus_matrix, normal_lcp
from box_toss_env.physics.colliding.parallel import make_partition
from box_toss_env.physics.colliding.prepare import apply_impulse, relative_velocity
from box_toss_env.physics.colliding.solve import solve_jointly as joint_solve
from box_toss_env.physics.colliding.solve import warm_start_holds as holds
from box_toss_env.physics.colliding.state import Bodies, Contacts, make_exact_work
from box_toss_env.physics.colliding.sweeps import friction_sweep
from box_toss_env.physics.tunables import DIRECT_LIMIT

LIMIT = DIRECT_LIMIT


@numba.njit(cache=False)
def solve_jointly(contacts, ids, count, vel, inv_mass, inv_inertia):
    exact = make_exact_work(vel.shape[0])
    none = np.zeros((vel.shape[0], 3))
    bodies = Bodies(none, vel, none[:, :2], none, inv_mass, inv_inertia, inv_mass)
    partition, spare = make_partition(count)
    rows = Contacts(contacts, ids, np.zeros(count, np.bool_), np.zeros(count, np.int64), partition, spare)
    solved = joint_solve(rows, count, bodies, exact)
    return solved, exact.state[:count].copy()


@numba.njit(cache=False)
def solve_by_alternation(contacts, ids, count, vel, inv_mass, inv_inertia, rounds):
    """The exact normal solve alternating with friction sweeps (``solve_velocities``' path past JOINT_LIMIT)."""
    w, factor = np.zeros((LIMIT, LIMIT)), np.zeros((LIMIT, LIMIT))
    free, x, y = np.zeros(LIMIT), np.zeros(LIMIT), np.zeros(LIMIT)
    active, index = np.zeros(LIMIT, np.bool_), np.zeros(LIMIT, np.int64)
    delassus_matrix(contacts, ids, count, inv_mass, inv_inertia, w)
    for _ in range(rounds):
        for c in range(count):
            ux, uy = relative_velocity(c, contacts, ids, vel)
            value = ux * contacts[c, NX] + uy * contacts[c, NY] - contacts[c, TARGET]
            for d in range(count):
                value -= w[c, d] * contacts[d, IMPULSE]
            free[c] = value
            active[c] = active[c] or free[c] < 0.0
        if not normal_lcp(w, free, x, active, count, factor, index, y):
            return False
        for c in range(count):
            dp = x[c] - contacts[c, IMPULSE]
            contacts[c, IMPULSE] = x[c]
            apply_impulse(c, dp * contacts[c, NX], dp * contacts[c, NY], contacts, ids, vel, inv_mass, inv_inertia)
        friction_sweep(contacts, ids, count, vel, inv_mass, inv_inertia)
    return True


def contact_set(rng: np.random.Generator):
    """A box (body 0) resting on another (body 1) that lies on the floor, both moving: two contacts between them
    along the base's top, two or three of the base on the floor, random lever arms, friction, velocities, targets
    and warm-start impulses, and each contact's effective masses."""
    rows = []
    for _ in range(2):  # box on base: n from the base into the box (up), r1 on the box, r2 on the base
        x = rng.uniform(-0.3, 0.3)
        rows.append((0, 1, 0.0, 1.0, x, -0.1, x, 0.1))
    for _ in range(int(rng.integers(2, 4))):  # base on the floor
        x = rng.uniform(-0.4, 0.4)
        rows.append((1, -1, 0.0, 1.0, x, -0.1, 0.0, 0.0))
    count = len(rows)
    contacts = np.zeros((count, CONTACT_COLUMNS))
    ids = np.zeros((count, ID_COLUMNS), np.int64)
    for c, (b1, b2, nx, ny, r1x, r1y, r2x, r2y) in enumerate(rows):
        ids[c, BODY1], ids[c, BODY2] = b1, b2
        contacts[c, [NX, NY, R1X, R1Y, R2X, R2Y]] = nx, ny, r1x, r1y, r2x, r2y
        contacts[c, FRICTION] = rng.uniform(0.1, 1.0)
        contacts[c, TARGET] = -rng.uniform(0.0, 0.05)
        contacts[c, IMPULSE] = rng.uniform(0.0, 0.5) * (rng.random() < 0.5)
        contacts[c, FRICTION_IMPULSE] = contacts[c, FRICTION] * contacts[c, IMPULSE] * rng.uniform(-1.0, 1.0)
    mass = rng.uniform(0.5, 5.0, 2)
    inv_mass = 1.0 / mass
    inv_inertia = 1.0 / (mass * (0.4**2 + 0.2**2) / 3.0)
    for c in range(count):  # effective masses 1 / (n . K n), 1 / (t . K t), as ``prepare.prepare_contact``'s
        b1, b2 = ids[c, BODY1], ids[c, BODY2]
        nx, ny = contacts[c, NX], contacts[c, NY]
        rn1 = contacts[c, R1X] * ny - contacts[c, R1Y] * nx
        rt1 = contacts[c, R1X] * nx + contacts[c, R1Y] * ny
        k_n = inv_mass[b1] + rn1 * rn1 * inv_inertia[b1]
        k_t = inv_mass[b1] + rt1 * rt1 * inv_inertia[b1]
        if b2 >= 0:
            rn2 = contacts[c, R2X] * ny - contacts[c, R2Y] * nx
            rt2 = contacts[c, R2X] * nx + contacts[c, R2Y] * ny
            k_n += inv_mass[b2] + rn2 * rn2 * inv_inertia[b2]
            k_t += inv_mass[b2] + rt2 * rt2 * inv_inertia[b2]
        contacts[c, NORMAL_MASS] = 1.0 / k_n
        contacts[c, TANGENT_MASS] = 1.0 / k_t
    vel = np.column_stack([rng.normal(0.0, 0.5, 2), rng.normal(-0.5, 0.5, 2), rng.normal(0.0, 2.0, 2)])
    return contacts, ids, count, vel, inv_mass, inv_inertia


def contact_speeds(contacts, ids, count, vel):
    """(u_n - target, u_t) of every contact."""
    normal, slip = np.zeros(count), np.zeros(count)
    for c in range(count):
        b1, b2 = ids[c, BODY1], ids[c, BODY2]
        ux = vel[b1, 0] - vel[b1, 2] * contacts[c, R1Y]
        uy = vel[b1, 1] + vel[b1, 2] * contacts[c, R1X]
        if b2 >= 0:
            ux -= vel[b2, 0] - vel[b2, 2] * contacts[c, R2Y]
            uy -= vel[b2, 1] + vel[b2, 2] * contacts[c, R2X]
        nx, ny = contacts[c, NX], contacts[c, NY]
        normal[c] = ux * nx + uy * ny - contacts[c, TARGET]
        slip[c] = -ux * ny + uy * nx
    return normal, slip


@pytest.mark.parametrize("seed", range(40))
def test_the_joint_solve_meets_the_coulomb_contact_conditions(seed):
    contacts, ids, count, vel, inv_mass, inv_inertia = contact_set(np.random.default_rng(seed))
    solved, _ = solve_jointly(contacts, ids, count, vel, inv_mass, inv_inertia)
    if not solved:
        pytest.skip("the states did not settle: the caller solves by alternation (counted below)")
    normal, slip = contact_speeds(contacts, ids, count, vel)
    p, q, mu = contacts[:count, IMPULSE], contacts[:count, FRICTION_IMPULSE], contacts[:count, FRICTION]
    scale = 1e-9 * (1.0 + np.abs(vel).max())
    assert np.all(p >= 0.0)
    assert np.all(normal >= -scale), "a contact penetrates"
    assert np.all(np.abs(p * normal) <= scale * (1.0 + p)), "a contact pushes while separating"
    assert np.all(np.abs(q) <= mu * p * (1.0 + 1e-9) + 1e-15), "friction outside the cone"
    sticking = np.abs(q) < mu * p * (1.0 - 1e-9)
    assert np.all(np.abs(slip[sticking]) <= scale), "a sticking contact slips"
    sliding = (p > 0.0) & ~sticking
    assert np.all(q[sliding] * slip[sliding] <= scale * np.abs(q[sliding])), "friction drives the slip"


def test_the_joint_solve_settles_on_nearly_every_contact_set_and_agrees_with_the_alternation():
    settled = 0
    for seed in range(40):
        joint = contact_set(np.random.default_rng(seed))
        alternation = contact_set(np.random.default_rng(seed))
        solved, _ = solve_jointly(*joint)
        if not solved:
            continue
        settled += 1
        assert solve_by_alternation(*alternation, 2000)
        # the velocities after the impulses (unique where the impulses may not be: redundant floor contacts)
        np.testing.assert_allclose(joint[3], alternation[3], atol=1e-6)
    assert settled >= 36


@numba.njit(cache=False)
def warm_start_holds(contacts, ids, count, vel, use_friction):
    return holds(contacts, ids, count, vel, use_friction)


@pytest.mark.parametrize("seed", range(40))
def test_the_warm_start_check_passes_a_solved_set_and_nothing_short_of_it(seed):
    # ``solve.warm_start_holds`` lets the exact solves skip a contact set whose impulses already solve it: it must
    # pass the joint solve's solution and fail the random impulses before it and the solution with a loaded body nudged
    contacts, ids, count, vel, inv_mass, inv_inertia = contact_set(np.random.default_rng(seed))
    assert not warm_start_holds(contacts, ids, count, vel, True)
    solved, _ = solve_jointly(contacts, ids, count, vel, inv_mass, inv_inertia)
    if not solved:
        pytest.skip("the states did not settle: the caller solves by alternation")
    if contacts[:count, IMPULSE].sum() == 0.0:
        pytest.skip("every contact separates: nothing for the check to weigh (it returns False)")
    assert warm_start_holds(contacts, ids, count, vel, True)
    nudged = vel.copy()  # the body of the most loaded contact moved along y by a micrometre a second
    nudged[ids[np.argmax(contacts[:count, IMPULSE]), BODY1], 1] -= 1e-6 * (1.0 + np.abs(vel).max())
    assert not warm_start_holds(contacts, ids, count, nudged, True)
