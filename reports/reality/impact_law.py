"""Impact laws applied to one measured impact at a time: the engine's own (the robust solver's
``impact_impulses``: Poisson restitution with Coulomb friction, exact for one contact point) and the plain
point-contact Newton + Coulomb map, both as compiled calls of the engine's stages on arrays of impacts.

One contact point with lever arm (rx, ry) from the centre of mass, floor normal (0, 1):
    u_n = vy + omega rx,  u_t = vx - omega ry
(for a generalised contact Jacobian with normal row (0, 1, n3) and tangent row (1, 0, d3): rx = n3, ry = -d3).

- ``ours``: compression stops the approach (sticking, or sliding with the impulse on the friction cone), then
  restitution adds e times the compression impulse with friction clamped to mu times it (it can stop the slip,
  never reverse it): ``restitution.impact_impulses`` with one corner, unchanged.
- ``newton``: u_n+ = -e u_n- and Coulomb friction on the whole impulse (sticking u_t+ = 0 if inside the cone,
  else sliding with |q| = mu lam): ``contact_solver.solve_one_corner`` with the target -e u_n-.

The normalised velocity error of a prediction v against the measured v* is |W (v - v*)| / |W v*| with
W = (1, 1, radius of gyration) (Fazeli et al. 2017): 1 for predicting zero velocity.
"""

from __future__ import annotations

import numpy as np

from box_toss_env.physics.compile.compilation import jit_kernel
from box_toss_env.physics.robust.contact_solver import CORNER_ROWS, MAX_CORNERS, RX, RY, TARGET, solve_one_corner
from box_toss_env.physics.robust.restitution import impact_impulses
from box_toss_env.physics.scene import Scene

LAWS = ("ours", "newton")
THRESHOLD = Scene.__dataclass_fields__["restitution_threshold"].default  # [m/s] the engine's default


@jit_kernel
def _apply(law, velocity, rx, ry, restitution, friction, inv_mass, inv_inertia, threshold, out):
    corners = np.zeros((CORNER_ROWS, MAX_CORNERS))
    k = np.zeros((MAX_CORNERS, MAX_CORNERS))
    for i in range(velocity.shape[0]):
        vx, vy, spin = velocity[i, 0], velocity[i, 1], velocity[i, 2]
        corners[RX, 0] = rx[i]
        corners[RY, 0] = ry[i]
        if law == 0:
            vx, vy, spin, _ = impact_impulses(
                vx, vy, spin, corners, 1, restitution[i], friction[i], threshold, inv_mass, inv_inertia, k
            )
        else:
            u_n = vy + spin * rx[i]
            if u_n < 0.0:
                corners[TARGET, 0] = -restitution[i] * u_n
                vx1, vy1, spin1, solved = solve_one_corner(vx, vy, spin, corners, friction[i], inv_mass, inv_inertia)
                if not solved:  # friction so high that no Coulomb impulse exists: frictionless
                    vx1, vy1, spin1, solved = solve_one_corner(vx, vy, spin, corners, 0.0, inv_mass, inv_inertia)
                vx, vy, spin = vx1, vy1, spin1
        out[i, 0], out[i, 1], out[i, 2] = vx, vy, spin


def apply(
    law: str, velocity, rx, ry, restitution, friction, mass: float, inertia: float, threshold: float = THRESHOLD
) -> np.ndarray:
    """(n, 3) post-impact velocities (vx, vy, omega) from the pre-impact ones ``velocity`` (n, 3) at contact points
    with lever arms ``rx``, ``ry`` (n,), by ``law`` ("ours" or "newton"); ``restitution`` and ``friction`` are
    scalars or (n,) arrays."""
    velocity = np.ascontiguousarray(velocity, dtype=float).reshape(-1, 3)
    n = len(velocity)

    def column(value):
        return np.ascontiguousarray(np.broadcast_to(np.asarray(value, dtype=float), (n,)))

    out = np.empty_like(velocity)
    _apply(
        LAWS.index(law),
        velocity,
        column(rx),
        column(ry),
        column(restitution),
        column(friction),
        1.0 / mass,
        1.0 / inertia,
        float(threshold),
        out,
    )
    return out


def normalised_error(predicted, measured, gyration: float) -> np.ndarray:
    """|W (predicted - measured)| / |W measured| per row, W = (1, 1, gyration)."""
    w = np.array([1.0, 1.0, gyration])
    predicted, measured = np.asarray(predicted), np.asarray(measured)
    return np.linalg.norm((predicted - measured) * w, axis=-1) / np.linalg.norm(measured * w, axis=-1)


