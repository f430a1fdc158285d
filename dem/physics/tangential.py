"""Tangential spring and dashpot from the tangential restitution eps_t (``"coulomb"`` contacts).

**eps_t as the paper uses it** (its Eq. 12): the tangential velocity of the grain's centre of
mass relative to the trough, after one landing over before it. "After" is the end of the impact:
the moment the normal contact force, having pushed the grain, first falls back to zero. With
eps_n = 0 a linear contact is critically damped and never separates, but its force
k_n x + gamma_n dx/dt still vanishes at omega_n t = 2 (x = v t exp(-omega_n t)); under gravity
the grain then rests on the floor and slides or sticks by Coulomb friction, as the point mass
does after its instantaneous landing. So eps_t is defined, and measured by
:mod:`dem.studies.calibrate`, for a gravity-free impact of one grain on the floor.

**Mapping.** The tangential part of the contact is a spring k_t with dashpot gamma_t acting on
the tangential effective mass f_t m* (f_t: :func:`tangential_mass_factor`), with
omega_t^2 = k_t / (f_t m*) and damping ratio zeta_t = gamma_t / (2 sqrt(k_t f_t m*)). An impact
that sticks (tangential force below mu |F_n| throughout) starts the tangential oscillator with
unit slip velocity, the slip velocity at the end of the impact t_e is V(omega_t t_e; zeta_t),
V(s; z) = d/ds of the unit-velocity response X(s; z) (V = exp(-z s) (cos(w s) - z / w sin(w s)),
w = sqrt(1 - z^2), for z < 1), and the centre of mass takes the fraction f_t of that change:

    eps_t = 1 - f_t (1 - V(omega_t t_e; zeta_t)),

where omega_n t_e is the first zero of the normal force of the linear law with damping ratio
zeta_n = -beta(eps_n) (:func:`impact_end_time`; 2 for eps_n = 0). Solving for the first root
theta of V(theta; zeta_t) = 1 - (1 - eps_t) / f_t gives

    kappa = k_t / k_n = f_t (theta / (omega_n t_e))^2.

With ``limit_force = true`` the grain leaves the floor at t_e and this is exact for an impact
that sticks (tested); with ``limit_force = false`` the attractive tail of the damped contact keeps
a weak contact a little longer, and the virtual impacts measure the difference.

This is the construction of Pournin et al. (2001) and Deen et al. (2007) -- coded in MercuryDPM
(``setCollisionTimeAndNormalAndTangentialRestitutionCoefficient``) and Yade, whose source notes
a factor-2 error in Pournin's damping -- with two changes: eps_t is the centre-of-mass ratio of
the paper (positive: the grain keeps moving forward) rather than the contact-point ratio of
Walton's model (negative for the same impact), and the end of the impact is the zero of the
normal force, which exists for eps_n = 0 where t_c = pi / omega_d does not. For eps_n = 0,
eps_t = 0.8 and a block (f_t = 1): kappa = 0.1035 with zeta_t = 0 (theta = acos 0.8) and 0.0216
with the default zeta_t = 0.3.

**Hertz.** There k_t = kappa S_n and gamma_t = 2 zeta_t sqrt(k_t f_t m*) grow with the overlap as
S_n = 2 Y* sqrt(R* delta) does, so the tangential oscillator stiffens and softens through the
impact and the closed form above does not hold (applied with S_n in place of k_n, it gave
eps_t = 0.777 for 0.8, +11.7 % in the impulse). The impact is self-similar instead: in the units
m* = v = Y* = R* = 1 the normal overlap follows x'' = -(4/3) x^(3/2) - 2 sqrt(2) zeta_n x^(1/4) x'
(zeta_n = -sqrt(5/6) beta, :func:`dem.kernels.contact.damping_ratio`) whatever the speed, mass,
size or modulus, and the slip u = s' of a sticking contact follows
f_t u' = -2 kappa sqrt(x) s - 2 zeta_t sqrt(2 kappa f_t sqrt(x)) u, s(0) = 0, u(0) = 1. eps_t is
then again a function of (kappa, zeta_n, zeta_t, f_t) alone: :func:`hertz_slip_velocity`
integrates the two together (fourth-order Runge-Kutta, converged to 2e-6 in eps_t) for many
kappa at once, and the first kappa whose eps_t reaches the target is found on a grid and refined.
For eps_n = 0, eps_t = 0.8, zeta_t = 0.3 and a block this gives kappa = 0.0175 (linear: 0.0216).

**Limits of the construction.** It holds for impacts that stick. An impact whose tangential
velocity is large against the normal one slides for part of the contact, and Coulomb friction
then takes at most mu (1 + eps_n) v_n from v_t: no tangential law that respects Coulomb can give
less than eps_t = 1 - mu (1 + eps_n) v_n / v_t there. The formula is the starting point; the
virtual impacts of :mod:`dem.studies.calibrate` measure what a grain actually does over the impact
angles of conveying, rotation and the Coulomb cap included.
"""

