"""What a contact law's kernels read: the parameter layout, its builder, the laws' time scales.

The ``P_*`` layout of the parameter array, its builder :func:`make_params` (one small builder
per sub-model), the law ids.

Plain Python (the builders run once per case); the numba sub-models are in
:mod:`dem.kernels.contact.laws` and the contact routine in :mod:`dem.kernels.contact.force`.
"""

import functools
import math

import numpy as np

from dem.config import (
    DEM_NORMAL_STICK_RATE,
    DEM_STICK_DAMPING_RATIO,
    DEM_STICK_RATE,
    DEM_TANGENTIAL_DAMPING_RATIO,
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
P_SLIP_ARM = 23  #: 1.0: the slip velocity takes the full radii (:data:`SLIP_LEVER_ARMS`), else 0.0
P_PLASTIC = 24  #: "impact" with eps_n = 0: 1.0, the perfectly plastic normal contact, else 0.0
P_MASS_N = 25  #: "impact", plastic: f_n, the normal stick's effective mass f_n m*
P_NORMAL_STICK_RATE = 26  #: "impact", plastic: alpha_n, the normal stick's rate (rad per step)
N_PARAMS = 27

#: Tangential conventions (the case's ``contact.tangential``) -> value of ``params[P_TANGENTIAL]``.
TANGENTIAL = {"coulomb": 0.0, "liggghts": 1.0, "impact": 2.0}
IMPACT = TANGENTIAL["impact"]
#: Floats of contact history per contact, by convention: the spring s (3); "impact" adds its
#: phase and the previous normal velocity (:func:`dem.kernels.contact.laws.impact_tangential`).
HISTORY_WIDTH = {"coulomb": 3, "liggghts": 3, "impact": 5}
#: "impact": an impact phase lasts at most this many radians of the local normal oscillation
#: (sqrt(k_n / m*) integrated over time); a free impact ends within about 3.
IMPACT_MAX_PHASE = 2.0 * math.pi
#: f_w of each ``wall_lever_arm``: "surface" puts a wall contact's point on the wall's surface
#: (r - delta from the centre), "midpoint" halfway into the overlap (r - delta / 2), as
#: LIGGGHTS 3.8 does for its walls (surface_model_default.h: ``cr = radi - 0.5 * deltan``).
#: "radius" puts it at the full radius r, as LAMMPS's ``fix wall/gran`` does (f_w = 0).
WALL_LEVER_ARMS = {"surface": 1.0, "midpoint": 0.5, "radius": 0.0}
#: The slip velocity's lever arms (``[contact] slip_lever_arm``) -> ``params[P_SLIP_ARM]``:
#: "contact" takes the torque's arms (r_i - delta / 2 between grains, r - f_w delta at a wall), so
#: the slip is that of the contact point; "radius" takes the full radii r_i, r_j, as LAMMPS's
#: ``pair granular`` and ``fix wall/gran`` do (its torques keep r_i - delta / 2 between grains).
#: With ``wall_lever_arm = "radius"`` too, dem's contact is LAMMPS's, term for term.
SLIP_LEVER_ARMS = {"contact": 0.0, "radius": 1.0}

_SQRT_5_6 = math.sqrt(5.0 / 6.0)


def damping_beta(restitution: float) -> float:
    """Return beta = ln(e) / sqrt(ln(e)^2 + pi^2) for 0 < e <= 1, and -1 for e = 0.

    beta = -1 is critical damping of the linear spring-dashpot (the limit e -> 0 of the formula);
    the logarithm of 0 is never evaluated. -beta is the damping ratio zeta of the linear
    spring-dashpot, e = exp(-zeta pi / sqrt(1 - zeta^2)); :mod:`dem.physics.tangential` and the
    LIGGGHTS export (:func:`dem.io.liggghts.damping_ratio`) take it from here.
    """
    if not 0.0 <= restitution <= 1.0:
        raise ValueError(f"restitution must lie in [0, 1], got {restitution}")
    if restitution == 0.0:
        return -1.0
    log_e = math.log(restitution)
    return log_e / math.sqrt(log_e * log_e + math.pi * math.pi)


@functools.lru_cache(maxsize=256)  # a pure function of two scalars: ~0.5 s of Python a call
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
    normal_mass_factor: float = 1.0,
    wall_lever_arm: str = "surface",
    slip_lever_arm: str = "contact",
    restitution_tangential: float = 0.8,
    stick_rate: float = DEM_STICK_RATE,
    stick_damping_ratio: float = DEM_STICK_DAMPING_RATIO,
    normal_stick_rate: float = DEM_NORMAL_STICK_RATE,
    beta: float | None = None,
) -> np.ndarray:
    """Pack a law's sub-model coefficients into the kernels' ``params`` array, (N_PARAMS,).

    ``model`` is the normal law (a key of :data:`MODELS`), ``tangential`` the tangential law
    (a key of :data:`TANGENTIAL`); each sub-model fills its own entries (:func:`_normal_params`,
    :func:`_damping_params`, :func:`_tangential_params`; rolling is mu_r alone).
    ``tangential_stiffness_ratio`` is kappa = k_t / k_n (linear; Hertz with "coulomb": k_t / S_n);
    ``tangential_damping_ratio`` zeta_t is used by "coulomb" only, ``tangential_mass_factor`` f_t
    by "coulomb" and "impact"; "impact" uses ``restitution_tangential`` eps_t, ``stick_rate``
    alpha and ``stick_damping_ratio``, and with eps_n = 0 ``normal_mass_factor`` f_n and
    ``normal_stick_rate`` alpha_n (its plastic normal contact's stick: effective mass f_n m*,
    alpha_n rad a step, :func:`_impact_params`). ``beta`` overrides
    the damping parameter derived from ``restitution`` (over-critical damping, beta < -1, for
    studies). ``wall_lever_arm`` is a key
    of :data:`WALL_LEVER_ARMS`, ``slip_lever_arm`` one of :data:`SLIP_LEVER_ARMS`.
    """
    if model not in MODELS:
        raise ValueError(f"model must be one of {sorted(MODELS)}, got {model!r}")
    if wall_lever_arm not in WALL_LEVER_ARMS:
        raise ValueError(
            f"wall_lever_arm must be one of {sorted(WALL_LEVER_ARMS)}, got {wall_lever_arm!r}"
        )
    if slip_lever_arm not in SLIP_LEVER_ARMS:
        raise ValueError(
            f"slip_lever_arm must be one of {sorted(SLIP_LEVER_ARMS)}, got {slip_lever_arm!r}"
        )
    if tangential not in TANGENTIAL:
        raise ValueError(f"tangential must be one of {sorted(TANGENTIAL)}, got {tangential!r}")
    p = np.zeros(N_PARAMS)
    nu = poisson_ratio
    p[P_KN] = stiffness
    p[P_KT_RATIO] = tangential_stiffness_ratio
    p[P_YSTAR] = youngs_star(youngs_modulus, nu)
    p[P_GSTAR] = youngs_modulus / (4.0 * (2.0 - nu) * (1.0 + nu))
    p[P_BETA] = damping_beta(restitution) if beta is None else beta
    p[P_MU] = friction
    p[P_MU_ROLL] = rolling_friction
    p[P_LIMIT_FORCE] = 1.0 if limit_force else 0.0
    p[P_TANGENTIAL] = TANGENTIAL[tangential]
    p[P_ZETA_T] = tangential_damping_ratio
    p[P_MASS_T] = tangential_mass_factor
    p[P_MASS_N] = normal_mass_factor
    p[P_NORMAL_STICK_RATE] = normal_stick_rate
    p[P_WALL_ARM] = WALL_LEVER_ARMS[wall_lever_arm]
    p[P_SLIP_ARM] = SLIP_LEVER_ARMS[slip_lever_arm]
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


