"""The contact sub-models as numba functions of scalars.

The normal size factor and the four coefficients, the "coulomb", "liggghts" and "impact"
tangential laws, the "impact" law's plastic normal contact (eps_n = 0), rolling resistance.

Scalars in, scalars out, so the same functions can run inside GPU kernels; their constants come
from the parameter array laid out by :mod:`dem.kernels.contact.params`.
"""

import math

import numba

from dem.config import (
    NUMBA_OPTIONS,
)
from dem.kernels.contact.params import (
    HERTZ,
    IMPACT_MAX_PHASE,
    P_DAMP_N,
    P_DAMP_N_SCALE,
    P_DAMP_T,
    P_DAMP_T_SCALE,
    P_KN_COEF,
    P_KT_COEF,
)

# --- sub-models: scalars in, scalars out (the same functions can run in GPU kernels) -------------


@numba.njit(inline="always", **NUMBA_OPTIONS)
def normal_scale(normal, delta, r_eff):
    """Normal sub-model: the contact-size factor a that every coefficient scales with.

    Linear: a = 1 (k_n constant). Hertz: a = sqrt(R* delta), the radius of the contact patch
    over sqrt(R*), so that k_n = 4/3 Y* a and the tangent stiffness S_n = 2 Y* a.
    """
    if normal == HERTZ:
        return math.sqrt(r_eff * delta)
    return 1.0


@numba.njit(**NUMBA_OPTIONS)
def law_coefficients(model, delta, m_eff, r_eff, p):
    """(k_n, gamma_n, k_t, gamma_t) of normal law ``model`` at overlap delta.

    Every coefficient is a constant of the sub-models (:func:`make_params`) times the normal
    sub-model's size factor a (:func:`normal_scale`):

        k_n = C_kn a,  gamma_n = C_dn sqrt(B_n a m*),  k_t = C_kt a,  gamma_t = C_dt sqrt(B_t a m*)

    linear: C_kn = k_n, C_dn = -2 beta, B_n = k_n, C_kt = kappa k_n; "liggghts" C_dt = C_dn,
    B_t = B_n (gamma_t = gamma_n); "coulomb" C_dt = 2 zeta_t, B_t = k_t f_t. Hertz: C_kn = 4/3 Y*,
    C_dn = -2 sqrt(5/6) beta sqrt(2 Y*), B_n = 1 (gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*));
    "liggghts" C_kt = 8 G*, C_dt = -2 sqrt(5/6) beta sqrt(8 G*); "coulomb" C_kt = 2 kappa Y*,
    C_dt = 2 zeta_t sqrt(2 kappa Y* f_t); B_t = 1. The tangential dashpot shares the normal
    one's square root where B_t = B_n: two square roots per contact.
    """
    a = normal_scale(model, delta, r_eff)
    kn = p[P_KN_COEF] * a
    qn = math.sqrt(p[P_DAMP_N_SCALE] * a * m_eff)
    gn = p[P_DAMP_N] * qn
    kt = p[P_KT_COEF] * a
    if p[P_DAMP_T_SCALE] == p[P_DAMP_N_SCALE]:
        return kn, gn, kt, p[P_DAMP_T] * qn
    return kn, gn, kt, p[P_DAMP_T] * math.sqrt(p[P_DAMP_T_SCALE] * a * m_eff)


