"""Event-driven integration of the point-mass model (numba kernels; arrays and scalars only).

Dimensionless variables (Sec. 2.2 of the paper, README, The point-mass model). The drive phase is
``theta = omega t``, kept in [0, 2 pi) within a cycle. Relative to the trough:

- ``u``: tangential velocity in units of ``A omega cos(phi)``; ``x`` its integral (units
  ``A cos(phi)``), so the mean of ``u`` over a cycle is the normalised conveying velocity;
- ``w``: normal velocity in units of ``A omega sin(phi)``; ``z`` the gap above the floor
  (units ``A sin(phi)``).

With ``c = tan(phi) tan(alpha) / Gamma`` and ``m = mu tan(phi)`` every phase has an
acceleration of the form ``a + b sin(theta)``:

==============  ==============================================  ==============================
phase           tangential ``u'``                               normal
==============  ==============================================  ==============================
stick           0                                               N ~ 1/Gamma - sin(theta) >= 0
slide forward   (1 + m) sin(theta) - (c + m / Gamma)            z = w = 0
slide backward  (1 - m) sin(theta) - (c - m / Gamma)            z = w = 0
flight          sin(theta) - c                                  w' = sin(theta) - 1/Gamma
==============  ==============================================  ==============================

Within a phase velocity and position are closed-form; phase changes are either closed-form
(stick-slip thresholds and take-off, where ``p sin(theta) + q`` changes sign) or the first root
of a closed-form function (slip-stick, landing), found by safe stepping with a rigorous lower
bound followed by a bracketed Newton-bisection to about 1e-15 rad. Landing multiplies ``u`` by
eps_t and ``w`` by -eps_n (Eq. 12).
"""

import math

import numpy as np
from numba import njit, prange

from dem.config import NUMBA_OPTIONS, NUMBA_PARALLEL_OPTIONS, PM_BOUNCE_SETTLE

STICK = 0
SLIDE_FORWARD = 1
SLIDE_BACKWARD = 2
FLIGHT = 3

TWO_PI = 2.0 * math.pi
_INF = math.inf

# indices into the per-cycle time fractions
_N_MODES = 4
#: Two section states closer than this (relative) belong to the same orbit when the period
#: of a just-closed orbit is reduced to its shortest divisor.
ORBIT_SIZE_TOL = 1e-6


@njit(**NUMBA_OPTIONS)
def _one_minus_cos(d):
    """1 - cos(d), without cancellation for small d."""
    s = math.sin(0.5 * d)
    return 2.0 * s * s


@njit(**NUMBA_OPTIONS)
def _d_minus_sin(d):
    """D - sin(d), without cancellation for small d (Taylor series below 0.25)."""
    if abs(d) < 0.25:
        d2 = d * d
        return (
            d
            * d2
            / 6.0
            * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0 * (1.0 - d2 / 110.0))))
        )
    return d - math.sin(d)


@njit(**NUMBA_OPTIONS)
def _trig_integrals(s0, c0, d):
    """Integrals of sin from theta0 over a span d: returns (T1, T2, sin(theta0+d), cos(...)).

    T1 = cos(theta0) - cos(theta0 + d) (first integral of sin), and
    T2 = d cos(theta0) - sin(theta0 + d) + sin(theta0) (its integral), written with
    1 - cos(d) and d - sin(d) so both keep full relative precision as d -> 0.
    """
    sd = math.sin(d)
    omc = _one_minus_cos(d)
    t1 = c0 * omc + s0 * sd
    t2 = c0 * _d_minus_sin(d) + s0 * omc
    s1 = s0 * (1.0 - omc) + c0 * sd
    c1 = c0 * (1.0 - omc) - s0 * sd
    return t1, t2, s1, c1


@njit(**NUMBA_OPTIONS)
def _f_and_derivative(p0, p1, p2, q1, q2, s0, c0, d):
    """F(d) = p0 + p1 d + p2 d^2/2 + q1 T1(d) + q2 T2(d) and F'(d)."""
    t1, t2, s1, _ = _trig_integrals(s0, c0, d)
    f = p0 + d * (p1 + 0.5 * p2 * d) + q1 * t1 + q2 * t2
    fp = p1 + p2 * d + q1 * s1 + q2 * t1
    return f, fp


