"""Contact laws as sub-models (normal, damping, tangential, rolling); one contact routine uses them.

Each sub-model is a small ``@njit`` function of scalars that returns scalars (the contact's
history goes in and comes out as numbers), so the same functions can run inside GPU kernels;
:func:`contact_force` is the thin wrapper that reads the parameter array and the history row.
What the rest of dem asks of a law (case keys, time step, export, calibration) is its row in
:mod:`dem.physics.laws`.

A contact between sphere i and sphere j (or a wall, j = wall) is described by

- the unit normal n pointing from j to i and the overlap delta = r_i + r_j - |x_i - x_j| > 0,
- the relative velocity of the centres v_r = v_i - v_j and the spins omega_i, omega_j,
- the lever arms c_i = r_i - delta / 2, c_j = r_j - delta / 2 (a wall: c_i = r_i - f_w delta,
  c_j = 0, with f_w = 1, the contact point on the wall's surface, or f_w = 1/2, LIGGGHTS's
  midpoint of the overlap: ``[contact] wall_lever_arm``, :data:`WALL_LEVER_ARMS`),
- the effective mass m* = m_i m_j / (m_i + m_j) and radius R* = r_i r_j / (r_i + r_j) (a wall has
  infinite mass and radius: m* = m_i, R* = r_i),
- the tangential spring elongation s (3 floats of contact history, per contact pair).

A *law* maps (delta, m*, R*) to the four coefficients (k_n, gamma_n, k_t, gamma_t); the
spring-dashpot routine :func:`contact_force` turns them into forces:

    F_n = k_n delta - gamma_n (v_r . n)                    (clamped to >= 0 with limit_force)
    v_t = v_r - (v_r . n) n - (c_i omega_i + c_j omega_j) x n   (slip velocity at the contact)
    s  <- s + v_t dt;  s <- s - (s . n) n                  (increment, then project)
    F_i = F_n n + F_t,  tau_i = -c_i n x F_t,  tau_j = -c_j n x F_t,  F_j = -F_i

with the tangential force F_t by one of two conventions (``[contact] tangential``):

- ``"coulomb"`` (default; Luding 2008, LAMMPS ``pair granular``): the *total* tangential force,
  spring plus dashpot, is capped at Coulomb's limit, and the spring is reset to match:

      F_t = -k_t s - gamma_t v_t;  if |F_t| > mu |F_n|:
          F_t <- mu |F_n| F_t / |F_t|,  s <- -(F_t + gamma_t v_t) / k_t

  so a contact never transmits more than mu |F_n|, and a stiff contact converges to rigid
  Coulomb friction (stick, or slide with mu |F_n| opposing the slip).
- ``"liggghts"`` (LIGGGHTS ``tangential_model history``, for deck equivalence): the Coulomb test
  is made on the spring alone and the dashpot is added while sticking:

      F_t = -k_t s - gamma_t v_t                            if k_t |s| <= mu |F_n|
      F_t = -mu |F_n| s / |s|,  s <- -F_t / k_t             otherwise (sliding, no damping)

  While sticking, a heavily damped contact can transmit more than mu |F_n|.
- ``"impact"`` (impact-aware: eps_t is a material property, not a per-drive fit). One spring
  cannot be both soft enough during an impact to return eps_t = 0.8 (k_t / k_n ~ 0.02-0.1) and
  stiff enough at rest to stick as Coulomb's rigid stick (that spring rings near the drive
  frequency). So a contact remembers its phase (5 floats of history, :data:`HISTORY_WIDTH`):

  * *impact*, from first touch while approaching (v_n = v_r . n < 0): at first touch the slip
    velocity v_t0 and approach speed |v_n0| fix a force ratio
    c = min((1 - eps_t) |v_t0| / |v_n0|, mu (1 + eps_n)) / (1 + e_n), and the tangential force is
    F_t = -c F_n^+ t0 (t0 = v_t0 / |v_t0| projected on the tangent plane, F_n^+ = max(F_n, 0)).
    Over a free impact the normal impulse is (1 + e_n) m* |v_n0|, e_n the normal law's own
    restitution (:func:`normal_law_restitution`), so the tangential impulse is
    min((1 - eps_t) m* |v_t0|, mu (1 + eps_n) m* |v_n0|): the paper's Eq. 12 where Coulomb allows
    it, the Coulomb-bounded landing (:mod:`dem.pointmass.bounded`) where it does not, and never
    more than mu F_n at any instant. Because F_t is proportional to F_n, a clump landing on
    several members at once gets the same total as on one. The impact ends when the separating
    speed stops growing (the contact force is back to the external load), when the slip along t0
    has stopped (a rolling sphere reaches rolling: it keeps eps_t >= 5/7), or after
    :data:`IMPACT_MAX_PHASE` radians of the local normal oscillation sqrt(k_n / m*).
  * *enduring*, after that: a stick spring-dashpot sized by the time step, not by the material,
    k_s = f_t m* (alpha / dt)^2, gamma_s = 2 zeta_s alpha f_t m* / dt (alpha = ``stick_rate``,
    :data:`dem.config.DEM_STICK_RATE`), total force capped at mu F_n^+ as in "coulomb". Its
    spring is set at the switch so that the force is continuous. As dt shrinks (a stiffer
    material) it converges to Coulomb's rigid stick.

  A contact that breaks (its history reset to zeros) starts a new impact when it re-forms.

Optional rolling resistance (LIGGGHTS ``rolling_model cdt``, constant directional torque):
w_r = omega_i - omega_j without its normal part; tau_i -= mu_r |F_n| R* w_r / |w_r|,
tau_j += the same.

Laws (kernel ids :data:`MODELS` and :data:`TANGENTIAL`; a new tangential law is a new function
here and one row in :data:`dem.physics.laws.TANGENTIAL_LAWS`). The normal part is that of LIGGGHTS;
the
tangential part depends on the convention:

- linear spring-dashpot (LIGGGHTS ``hooke/stiffness`` with a restitution-derived damping):
  k_n given, gamma_n = -2 beta sqrt(k_n m*); k_t = kappa k_n with kappa =
  ``tangential_stiffness_ratio``. "liggghts": gamma_t = gamma_n. "coulomb":
  gamma_t = 2 zeta_t sqrt(k_t f_t m*) with zeta_t = ``tangential_damping_ratio`` and f_t the
  tangential mass factor (:func:`tangential_mass_factor`).
- Hertz-Mindlin: with S_n = 2 Y* sqrt(R* delta) (the tangent normal stiffness),
  k_n = 4/3 Y* sqrt(R* delta), gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*). "liggghts" (as coded in
  LIGGGHTS, tangential damping on): k_t = S_t = 8 G* sqrt(R* delta),
  gamma_t = -2 sqrt(5/6) beta sqrt(S_t m*). "coulomb": k_t = kappa S_n,
  gamma_t = 2 zeta_t sqrt(k_t f_t m*).

Here beta = ln(e) / sqrt(ln(e)^2 + pi^2) for 0 < e <= 1 and beta = -1 for e = 0 (critical damping
of the linear law; ln 0 is never evaluated), see :func:`damping_beta`. For equal materials
Y* = Y / (2 (1 - nu^2)) and G* = Y / (4 (2 - nu)(1 + nu)). How kappa and zeta_t follow from the
tangential restitution eps_t is in :mod:`dem.physics.tangential`.

Parameters reach the kernels as one float64 array ``params`` indexed by the ``P_*`` constants.
"""