@numba.njit(**NUMBA_OPTIONS)
def coulomb_tangential(kt, gt, f_max, sx, sy, sz, vtx, vty, vtz, passive):
    """Tangential sub-model "coulomb": total force capped at f_max = mu |F_n|, spring reset.

    F_t = -k_t s - gamma_t v_t. Where |F_t| > f_max the force is scaled to f_max (the contact
    slides) and the spring reset to the part of it that the dashpot does not take,
    -k_t s = F_t + gamma_t v_t (LAMMPS's ``tangential mindlin`` stops there), with one rule:
    the reset never leaves the spring more force along the slip v_t than it held before the
    reset, and none where it held none. Where (F_t + gamma_t v_t) . v_t exceeds
    max(-k_t s . v_t, 0), the excess is taken off along v_t (the nearest such force).

    Why: sliding relaxes the spring; it cannot load it along the slip. The plain reset does so
    where the dashpot alone exceeds the cap, gamma_t |v_t| > f_max: at first touch, where F_n
    and so f_max are near zero, it stores about +gamma_t v_t, a force along the slip. With Hertz
    k_t grows with the contact radius faster than gamma_t, the stored force outgrows the
    dashpot, and friction of mu F_n then pushed the slip forward: the contact raised the kinetic
    energy of the tangential motion and the spins (by 24 % in the dt -> 0 limit,
    validation/contact-benchmarks, test 5 at psi_1 = 1) and psi_2 depended on dt at first
    order. A spring whose own force already points along a reversed slip (it returns what it
    stored, capped) keeps the plain reset, and so does every reset that stores no force along
    the slip: there the arithmetic is the plain one, bit for bit. Without a dashpot the capped
    force is the spring's own scaled down, so the rule does not act (to round-off).

    ``passive`` False: the plain reset (the "impact" law's enduring stick, whose k and gamma are
    constants of the step). Returns (F_t, s) as six floats.
    """
    ftx = -kt * sx - gt * vtx
    fty = -kt * sy - gt * vty
    ftz = -kt * sz - gt * vtz
    f_mag = math.sqrt(ftx * ftx + fty * fty + ftz * ftz)
    if f_mag > f_max:
        ratio = f_max / f_mag
        ftx *= ratio
        fty *= ratio
        ftz *= ratio
        if kt > 0.0:
            fsx = ftx + gt * vtx
            fsy = fty + gt * vty
            fsz = ftz + gt * vtz
            along = fsx * vtx + fsy * vty + fsz * vtz
            if passive and along > 0.0:  # > 0 only where v_t != 0
                held = -kt * (sx * vtx + sy * vty + sz * vtz)  # the spring's, along v_t
                if held < 0.0:
                    held = 0.0
                if along > held:
                    c = (along - held) / (vtx * vtx + vty * vty + vtz * vtz)
                    fsx -= c * vtx
                    fsy -= c * vty
                    fsz -= c * vtz
            sx = -fsx / kt
            sy = -fsy / kt
            sz = -fsz / kt
    return ftx, fty, ftz, sx, sy, sz


@numba.njit(**NUMBA_OPTIONS)
def liggghts_tangential(kt, gt, f_max, sx, sy, sz, vtx, vty, vtz):
    """Tangential sub-model "liggghts": spring capped at f_max, dashpot only while sticking.

    Returns (F_t, s) as six floats.
    """
    ftx = -kt * sx
    fty = -kt * sy
    ftz = -kt * sz
    s_mag = math.sqrt(sx * sx + sy * sy + sz * sz)
    f_shear = kt * s_mag
    if f_shear > f_max:
        if s_mag > 0.0:
            ratio = f_max / f_shear
            ftx *= ratio
            fty *= ratio
            ftz *= ratio
            sx = -ftx / kt
            sy = -fty / kt
            sz = -ftz / kt
        else:
            ftx = 0.0
            fty = 0.0
            ftz = 0.0
    else:
        ftx -= gt * vtx
        fty -= gt * vty
        ftz -= gt * vtz
    return ftx, fty, ftz, sx, sy, sz


@numba.njit(inline="always", **NUMBA_OPTIONS)
def spring_step(s0, s1, s2, vtx, vty, vtz, nx, ny, nz, dt):
    """Spring s plus v_t dt, projected onto the tangent plane of n: (s_x, s_y, s_z)."""
    sx = s0 + vtx * dt
    sy = s1 + vty * dt
    sz = s2 + vtz * dt
    sn = sx * nx + sy * ny + sz * nz
    return sx - sn * nx, sy - sn * ny, sz - sn * nz


@numba.njit(inline="always", **NUMBA_OPTIONS)
def _stick(m_t, stick_rate, stick_zeta, dt):
    """The enduring stick's spring and dashpot (k_s, gamma_s) for mass m_t.

    Computed only where the stick acts (an impact's end, an enduring contact): an impact's steps
    skip its two divisions.
    """
    return m_t * stick_rate * stick_rate / (dt * dt), 2.0 * stick_zeta * stick_rate * m_t / dt