from __future__ import annotations

import functools
import math

import numpy as np


def unit_response(s: np.ndarray, zeta: float) -> tuple[np.ndarray, np.ndarray]:
    """Displacement X and velocity V of x'' + 2 zeta x' + x = 0, x(0) = 0, x'(0) = 1, at s."""
    s = np.asarray(s, dtype=float)
    if zeta < 1.0:
        w = math.sqrt(1.0 - zeta * zeta)
        e = np.exp(-zeta * s)
        return e * np.sin(w * s) / w, e * (np.cos(w * s) - zeta / w * np.sin(w * s))
    if zeta == 1.0:
        e = np.exp(-s)
        return s * e, (1.0 - s) * e
    root = math.sqrt(zeta * zeta - 1.0)
    r1, r2 = -zeta + root, -zeta - root
    e1, e2 = np.exp(r1 * s), np.exp(r2 * s)
    return (e1 - e2) / (r1 - r2), (r1 * e1 - r2 * e2) / (r1 - r2)


def _first_crossing(f, start: float, level: float) -> float:
    """First s > 0 where f(s) (starting above ``level``) falls to ``level``; f vectorised."""
    hi = start
    while True:
        s = np.linspace(0.0, hi, 4001)
        below = np.nonzero(f(s) <= level)[0]
        if below.size:
            lo, hi = s[below[0] - 1], s[below[0]]
            break
        hi *= 2.0
        if hi > 1e6:
            raise ValueError(f"no crossing of {level} found")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(np.array([mid]))[0] <= level:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def impact_end_time(zeta_n: float) -> float:
    """omega_n t_e: first zero of the normal force x + 2 zeta_n x' of a unit-velocity impact.

    Linear spring-dashpot, no gravity: 2 for critical damping (zeta_n = 1), pi - ... below it.
    """
    if zeta_n < 0.0:
        raise ValueError(f"zeta_n must be >= 0, got {zeta_n}")
    if zeta_n == 0.0:
        return math.pi

    def force(s):
        x, v = unit_response(s, zeta_n)
        return x + 2.0 * zeta_n * v

    return _first_crossing(force, 4.0, 0.0)


def minimum_velocity(zeta_t: float) -> float:
    """Smallest V(s; zeta_t) over s > 0: how far a sticking impact can reverse the slip."""
    if zeta_t >= 1.0:
        return 0.0
    w = math.sqrt(1.0 - zeta_t * zeta_t)
    return -math.exp(-zeta_t * math.pi / w)


def reachable_restitution(zeta_t: float, mass_factor: float) -> float:
    """Smallest centre-of-mass eps_t a sticking impact reaches: 1 - f_t (1 - min V)."""
    return 1.0 - mass_factor * (1.0 - minimum_velocity(zeta_t))


#: Hertz mapping: the grid of kappa searched for the first crossing, and the Runge-Kutta step in
#: the impact's own units (eps_t changes by 2e-6 when it halves).
_HERTZ_KAPPAS = np.geomspace(1e-16, 1e2, 721)
_HERTZ_STEP = 2e-3