@njit(**NUMBA_OPTIONS)
def _refine(p0, p1, p2, q1, q2, s0, c0, lo, hi):
    """Bracketed Newton-bisection for F(lo) > 0 >= F(hi); returns a point where F <= 0."""
    x = hi
    for _ in range(200):
        if hi - lo <= 4e-16 * (1.0 + hi):
            break
        f, fp = _f_and_derivative(p0, p1, p2, q1, q2, s0, c0, x)
        if f > 0.0:
            lo = x
        else:
            hi = x
            if f == 0.0:
                break
        xn = x - f / fp if fp != 0.0 else 0.5 * (lo + hi)
        if not (lo < xn < hi):
            xn = 0.5 * (lo + hi)
        x = xn
    return hi


@njit(**NUMBA_OPTIONS)
def first_root(p0, p1, p2, q1, q2, theta0, horizon):
    """First d in (0, horizon] where F(d) <= 0, for F positive just after d = 0.

    ``F(d) = p0 + p1 d + p2 d^2/2 + q1 T1(d) + q2 T2(d)``: a phase's velocity (p2 = q2 = 0) or
    gap (q1 = 0) as a function of the time span d from ``theta0``. Since
    ``F'' = p2 + q1 cos + q2 sin >= L = p2 - sqrt(q1^2 + q2^2)``, from a point with F = f > 0,
    F' = g no root lies closer than ``h = 2 f / (sqrt(g^2 - 2 L f) - g)``; stepping by h never
    jumps over a root, so the FIRST root is found even when F dips below zero only briefly.
    If F(0) = 0 the start is left with the Taylor bound using ``|F'''| <= sqrt(q1^2 + q2^2)``.
    Returns inf when there is no root within the horizon.
    """
    s0 = math.sin(theta0)
    c0 = math.cos(theta0)
    r = math.sqrt(q1 * q1 + q2 * q2)
    lower = min(p2 - r, 0.0)
    d = 0.0
    f = p0
    if f <= 0.0:
        # leave d = 0 where F vanishes: F(d) >= F'(0) d + F''(0) d^2/2 - r d^3/6
        fp0 = p1 + q1 * s0
        fpp0 = p2 + q1 * c0 + q2 * s0
        scale = 1e-14 * (abs(p1) + abs(q1) + 1e-300)
        if fp0 > scale:
            h0 = 2.0 * fp0 / (-lower) if lower < 0.0 else _INF
            if r > 0.0 and fpp0 >= 0.0:
                # with F''(0) >= 0 either term of the cubic bound alone keeps F > 0
                h0 = max(h0, math.sqrt(6.0 * fp0 / r), 3.0 * fpp0 / r)
        elif fp0 < -scale:
            return 0.0
        elif fpp0 > 1e-14 * (abs(p2) + r):
            h0 = 3.0 * fpp0 / r if r > 0.0 else _INF
        else:
            # F, F' and F'' vanish (take-off exactly at sin(theta) = 1/Gamma):
            # F(d) >= F3 d^3/6 - r d^4/24 with F3 = F'''(0) = q2 cos - q1 sin
            f3 = q2 * c0 - q1 * s0
            if f3 <= 0.0 or r == 0.0:
                return 0.0
            h0 = 4.0 * f3 / r
        d = min(0.999 * h0, horizon)
        f, _ = _f_and_derivative(p0, p1, p2, q1, q2, s0, c0, d)
        if d >= horizon:
            return _INF if f > 0.0 else _refine(p0, p1, p2, q1, q2, s0, c0, 0.5 * d, d)
        f = max(f, 0.0)
    for _ in range(100000):
        _, g = _f_and_derivative(p0, p1, p2, q1, q2, s0, c0, d)
        denom = math.sqrt(g * g - 2.0 * lower * f) - g
        if denom <= 0.0:
            return _INF  # F convex and not decreasing: no root ahead
        h = 2.0 * f / denom
        if h < 1e-13:
            return d  # grazing: F touches zero tangentially
        dn = d + h
        if dn >= horizon:
            fh, _ = _f_and_derivative(p0, p1, p2, q1, q2, s0, c0, horizon)
            if fh > 0.0:
                return _INF
            return _refine(p0, p1, p2, q1, q2, s0, c0, d, horizon)
        fn, _ = _f_and_derivative(p0, p1, p2, q1, q2, s0, c0, dn)
        if fn <= 0.0:
            return _refine(p0, p1, p2, q1, q2, s0, c0, d, dn)
        d = dn
        f = fn
    return d


