"""The references of the contact benchmarks: closed forms, rigid-body limits and each law's design.

Plain Python and numpy, nothing of dem's kernels (dem's parameter builder is used only to read a
law's coefficients, :func:`law_constants`).

**Elastic normal impact** (Hertz 1882; Johnson, Contact Mechanics, 1985, sec. 11.4). Two bodies
of effective mass m*, radius R* and modulus Y* (1/Y* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2) meeting
at relative speed v, F = 4/3 Y* sqrt(R*) delta^(3/2), energy conservation gives

    delta_max = (15 m* v^2 / (16 Y* sqrt(R*)))^(2/5),   F_max = 4/3 Y* sqrt(R*) delta_max^(3/2),
    t_c = 2 (delta_max / v) int_0^1 dx / sqrt(1 - x^(5/2)) = (4/5) B(2/5, 1/2) delta_max / v
        = 2.9432 delta_max / v = 2.8683 (m*^2 / (R* Y*^2 v))^(1/5)

(B the beta function). A linear spring k: delta_max = v sqrt(m*/k), F_max = v sqrt(k m*),
t_c = pi sqrt(m*/k).

**Rigid bodies with Coulomb friction** (Maw, Barber and Fawcett 1976 in their limits; Routh).
Solid spheres (I = 2/5 m r^2) at a point contact: a tangential impulse J changes the contact
point's slip velocity u (the relative tangential velocity of the contact points, with the full
radii) by -J (1/m_1 + 1/m_2 + r_1^2/I_1 + r_2^2/I_2) = -(7/2) J / m* (a wall: m* = m), the
centre velocities by -J/m_1 and +J/m_2 and the spins by (5/2) J / (m_i r_i) each. If the
contact slides throughout, J = mu (1 + e) m* v_n, e the normal restitution, so

    u2 = u1 - (7/2) mu (1 + e) v_n,   dv_t = -mu (1 + e) v_n m*/m_i,
    dw_i = (5/2) mu (1 + e) v_n m* / (m_i r_i),   tan(rebound angle) = v_t2 / (e v_n),

which holds while u2 >= 0, i.e. from psi_1 >= psi* = (7/2) (1 + e) kappa (below). In
Maw et al.'s normalisation, with kappa = k_t / S_n = 4 G* / Y* the ratio of Mindlin's no-slip
tangential stiffness 8 G* a to Hertz's normal tangent stiffness 2 Y* a (2 (1 - nu) / (2 - nu)
for two bodies of one material; 1/G* = (2 - nu1)/G1 + (2 - nu2)/G2),

    psi_1 = kappa u1 / (mu v_n),   psi_2 = kappa u2 / (mu v_n),   Omega = kappa r dw / (mu v_n),

the sliding regime is the line psi_2 = psi_1 - psi* and the spin's change is the constant
Omega = (5/2)(1 + e) kappa (m*/m). Below psi*, rigid-body theory has no answer without a
tangential law: that is what each law decides (:func:`impact_design`, :func:`law_reference`).

**What each of dem's tangential laws is designed to do**:

- ``"impact"``: each impact takes (1 - eps_t) of the slip velocity at first touch, capped by
  Coulomb: J = m* min((1 - eps_t) |u1|, (2/7) |u1|, mu (1 + min(e_n, eps_n)) v_n), e_n the
  normal law's own restitution at the end of its repulsion (the (2/7) |u1| cap is rolling: the
  impact ends when the slip stops). A sphere without spin keeps eps_t of its centre's tangential
  velocity, the contact point 1 - 7/2 (1 - eps_t) of its slip (0.3 at eps_t = 0.8).
- ``"coulomb"``: a tangential spring and dashpot whose k_t / S_n is derived from eps_t
  (:mod:`dem.physics.tangential`) so that an impact that sticks keeps eps_t of the centre's
  tangential velocity; the total force capped at mu |F_n|, the spring then reset to the capped
  force less the dashpot's, but never to more force along the slip than it held (none if it
  held none: :func:`dem.kernels.contact.coulomb_tangential`).
- ``"liggghts"``: LIGGGHTS's history law; for Hertz, Mindlin's no-slip stiffness
  k_t = 8 G* a in total form (F_t = -k_t(a) s), the spring alone capped at mu |F_n|; for the
  linear law k_t = kappa k_n (2/7 by default).

:func:`law_reference` integrates a spring law's own equations (those of the contact routine's
docstring, :mod:`dem.kernels.contact`) in this module's own numpy code, with rigid-body
kinematics at the full radius and a step of 1/20000 of the contact: the continuous-time answer
that dem's kernels approach as dt -> 0. Its ``incremental`` option is Mindlin's no-slip spring
in incremental form (dF_t = -k_t u dt while the contact grows, F_t scaled with a while it
shrinks), the form Maw et al.'s theory tends to where microslip vanishes; the full theory
(Mindlin and Deresiewicz's partial slip) is not integrated here.
"""