def hertz_slip_velocity(kappas, zeta_n: float, zeta_t: float, mass_factor: float) -> np.ndarray:
    """V: the slip velocity at the end of a sticking Hertz impact over that at its start.

    One V per entry of ``kappas`` (k_t / S_n), all integrated together with the normal overlap
    (module docstring: units m* = v = Y* = R* = 1, the end where the normal force, spring plus
    dashpot, first returns to zero, interpolated within the step).
    """
    k = np.asarray(kappas, dtype=float)
    f_t, h = mass_factor, _HERTZ_STEP
    c_n = 2.0 * math.sqrt(2.0) * zeta_n
    c_t = 2.0 * zeta_t * np.sqrt(2.0 * k * f_t)

    def rates(x, v, s, u):
        r = math.sqrt(max(x, 0.0))
        return (
            v,
            -((4.0 / 3.0) * r * x + c_n * math.sqrt(r) * v),
            u,
            -(2.0 * k * r * s + c_t * math.sqrt(r) * u) / f_t,
        )

    def force(x, v):
        r = math.sqrt(max(x, 0.0))
        return (4.0 / 3.0) * r * x + c_n * math.sqrt(r) * v

    x, v, s, u = 0.0, 1.0, np.zeros_like(k), np.ones_like(k)
    f_old = 0.0
    for _ in range(1_000_000):
        d1 = rates(x, v, s, u)
        d2 = rates(*(y + 0.5 * h * dy for y, dy in zip((x, v, s, u), d1, strict=True)))
        d3 = rates(*(y + 0.5 * h * dy for y, dy in zip((x, v, s, u), d2, strict=True)))
        d4 = rates(*(y + h * dy for y, dy in zip((x, v, s, u), d3, strict=True)))
        step = [h / 6.0 * (a + 2.0 * b + 2.0 * c + d)
                for a, b, c, d in zip(d1, d2, d3, d4, strict=True)]  # fmt: skip
        x_new, v_new = x + step[0], v + step[1]
        s_new, u_new = s + step[2], u + step[3]
        f_new = force(x_new, v_new)
        if x_new <= 0.0 or (v_new < 0.0 and f_new <= 0.0):
            w = f_old / (f_old - f_new) if f_old > f_new else 1.0
            return u + w * (u_new - u)
        x, v, s, u, f_old = x_new, v_new, s_new, u_new, f_new
    raise RuntimeError("the Hertz impact did not end")  # pragma: no cover - it always ends


@functools.lru_cache(maxsize=64)  # a pure function of four scalars: ~0.5 s a call
def _hertz_ratio(eps_t: float, zeta_n: float, zeta_t: float, mass_factor: float) -> float:
    """The first kappa at which eps_t(kappa) reaches ``eps_t`` (Hertz)."""
    slip = hertz_slip_velocity(_HERTZ_KAPPAS, zeta_n, zeta_t, mass_factor)
    eps = 1.0 - mass_factor * (1.0 - slip)
    below = np.nonzero(eps <= eps_t)[0]
    if not below.size or below[0] == 0:
        raise ValueError(
            f"{eps.min():.4g} < eps_t < 1 for a Hertz contact of tangential mass factor "
            f"{mass_factor:.4g} with tangential damping ratio {zeta_t:g} (a sticking impact "
            "cannot take more)"
        )
    lo, hi = _HERTZ_KAPPAS[below[0] - 1], _HERTZ_KAPPAS[below[0]]
    for _ in range(4):  # each round narrows the bracket 32-fold
        grid = np.linspace(lo, hi, 33)
        eps = 1.0 - mass_factor * (1.0 - hertz_slip_velocity(grid, zeta_n, zeta_t, mass_factor))
        j = int(np.nonzero(eps <= eps_t)[0][0])
        lo, hi = grid[j - 1], grid[j]
    return float(0.5 * (lo + hi))