@njit(**NUMBA_OPTIONS)
def next_positive(theta0, p, q, horizon):
    """First d in [0, horizon] at which ``p sin(theta0 + d) + q`` becomes positive (or inf)."""
    s0 = math.sin(theta0)
    c0 = math.cos(theta0)
    v0 = p * s0 + q
    tol = 1e-15 * (abs(p) + abs(q))
    if v0 > tol or (v0 >= -tol and p * c0 > 0.0):
        return 0.0
    if p == 0.0:
        return _INF
    level = -q / p
    if p > 0.0:
        if level >= 1.0:
            return _INF
        if level < -1.0:
            return 0.0
        crossing = math.asin(level)  # sin rises through level here
    else:
        if level <= -1.0:
            return _INF
        if level > 1.0:
            return 0.0
        crossing = math.pi - math.asin(level)  # sin falls through level here
    d = (crossing - theta0) % TWO_PI
    return d if d <= horizon else _INF


@njit(**NUMBA_OPTIONS)
def _contact_mode(theta, u, b_f, a_f, b_b, a_b):
    """Mode on the floor with tangential velocity u (Coulomb friction, Filippov at u = 0)."""
    if u > 0.0:
        return SLIDE_FORWARD
    if u < 0.0:
        return SLIDE_BACKWARD
    s = math.sin(theta)
    if b_f * s + a_f > 0.0:
        return SLIDE_FORWARD
    if b_b * s + a_b < 0.0:
        return SLIDE_BACKWARD
    return STICK