def tangent_stiffness(model: str, p: np.ndarray, r_eff: float, delta: float) -> tuple[float, float]:
    """(S_n, a): the normal law's tangent stiffness dF_n/d delta, N/m, and its size factor a.

    At overlap ``delta``; a as :func:`dem.kernels.contact.laws.normal_scale` computes it.
    Linear: (k_n, 1). Hertz: (2 Y* a, a), a = sqrt(R* delta); k_n = 4/3 Y* a is the secant.
    The normal dashpot is 2 zeta_n sqrt(S_n m*) (:func:`damping_ratio`); the time step resolves
    the oscillator (S_n, m*).
    """
    if model == "linear":
        return p[P_KN], 1.0
    a = math.sqrt(r_eff * delta)
    return 2.0 * p[P_YSTAR] * a, a


def damping_ratio(model: str, beta: float) -> float:
    """zeta_n, the normal dashpot's damping ratio against S_n: -beta, or -sqrt(5/6) beta (Hertz).

    gamma_n = 2 zeta_n sqrt(S_n m*) (:func:`tangent_stiffness`): linear -2 beta sqrt(k_n m*);
    Hertz (LIGGGHTS, Tsuji et al. 1992) -2 sqrt(5/6) beta sqrt(S_n m*), S_n = 2 Y* a.
    """
    return -beta if model == "linear" else -_SQRT_5_6 * beta


def _damping_params(p: np.ndarray, model: str) -> None:
    """Damping sub-model from beta: gamma_n = C_dn sqrt(B_n a m*) (:func:`law_coefficients`).

    gamma_n = 2 zeta_n sqrt(S_n m*) (:func:`damping_ratio`, :func:`tangent_stiffness`): linear
    C_dn = 2 zeta_n, B_n = k_n; Hertz C_dn = 2 zeta_n sqrt(2 Y*), B_n = 1.
    """
    zeta = damping_ratio(model, p[P_BETA])
    if model == "linear":
        p[P_DAMP_N] = 2.0 * zeta
        p[P_DAMP_N_SCALE] = p[P_KN]
    else:
        p[P_DAMP_N] = 2.0 * zeta * math.sqrt(2.0 * p[P_YSTAR])
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
    """Tangential sub-model "impact": the force ratio, its cap, e_n and the stick's alpha, zeta.

    With eps_n = 0 the contact is perfectly plastic (``P_PLASTIC``,
    :func:`dem.kernels.contact.laws.plastic_normal`): its impacts return none of the approach
    speed, so e_n = 0 there; otherwise e_n is the normal law's own restitution
    (:func:`normal_law_restitution`).
    """
    if not 0.0 <= restitution_tangential <= 1.0:
        raise ValueError(f"eps_t must lie in [0, 1], got {restitution_tangential}")
    plastic = restitution == 0.0
    p[P_PLASTIC] = 1.0 if plastic else 0.0
    e_n = 0.0 if plastic else normal_law_restitution(MODELS[model], p[P_BETA])
    friction = p[P_MU]
    p[P_IMPACT_RATIO] = (1.0 - restitution_tangential) / (1.0 + e_n)
    p[P_IMPACT_CAP] = min(friction, friction * (1.0 + restitution) / (1.0 + e_n))
    p[P_NORMAL_E] = e_n
    p[P_STICK_RATE] = stick_rate
    p[P_STICK_ZETA] = stick_zeta


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