def tangential_stiffness_ratio(
    eps_t: float, zeta_n: float, zeta_t: float, mass_factor: float, normal: str = "linear"
) -> float:
    """Return kappa = k_t / k_n that gives eps_t in a sticking impact (module docstring).

    The slip velocity of the contact point follows V(omega_t t; zeta_t); the centre of mass
    takes the fraction f_t of its change (a rolling sphere's centre loses 2/7 of what its contact
    point loses), so eps_t = 1 - f_t (1 - V) and the target of V is 1 - (1 - eps_t) / f_t.

    Args:
        eps_t: Target centre-of-mass tangential restitution, below 1 and at least
            :func:`reachable_restitution`.
        zeta_n: Normal damping ratio against S_n (:func:`dem.kernels.contact.damping_ratio`:
            -beta(eps_n) linear, 1 for eps_n = 0; -sqrt(5/6) beta Hertz).
        zeta_t: Tangential damping ratio, >= 0.
        mass_factor: f_t, tangential effective mass over m*, in (0, 1].
        normal: ``"linear"`` (closed form) or ``"hertz_mindlin"`` (kappa = k_t / S_n of the
            self-similar Hertz impact, :func:`hertz_slip_velocity`).

    Raises:
        ValueError: eps_t is out of reach (the message gives the reachable range).

    """
    if normal != "linear":  # eps_t >= 1 is refused there: it lies above the grid's first point
        return _hertz_ratio(float(eps_t), float(zeta_n), float(zeta_t), float(mass_factor))
    lowest = reachable_restitution(zeta_t, mass_factor)
    if not lowest < eps_t < 1.0:
        raise ValueError(
            f"{lowest:.4g} < eps_t < 1 for a grain of tangential mass factor {mass_factor:.4g} "
            f"with tangential damping ratio {zeta_t:g} (a sticking impact cannot take more)"
        )
    level = 1.0 - (1.0 - eps_t) / mass_factor
    theta = _first_crossing(lambda s: unit_response(s, zeta_t)[1], 4.0, level)
    return mass_factor * (theta / impact_end_time(zeta_n)) ** 2


def sticking_restitution(
    kappa: float, zeta_n: float, zeta_t: float, mass_factor: float, normal: str = "linear"
) -> float:
    """eps_t = 1 - f_t (1 - V(theta)) of a sticking impact (the inverse of the mapping above)."""
    if normal != "linear":
        slip = hertz_slip_velocity([kappa], zeta_n, zeta_t, mass_factor)[0]
        return 1.0 - mass_factor * (1.0 - float(slip))
    theta = math.sqrt(kappa / mass_factor) * impact_end_time(zeta_n)
    return 1.0 - mass_factor * (1.0 - float(unit_response(np.array([theta]), zeta_t)[1][0]))


def resolve(contact, material, particles) -> tuple[float, float, float]:
    """(kappa, zeta_t, f_t) of a case's ``"coulomb"`` contact: given values, else derived.

    Raises:
        ValueError: eps_t is out of reach of the derivation (see above).

    """
    from dem.config import DEM_TANGENTIAL_DAMPING_RATIO
    from dem.kernels.contact import damping_beta, damping_ratio

    f_t = tangential_mass_factor(particles.shape, particles.rotation, particles.grain)
    zeta_t = contact.tangential_damping_ratio
    if zeta_t is None:
        zeta_t = DEM_TANGENTIAL_DAMPING_RATIO
    kappa = contact.tangential_stiffness_ratio
    if kappa is None:
        normal = "linear" if contact.model == "linear" else "hertz_mindlin"
        zeta_n = damping_ratio(normal, damping_beta(material.restitution_normal))
        kappa = tangential_stiffness_ratio(
            material.restitution_tangential, zeta_n, zeta_t, f_t, normal
        )
    return kappa, zeta_t, f_t


def tangential_mass_factor(shape: str, rotation: bool, template=None) -> float:
    """f_t: the tangential effective mass of a contact over its m*.

    A solid sphere that rolls: 2/7 (the contact point of a sphere pushed tangentially moves as a
    mass 2/7 m). Rotation locked: 1. A clump that rotates: its contact mass over its mass
    (:meth:`dem.scene.shapes.Template.contact_mass`: the smallest effective mass of any surface
    point).
    """
    if not rotation:
        return 1.0
    if shape == "sphere":
        return 2.0 / 7.0
    return float(template.contact_mass() / template.mass)


def normal_mass_factor(shape: str, rotation: bool, template=None) -> float:
    """f_n: the normal effective mass of a contact over its m* (the plastic contact's stick).

    A sphere pushed along the normal through its centre moves as its whole mass, rolling or
    not: 1. Rotation locked: 1. A clump that rotates: its contact mass over its mass, as
    :func:`tangential_mass_factor` (the smallest effective mass of any surface point in any
    direction, so that the stick sized by the step stays within the step's limit).
    """
    if not rotation or shape == "sphere":
        return 1.0
    return float(template.contact_mass() / template.mass)