@numba.njit(**NUMBA_OPTIONS)
def impact_tangential(
    impact_ratio, impact_cap, mu, mass_t, stick_rate, stick_zeta,
    nx, ny, nz, vn, fn, vtx, vty, vtz, kn, m_eff, dt, h0, h1, h2, h3, h4, plastic, stopped,
):  # fmt: skip
    """Tangential sub-model "impact" (module docstring): force and the contact's new history.

    History (5 floats): h3 is the phase (0 a new contact, 1 + theta an impact, theta the radians
    of the local normal oscillation sqrt(k_n / m*) since first touch, -1 enduring; -2 enduring
    while a plastic contact's approach goes on, :func:`plastic_normal`), h4 the normal velocity
    v_n = v_r . n of the previous step (a plastic contact keeps its normal stick's force there
    instead, :func:`plastic_normal`), (h0, h1, h2) the impact's force ratio vector c (impact)
    or the stick's spring s (enduring). Parameters: ``impact_ratio`` (1 - eps_t) / (1 + e_n),
    ``impact_cap`` the largest c, ``mu``, ``mass_t`` f_t, ``stick_rate`` alpha and
    ``stick_zeta`` of the stick, ``plastic`` True for the perfectly plastic normal contact
    (eps_n = 0), whose impact ends in the step its approach stops (``stopped``: it has no
    restitution phase), else when the separating speed stops growing.

    Returns (F_t, h) as eight floats.
    """
    fnp = fn if fn > 0.0 else 0.0
    f_max = mu * fnp
    phase = h3
    if phase == 0.0:
        # first touch: an approach makes an impact that takes (1 - eps_t) of the slip velocity
        # through a tangential force c F_n, c = (1 - eps_t) |v_t| / ((1 + e_n) |v_n|), capped
        # where the rigid impact's Coulomb bound mu (1 + eps_n) m |v_n| is reached
        vt = math.sqrt(vtx * vtx + vty * vty + vtz * vtz)
        h0 = 0.0
        h1 = 0.0
        h2 = 0.0
        if vn < 0.0:
            phase = 1.0
            if vt > 0.0:
                ratio = impact_ratio * vt / -vn
                if ratio > impact_cap:
                    ratio = impact_cap
                h0 = ratio * vtx / vt
                h1 = ratio * vty / vt
                h2 = ratio * vtz / vt
        else:
            phase = -1.0
    if phase > 0.0:
        # impact: F_t = -F_n c, c projected onto the tangent plane; ends when the separating
        # speed stops growing (the contact force is back to the external load), when the slip
        # along c has stopped, or after IMPACT_MAX_PHASE
        cn = h0 * nx + h1 * ny + h2 * nz
        cx = h0 - cn * nx
        cy = h1 - cn * ny
        cz = h2 - cn * nz
        ftx = -fnp * cx
        fty = -fnp * cy
        ftz = -fnp * cz
        theta = phase - 1.0 + dt * math.sqrt(kn / m_eff)
        slip = vtx * cx + vty * cy + vtz * cz
        if plastic:
            over = stopped
        else:
            over = vn > 0.0 and vn <= h4
        stuck = slip <= 0.0 and cx * cx + cy * cy + cz * cz > 0.0
        if not (over or stuck or theta > IMPACT_MAX_PHASE):
            return ftx, fty, ftz, cx, cy, cz, 1.0 + theta, vn
        # switch to the enduring stick, its spring set so that the force is continuous; a
        # plastic contact whose approach goes on marks it (-2, :func:`plastic_normal`)
        after = -2.0 if plastic and not over else -1.0
        ks, gs = _stick(mass_t * m_eff, stick_rate, stick_zeta, dt)
        return (ftx, fty, ftz, -(ftx + gs * vtx) / ks, -(fty + gs * vty) / ks,
                -(ftz + gs * vtz) / ks, after, vn)  # fmt: skip
    # enduring: a stiff stick, the total force capped at mu F_n (spring reset to match)
    ks, gs = _stick(mass_t * m_eff, stick_rate, stick_zeta, dt)
    sx, sy, sz = spring_step(h0, h1, h2, vtx, vty, vtz, nx, ny, nz, dt)
    ftx, fty, ftz, sx, sy, sz = coulomb_tangential(ks, gs, f_max, sx, sy, sz, vtx, vty, vtz, False)
    return ftx, fty, ftz, sx, sy, sz, phase, vn


