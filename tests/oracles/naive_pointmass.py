"""Brute-force twin of the point-mass model: fixed-step Moreau-Jean time stepping.

Independent of :mod:`dem.pointmass` by construction: no phases, no events, no closed forms.
Each step of length h takes the free velocity, and if the gap would close, solves the contact
at velocity level: a landing multiplies the tangential relative velocity by eps_t and the
normal one by -eps_n; a persisting contact takes the normal impulse that stops penetration and
a Coulomb friction impulse bounded by mu times it. First order in h.

Units as in the paper: phase theta = omega t, tangential velocity in A omega cos(phi), normal
velocity in A omega sin(phi), so the friction impulse carries a factor tan(phi).
"""

import math

import numpy as np
from numba import njit, prange


@njit(cache=True)
def brute_velocity(gamma, phi_deg, mu, alpha_deg, eps_t, eps_n, steps, transient, measured):
    """Normalised mean velocity over ``measured`` cycles after ``transient`` cycles."""
    tphi = math.tan(math.radians(phi_deg))
    c = tphi * math.tan(math.radians(alpha_deg)) / gamma
    inv_g = 1.0 / gamma
    h = 2.0 * math.pi / steps
    u = 0.0
    w = 0.0
    z = 0.0
    flying = False
    x = 0.0
    for n in range((transient + measured) * steps):
        if n == transient * steps:
            x = 0.0
        s = math.sin((n % steps + 0.5) * h)
        w_free = w + h * (s - inv_g)
        u_free = u + h * (s - c)
        if z + h * w_free > 0.0:
            u, w = u_free, w_free
            z += h * w
            flying = True
        elif flying:  # impact
            u = eps_t * u_free
            w = -eps_n * w_free if w_free < 0.0 else 0.0
            z = 0.0
            flying = w > 0.0
        else:  # persisting contact: impulse keeps z = 0, Coulomb friction
            impulse = -w_free
            limit = mu * tphi * impulse
            if abs(u_free) <= limit:
                u = 0.0
            else:
                u = u_free - math.copysign(limit, u_free)
            w = 0.0
            z = 0.0
        x += h * u
    return x / (2.0 * math.pi * measured)


@njit(cache=True, parallel=True)
def brute_velocities(params, steps, transient, measured, out):
    """``brute_velocity`` for each row (Gamma, phi, mu, alpha, eps_t, eps_n) of params.

    ``transient`` holds the cycles to skip for each row.
    """
    for i in prange(params.shape[0]):
        out[i] = brute_velocity(
            params[i, 0],
            params[i, 1],
            params[i, 2],
            params[i, 3],
            params[i, 4],
            params[i, 5],
            steps,
            transient[i],
            measured,
        )


def brute(params, steps=4000, transient=300, measured=48):
    """Vectorised wrapper: params (n, 6) -> velocities (n,)."""
    params = np.ascontiguousarray(params, dtype=float)
    transient = np.broadcast_to(np.asarray(transient, dtype=np.int64), params.shape[:1]).copy()
    out = np.empty(params.shape[0])
    brute_velocities(params, steps, transient, measured, out)
    return out
