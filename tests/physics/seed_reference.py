"""A plain-Python transcription of the reference text (restated in docs/engine.md), written from
the text alone (no kernel code), to check the seed solver against.

Vectors are 2-tuples and every formula is spelled out as the text gives it, with the floor
normal n = (0, 1) kept general.
"""

import math

# local corners in the demo's order: (-L/2, -W/2), (-L/2, +W/2), (+L/2, +W/2), (+L/2, -W/2) (read off its
# page source; the text does not say). Corners are resolved one after another, so the order matters.
CORNERS = ((-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0))


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1]


def cross(a, b):  # 2D cross product r x n = r_x n_y - r_y n_x
    return a[0] * b[1] - a[1] * b[0]


def scale(s, a):
    return (s * a[0], s * a[1])


def add(a, b):
    return (a[0] + b[0], a[1] + b[1])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1])


def norm(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1])


class ReferenceBody:
    def __init__(self, length, width, mass, x, y, angle, vx=0.0, vy=0.0, omega=0.0):
        self.half = (0.5 * length, 0.5 * width)
        self.m = mass
        self.inertia = mass * (length * length + width * width) / 12.0
        self.x = (x, y)
        self.alpha = angle
        self.v = (vx, vy)
        self.omega = omega

    def state(self):
        return (self.x[0], self.x[1], self.alpha, self.v[0], self.v[1], self.omega)


def reference_step(body, dt, g, k, e, mu, use_impulses=True, use_penalty=True):
    """One time step of the text's method for one body."""
    n = (0.0, 1.0)
    force = (0.0, 0.0)
    tau = 0.0
    c, s = math.cos(body.alpha), math.sin(body.alpha)
    for sx, sy in CORNERS:
        b_local = (sx * body.half[0], sy * body.half[1])
        r = (c * b_local[0] - s * b_local[1], s * b_local[0] + c * b_local[1])  # R b_local
        corner = add(r, body.x)  # b_global = R b_local + x
        if not corner[1] < 0.0:  # 1. a corner below y = 0 collides
            continue
        u = add(body.v, (-body.omega * r[1], body.omega * r[0]))  # u = v + omega x r
        u_n = scale(dot(u, n), n)
        u_t = sub(u, u_n)
        t = u_t
        if norm(u_t) > 1e-4:
            t = (u_t[0] / norm(u_t), u_t[1] / norm(u_t))
        if use_impulses:
            r_x_n = cross(r, n)
            denominator = 1.0 / body.m + r_x_n * r_x_n / body.inertia
            p_prime = (-u_n[0] / denominator, -u_n[1] / denominator)
            p = scale(1.0 + e, p_prime)
            p = add(p, scale(-mu * norm(p), t))  # friction impulse, added before the test
            if dot(p, n) > 0.0:
                body.v = add(body.v, (p[0] / body.m, p[1] / body.m))
                body.omega = body.omega + cross(r, p) / body.inertia
        if use_penalty:
            d = -corner[1]
            f_n = scale(k * d, n)
            f_friction = scale(-mu * norm(f_n), t)
            f = add(f_n, f_friction)
            force = add(force, f)
            tau = tau + cross(r, f)
    # 4. symplectic Euler, gravity with the external forces
    body.v = (body.v[0] + dt * (force[0] / body.m), body.v[1] + dt * (force[1] / body.m + g))
    body.x = add(body.x, scale(dt, body.v))
    body.omega = body.omega + dt * (tau / body.inertia)
    body.alpha = body.alpha + dt * body.omega
