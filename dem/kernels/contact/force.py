"""One contact's forces: the law on scalars for CPU and GPU, its CPU wrapper, lever arms, walls.

:func:`contact_core` is the contact law on scalars (the history in and out as numbers), for the
CPU and GPU engines alike; :func:`contact_force` is the CPU's wrapper that reads the contact's
history row, calls the core and writes the row back.
"""

import numba

from dem.config import (
    NUMBA_OPTIONS,
)
from dem.kernels.contact.laws import (
    coulomb_tangential,
    impact_tangential,
    law_coefficients,
    liggghts_tangential,
    plastic_normal,
    rolling_cdt,
    spring_step,
)
from dem.kernels.contact.params import (
    IMPACT,
    N_PARAMS,
    P_IMPACT_CAP,
    P_IMPACT_RATIO,
    P_LIMIT_FORCE,
    P_MASS_N,
    P_MASS_T,
    P_MU,
    P_MU_ROLL,
    P_NORMAL_STICK_RATE,
    P_PLASTIC,
    P_SLIP_ARM,
    P_STICK_RATE,
    P_STICK_ZETA,
    P_TANGENTIAL,
    P_WALL_ARM,
)


@numba.njit(inline="always", **NUMBA_OPTIONS)
def contact_core(
    model, p, nx, ny, nz, delta, vrx, vry, vrz, wix, wiy, wiz, wjx, wjy, wjz,
    ci, cj, ai, aj, m_eff, r_eff, h0, h1, h2, h3, h4, dt,
):  # fmt: skip
    """Force on i, torques on i and j and the new history of one touching contact: scalars only.

    The contact law itself, shared by the CPU engine (through :func:`contact_force`) and the GPU
    kernels (:mod:`dem.kernels.cuda`), which call it as a device function. It takes the
    contact's history as five numbers and returns the new five, so it touches no array but
    ``p``, which may be anything indexable: the float64 parameter array on the CPU, a tuple of
    floats on the GPU (numba compiles one specialisation per type). Inlined at numba's IR level
    so that the CPU's wrappers compile to the same code as before the split.

    Args:
        model: Normal law id (:data:`MODELS`).
        p: Contact parameters, N_PARAMS floats (:mod:`dem.kernels.contact.params`).
        nx, ny, nz: Unit normal from j to i.
        delta: Overlap > 0, m.
        vrx, vry, vrz: v_i - v_j, m/s.
        wix, wiy, wiz, wjx, wjy, wjz: Spins of i and j, rad/s.
        ci, cj: Lever arms of the torques, from the centres to the contact point, m.
        ai, aj: Lever arms of the slip velocity, m: ci, cj, or the full radii
            (``[contact] slip_lever_arm``).
        m_eff, r_eff: m*, kg, and R*, m.
        h0, h1, h2, h3, h4: The contact's history (:data:`HISTORY_WIDTH`): the spring s (h0..h2);
            "impact" adds its phase and the previous normal velocity (h3, h4; with eps_n = 0
            h4 is the plastic contact's stick force, :func:`plastic_normal`), which the other
            laws pass through unchanged.
        dt: Time step, s.

    Returns:
        (fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz, fn, h0, h1, h2, h3, h4): force on i (N),
        torques on i and j (N m), the normal force F_n (N) and the new history.

    """
    kn, gn, kt, gt = law_coefficients(model, delta, m_eff, r_eff, p)
    vn = vrx * nx + vry * ny + vrz * nz
    fn = kn * delta - gn * vn
    if p[P_LIMIT_FORCE] != 0.0 and fn < 0.0:
        fn = 0.0
    # slip velocity at the contact point: tangential part minus (a_i w_i + a_j w_j) x n
    wx = ai * wix + aj * wjx
    wy = ai * wiy + aj * wjy
    wz = ai * wiz + aj * wjz
    vtx = vrx - vn * nx - (wy * nz - wz * ny)
    vty = vry - vn * ny - (wz * nx - wx * nz)
    vtz = vrz - vn * nz - (wx * ny - wy * nx)
    tangential = p[P_TANGENTIAL]
    if tangential == IMPACT:
        plastic = p[P_PLASTIC] != 0.0
        fs = h4
        stopped = False
        if plastic:  # eps_n = 0: the perfectly plastic contact; h4 holds its stick's force
            fn, h3, fs, stopped = plastic_normal(fn, vn, p[P_MASS_N] * m_eff,
                                                 p[P_NORMAL_STICK_RATE], p[P_STICK_ZETA], dt,
                                                 h3, h4)  # fmt: skip
        ftx, fty, ftz, h0, h1, h2, h3, h4 = impact_tangential(
            p[P_IMPACT_RATIO], p[P_IMPACT_CAP], p[P_MU], p[P_MASS_T], p[P_STICK_RATE],
            p[P_STICK_ZETA], nx, ny, nz, vn, fn, vtx, vty, vtz, kn, m_eff, dt,
            h0, h1, h2, h3, h4, plastic, stopped,
        )  # fmt: skip
        if plastic:
            h4 = fs
    else:
        # tangential spring: increment, then project onto the current tangent plane
        sx, sy, sz = spring_step(h0, h1, h2, vtx, vty, vtz, nx, ny, nz, dt)
        f_max = p[P_MU] * abs(fn)
        if tangential != 0.0:
            ftx, fty, ftz, h0, h1, h2 = liggghts_tangential(kt, gt, f_max, sx, sy, sz, vtx, vty,
                                                            vtz)  # fmt: skip
        else:
            ftx, fty, ftz, h0, h1, h2 = coulomb_tangential(kt, gt, f_max, sx, sy, sz, vtx, vty,
                                                           vtz, True)  # fmt: skip
    # torques -c n x F_t, plus rolling resistance
    cx = ny * ftz - nz * fty
    cy = nz * ftx - nx * ftz
    cz = nx * fty - ny * ftx
    ti, tj = rolling_cdt(
        p[P_MU_ROLL], fn, r_eff, nx, ny, nz, wix, wiy, wiz, wjx, wjy, wjz,
        (-ci * cx, -ci * cy, -ci * cz), (-cj * cx, -cj * cy, -cj * cz),
    )  # fmt: skip
    return (fn * nx + ftx, fn * ny + fty, fn * nz + ftz, ti[0], ti[1], ti[2], tj[0], tj[1], tj[2],
            fn, h0, h1, h2, h3, h4)  # fmt: skip


