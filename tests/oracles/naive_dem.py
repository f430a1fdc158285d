"""Brute-force NumPy twins of the DEM contact forces (O(N^2), plain loops, no numba).

Written from the formulas (LIGGGHTS hooke / hertz + tangential history + cdt rolling, or the
total force capped at Coulomb with ``c["tangential"] = "coulomb"``), not from
the kernels, so that a test comparing both checks the kernels against an independent oracle.
"""

import math

import numpy as np


def coefficients(model, delta, m_eff, r_eff, c):
    """(k_n, gamma_n, k_t, gamma_t) of the law; ``c`` is a dict of coefficients."""
    if c["e"] == 0:
        beta = -1.0
    else:
        beta = math.log(c["e"]) / math.sqrt(math.log(c["e"]) ** 2 + math.pi**2)
    coulomb = c.get("tangential", "coulomb") == "coulomb"
    if model == "linear":
        kn = c["kn"]
        gn = -2 * beta * math.sqrt(kn * m_eff)
        kt = c["kt_ratio"] * kn
        if coulomb:
            return kn, gn, kt, 2 * c["zeta_t"] * math.sqrt(kt * c["f_t"] * m_eff)
        return kn, gn, kt, gn
    nu, y = c["nu"], c["E"]
    ystar = 1 / (2 * (1 - nu**2) / y)
    gstar = 1 / (2 * 2 * (2 - nu) * (1 + nu) / y)
    sn = 2 * ystar * math.sqrt(r_eff * delta)
    st = 8 * gstar * math.sqrt(r_eff * delta)
    if coulomb:
        kt = c["kt_ratio"] * sn
        gamma_t = 2 * c["zeta_t"] * math.sqrt(kt * c["f_t"] * m_eff)
        return (
            4 / 3 * ystar * math.sqrt(r_eff * delta),
            -2 * math.sqrt(5 / 6) * beta * math.sqrt(sn * m_eff),
            kt,
            gamma_t,
        )
    return (
        4 / 3 * ystar * math.sqrt(r_eff * delta),
        -2 * math.sqrt(5 / 6) * beta * math.sqrt(sn * m_eff),
        st,
        -2 * math.sqrt(5 / 6) * beta * math.sqrt(st * m_eff),
    )


def one_contact(model, c, n, delta, vr, wi, wj, ci, cj, m_eff, r_eff, shear, dt, ai=None, aj=None):
    """Force on i, torques on i and j, new shear, for one contact (vectors as arrays).

    ci, cj are the torques' lever arms; ai, aj the slip velocity's (default ci, cj).
    """
    ai = ci if ai is None else ai
    aj = cj if aj is None else aj
    kn, gn, kt, gt = coefficients(model, delta, m_eff, r_eff, c)
    fn = kn * delta - gn * np.dot(vr, n)
    if c.get("limit", False):
        fn = max(fn, 0.0)
    vt = vr - np.dot(vr, n) * n - np.cross(ai * wi + aj * wj, n)
    s = shear + vt * dt
    s = s - np.dot(s, n) * n
    if c.get("tangential", "coulomb") == "coulomb":
        # total force (spring + dashpot) capped at mu |F_n|, the spring reset to the capped
        # force's part the dashpot does not take, but never to more force along the slip v_t
        # than it held (none if it held none)
        ft = -kt * s - gt * vt
        if np.linalg.norm(ft) > c["mu"] * abs(fn):
            ft = ft / np.linalg.norm(ft) * c["mu"] * abs(fn)
            spring = ft + gt * vt
            along, held = np.dot(spring, vt), max(-kt * np.dot(s, vt), 0.0)
            if along > held:
                spring = spring - (along - held) / np.dot(vt, vt) * vt
            s = -spring / kt
        return _with_torques(fn, n, ft, ci, cj, wi, wj, r_eff, c, s)
    ft = -kt * s
    if np.linalg.norm(ft) > c["mu"] * abs(fn):
        ft = ft / np.linalg.norm(ft) * c["mu"] * abs(fn) if np.linalg.norm(s) > 0 else 0 * ft
        s = -ft / kt
    else:
        ft = ft - gt * vt
    return _with_torques(fn, n, ft, ci, cj, wi, wj, r_eff, c, s)


def _with_torques(fn, n, ft, ci, cj, wi, wj, r_eff, c, s):
    ti = -ci * np.cross(n, ft)
    tj = -cj * np.cross(n, ft)
    wr = wi - wj
    wr = wr - np.dot(wr, n) * n
    if c.get("mu_roll", 0) > 0 and np.linalg.norm(wr) > 0:
        tr = c["mu_roll"] * abs(fn) * r_eff * wr / np.linalg.norm(wr)
        ti = ti - tr
        tj = tj + tr
    return fn * n + ft, ti, tj, s


def all_forces(model, c, x, v, w, r, m, length, width, gravity, dt, history):
    """Forces and torques on all spheres (periodic x, floor and side walls, gravity).

    ``history`` maps (i, j) (j = -1 - wall for walls) to the shear vector; updated in place.
    ``c["f_w"]`` sets a wall's lever arm r - f_w delta; ``c["slip"] == "radius"`` takes the slip
    velocity at the full radii.
    """
    full = c.get("slip", "contact") == "radius"
    n = len(r)
    f = m[:, None] * np.asarray(gravity)[None, :]
    t = np.zeros((n, 3))
    for i in range(n):
        for j in range(i + 1, n):
            d = x[i] - x[j]
            d[0] -= length * round(d[0] / length)
            dist = np.linalg.norm(d)
            delta = r[i] + r[j] - dist
            if delta <= 0:
                history.pop((i, j), None)
                continue
            fi, ti, tj, s = one_contact(
                model, c, d / dist, delta, v[i] - v[j], w[i], w[j], r[i] - delta / 2,
                r[j] - delta / 2, m[i] * m[j] / (m[i] + m[j]), r[i] * r[j] / (r[i] + r[j]),
                history.get((i, j), np.zeros(3)), dt,
                ai=r[i] if full else None, aj=r[j] if full else None,
            )  # fmt: skip
            history[(i, j)] = s
            f[i] += fi
            f[j] -= fi
            t[i] += ti
            t[j] += tj
        walls = [
            (np.array([0, 0, 1.0]), x[i, 2]),
            (np.array([0, 1.0, 0]), x[i, 1] + width / 2),
            (np.array([0, -1.0, 0]), width / 2 - x[i, 1]),
        ]
        for k, (normal, gap) in enumerate(walls):
            delta = r[i] - gap
            if delta <= 0:
                history.pop((i, -1 - k), None)
                continue
            fi, ti, _, s = one_contact(
                model, c, normal, delta, v[i], w[i], np.zeros(3),
                r[i] - c.get("f_w", 1.0) * delta, 0.0, m[i], r[i],
                history.get((i, -1 - k), np.zeros(3)), dt, ai=r[i] if full else None,
            )  # fmt: skip
            history[(i, -1 - k)] = s
            f[i] += fi
            t[i] += ti
    return f, t