COARSE = np.linspace(0.0, 1.0, 11)


def grid_fit(loss, coarse=COARSE, friction_max: float = 2.0) -> tuple[float, float, float]:
    """(e, mu, loss) minimising ``loss(e, mu)`` (arrays of points in, an array of losses out) on ``coarse`` x
    ``coarse``, then on a grid of a fifth of its spacing around the best point."""
    e, mu = (a.ravel() for a in np.meshgrid(coarse, coarse, indexing="ij"))
    values = loss(e, mu)
    best = int(np.argmin(values))
    step = (coarse[1] - coarse[0]) / 5
    fine = np.arange(-4, 5) * step
    e2, mu2 = (
        a.ravel()
        for a in np.meshgrid(np.clip(e[best] + fine, 0, 1), np.clip(mu[best] + fine, 0, friction_max), indexing="ij")
    )
    values2 = loss(e2, mu2)
    best2 = int(np.argmin(values2))
    return float(e2[best2]), float(mu2[best2]), float(values2[best2])


def tangential(
    velocity, rx, ry, restitution, friction, tangential_restitution, mass: float, inertia: float
) -> np.ndarray:
    """The proposal measured, not in the engine: the point-contact Newton + Coulomb map with a tangential
    restitution e_t, the impulse (lam, q) that gives u_n+ = -e u_n- and u_t+ = -e_t u_t- (the contact point
    springs back along the surface) if it lies in the friction cone |q| <= mu lam, else sliding with
    q = -sign(u_t) mu lam. e_t = 0 is ``apply("newton", ...)``. Vectorised: every argument may be an (n,) array."""
    velocity = np.asarray(velocity, dtype=float).reshape(-1, 3)
    vx, vy, spin = velocity.T
    rx, ry = np.asarray(rx, dtype=float), np.asarray(ry, dtype=float)
    e, mu, et = (np.asarray(v, dtype=float) for v in (restitution, friction, tangential_restitution))
    inv_m, inv_i = 1.0 / mass, 1.0 / inertia
    u_n, u_t = vy + spin * rx, vx - spin * ry
    k_nn, k_tt, k_nt = inv_m + rx * rx * inv_i, inv_m + ry * ry * inv_i, -rx * ry * inv_i
    dn, dt = -(1.0 + e) * u_n, -(1.0 + et) * u_t
    det = k_nn * k_tt - k_nt * k_nt
    lam = (dn * k_tt - dt * k_nt) / det
    q = (dt * k_nn - dn * k_nt) / det
    slide = np.abs(q) > mu * lam
    # sliding on in the slip's direction, or (a slip the normal impulse reverses) the other way, as
    # ``contact_solver.solve_one_corner`` decides it
    sign = np.where(u_t > 0.0, 1.0, -1.0)
    lam_slide = dn / np.maximum(k_nn - sign * mu * k_nt, 1e-300)
    reverses = sign * (u_t + k_nt * lam_slide - k_tt * sign * mu * lam_slide) < 0.0
    sign = np.where(reverses, -sign, sign)
    lam_slide = dn / np.maximum(k_nn - sign * mu * k_nt, 1e-300)
    lam = np.where(slide, lam_slide, lam)
    q = np.where(slide, -sign * mu * lam_slide, q)
    approaching = u_n < 0.0
    lam, q = np.where(approaching, lam, 0.0), np.where(approaching, q, 0.0)
    return np.stack([vx + q * inv_m, vy + lam * inv_m, spin + (rx * lam - ry * q) * inv_i], axis=-1)


def grid_fit3(loss, coarse=COARSE, friction_max: float = 2.0) -> tuple[float, float, float, float]:
    """(e, mu, e_t, loss) minimising ``loss(e, mu, e_t)`` on ``coarse``^3 (e_t on [0, 1]), then on a grid of a
    fifth of its spacing around the best point."""
    points = [a.ravel() for a in np.meshgrid(coarse, coarse, coarse, indexing="ij")]
    best = int(np.argmin(loss(*points)))
    fine = np.arange(-4, 5) * (coarse[1] - coarse[0]) / 5
    e, mu, et = (np.clip(p[best] + fine, 0, top) for p, top in zip(points, (1, friction_max, 1), strict=True))
    points = [a.ravel() for a in np.meshgrid(e, mu, et, indexing="ij")]
    values = loss(*points)
    best = int(np.argmin(values))
    return float(points[0][best]), float(points[1][best]), float(points[2][best]), float(values[best])