@numba.njit(**NUMBA_OPTIONS)
def contact_force(
    model, p, nx, ny, nz, delta, vrx, vry, vrz, wix, wiy, wiz, wjx, wjy, wjz,
    ci, cj, ai, aj, m_eff, r_eff, hist, k, dt,
):  # fmt: skip
    """Force on i and torques on i and j of one touching contact; updates ``hist[k]`` in place.

    The CPU's array-facing wrapper of :func:`contact_core`: it reads the contact's history row
    (h3, h4 only where the row has five columns, else zeros), calls the core and writes the row
    back. Arguments as :func:`contact_core`, with the history as ``hist``, shape (n, width)
    (:data:`HISTORY_WIDTH`), whose row ``k`` is this contact.

    Returns:
        (fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz, fn): force on i (N), torques on i and j
        (N m) and the normal force F_n (N).

    """
    wide = hist.shape[1] > 3
    h3 = hist[k, 3] if wide else 0.0
    h4 = hist[k, 4] if wide else 0.0
    f = contact_core(
        model, p, nx, ny, nz, delta, vrx, vry, vrz, wix, wiy, wiz, wjx, wjy, wjz,
        ci, cj, ai, aj, m_eff, r_eff, hist[k, 0], hist[k, 1], hist[k, 2], h3, h4, dt,
    )  # fmt: skip
    hist[k, 0] = f[10]
    hist[k, 1] = f[11]
    hist[k, 2] = f[12]
    if wide:
        hist[k, 3] = f[13]
        hist[k, 4] = f[14]
    return f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8], f[9]


@numba.njit(inline="always", **NUMBA_OPTIONS)
def wall_row(p):
    """The grain-wall law's parameters: the second row of ``p``, or ``p`` if it holds one law.

    :class:`dem.physics.contact.ContactLaw` packs the grain-grain row, then the grain-wall row.
    """
    if p.shape[0] >= 2 * N_PARAMS:
        return p[N_PARAMS : 2 * N_PARAMS]
    return p


@numba.njit(inline="always", **NUMBA_OPTIONS)
def pair_arms(p, ri, rj, delta):
    """Lever arms of a sphere-sphere contact of overlap delta: (c_i, c_j, a_i, a_j), m.

    Torques act at c = r - delta / 2 (the middle of the overlap); the slip velocity takes the
    same arms, or the full radii with ``slip_lever_arm = "radius"`` (``p[P_SLIP_ARM]`` = 1).
    """
    return (ri - 0.5 * delta, rj - 0.5 * delta, ri - (1.0 - p[P_SLIP_ARM]) * 0.5 * delta,
            rj - (1.0 - p[P_SLIP_ARM]) * 0.5 * delta)  # fmt: skip


@numba.njit(inline="always", **NUMBA_OPTIONS)
def wall_arms(p, r, delta):
    """Lever arms of a sphere-wall contact of overlap delta: (c_i, a_i), m.

    c_i = r - f_w delta (``p[P_WALL_ARM]``); the slip's arm a_i is c_i, or r with
    ``slip_lever_arm = "radius"``. The wall's own arms are zero.
    """
    f_w = p[P_WALL_ARM]
    return r - f_w * delta, r - (1.0 - p[P_SLIP_ARM]) * f_w * delta


@numba.njit(inline="always", **NUMBA_OPTIONS)
def add_wall_contact(
    model, p, nx, ny, nz, delta, v, omega, i, m, r, hist, row, dt, fx, fy, fz, tx, ty, tz,
):  # fmt: skip
    """(fx, ..., tz) plus the force and torque of sphere i's contact with a wall or triangle.

    The wall is fixed in the trough frame, of infinite mass and radius: normal n (wall to
    sphere), overlap delta, m* = m, R* = r, lever arm r - f_w delta (``p[P_WALL_ARM]``),
    spring in ``hist[row]``.
    """
    ci, ai = wall_arms(p, r, delta)
    f = contact_force(
        model, p, nx, ny, nz, delta, v[i, 0], v[i, 1], v[i, 2], omega[i, 0], omega[i, 1],
        omega[i, 2], 0.0, 0.0, 0.0, ci, 0.0, ai, 0.0, m, r, hist, row, dt,
    )  # fmt: skip
    return fx + f[0], fy + f[1], fz + f[2], tx + f[3], ty + f[4], tz + f[5]


#: :func:`contact_force` inlined at numba's IR level, for the pair loop, where a call per pair
#: (two arrays and twenty scalars) cost about a sixth of the loop; the walls, which call it only
#: on contact, keep the call (inlining it everywhere doubled the compile time).
contact_force_inlined = numba.njit(inline="always", **NUMBA_OPTIONS)(contact_force.py_func)


# --- time scales of the laws (Python; used to choose and to check the time step) ----------------