@njit(**NUMBA_OPTIONS)
def advance(theta, theta_end, mode, u, w, z, params, out_time):
    """Integrate from phase ``theta`` to ``theta_end`` (<= 2 pi) through every phase change.

    ``params = (Gamma, tan phi, tan alpha, mu, eps_t, eps_n, bounded)``; ``bounded`` 1.0 caps a
    landing's tangential change at mu (1 + eps_n) times its normal speed (Coulomb, the DEM's
    reference), 0.0 is the paper's Eq. 12. ``out_time[mode]`` accumulates
    the phase time spent in each mode. Returns ``(mode, u, w, z, dx, events)`` where dx is the
    relative tangential displacement (units A cos phi) over the span.
    """
    gamma, tphi, talpha, mu, eps_t, eps_n, bounded = params
    inv_g = 1.0 / gamma
    c = tphi * talpha * inv_g
    m = mu * tphi
    b_f = 1.0 + m
    a_f = -(c + m * inv_g)
    b_b = 1.0 - m
    a_b = -(c - m * inv_g)
    can_fly = gamma > 1.0
    dx = 0.0
    events = 0
    while theta < theta_end:
        horizon = theta_end - theta
        events += 1
        if events > 100000:
            return mode, u, w, z, dx, -1
        if mode == STICK:
            d_f = next_positive(theta, b_f, a_f, horizon)
            d_b = next_positive(theta, -b_b, -a_b, horizon)
            d_t = next_positive(theta, 1.0, -inv_g, horizon) if can_fly else _INF
            d = min(d_f, min(d_b, d_t))
            if d == _INF:
                out_time[STICK] += horizon
                theta = theta_end
                break
            out_time[STICK] += d
            theta += d
            if d_t == d:
                mode = FLIGHT
                w = 0.0
                z = 0.0
            elif d_f == d:
                mode = SLIDE_FORWARD
            else:
                mode = SLIDE_BACKWARD
        elif mode == FLIGHT:
            d = first_root(z, w, -inv_g, 0.0, 1.0, theta, horizon)
            span = min(d, horizon)
            t1, t2, _, _ = _trig_integrals(math.sin(theta), math.cos(theta), span)
            dx += u * span - 0.5 * c * span * span + t2
            u += -c * span + t1
            out_time[FLIGHT] += span
            theta += span
            if d == _INF:
                z += w * span - 0.5 * inv_g * span * span + t2
                w += -inv_g * span + t1
                break
            w_in = w - inv_g * span + t1
            z = 0.0
            if bounded != 0.0 and w_in < 0.0:
                # u and w are in units of A omega cos(phi) and A omega sin(phi): the normal
                # impulse (1 + eps_n) m |v_n| allows |du| <= mu (1 + eps_n) |w_in| tan(phi)
                du = (1.0 - eps_t) * u
                cap = m * (1.0 + eps_n) * -w_in
                if abs(du) > cap:
                    du = cap if du > 0.0 else -cap
                u -= du
            else:
                u *= eps_t
            w = -eps_n * min(w_in, 0.0)
            s = math.sin(theta)
            if w > PM_BOUNCE_SETTLE:
                continue  # bounce
            if w_in < 0.0 and eps_n > 0.0:
                # The bounces that remain form a Zeno sequence: infinitely many impacts in a
                # finite time, each multiplying u by eps_t, so the literal impact law (Eq. 12)
                # leaves no tangential relative velocity when the bouncing ends. Bounded by
                # Coulomb, they take at most mu tan(phi) times their normal impulses,
                # (1 + e) w (1 + e + e^2 + ...) = (1 + e) w / (1 - e).
                if eps_t < 1.0:
                    if bounded != 0.0:
                        cap = m * (1.0 + eps_n) * w / (1.0 - eps_n)
                        u = u - cap if u > cap else (u + cap if u < -cap else 0.0)
                    else:
                        u = 0.0
            w = 0.0
            if can_fly and s - inv_g > 1e-14:
                continue  # landed while the floor pulls away: flight goes on from rest
            mode = _contact_mode(theta, u, b_f, a_f, b_b, a_b)
        else:
            sign = 1.0 if mode == SLIDE_FORWARD else -1.0
            if mode == SLIDE_FORWARD:
                a, b = a_f, b_f
            else:
                a, b = a_b, b_b
            d_u = first_root(sign * u, sign * a, 0.0, sign * b, 0.0, theta, horizon)
            d_t = next_positive(theta, 1.0, -inv_g, horizon) if can_fly else _INF
            d = min(d_u, d_t)
            span = min(d, horizon)
            t1, t2, _, _ = _trig_integrals(math.sin(theta), math.cos(theta), span)
            dx += u * span + 0.5 * a * span * span + b * t2
            u += a * span + b * t1
            out_time[mode] += span
            theta += span
            if d == _INF:
                break
            if d_t <= d_u:
                mode = FLIGHT
                w = 0.0
                z = 0.0
            else:
                u = 0.0
                mode = _contact_mode(theta, 0.0, b_f, a_f, b_b, a_b)
    return mode, u, w, z, dx, events


@njit(**NUMBA_OPTIONS)
def _same_state(ma, ua, wa, za, mb, ub, wb, zb, tol):
    if ma != mb:
        return False
    scale = 1.0 + abs(ua) + abs(wa) + abs(za)
    return abs(ua - ub) + abs(wa - wb) + abs(za - zb) <= tol * scale