import math

import numba
import numpy as np

from dem.config import (
    DEM_STICK_DAMPING_RATIO,
    DEM_STICK_RATE,
    DEM_TANGENTIAL_DAMPING_RATIO,
    NUMBA_OPTIONS,
)

#: Contact law selectors (the case's ``contact.model``) -> integer id used by the kernels.
MODELS = {"linear": 0, "hertz_mindlin": 1}
LINEAR = MODELS["linear"]
HERTZ = MODELS["hertz_mindlin"]

# Layout of the float64 ``params`` array of the kernels.
P_KN = 0  #: linear normal stiffness k_n, N/m
P_KT_RATIO = 1  #: linear k_t / k_n
P_YSTAR = 2  #: effective Young's modulus Y*, Pa
P_GSTAR = 3  #: effective shear modulus G*, Pa
P_BETA = 4  #: damping parameter beta (<= 0)
P_MU = 5  #: Coulomb friction coefficient mu
P_MU_ROLL = 6  #: rolling resistance coefficient mu_r (0: off)
P_LIMIT_FORCE = 7  #: 1.0 keeps F_n >= 0 (LIGGGHTS limitForce), else 0.0
P_KN_COEF = 8  #: normal sub-model: C_kn, k_n = C_kn a (:func:`law_coefficients`)
P_DAMP_N = 9  #: damping sub-model: C_dn, gamma_n = C_dn sqrt(B_n a m*)
P_TANGENTIAL = 10  #: tangential convention: 0.0 "coulomb", 1.0 "liggghts" (:data:`TANGENTIAL`)
P_ZETA_T = 11  #: "coulomb": tangential damping ratio zeta_t
P_MASS_T = 12  #: "coulomb", "impact": tangential mass factor f_t (effective mass f_t m*)
P_DAMP_N_SCALE = 13  #: damping sub-model: B_n
P_WALL_ARM = 14  #: f_w: a wall contact's lever arm is r - f_w delta (:data:`WALL_LEVER_ARMS`)
P_IMPACT_RATIO = 15  #: "impact": (1 - eps_t) / (1 + e_n), e_n the normal law's own restitution
P_STICK_RATE = 16  #: "impact": alpha, the stick's angular frequency times dt (rad per step)
P_STICK_ZETA = 17  #: "impact": damping ratio of the stick
P_IMPACT_CAP = 18  #: "impact": the largest c, min(mu, mu (1 + eps_n) / (1 + e_n))
P_NORMAL_E = 19  #: "impact": e_n, the normal law's own restitution (:func:`normal_law_restitution`)
P_KT_COEF = 20  #: tangential spring: C_kt, k_t = C_kt a
P_DAMP_T = 21  #: tangential dashpot: C_dt, gamma_t = C_dt sqrt(B_t a m*)
P_DAMP_T_SCALE = 22  #: tangential dashpot: B_t
N_PARAMS = 23