#: The constant of the elastic Hertz contact time, t_c = C (m*^2 / (R* Y*^2 v))^(1/5).
HERTZ_TIME_CONSTANT = 2.87


def hertz_collision_time(youngs_star: float, r_eff: float, m_eff: float, speed: float) -> float:
    """Elastic Hertz contact duration 2.87 (m*^2 / (R* Y*^2 v))^(1/5), s."""
    return HERTZ_TIME_CONSTANT * (m_eff**2 / (r_eff * youngs_star**2 * speed)) ** 0.2


def hertz_youngs_star_for_time(duration: float, r_eff: float, m_eff: float, speed: float) -> float:
    """Y* whose elastic Hertz impact at ``speed`` lasts ``duration``, Pa.

    :func:`hertz_collision_time` solved for Y*: sqrt(m*^2 / (R* v (t_c / 2.87)^5)).
    """
    return math.sqrt(m_eff**2 / (r_eff * speed * (duration / HERTZ_TIME_CONSTANT) ** 5))


def youngs_star(youngs_modulus: float, poisson_ratio: float) -> float:
    """Y* = E / (2 (1 - nu^2)) of two bodies of one material, Pa."""
    return youngs_modulus / (2.0 * (1.0 - poisson_ratio * poisson_ratio))


def youngs_modulus_from_star(y_star: float, poisson_ratio: float) -> float:
    """E of the material whose Y* (:func:`youngs_star`) this is, Pa."""
    return y_star * 2.0 * (1.0 - poisson_ratio**2)


def contact_moduli(e1: float, nu1: float, e2: float, nu2: float) -> tuple[float, float]:
    """(Y*, G*) of a contact between two elastic materials (E_i Pa, nu_i), Pa.

    Hertz's and Mindlin's effective moduli: 1/Y* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (the
    normal stiffness S_n = 2 Y* a) and 1/G* = (2 - nu1)/G1 + (2 - nu2)/G2 with
    G_i = E_i / (2 (1 + nu_i)) (the no-slip tangential stiffness 8 G* a, Mindlin 1949). For
    one material they are :func:`youngs_star` and E / (4 (2 - nu)(1 + nu)), what
    :func:`make_params` packs. A rigid body is E = inf (its terms vanish).
    """
    inv_y = (1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2
    inv_g = 2.0 * (2.0 - nu1) * (1.0 + nu1) / e1 + 2.0 * (2.0 - nu2) * (1.0 + nu2) / e2
    return 1.0 / inv_y, 1.0 / inv_g


def equivalent_material(e1: float, nu1: float, e2: float, nu2: float) -> tuple[float, float]:
    """(E, nu) of the one material whose contact with itself has the moduli of materials 1 and 2.

    dem's laws take one ``youngs_modulus`` and ``poisson_ratio`` per case and pack the contact
    of two bodies of that material (:func:`make_params`: Y* = E / (2 (1 - nu^2)),
    G* = E / (4 (2 - nu)(1 + nu))). A sphere of material 1 against a wall or a sphere of
    material 2 has the moduli of :func:`contact_moduli`; since only Y* and G* enter Hertz's
    normal force and Mindlin's tangential stiffness, the material with the same two is the
    same contact. Its Poisson ratio follows from the stiffness ratio kappa = k_t / S_n =
    4 G* / Y*, which is 2 (1 - nu) / (2 - nu) for one material: nu = (2 - 2 kappa) / (2 - kappa);
    then E = 2 (1 - nu^2) Y*. Of two equal materials it returns the material itself.

    Raises:
        ValueError: The pair's kappa has no one-material equivalent with -1 < nu < 1/2.

    """
    y_star, g_star = contact_moduli(e1, nu1, e2, nu2)
    kappa = 4.0 * g_star / y_star
    nu = (2.0 - 2.0 * kappa) / (2.0 - kappa)
    if not -1.0 < nu < 0.5:
        raise ValueError(
            f"k_t / S_n = {kappa:.4g} of this pair has no one-material equivalent "
            f"(its Poisson ratio would be {nu:.4g}, outside (-1, 0.5))"
        )
    return 2.0 * (1.0 - nu * nu) * y_star, nu


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
