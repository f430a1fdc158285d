"""The plain sphere on the floor once more, in Python, with either lever arm of a wall contact.

It shows where the plain-sphere difference between the codes comes from (README.md, part B):
with dem's lever arm it reproduces dem, with LIGGGHTS's it reproduces LIGGGHTS.
"""

from __future__ import annotations

import numpy as np
from impact_setup import SPHERE_MASS, SPHERE_RADIUS

from dem.kernels import contact
from dem.scene.timestep import ContactLaw


def replica_sphere(start: np.ndarray, times: np.ndarray, case, dt: float, lever: str):
    """The plain sphere on the floor once more, in Python, with a chosen wall lever arm.

    Velocity Verlet (half kick, drift, forces, half kick) as both codes integrate a sphere;
    gravity plus the floor contact through :func:`dem.kernels.contact.contact_force` (the law
    dem uses and documents as LIGGGHTS's); ``lever`` = "dem" passes c = r - delta, "liggghts"
    c = r - delta/2 (surface_model_default.h: radi - deltan/2 for a wall). Only the floor: the
    sphere never reaches the side walls.
    """
    law = ContactLaw.from_case(case)
    p, model = law.params, law.model_id
    r, m = SPHERE_RADIUS, SPHERE_MASS
    inv_i = 1.0 / (0.4 * m * r * r)
    g = -9.81
    x, v, w = start[1:4].copy(), start[4:7].copy(), start[7:10].copy()
    hist = np.zeros((1, 3))

    def forces():
        delta = r - x[2]
        if delta <= 0.0:
            hist[0] = 0.0
            return np.array([0.0, 0.0, m * g]), np.zeros(3)
        c = r - delta if lever == "dem" else r - 0.5 * delta
        f = contact_force(
            model, p, 0.0, 0.0, 1.0, delta, v[0], v[1], v[2], w[0], w[1], w[2],
            0.0, 0.0, 0.0, c, 0.0, c, 0.0, m, r, hist, 0, dt,
        )  # fmt: skip
        return np.array([f[0], f[1], f[2] + m * g]), np.array(f[3:6])

    contact_force = contact.contact_force.py_func
    f, tq = forces()
    rows, n = [], 0
    for t in times:
        target = round((t - start[0]) / dt)
        while n < target:
            v += 0.5 * dt * f / m
            w += 0.5 * dt * tq * inv_i
            x += dt * v
            f, tq = forces()
            v += 0.5 * dt * f / m
            w += 0.5 * dt * tq * inv_i
            n += 1
        rows.append([t, *x, *v, *w])
    return np.array(rows)