@numba.njit(**NUMBA_OPTIONS)
def plastic_normal(fn, vn, m_n, stick_rate, stick_zeta, dt, phase, fs):
    """The "impact" law's normal force with eps_n = 0: a perfectly plastic contact.

    A contact of eps_n = 0 returns none of its approach speed, and no contact pulls. The
    material law (``fn``: the spring and its damping, F_n = k_n delta - gamma_n v_n) alone
    cannot do both: its dashpot leaves a rebound of e_n = 0.135 of the approach speed when the
    force is not let pull, and pulls the grains back together when it is (then it also holds
    them after the load has gone). So:

    - while the contact approaches (an impact, phase > 0, a new contact with v_n < 0, or -2:
      the impact's slip has stopped but the approach goes on) the force is the material law's,
      but never more than m_n |v_n| / dt, the force that stops the approach within the step
      (velocity Verlet changes v_n by F dt / m_n from this half step to the next), and never
      below zero: the approach is stopped by Hertz's (or the linear) spring and damping, and
      the normal impulse of the impact is m* |v_n0|, Newton's impact law with eps_n = 0;
    - in the step the approach stops (the cap binds, or v_n >= 0) the elastic energy the impact
      stored is dissipated, and the contact then unloads rigidly: a stick spring-dashpot sized
      by the time step (``stick_rate`` alpha_n, :data:`dem.config.DEM_NORMAL_STICK_RATE`, and the
      tangential stick's zeta: k = m_n (alpha_n / dt)^2, gamma = 2 zeta alpha_n m_n / dt) from
      zero force, capped at the
      material force (loading beyond the dent follows the material law, the spring reset to
      match) and at zero (it never pulls; the anchor follows a grain that leaves). As dt
      shrinks it converges to a rigid support.

    This is Walton and Braun's elastic-plastic contact with an unloading branch as stiff as the
    step resolves (its restitution sqrt(k_load / k_unload) -> 0). ``m_n`` is the contact's
    normal effective mass f_n m*, ``phase`` the contact's phase (h3 of
    :func:`impact_tangential`), ``fs`` the stick's spring force (h4; 0 for a new contact).

    Returns (F_n, phase, fs, stopped): the normal force, N, the phase (-2 becomes -1 when the
    approach stops), the stick's new spring force, N, and whether the approach stopped in this
    step (the impact's end, :func:`impact_tangential`).
    """
    if fn < 0.0:
        fn = 0.0
    approaching = phase > 0.0 or phase == -2.0 or (phase == 0.0 and vn < 0.0)
    if approaching:
        stop = -m_n * vn / dt
        if fn < stop:
            return fn, phase, 0.0, False
        if stop < 0.0:
            stop = 0.0
        return stop, (-1.0 if phase == -2.0 else phase), 0.0, True
    ks = m_n * stick_rate * stick_rate / (dt * dt)
    gs = 2.0 * stick_zeta * stick_rate * m_n / dt
    fs -= ks * vn * dt
    f = fs - gs * vn
    if f > fn:
        f = fn
        fs = fn + gs * vn
    if f < 0.0:
        f = 0.0
        fs = gs * vn
    return f, phase, fs, False


@numba.njit(inline="always", **NUMBA_OPTIONS)
def rolling_cdt(mu_roll, fn, r_eff, nx, ny, nz, wix, wiy, wiz, wjx, wjy, wjz, ti, tj):
    """Rolling sub-model (LIGGGHTS ``cdt``): the torques ``ti`` on i and ``tj`` on j plus its own.

    tau_i -= mu_r |F_n| R* w_r / |w_r|, tau_j += the same, with w_r = omega_i - omega_j
    without its normal part; nothing when mu_r = 0 or w_r = 0. ``ti`` and ``tj`` are 3-tuples;
    returns the two updated 3-tuples.
    """
    if mu_roll > 0.0:
        rx = wix - wjx
        ry = wiy - wjy
        rz = wiz - wjz
        rn = rx * nx + ry * ny + rz * nz
        rx -= rn * nx
        ry -= rn * ny
        rz -= rn * nz
        r_mag = math.sqrt(rx * rx + ry * ry + rz * rz)
        if r_mag > 0.0:
            scale = mu_roll * abs(fn) * r_eff / r_mag
            ti = (ti[0] - scale * rx, ti[1] - scale * ry, ti[2] - scale * rz)
            tj = (tj[0] + scale * rx, tj[1] + scale * ry, tj[2] + scale * rz)
    return ti, tj
