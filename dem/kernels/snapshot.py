"""Every contact of a frame: where it is, its normal and tangential force and its overlap.

:func:`contact_snapshot` evaluates each touching pair and each flat-wall contact with the
step's own contact routine (:func:`dem.kernels.contact.contact_force`, the same law, lever arms
and contact history) on a copy of its history row, so the run's state is left as it was. The
forces are those of the frame's positions and velocities from the stored history: the
tangential spring advanced by one step's slip v_t dt, as the next step would advance it (for a
sticking contact a fraction dt / (its age) of its force; none for one sliding at the Coulomb
cap). A trough mesh's triangle contacts are not listed (``output.contacts`` refuses a mesh).

Cost: one pass over the pairs and the spheres, O(pairs + spheres), at each frame that asks.
"""

import math

import numba
import numpy as np

from dem.config import NUMBA_OPTIONS
from dem.kernels.contact import contact_force, pair_arms, wall_arms, wall_row
from dem.kernels.forces import N_WALLS, flat_wall, pair_separation

#: What ``out_kind`` holds: a pair of spheres, or sphere i on the floor, a side wall, the back.
PAIR, FLOOR, WALL_LOW_Y, WALL_HIGH_Y, BACK = 0, 1, 2, 3, 4


@numba.njit(**NUMBA_OPTIONS)
def contact_snapshot(
    model, p, x, v, omega, radius, mass, pair_i, pair_j, n_pairs, hist, wall_hist, length,
    half_width, back, dt, out_kind, out_i, out_j, out_point, out_normal, out_fn, out_ft,
    out_overlap,
):  # fmt: skip
    """Fill the ``out_*`` rows with every touching contact; returns how many.

    ``out_kind`` (:data:`PAIR` ...), ``out_i``/``out_j`` (spheres; j = -1 for a wall),
    ``out_point`` (the middle of the overlap, m), ``out_normal`` (unit, from j or the wall to
    i), ``out_fn`` (F_n on i along the normal, N: positive pushes), ``out_ft`` (the tangential
    force on i, N), ``out_overlap`` (m). The rows must hold ``n_pairs + N_WALLS n``.
    """
    half = 0.5 * length
    tmp = np.empty((1, hist.shape[1]))
    c = 0
    for k in range(n_pairs):
        i = pair_i[k]
        j = pair_j[k]
        dx, dy, dz, d2 = pair_separation(x, i, j, length, half)
        ri = radius[i]
        rj = radius[j]
        rsum = ri + rj
        if d2 >= rsum * rsum:
            continue
        d = math.sqrt(d2)
        delta = rsum - d
        nx, ny, nz = dx / d, dy / d, dz / d
        for w in range(hist.shape[1]):
            tmp[0, w] = hist[k, w]
        ci, cj, ai, aj = pair_arms(p, ri, rj, delta)
        mi = mass[i]
        mj = mass[j]
        f = contact_force(
            model, p, nx, ny, nz, delta, v[i, 0] - v[j, 0], v[i, 1] - v[j, 1], v[i, 2] - v[j, 2],
            omega[i, 0], omega[i, 1], omega[i, 2], omega[j, 0], omega[j, 1], omega[j, 2],
            ci, cj, ai, aj, mi * mj / (mi + mj), ri * rj / rsum, tmp, 0, dt,
        )  # fmt: skip
        reach = ri - 0.5 * delta
        c = _row(c, PAIR, i, j, x[i, 0] - nx * reach, x[i, 1] - ny * reach, x[i, 2] - nz * reach,
                 nx, ny, nz, f, delta, out_kind, out_i, out_j, out_point, out_normal, out_fn,
                 out_ft, out_overlap)  # fmt: skip
    pw = wall_row(p)
    for i in range(x.shape[0]):
        r = radius[i]
        for w in range(N_WALLS):
            if w < N_WALLS - 1:
                gap, ny, nz = flat_wall(w, x[i, 1], x[i, 2], half_width)
                nx = 0.0
            else:
                gap, nx, ny, nz = x[i, 0] - back, 1.0, 0.0, 0.0
            delta = r - gap
            if delta <= 0.0:
                continue
            row = N_WALLS * i + w
            for h in range(wall_hist.shape[1]):
                tmp[0, h] = wall_hist[row, h]
            ci, ai = wall_arms(pw, r, delta)
            f = contact_force(
                model, pw, nx, ny, nz, delta, v[i, 0], v[i, 1], v[i, 2], omega[i, 0],
                omega[i, 1], omega[i, 2], 0.0, 0.0, 0.0, ci, 0.0, ai, 0.0, mass[i], r, tmp, 0, dt,
            )  # fmt: skip
            reach = r - 0.5 * delta
            c = _row(c, FLOOR + w, i, -1, x[i, 0] - nx * reach, x[i, 1] - ny * reach,
                     x[i, 2] - nz * reach, nx, ny, nz, f, delta, out_kind, out_i, out_j,
                     out_point, out_normal, out_fn, out_ft, out_overlap)  # fmt: skip
    return c


@numba.njit(inline="always", **NUMBA_OPTIONS)
def _row(c, kind, i, j, px, py, pz, nx, ny, nz, f, delta, out_kind, out_i, out_j, out_point,
         out_normal, out_fn, out_ft, out_overlap):  # fmt: skip
    fn = f[9]
    out_kind[c] = kind
    out_i[c] = i
    out_j[c] = j
    out_point[c, 0] = px
    out_point[c, 1] = py
    out_point[c, 2] = pz
    out_normal[c, 0] = nx
    out_normal[c, 1] = ny
    out_normal[c, 2] = nz
    out_fn[c] = fn
    out_ft[c, 0] = f[0] - fn * nx
    out_ft[c, 1] = f[1] - fn * ny
    out_ft[c, 2] = f[2] - fn * nz
    out_overlap[c] = delta
    return c + 1
