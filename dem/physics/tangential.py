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
with the default zeta_t = 0.3. For Hertz the tangent stiffness S_n takes the place of k_n.

**Limits of the construction.** It holds for impacts that stick. An impact whose tangential
velocity is large against the normal one slides for part of the contact, and Coulomb friction
then takes at most mu (1 + eps_n) v_n from v_t: no tangential law that respects Coulomb can give
less than eps_t = 1 - mu (1 + eps_n) v_n / v_t there. The formula is the starting point; the
virtual impacts of :mod:`dem.studies.calibrate` measure what a grain actually does over the impact
angles of conveying, rotation and the Coulomb cap included.
"""

from __future__ import annotations

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


def tangential_stiffness_ratio(
    eps_t: float, zeta_n: float, zeta_t: float, mass_factor: float
) -> float:
    """Return kappa = k_t / k_n that gives eps_t in a sticking impact (module docstring).

    The slip velocity of the contact point follows V(omega_t t; zeta_t); the centre of mass
    takes the fraction f_t of its change (a rolling sphere's centre loses 2/7 of what its contact
    point loses), so eps_t = 1 - f_t (1 - V) and the target of V is 1 - (1 - eps_t) / f_t.

    Args:
        eps_t: Target centre-of-mass tangential restitution, below 1 and at least
            :func:`reachable_restitution`.
        zeta_n: Normal damping ratio -beta(eps_n) (1 for eps_n = 0).
        zeta_t: Tangential damping ratio, >= 0.
        mass_factor: f_t, tangential effective mass over m*, in (0, 1].

    Raises:
        ValueError: eps_t is out of reach (the message gives the reachable range).

    """
    lowest = reachable_restitution(zeta_t, mass_factor)
    if not lowest < eps_t < 1.0:
        raise ValueError(
            f"{lowest:.4g} < eps_t < 1 for a grain of tangential mass factor {mass_factor:.4g} "
            f"with tangential damping ratio {zeta_t:g} (a sticking impact cannot take more)"
        )
    level = 1.0 - (1.0 - eps_t) / mass_factor
    theta = _first_crossing(lambda s: unit_response(s, zeta_t)[1], 4.0, level)
    return mass_factor * (theta / impact_end_time(zeta_n)) ** 2


def sticking_restitution(kappa: float, zeta_n: float, zeta_t: float, mass_factor: float) -> float:
    """eps_t = 1 - f_t (1 - V(theta)) of a sticking impact (the inverse of the mapping above)."""
    theta = math.sqrt(kappa / mass_factor) * impact_end_time(zeta_n)
    return 1.0 - mass_factor * (1.0 - float(unit_response(np.array([theta]), zeta_t)[1][0]))


def resolve(contact, material, particles) -> tuple[float, float, float]:
    """(kappa, zeta_t, f_t) of a case's ``"coulomb"`` contact: given values, else derived.

    Raises:
        ValueError: eps_t is out of reach of the derivation (see above).

    """
    from dem.config import DEM_TANGENTIAL_DAMPING_RATIO
    from dem.kernels.contact import damping_beta

    f_t = tangential_mass_factor(particles.shape, particles.rotation, particles.grain)
    zeta_t = contact.tangential_damping_ratio
    if zeta_t is None:
        zeta_t = DEM_TANGENTIAL_DAMPING_RATIO
    kappa = contact.tangential_stiffness_ratio
    if kappa is None:
        zeta_n = -damping_beta(material.restitution_normal)
        kappa = tangential_stiffness_ratio(material.restitution_tangential, zeta_n, zeta_t, f_t)
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
