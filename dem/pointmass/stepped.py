"""The point mass stepped in time (Moreau-Jean), for what the event-driven kernel does not give.

:mod:`dem.pointmass.model` integrates the paper's model event by event. Three questions need the
motion step by step instead: the landings it makes (their incidence and speed, which
:mod:`dem.studies.calibrate` throws a DEM grain at), the variant whose landings never take more than
Coulomb allows (:mod:`dem.pointmass.bounded`) and a trough moving on an ellipse, whose along-
and normal accelerations are out of phase (:mod:`dem.pointmass.elliptic`). All are one kernel,
:func:`step_motion`.

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
    g_scale = math.sin(phi) / (gamma * math.cos(alpha))  # g / (A omega^2)
    return step_motion(
        math.cos(phi), 0.0, math.sin(phi), 0.0, -g_scale * math.sin(alpha),
        -g_scale * math.cos(alpha), mu, eps_t, eps_n, steps, transient, measured, coulomb_bound,
        out,
    )  # fmt: skip


@numba.njit(**NUMBA_OPTIONS)
def step_motion(
    x_amp, x_phase, z_amp, z_phase, gx, gz, mu, eps_t, eps_n, steps, transient, measured,
    coulomb_bound, out,
):  # fmt: skip
    """Step the point mass on any sinusoidal trough motion (an elliptical drive).

    Units: phase omega t, lengths L, so accelerations in L omega^2 and velocities in L omega.
    The frame acceleration is (x_amp sin(t + x_phase), z_amp sin(t + z_phase)) along and
    normal to the floor, gravity (gx, gz); :func:`step_point_mass` is the line drive
    (cos phi, sin phi) sin(t) with L = A. Arguments and returns otherwise as there.
    """
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
        th = (n % steps + 0.5) * h
        u_free = u + h * (x_amp * math.sin(th + x_phase) + gx)
        w_free = w + h * (z_amp * math.sin(th + z_phase) + gz)
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