#: Tangential conventions (the case's ``contact.tangential``) -> value of ``params[P_TANGENTIAL]``.
TANGENTIAL = {"coulomb": 0.0, "liggghts": 1.0, "impact": 2.0}
IMPACT = TANGENTIAL["impact"]
#: Floats of contact history per contact, by convention: the spring s (3); "impact" adds its
#: phase and the previous normal velocity (:func:`_impact_tangential`).
HISTORY_WIDTH = {"coulomb": 3, "liggghts": 3, "impact": 5}
#: "impact": an impact phase lasts at most this many radians of the local normal oscillation
#: (sqrt(k_n / m*) integrated over time); a free impact ends within about 3.
IMPACT_MAX_PHASE = 2.0 * math.pi
#: f_w of each ``wall_lever_arm``: "surface" puts a wall contact's point on the wall's surface
#: (r - delta from the centre), "midpoint" halfway into the overlap (r - delta / 2), as
#: LIGGGHTS 3.8 does for its walls (surface_model_default.h: ``cr = radi - 0.5 * deltan``).
WALL_LEVER_ARMS = {"surface": 1.0, "midpoint": 0.5}

_SQRT_5_6 = math.sqrt(5.0 / 6.0)


def damping_beta(restitution: float) -> float:
    """Return beta = ln(e) / sqrt(ln(e)^2 + pi^2) for 0 < e <= 1, and -1 for e = 0.

    beta = -1 is critical damping of the linear spring-dashpot (the limit e -> 0 of the formula);
    the logarithm of 0 is never evaluated. -beta is the damping ratio zeta of the linear
    spring-dashpot, e = exp(-zeta pi / sqrt(1 - zeta^2)); :mod:`dem.physics.tangential` and the
    LIGGGHTS
    export (:func:`dem.io.liggghts.damping_ratio`) take it from here.
    """
    if not 0.0 <= restitution <= 1.0:
        raise ValueError(f"restitution must lie in [0, 1], got {restitution}")
    if restitution == 0.0:
        return -1.0
    log_e = math.log(restitution)
    return log_e / math.sqrt(log_e * log_e + math.pi * math.pi)


