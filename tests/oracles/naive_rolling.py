"""Brute-force twin of the rolling sphere: fixed-step time stepping of its centre and its spin.

Independent of :mod:`dem.pointmass.rolling` by construction: it integrates the sphere's own
unknowns (the centre's velocity and the spin), with no phases, no events, no closed forms and no
reduction to a point mass. Plain numpy, vectorised over drives (one array element a drive).

Units as the point mass's (:mod:`naive_pointmass`): phase theta = omega t; ``u`` the centre's
velocity along the trough relative to the trough and ``W = r omega_y`` the rim speed of the
spin, both in A omega cos(phi); ``w`` the normal velocity in A omega sin(phi). omega_y is the
spin about +y (x along the trough, z the floor's normal, y = z x x): rolling forward has
W = u, and the contact point slips at sigma = u - W.

A tangential impulse J on the contact point (m j in these units) changes u by j and W by
-j / k (k = I / (m r^2); torque -r J about y), so sigma by j (1 + 1/k). Per step of
h = 2 pi / steps: the free update by the drive, sin(theta) - c along and sin(theta) - 1/Gamma
normal (c = tan(phi) tan(alpha) / Gamma); if the gap would close, the contact at velocity level:

- landing (in flight before): normal impulse P = (1 + eps_n) |w|; the tangential j that the
  landing law asks for (``contact``: sigma -> eps_t sigma; ``centre``: u changes by
  (1 - eps_t) sigma, never past rolling), capped at mu tan(phi) P when ``bounded``;
- persisting contact: P = |w|, j stops the slip if |j| <= mu tan(phi) P (rolling), else
  j = -mu tan(phi) P sgn(sigma) (slipping).

First order in h.
"""

import math

import numpy as np


def brute_rolling(
    gamma, phi_deg, mu, alpha_deg=0.0, eps_t=0.8, eps_n=0.0, inertia_factor=0.4,
    landing="contact", bounded=True, steps=4000, transient=60, measured=20,
):  # fmt: skip
    """Mean u over ``measured`` cycles after ``transient``, started at rest at phase 0.

    Arguments broadcast together (one drive per element), ``landing`` too (``"contact"`` or
    ``"centre"``, a string or an array of them); ``inertia_factor`` may be inf (the spin
    locked). Returns (mean u, u at the end of each of the last 2 cycles' ends,
    (2, n)) as numpy arrays.
    """
    g, phi, mu, alpha, et, en, k, by_contact = np.broadcast_arrays(
        *(np.atleast_1d(np.asarray(v, dtype=float)) for v in
          (gamma, phi_deg, mu, alpha_deg, eps_t, eps_n, inertia_factor)),
        np.atleast_1d(np.asarray(landing) == "contact"),
    )  # fmt: skip
    tphi = np.tan(np.radians(phi))
    c = tphi * np.tan(np.radians(alpha)) / g
    inv_g = 1.0 / g
    inv_k = 1.0 / k  # 0 for a locked spin
    share = 1.0 / (1.0 + inv_k)  # m_t / m: the contact point's reduced mass over m
    mut = mu * tphi
    h = 2.0 * math.pi / steps
    n = g.size
    u = np.zeros(n)
    spin = np.zeros(n)
    w = np.zeros(n)
    z = np.zeros(n)
    flying = np.zeros(n, dtype=bool)
    x = np.zeros(n)
    ends = []
    for step in range((transient + measured) * steps):
        if step == transient * steps:
            x[:] = 0.0
        s = math.sin((step % steps + 0.5) * h)
        u_f = u + h * (s - c)
        w_f = w + h * (s - inv_g)
        free = z + h * w_f > 0.0
        landing_now = ~free & flying
        resting = ~free & ~flying
        sigma = u_f - spin
        # landing
        p_land = (1.0 + en) * np.maximum(-w_f, 0.0)
        j_contact = -(1.0 - et) * sigma * share
        j_centre = -np.sign(sigma) * np.minimum((1.0 - et) * np.abs(sigma), share * np.abs(sigma))
        j_land = np.where(by_contact, j_contact, j_centre)
        if bounded:
            cap = mut * p_land
            j_land = np.clip(j_land, -cap, cap)
        # persisting contact
        cap_rest = mut * np.maximum(-w_f, 0.0)
        j_stop = -sigma * share
        j_rest = np.where(np.abs(j_stop) <= cap_rest, j_stop, -np.sign(sigma) * cap_rest)
        j = np.where(landing_now, j_land, np.where(resting, j_rest, 0.0))
        u = u_f + j
        spin = spin - j * inv_k
        w_bounce = np.where(w_f < 0.0, -en * w_f, 0.0)
        w = np.where(free, w_f, np.where(landing_now, w_bounce, 0.0))
        z = np.where(free, z + h * w_f, 0.0)
        flying = np.where(free, True, np.where(landing_now, w > 0.0, False))
        x += h * u
        if step % steps == steps - 1 and step >= (transient + measured - 2) * steps:
            ends.append(u.copy())
    return x / (2.0 * math.pi * measured), np.array(ends)