@njit(**NUMBA_OPTIONS)
def mean_velocity(params, start_phase, max_cycles, average_cycles, max_period, tol, out_time):
    """Mean normalised velocity of the steady motion started at rest at phase ``start_phase``.

    Cycles run from phase 0 to 2 pi; the state (mode, u, w, z) at phase 0 is the Poincare
    section. The motion is periodic with period p cycles when the section state repeats after p
    cycles, twice in a row, to ``tol``; the velocity is then the displacement over those p
    cycles over 2 pi p. Otherwise, after ``max_cycles``, the mean over the last
    ``average_cycles`` is returned with ``period = 0``.

    Returns ``(velocity_norm, period, cycles, status)``; status 0 ok, -1 too many events.
    ``out_time[0:4]`` receives the fraction of the measured time spent in each mode.
    """
    ring = max_period + 2
    modes = np.empty(ring, dtype=np.int64)
    us = np.empty(ring)
    ws = np.empty(ring)
    zs = np.empty(ring)
    dxs = np.empty(ring)
    times = np.zeros((ring, _N_MODES))
    avg_dx = 0.0
    avg_time = np.zeros(_N_MODES)
    avg_n = 0
    mode, u, w, z = STICK, 0.0, 0.0, 0.0
    scratch = np.zeros(_N_MODES)
    mode, u, w, z, _, ev = advance(start_phase % TWO_PI, TWO_PI, mode, u, w, z, params, scratch)
    if ev < 0:
        return math.nan, 0, 0, -1
    for k in range(max_cycles):
        slot = k % ring
        times[slot, :] = 0.0
        mode, u, w, z, dx, ev = advance(0.0, TWO_PI, mode, u, w, z, params, times[slot])
        if ev < 0:
            return math.nan, 0, k, -1
        modes[slot] = mode
        us[slot] = u
        ws[slot] = w
        zs[slot] = z
        dxs[slot] = dx
        if k >= max_cycles - average_cycles:
            avg_dx += dx
            avg_time += times[slot]
            avg_n += 1
        for p in range(1, max_period + 1):
            if k < 2 * p + 1:
                break
            a = slot
            b = (k - p) % ring
            a1 = (k - 1) % ring
            b1 = (k - 1 - p) % ring
            if _same_state(modes[a], us[a], ws[a], zs[a], modes[b], us[b], ws[b], zs[b], tol):
                if _same_state(
                    modes[a1], us[a1], ws[a1], zs[a1], modes[b1], us[b1], ws[b1], zs[b1], tol
                ):
                    total = 0.0
                    out_time[:] = 0.0
                    for j in range(p):
                        s = (k - j) % ring
                        total += dxs[s]
                        out_time += times[s]
                    out_time /= TWO_PI * p
                    # An orbit that converges slowly while alternating (multiplier near -1,
                    # close to a period doubling) closes after 2 cycles before it closes after
                    # 1; report the shortest period whose mismatch is below ORBIT_SIZE_TOL.
                    period = p
                    for q in range(1, p):
                        if p % q == 0:
                            b = (k - q) % ring
                            if _same_state(
                                modes[a],
                                us[a],
                                ws[a],
                                zs[a],
                                modes[b],
                                us[b],
                                ws[b],
                                zs[b],
                                ORBIT_SIZE_TOL,
                            ):
                                period = q
                                break
                    return total / (TWO_PI * p), period, k + 1, 0
    out_time[:] = avg_time / (TWO_PI * avg_n)
    # Close to a bifurcation an orbit converges too slowly to close to ``tol`` within
    # max_cycles; one that repeats to ORBIT_SIZE_TOL is periodic for every practical purpose
    # (its velocity is the long average above either way).
    k = max_cycles - 1
    for p in range(1, max_period + 1):
        a, b = k % ring, (k - p) % ring
        a1, b1 = (k - 1) % ring, (k - 1 - p) % ring
        if _same_state(
            modes[a], us[a], ws[a], zs[a], modes[b], us[b], ws[b], zs[b], ORBIT_SIZE_TOL
        ) and _same_state(
            modes[a1], us[a1], ws[a1], zs[a1], modes[b1], us[b1], ws[b1], zs[b1], ORBIT_SIZE_TOL
        ):
            return avg_dx / (TWO_PI * avg_n), p, max_cycles, 0
    return avg_dx / (TWO_PI * avg_n), 0, max_cycles, 0


@njit(**NUMBA_PARALLEL_OPTIONS)
def mean_velocity_many(
    params,
    start_phases,
    max_cycles,
    average_cycles,
    max_period,
    tol,
    out_velocity,
    out_period,
    out_cycles,
    out_status,
    out_time,
):
    """``mean_velocity`` for each row of ``params`` (n, 7) in parallel; results into out_*."""
    n = params.shape[0]
    for i in prange(n):
        v, p, k, st = mean_velocity(
            (
                params[i, 0],
                params[i, 1],
                params[i, 2],
                params[i, 3],
                params[i, 4],
                params[i, 5],
                params[i, 6],
            ),
            start_phases[i],
            max_cycles,
            average_cycles,
            max_period,
            tol,
            out_time[i],
        )
        out_velocity[i] = v
        out_period[i] = p
        out_cycles[i] = k
        out_status[i] = st