def normal_law_restitution(model: int, beta: float) -> float:
    """Normal restitution e_n that the normal law itself gives a free impact (no gravity).

    The rebound speed over the approach speed at the end of the repulsion (the force, spring
    plus dashpot, first back to zero), from a Runge-Kutta integration of the dimensionless
    impact (m* = 1, v = 1; k_n = 1 for the linear law, Y* = R* = 1 for Hertz). Both laws give an
    e_n independent of the impact speed: the linear law's damping ratio -beta is a constant, and
    Hertz's damping grows with the overlap as sqrt(S_n) does (Tsuji et al. 1992). e_n is close to
    the case's eps_n for eps_n > 0, and 0.135 for eps_n = 0 (both laws):
    critical damping still returns a little of the approach speed as the spring unloads.
    """
    damp = -2.0 * beta if model == LINEAR else -2.0 * _SQRT_5_6 * beta * math.sqrt(2.0)

    def accel(x, v):  # x the overlap, v its rate; returns the overlap's acceleration
        if model == LINEAR:
            return -(x + damp * v)
        root = math.sqrt(max(x, 0.0))
        return -((4.0 / 3.0) * root * x + damp * math.sqrt(root) * v)

    x, v, h = 0.0, 1.0, 1e-4
    while True:
        k1x, k1v = v, accel(x, v)
        k2x, k2v = v + 0.5 * h * k1v, accel(x + 0.5 * h * k1x, v + 0.5 * h * k1v)
        k3x, k3v = v + 0.5 * h * k2v, accel(x + 0.5 * h * k2x, v + 0.5 * h * k2v)
        k4x, k4v = v + h * k3v, accel(x + h * k3x, v + h * k3v)
        x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        if x <= 0.0 or (v < 0.0 and accel(x, v) >= 0.0):
            return -v


def make_params(
    *,
    model: str,
    stiffness: float = 0.0,
    tangential_stiffness_ratio: float = 2.0 / 7.0,
    youngs_modulus: float = 0.0,
    poisson_ratio: float = 0.3,
    restitution: float = 0.0,
    friction: float = 0.0,
    rolling_friction: float = 0.0,
    limit_force: bool = False,
    tangential: str = "coulomb",
    tangential_damping_ratio: float = DEM_TANGENTIAL_DAMPING_RATIO,
    tangential_mass_factor: float = 1.0,
    wall_lever_arm: str = "surface",
    restitution_tangential: float = 0.8,
    stick_rate: float = DEM_STICK_RATE,
    stick_damping_ratio: float = DEM_STICK_DAMPING_RATIO,
    beta: float | None = None,
) -> np.ndarray:
    """Pack a law's sub-model coefficients into the kernels' ``params`` array, (N_PARAMS,).

    ``model`` is the normal law (a key of :data:`MODELS`), ``tangential`` the tangential law
    (a key of :data:`TANGENTIAL`); each sub-model fills its own entries (:func:`_normal_params`,
    :func:`_damping_params`, :func:`_tangential_params`; rolling is mu_r alone).
    ``tangential_stiffness_ratio`` is kappa = k_t / k_n (linear; Hertz with "coulomb": k_t / S_n);
    ``tangential_damping_ratio`` zeta_t is used by "coulomb" only, ``tangential_mass_factor`` f_t
    by "coulomb" and "impact"; "impact" uses ``restitution_tangential`` eps_t, ``stick_rate``
    alpha and ``stick_damping_ratio``. ``beta`` overrides the damping parameter derived from
    ``restitution`` (over-critical damping, beta < -1, for studies). ``wall_lever_arm`` is a key
    of :data:`WALL_LEVER_ARMS`.
    """
    if model not in MODELS:
        raise ValueError(f"model must be one of {sorted(MODELS)}, got {model!r}")
    if wall_lever_arm not in WALL_LEVER_ARMS:
        raise ValueError(
            f"wall_lever_arm must be one of {sorted(WALL_LEVER_ARMS)}, got {wall_lever_arm!r}"
        )
    if tangential not in TANGENTIAL:
        raise ValueError(f"tangential must be one of {sorted(TANGENTIAL)}, got {tangential!r}")
    p = np.zeros(N_PARAMS)
    nu = poisson_ratio
    p[P_KN] = stiffness
    p[P_KT_RATIO] = tangential_stiffness_ratio
    p[P_YSTAR] = youngs_modulus / (2.0 * (1.0 - nu * nu))
    p[P_GSTAR] = youngs_modulus / (4.0 * (2.0 - nu) * (1.0 + nu))
    p[P_BETA] = damping_beta(restitution) if beta is None else beta
    p[P_MU] = friction
    p[P_MU_ROLL] = rolling_friction
    p[P_LIMIT_FORCE] = 1.0 if limit_force else 0.0
    p[P_TANGENTIAL] = TANGENTIAL[tangential]
    p[P_ZETA_T] = tangential_damping_ratio
    p[P_MASS_T] = tangential_mass_factor
    p[P_WALL_ARM] = WALL_LEVER_ARMS[wall_lever_arm]
    _normal_params(p, model)
    _damping_params(p, model)
    _tangential_params(p, model, tangential)
    if tangential == "impact":
        _impact_params(p, model, restitution, restitution_tangential, stick_rate,
                       stick_damping_ratio)  # fmt: skip
    return p


