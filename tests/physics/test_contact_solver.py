"""The contact stages against their definitions: the corner LCP's complementarity conditions, and the exact
one-corner friction solve against Gauss-Seidel run to convergence."""

import math
import os
import subprocess
import sys

import numba
import numpy as np
import pytest

from box_toss_env.physics.robust import contact_solver as cs

# The stages have no Python wrapper (they are compiled to be called from compiled code only), so their
# checks run in plain Python: this module again, in a subprocess with NUMBA_DISABLE_JIT=1 (same source).
compiled = pytest.mark.skipif(not numba.config.DISABLE_JIT, reason="run in plain Python by the test below")


@pytest.mark.skipif(bool(numba.config.DISABLE_JIT), reason="already plain Python")
def test_the_stages_pass_their_checks_in_plain_python():
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", __file__],
        env={**os.environ, "NUMBA_DISABLE_JIT": "1"},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "4 passed" in done.stdout, done.stdout  # every check below ran


def random_corners(rng, n):
    """n corners of a random box at a random angle, with random targets b_i <= 0."""
    length, width = rng.uniform(0.05, 2.0), rng.uniform(0.005, 1.0)
    angle = rng.uniform(-math.pi, math.pi)
    signs = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    corners = np.zeros((cs.CORNER_ROWS, cs.MAX_CORNERS))
    for i, (sx, sy) in enumerate(signs[:n]):
        bx, by = 0.5 * sx * length, 0.5 * sy * width
        corners[cs.RX, i] = math.cos(angle) * bx - math.sin(angle) * by
        corners[cs.RY, i] = math.sin(angle) * bx + math.cos(angle) * by
        corners[cs.TARGET, i] = -rng.exponential(0.5) if rng.uniform() < 0.5 else 0.0
    mass = 10.0 ** rng.uniform(-3, 3)
    inertia = mass * (length**2 + width**2) / 12.0
    return corners, 1.0 / mass, 1.0 / inertia


@compiled
@pytest.mark.parametrize("n", [1, 2, 3])
def test_normal_impulses_solve_the_corner_lcp(n):
    """lam_i >= 0, u_i' >= b_i and lam_i (u_i' - b_i) = 0 for every corner, to rounding."""
    rng = np.random.default_rng(n)
    k = np.zeros((cs.MAX_CORNERS, cs.MAX_CORNERS))
    for _ in range(500):
        corners, inv_mass, inv_inertia = random_corners(rng, n)
        vy, spin = rng.normal(0.0, 3.0), rng.normal(0.0, 20.0)
        cs.delassus(corners, n, inv_mass, inv_inertia, k)
        corners[cs.IMPULSE, :] = 0.0
        vy2, spin2 = cs.solve_normal_block(vy, spin, corners, n, inv_mass, inv_inertia, k)
        scale = abs(vy) + abs(spin) * 2.0 + 1.0
        for i in range(n):
            lam, w = corners[cs.IMPULSE, i], vy2 + spin2 * corners[cs.RX, i] - corners[cs.TARGET, i]
            assert lam >= 0.0
            assert w >= -1e-9 * scale
            assert lam * w <= 1e-9 * scale * (lam + 1.0)


@compiled
def test_one_corner_with_friction_is_solved_exactly():
    """The closed form meets every condition that defines the one-corner contact with Coulomb friction (which
    fix it uniquely): u_n' >= b, lam >= 0, lam (u_n' - b) = 0, |q| <= mu lam, and q = -mu lam sign(u_t') while
    the corner slips. (Gauss-Seidel sweeps, its fallback, stall short of this: their stopping test compares
    successive sweeps, not the conditions.)"""
    rng = np.random.default_rng(0)
    checked = 0
    for _ in range(2000):
        corners, inv_mass, inv_inertia = random_corners(rng, 1)
        vx, vy, spin = rng.normal(0.0, 2.0), rng.normal(-1.0, 2.0), rng.normal(0.0, 10.0)
        friction = rng.uniform(0.0, 1.5)
        vx2, vy2, spin2, solved = cs.solve_one_corner(vx, vy, spin, corners, friction, inv_mass, inv_inertia)
        if not solved:
            continue
        rx, ry, target = corners[cs.RX, 0], corners[cs.RY, 0], corners[cs.TARGET, 0]
        lam, q = corners[cs.IMPULSE, 0], (vx2 - vx) / inv_mass
        assert lam == pytest.approx((vy2 - vy) / inv_mass, rel=1e-9, abs=1e-12)
        assert spin2 - spin == pytest.approx((rx * lam - ry * q) * inv_inertia, rel=1e-9, abs=1e-9)
        scale = abs(vx) + abs(vy) + abs(spin) + 1.0
        gap_rate = vy2 + spin2 * rx - target
        assert lam >= 0.0 and gap_rate >= -1e-9 * scale and lam * gap_rate <= 1e-9 * scale * (lam + 1.0)
        assert abs(q) <= friction * lam * (1 + 1e-9) + 1e-12
        slip = vx2 - spin2 * ry
        if abs(slip) > 1e-9 * scale:
            assert q == pytest.approx(-math.copysign(friction * lam, slip), rel=1e-9, abs=1e-12)
        checked += 1
    assert checked > 1900