from __future__ import annotations

import math

import numpy as np

#: int_0^1 dx / sqrt(1 - x^(5/2)) = (2/5) B(2/5, 1/2): the elastic Hertz impact's time factor.
HERTZ_TIME_INTEGRAL = 0.4 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)
#: A solid sphere's contact-point compliance: the slip changes by 7/2 J / m*.
ROLL = 3.5


def hertz_impact(y_star: float, r_eff: float, m_eff: float, speed: float) -> dict:
    """Elastic Hertz impact at relative speed v: delta_max (m), F_max (N), t_c (s)."""
    delta = (15.0 * m_eff * speed**2 / (16.0 * y_star * math.sqrt(r_eff))) ** 0.4
    return {
        "max_overlap_m": delta,
        "peak_force_n": 4.0 / 3.0 * y_star * math.sqrt(r_eff) * delta**1.5,
        "duration_s": 2.0 * HERTZ_TIME_INTEGRAL * delta / speed,
    }


def linear_impact(stiffness: float, m_eff: float, speed: float) -> dict:
    """Undamped linear spring impact at relative speed v: delta_max, F_max, t_c."""
    return {
        "max_overlap_m": speed * math.sqrt(m_eff / stiffness),
        "peak_force_n": speed * math.sqrt(stiffness * m_eff),
        "duration_s": math.pi * math.sqrt(m_eff / stiffness),
    }


def linear_stiffness_for(duration: float, m_eff: float) -> float:
    """k_n of the linear spring whose undamped impact lasts ``duration``: m* (pi / t_c)^2."""
    return m_eff * (math.pi / duration) ** 2


def sliding_impulse(friction: float, restitution: float, m_eff: float, vn: float) -> float:
    """Rigid Coulomb sliding: the tangential impulse mu (1 + e) m* v_n, N s."""
    return friction * (1.0 + restitution) * m_eff * vn


def impact_design(u1: float, vn: float, m_eff: float, *, eps_t: float, friction: float,
                  eps_n: float, e_n: float) -> float:  # fmt: skip
    """The ``"impact"`` law's tangential impulse |J| (module docstring), N s."""
    return m_eff * min((1.0 - eps_t) * abs(u1), abs(u1) / ROLL,
                       friction * (1.0 + min(e_n, eps_n)) * vn)  # fmt: skip


def normalise(value: float, kappa: float, friction: float, vn: float) -> float:
    """Maw et al.'s normalisation of a slip (or r dw) velocity: kappa value / (mu v_n)."""
    return kappa * value / (friction * vn)