def _normal_params(p: np.ndarray, model: str) -> None:
    """Normal sub-model: C_kn = k_n (linear) or 4/3 Y* (Hertz), k_n = C_kn a."""
    p[P_KN_COEF] = p[P_KN] if model == "linear" else (4.0 / 3.0) * p[P_YSTAR]


def _damping_params(p: np.ndarray, model: str) -> None:
    """Damping sub-model from beta: gamma_n = C_dn sqrt(B_n a m*) (:func:`law_coefficients`).

    Linear: gamma_n = -2 beta sqrt(k_n m*); Hertz (LIGGGHTS, Tsuji et al. 1992):
    gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*), S_n = 2 Y* a.
    """
    if model == "linear":
        p[P_DAMP_N] = -2.0 * p[P_BETA]
        p[P_DAMP_N_SCALE] = p[P_KN]
    else:
        p[P_DAMP_N] = -2.0 * _SQRT_5_6 * p[P_BETA] * math.sqrt(2.0 * p[P_YSTAR])
        p[P_DAMP_N_SCALE] = 1.0


def _tangential_params(p: np.ndarray, model: str, tangential: str) -> None:
    """Tangential spring-dashpot of "coulomb" and "liggghts": C_kt, C_dt, B_t.

    "liggghts": linear k_t = kappa k_n, gamma_t = gamma_n; Hertz (Mindlin, as LIGGGHTS codes it)
    k_t = S_t = 8 G* a, gamma_t = -2 sqrt(5/6) beta sqrt(S_t m*). "coulomb": k_t = kappa S_n,
    gamma_t = 2 zeta_t sqrt(k_t f_t m*). "impact" has no material spring (C_kt = C_dt = 0; B_t = B_n
    so that no square root is spent on it).
    """
    kappa, zeta_t, f_t = p[P_KT_RATIO], p[P_ZETA_T], p[P_MASS_T]
    if tangential == "impact":
        p[P_DAMP_T_SCALE] = p[P_DAMP_N_SCALE]
        return
    if model == "linear":
        p[P_KT_COEF] = kappa * p[P_KN]
        if tangential == "liggghts":
            p[P_DAMP_T], p[P_DAMP_T_SCALE] = p[P_DAMP_N], p[P_DAMP_N_SCALE]
        else:
            p[P_DAMP_T], p[P_DAMP_T_SCALE] = 2.0 * zeta_t, p[P_KT_COEF] * f_t
        return
    p[P_DAMP_T_SCALE] = 1.0
    if tangential == "liggghts":
        p[P_KT_COEF] = 8.0 * p[P_GSTAR]
        p[P_DAMP_T] = -2.0 * _SQRT_5_6 * p[P_BETA] * math.sqrt(8.0 * p[P_GSTAR])
    else:
        p[P_KT_COEF] = 2.0 * kappa * p[P_YSTAR]
        p[P_DAMP_T] = 2.0 * zeta_t * math.sqrt(2.0 * kappa * p[P_YSTAR] * f_t)


