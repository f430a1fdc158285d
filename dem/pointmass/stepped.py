"""The point mass stepped in time (Moreau-Jean), for what the event-driven kernel does not give.

:mod:`dem.pointmass.model` integrates the paper's model event by event. Two questions need the
motion step by step instead: the landings it makes (their incidence and speed, which
:mod:`dem.calibrate` throws a DEM grain at) and the variant whose landings never take more than
Coulomb allows (:mod:`dem.pointmass.bounded`). Both are this one kernel.

Units: phase omega t; velocities relative to the trough in A omega, u along the trough, w
normal to it. Per step of h = 2 pi / ``steps``: the free update by the frame acceleration
sin(t) (cos phi, sin phi) and gravity; if the grain would go below the floor it lands (in
flight before: the paper's Eq. 12, u <- eps_t u, w <- -eps_n w) or is held by the floor (static
or sliding Coulomb friction, mu times the normal impulse).
"""

import math

import numba

from dem.config import NUMBA_OPTIONS


@numba.njit(**NUMBA_OPTIONS)
def step_point_mass(
    gamma, phi, mu, alpha, eps_t, eps_n, steps, transient, measured, coulomb_bound, out
):  # fmt: skip
    """Step the point mass; record its landings and its mean velocity along the trough.

    Args:
        gamma: Throw number Gamma.
        phi, alpha: Vibration angle and inclination, rad.
        mu: Friction coefficient.
        eps_t, eps_n: Restitution of a landing (Eq. 12).
        steps: Steps per drive period.
        transient, measured: Periods discarded, then recorded.
        coulomb_bound: A landing takes at most mu (1 + eps_n) |w| of tangential velocity (the
            most a Coulomb contact can give in that impact) instead of always (1 - eps_t) |u|.
        out: (L, 2) array for the relative velocities (u, w) just before each recorded landing.

    Returns:
        (landings recorded, mean u over the measured periods in units of A omega).

    """
    s_phi = math.sin(phi)
    c_phi = math.cos(phi)
    g_scale = math.sin(phi) / (gamma * math.cos(alpha))  # g / (A omega^2)
    gx = -g_scale * math.sin(alpha)
    gz = -g_scale * math.cos(alpha)
    h = 2.0 * math.pi / steps
    u = 0.0
    w = 0.0
    z = 0.0
    x = 0.0
    flying = False
    n_out = 0
    for n in range((transient + measured) * steps):
        if n == transient * steps:
            x = 0.0
        s = math.sin((n % steps + 0.5) * h)
        u_free = u + h * (s * c_phi + gx)
        w_free = w + h * (s * s_phi + gz)
        if z + h * w_free > 0.0:
            u, w = u_free, w_free
            z += h * w
            flying = True
        elif flying:
            if n >= transient * steps and n_out < out.shape[0]:
                out[n_out, 0] = u_free
                out[n_out, 1] = w_free
                n_out += 1
            u = eps_t * u_free
            if coulomb_bound:
                limit = mu * (1.0 + eps_n) * max(-w_free, 0.0)
                if abs(u_free - u) > limit:
                    u = u_free - math.copysign(limit, u_free)
            w = -eps_n * w_free if w_free < 0.0 else 0.0
            z = 0.0
            flying = w > 0.0
        else:
            impulse = -w_free
            limit = mu * impulse
            if abs(u_free) <= limit:
                u = 0.0
            else:
                u = u_free - math.copysign(limit, u_free)
            w = 0.0
            z = 0.0
        x += h * u
    return n_out, x / (2.0 * math.pi * measured)