def law_reference(law: dict, u1, vn, m_eff: float, r_eff: float, *,
                  steps: int = 20_000, incremental: bool = False) -> dict:  # fmt: skip
    """A spring law's impact in continuous time, for each slip u1 and approach speed vn (arrays).

    ``law``: {"normal": "hertz_mindlin" | "linear", "tangential": "coulomb" | "liggghts" |
    "none" (no cap), "kn": C_kn (k_n = C_kn a, a = sqrt(R* delta) or 1), "dn": gamma_n =
    dn sqrt(a m*) (Hertz; linear: dn sqrt(m*)), "kt": C_kt (k_t = C_kt a), "dt": gamma_t =
    dt sqrt(a m*) (linear: dt sqrt(m*)), "mu", "limit_force"} (:func:`law_constants`).
    Relative normal and slip motion of rigid spheres: m* delta'' = -F_n, (2/7) m* u' = F_t.
    Velocity Verlet at t_c / ``steps``; the contact ends when delta returns to 0 (or F_n to 0
    with ``limit_force``). Returns {"restitution", "u_out", "impulse_t" (|J|, N s)} as arrays.
    """
    u1 = np.atleast_1d(np.asarray(u1, dtype=float))
    vn = np.broadcast_to(np.asarray(vn, dtype=float), u1.shape)
    hertz = law["normal"] == "hertz_mindlin"
    m_t = m_eff / ROLL
    if hertz:  # the longest contact: the slowest approach's
        t_c = 2.9 * (m_eff**2 / (r_eff * (0.75 * law["kn"]) ** 2 * float(vn.min()))) ** 0.2
    else:
        t_c = math.pi * math.sqrt(m_eff / law["kn"])
    h = t_c / steps
    n = u1.size
    delta = np.zeros(n)
    ddot = vn.copy()  # overlap rate, > 0 approaching
    u = u1.copy()
    s = np.zeros(n)  # spring elongation (total form) or spring force (incremental)
    a_prev = np.zeros(n)
    jt = np.zeros(n)
    done = np.zeros(n, dtype=bool)
    out_e = np.full(n, np.nan)
    out_u = np.full(n, np.nan)
    out_j = np.full(n, np.nan)

    def forces(delta, ddot, u, s, a_prev):
        a = np.sqrt(r_eff * np.maximum(delta, 0.0)) if hertz else np.ones_like(delta)
        fn = law["kn"] * a * delta + law["dn"] * np.sqrt(a * m_eff) * ddot
        if law["limit_force"]:
            fn = np.maximum(fn, 0.0)
        kt = law["kt"] * a
        gt = law["dt"] * np.sqrt(a * m_eff)
        if incremental:
            # s is the spring force: scaled with a while the contact shrinks, plus -k_t u h
            shrink = (a < a_prev) & (a_prev > 0.0)
            s = np.where(shrink, s * a / np.where(a_prev > 0.0, a_prev, 1.0), s) - kt * u * h
            spring = s
        else:
            s = s + u * h  # the elongation; spring force -k_t s
            spring = -kt * s
        cap = law["mu"] * np.abs(fn)
        if law["tangential"] == "coulomb":  # the total force capped, the spring reset to match
            ft = spring - gt * u
            over = np.abs(ft) > cap
            ft = np.where(over, cap * np.sign(ft), ft)
            # ... but never to more force along the slip than the spring held
            reset = ft + gt * u
            held = np.maximum(spring * u, 0.0)
            reset = np.where(reset * u > held, np.where(held > 0.0, spring, 0.0), reset)
            spring = np.where(over, reset, spring)
        elif law["tangential"] == "liggghts":  # the spring capped; dashpot only while sticking
            over = np.abs(spring) > cap
            ft = np.where(over, cap * np.sign(spring), spring - gt * u)
            spring = np.where(over, ft, spring)
        else:
            ft = spring - gt * u
        if incremental:
            s = spring
        else:
            s = np.where(kt > 0.0, -spring / np.where(kt > 0.0, kt, 1.0), s)
        return fn, ft, s, a

    fn, ft, s, a_prev = forces(delta, ddot, u, s, a_prev)
    for _ in range(20 * steps):
        ddot = ddot - 0.5 * h * fn / m_eff
        u = u + 0.5 * h * ft / m_t
        jt = jt + 0.5 * h * ft
        delta = delta + h * ddot
        fn, ft, s, a_prev = forces(delta, ddot, u, s, a_prev)
        ddot = ddot - 0.5 * h * fn / m_eff
        u = u + 0.5 * h * ft / m_t
        jt = jt + 0.5 * h * ft
        over = ~done & ((delta <= 0.0) | (law["limit_force"] & (fn <= 0.0) & (ddot < 0.0)))
        out_e[over] = -ddot[over] / vn[over]
        out_u[over] = u[over]
        out_j[over] = np.abs(jt[over])
        done |= over
        fn = np.where(done, 0.0, fn)
        ft = np.where(done, 0.0, ft)
        if done.all():
            break
    return {"restitution": out_e, "u_out": out_u, "impulse_t": out_j}