def _impact_params(p, model, restitution, restitution_tangential, stick_rate, stick_zeta) -> None:
    """Tangential sub-model "impact": the force ratio, its cap, e_n and the stick's alpha, zeta."""
    if not 0.0 <= restitution_tangential <= 1.0:
        raise ValueError(f"eps_t must lie in [0, 1], got {restitution_tangential}")
    e_n = normal_law_restitution(MODELS[model], p[P_BETA])
    friction = p[P_MU]
    p[P_IMPACT_RATIO] = (1.0 - restitution_tangential) / (1.0 + e_n)
    p[P_IMPACT_CAP] = min(friction, friction * (1.0 + restitution) / (1.0 + e_n))
    p[P_NORMAL_E] = e_n
    p[P_STICK_RATE] = stick_rate
    p[P_STICK_ZETA] = stick_zeta


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
def coulomb_tangential(kt, gt, f_max, sx, sy, sz, vtx, vty, vtz):
    """Tangential sub-model "coulomb": total force capped at f_max = mu |F_n|, spring reset.

    Returns (F_t, s) as six floats.
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
            sx = -(ftx + gt * vtx) / kt
            sy = -(fty + gt * vty) / kt
            sz = -(ftz + gt * vtz) / kt
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


@numba.njit(**NUMBA_OPTIONS)
def impact_tangential(
    impact_ratio, impact_cap, mu, mass_t, stick_rate, stick_zeta,
    nx, ny, nz, vn, fn, vtx, vty, vtz, kn, m_eff, dt, h0, h1, h2, h3, h4,
):  # fmt: skip
    """Tangential sub-model "impact" (module docstring): force and the contact's new history.

    History (5 floats): h3 is the phase (0 a new contact, 1 + theta an impact, theta the radians
    of the local normal oscillation sqrt(k_n / m*) since first touch, -1 enduring), h4 the
    normal velocity v_n = v_r . n of the previous step, (h0, h1, h2) the impact's force ratio
    vector c (impact) or the stick's spring s (enduring). Parameters: ``impact_ratio``
    (1 - eps_t) / (1 + e_n), ``impact_cap`` the largest c, ``mu``, ``mass_t`` f_t,
    ``stick_rate`` alpha and ``stick_zeta`` of the stick.

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
    m_t = mass_t * m_eff
    ks = m_t * stick_rate * stick_rate / (dt * dt)
    gs = 2.0 * stick_zeta * stick_rate * m_t / dt
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
        over = vn > 0.0 and vn <= h4
        stuck = slip <= 0.0 and cx * cx + cy * cy + cz * cz > 0.0
        if not (over or stuck or theta > IMPACT_MAX_PHASE):
            return ftx, fty, ftz, cx, cy, cz, 1.0 + theta, vn
        # switch to the enduring stick, its spring set so that the force is continuous
        return (ftx, fty, ftz, -(ftx + gs * vtx) / ks, -(fty + gs * vty) / ks,
                -(ftz + gs * vtz) / ks, -1.0, vn)  # fmt: skip
    # enduring: a stiff stick, the total force capped at mu F_n (spring reset to match)
    sx, sy, sz = spring_step(h0, h1, h2, vtx, vty, vtz, nx, ny, nz, dt)
    ftx, fty, ftz, sx, sy, sz = coulomb_tangential(ks, gs, f_max, sx, sy, sz, vtx, vty, vtz)
    return ftx, fty, ftz, sx, sy, sz, -1.0, vn


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


@numba.njit(**NUMBA_OPTIONS)
def contact_force(
    model, p, nx, ny, nz, delta, vrx, vry, vrz, wix, wiy, wiz, wjx, wjy, wjz,
    ci, cj, m_eff, r_eff, hist, k, dt,
):  # fmt: skip
    """Force on i and torques on i and j of one touching contact; updates ``hist[k]`` in place.

    The array-facing wrapper of the sub-models: it reads the parameters and the contact's
    history row, calls the scalar sub-models (normal, damping, tangential, rolling) and writes
    the history back.

    Args:
        model: Normal law id (:data:`MODELS`).
        p: Contact parameters, shape (N_PARAMS,).
        nx, ny, nz: Unit normal from j to i.
        delta: Overlap > 0, m.
        vrx, vry, vrz: v_i - v_j, m/s.
        wix, wiy, wiz, wjx, wjy, wjz: Spins of i and j, rad/s.
        ci, cj: Lever arms from the centres to the contact point, m.
        m_eff, r_eff: m*, kg, and R*, m.
        hist: Contact history, shape (n, width) (:data:`HISTORY_WIDTH`); row k is this contact.
        k: Row of ``hist``.
        dt: Time step, s.

    Returns:
        (fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz, fn): force on i (N), torques on i and j
        (N m) and the normal force F_n (N).

    """
    kn, gn, kt, gt = law_coefficients(model, delta, m_eff, r_eff, p)
    vn = vrx * nx + vry * ny + vrz * nz
    fn = kn * delta - gn * vn
    if p[P_LIMIT_FORCE] != 0.0 and fn < 0.0:
        fn = 0.0
    # slip velocity at the contact point: tangential part minus (c_i w_i + c_j w_j) x n
    wx = ci * wix + cj * wjx
    wy = ci * wiy + cj * wjy
    wz = ci * wiz + cj * wjz
    vtx = vrx - vn * nx - (wy * nz - wz * ny)
    vty = vry - vn * ny - (wz * nx - wx * nz)
    vtz = vrz - vn * nz - (wx * ny - wy * nx)
    tangential = p[P_TANGENTIAL]
    if tangential == IMPACT:
        ftx, fty, ftz, h0, h1, h2, h3, h4 = impact_tangential(
            p[P_IMPACT_RATIO], p[P_IMPACT_CAP], p[P_MU], p[P_MASS_T], p[P_STICK_RATE],
            p[P_STICK_ZETA], nx, ny, nz, vn, fn, vtx, vty, vtz, kn, m_eff, dt,
            hist[k, 0], hist[k, 1], hist[k, 2], hist[k, 3], hist[k, 4],
        )  # fmt: skip
        hist[k, 3] = h3
        hist[k, 4] = h4
    else:
        # tangential spring: increment, then project onto the current tangent plane
        sx, sy, sz = spring_step(hist[k, 0], hist[k, 1], hist[k, 2], vtx, vty, vtz, nx, ny, nz, dt)
        f_max = p[P_MU] * abs(fn)
        if tangential != 0.0:
            ftx, fty, ftz, h0, h1, h2 = liggghts_tangential(kt, gt, f_max, sx, sy, sz, vtx, vty,
                                                            vtz)  # fmt: skip
        else:
            ftx, fty, ftz, h0, h1, h2 = coulomb_tangential(kt, gt, f_max, sx, sy, sz, vtx, vty,
                                                           vtz)  # fmt: skip
    hist[k, 0] = h0
    hist[k, 1] = h1
    hist[k, 2] = h2
    # torques -c n x F_t, plus rolling resistance
    cx = ny * ftz - nz * fty
    cy = nz * ftx - nx * ftz
    cz = nx * fty - ny * ftx
    ti, tj = rolling_cdt(
        p[P_MU_ROLL], fn, r_eff, nx, ny, nz, wix, wiy, wiz, wjx, wjy, wjz,
        (-ci * cx, -ci * cy, -ci * cz), (-cj * cx, -cj * cy, -cj * cz),
    )  # fmt: skip
    return fn * nx + ftx, fn * ny + fty, fn * nz + ftz, ti[0], ti[1], ti[2], tj[0], tj[1], tj[2], fn


@numba.njit(inline="always", **NUMBA_OPTIONS)
def wall_row(p):
    """The grain-wall law's parameters: the second row of ``p``, or ``p`` if it holds one law.

    :class:`dem.physics.laws.ContactLaw` packs the grain-grain row, then the grain-wall row.
    """
    if p.shape[0] >= 2 * N_PARAMS:
        return p[N_PARAMS : 2 * N_PARAMS]
    return p


@numba.njit(inline="always", **NUMBA_OPTIONS)
def add_wall_contact(
    model, p, nx, ny, nz, delta, v, omega, i, m, r, hist, row, dt, fx, fy, fz, tx, ty, tz,
):  # fmt: skip
    """(fx, ..., tz) plus the force and torque of sphere i's contact with a wall or triangle.

    The wall is fixed in the trough frame, of infinite mass and radius: normal n (wall to
    sphere), overlap delta, m* = m, R* = r, lever arm r - f_w delta (``p[P_WALL_ARM]``),
    spring in ``hist[row]``.
    """
    f = contact_force(
        model, p, nx, ny, nz, delta, v[i, 0], v[i, 1], v[i, 2], omega[i, 0], omega[i, 1],
        omega[i, 2], 0.0, 0.0, 0.0, r - p[P_WALL_ARM] * delta, 0.0, m, r, hist, row, dt,
    )  # fmt: skip
    return fx + f[0], fy + f[1], fz + f[2], tx + f[3], ty + f[4], tz + f[5]


#: :func:`contact_force` inlined at numba's IR level, for the pair loop, where a call per pair
#: (two arrays and twenty scalars) cost about a sixth of the loop; the walls, which call it only
#: on contact, keep the call (inlining it everywhere doubled the compile time).
contact_force_inlined = numba.njit(inline="always", **NUMBA_OPTIONS)(contact_force.py_func)


# --- time scales of the laws (Python; used to choose and to check the time step) ----------------


def linear_collision_time(stiffness: float, m_eff: float, beta: float) -> float:
    """Contact duration pi / sqrt(k_n/m* - (gamma_n / 2 m*)^2) of the linear law, s.

    With gamma_n = -2 beta sqrt(k_n m*) the radicand is (k_n/m*)(1 - beta^2); at or beyond
    critical damping (beta^2 >= 1) the undamped time pi / sqrt(k_n/m*) is returned.
    """
    w0_sq = stiffness / m_eff
    wd_sq = w0_sq * (1.0 - beta * beta)
    return math.pi / math.sqrt(wd_sq if wd_sq > 0.0 else w0_sq)


def hertz_max_overlap(youngs_star: float, r_eff: float, m_eff: float, speed: float) -> float:
    """Largest overlap of an elastic Hertz impact, (15 m* v^2 / (16 Y* sqrt(R*)))^(2/5), m."""
    return (15.0 * m_eff * speed**2 / (16.0 * youngs_star * math.sqrt(r_eff))) ** 0.4


def hertz_collision_time(youngs_star: float, r_eff: float, m_eff: float, speed: float) -> float:
    """Elastic Hertz contact duration 2.87 (m*^2 / (R* Y*^2 v))^(1/5), s."""
    return 2.87 * (m_eff**2 / (r_eff * youngs_star**2 * speed)) ** 0.2


def rayleigh_time(radius: float, density: float, youngs_modulus: float, poisson: float) -> float:
    """Rayleigh time pi R sqrt(rho / G) / (0.1631 nu + 0.8766), G = Y / (2 (1 + nu)), s."""
    shear = youngs_modulus / (2.0 * (1.0 + poisson))
    return math.pi * radius * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)


def critical_timestep(stiffness: float, m_eff: float, zeta: float) -> float:
    """Stability limit of velocity Verlet for a damped spring, 2/w0 (sqrt(1 + z^2) - z), s.

    w0 = sqrt(k / m*), z = gamma / (2 sqrt(k m*)) the damping ratio.
    """
    w0 = math.sqrt(stiffness / m_eff)
    return 2.0 / w0 * (math.sqrt(1.0 + zeta * zeta) - zeta)
