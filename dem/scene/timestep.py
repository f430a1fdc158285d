"""The time step of a case, from the case alone: contact time scales and stability limits.

:class:`dem.physics.contact.ContactLaw` is a case's contact law in kernel form (re-exported here).
:func:`timestep_limits` gives the automatic step and the stability limit for one contact, and
:func:`timestep_for` applies them to a case: every member radius of its grain, sphere-sphere
and sphere-wall contacts, and the hardest impact the case can produce, taken from the drive and
a fall from the top of the fill box (:func:`dem.scene.fill.box_height`). Nothing is filled or
simulated, so ``dem export liggghts``, the validation scripts and ``dem run`` agree on dt before
any grain is placed.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dem import config
from dem.errors import InputError
from dem.physics.contact import ContactLaw
from dem.physics.mass import sphere_mass
from dem.scene import fill

__all__ = ["ContactLaw", "Timestep", "impact_speed_for", "timestep_for", "timestep_limits"]


def timestep_limits(
    law: ContactLaw,
    radius: float,
    density: float,
    impact_speed: float,
    *,
    rotation: bool = True,
    pairs: bool = True,
    mass: float | None = None,
    other: tuple[float, float] | None = None,
) -> tuple[float, float]:
    """Automatic time step and stability limit, s, for equal spheres.

    ``mass`` replaces the sphere's own mass (a clump member: the clump's effective mass at the
    member, see :func:`timestep_for`). ``other``: (mass kg, radius m) of the pair's other
    sphere where it differs (spheres of several sizes): the pair contact takes m* = m m_2 /
    (m + m_2) and R* = r r_2 / (r + r_2), as the pair kernel does.

    Stability: ``DEM_DT_STABILITY_FRACTION`` of the critical step 2/w0 (sqrt(1 + z^2) - z) of
    the stiffest single contact, normal (k_n) and tangential (k_t, times 7/2 with rotation on:
    a rolling sphere's tangential effective mass is 2/7 m*; damping ratio zeta_t with
    ``tangential = "coulomb"``), sphere-sphere (m* = m/2, R* = r/2;
    only if ``pairs``) and sphere-wall (m* = m, R* = r). Hertz stiffnesses are the tangent
    stiffnesses S_n, S_t at the overlap of an impact at ``impact_speed``.

    Automatic: linear: ``DEM_DT_COLLISION_FRACTION`` of the collision time; Hertz: the smaller
    of ``DEM_DT_RAYLEIGH_FRACTION`` of the Rayleigh time and ``DEM_DT_HERTZ_FRACTION`` of the
    Hertz collision time at ``impact_speed``; never above the stability limit.
    """
    if mass is None:
        mass = sphere_mass(density, radius)
    rotation_factor = 3.5 if rotation else 1.0
    contacts_list = [(mass, radius, True)]  # the grain-wall law ([wall])
    if pairs and other is None:
        contacts_list.append((0.5 * mass, 0.5 * radius, False))
    elif pairs and other is not None:
        m2, r2 = other
        contacts_list.append((mass * m2 / (mass + m2), radius * r2 / (radius + r2), False))
    limit = math.inf
    auto = math.inf
    for m_eff, r_eff, wall in contacts_list:
        t_c, critical = law.contact_times(m_eff, r_eff, impact_speed, rotation_factor, wall)
        auto, limit = min(auto, t_c), min(limit, critical)
    limit *= config.DEM_DT_STABILITY_FRACTION
    auto = law.automatic_step(auto, radius, density)
    return min(auto, limit), limit


def _typed_limits(case, law: ContactLaw, impact_speed: float, grains: int) -> tuple[float, float]:
    """Automatic step and stability limit of spheres of several types or sizes, s.

    The hardest contacts are those of the smallest spheres: within one type both m* and R* of a
    pair grow with either radius, and the critical step with them (linear: sqrt(m* / k_n);
    Hertz at an impact: m*^(2/5) R*^(-1/5), which grows as r for m proportional to r^3). So each
    type's smallest sphere (its density) is taken against a wall and against every type's
    smallest sphere, each pair with its own m* and R*; the Rayleigh time of each is taken too.
    """
    pt = case.particles
    small = sorted({(g.size.smallest, g.density) for g in pt.types})
    auto, limit = math.inf, math.inf
    for i, (radius, density) in enumerate(small):
        for r2, rho2 in small[i:]:
            a, b = timestep_limits(
                law, radius, density, impact_speed, rotation=pt.rotation, pairs=grains > 1,
                other=(sphere_mass(rho2, r2), r2),
            )  # fmt: skip
            auto, limit = min(auto, a), min(limit, b)
    return auto, limit


class Timestep(NamedTuple):
    """A case's time step.

    Attributes:
        dt: The step the run uses, s (the user's ``run.timestep`` or the automatic one).
        auto: The automatic step, s (a drive period holds a whole number of them).
        limit: The stability limit, s; a user step above it is refused.
        impact_speed: The impact speed the Hertz time scales were taken at, m/s.

    """

    dt: float
    auto: float
    limit: float
    impact_speed: float


def impact_speed_for(case, height: float | None = None, fastest: float = 0.0) -> float:
    """The hardest impact speed a case's grains meet, m/s.

    Peak trough speed A omega, plus the fastest grain's own speed, plus a free fall from
    ``height`` (default the top of the fill box, :func:`dem.scene.fill.box_height`).
    """
    d = case.drive
    if height is None:
        height = fill.box_height(case)
    peak = d.peak_speed
    return peak + fastest + math.sqrt(2.0 * config.GRAVITY * max(height, 0.0))


def _hardest_impact_text(case, speed: float) -> str:
    """What sets the hardest impact, for a step refused against its limit: the keys to check.

    A unit mistake elsewhere (an angle in radians, a throw number of 50, 20000 grains) shows
    here first, as an impact harder than the shipped cases' few tenths of a m/s.
    """
    d = case.drive
    fall = max(speed - d.peak_speed, 0.0)
    height = fill.box_height(case)
    return (
        f"; at this case's hardest impact, {speed:.3g} m/s: the trough's peak speed A omega = "
        f"{d.peak_speed:.3g} m/s (drive.amplitude {d.amplitude:.3g} m, Gamma "
        f"{d.throw_number:.3g}, drive.angle {d.angle:g} deg, frequency {d.frequency:g} Hz) and a "
        f"fall of {fall:.3g} m/s from the top of the fill, {height:.3g} m up "
        f"(particles.count {case.particles.count}): check those keys if the speed looks wrong"
    )


def timestep_for(
    case,
    *,
    timestep: float | None = None,
    impact_speed: float | None = None,
    grains: int | None = None,
    check_limit: bool = True,
    law: ContactLaw | None = None,
) -> Timestep:
    """The time step of a :class:`dem.scene.case.Case`, without placing a grain.

    Args:
        case: The case (contact, material, grain, drive, run).
        timestep: dt, s; default ``case.run.timestep``, else automatic.
        impact_speed: Hardest impact, m/s; default :func:`impact_speed_for` the fill box.
        grains: Number of grains (sphere-sphere contacts count only if more than one); default
            ``particles.count``.
        check_limit: False lets a given step exceed the stability limit: for stability studies
            (validation/stability), whose runs the instability guard must then stop.
        law: The case's contact law when it is already built (:func:`dem.scene.resolved.resolve`);
            default ``case.law`` (:attr:`dem.scene.spec.Case.law`).

    The step of a clump takes the smallest effective mass a point of its surface has for a force
    in any direction (:meth:`dem.scene.shapes.Template.contact_mass`; the clump mass M with rotation
    locked), for every member radius. A given step above the stability limit raises InputError
    naming ``run.timestep``; an automatic step is shortened so that a drive period holds a whole
    number of steps.

    """
    pt, mat = case.particles, case.material
    if law is None:
        law = case.law
    hardest = ""
    if impact_speed is None:
        impact_speed = impact_speed_for(case)
        hardest = _hardest_impact_text(case, impact_speed)
    if grains is None:
        grains = pt.count
    if pt.types:
        auto, limit = _typed_limits(case, law, impact_speed, grains)
    elif not pt.clumps:
        sizes = [(pt.radius, None)]
        density = mat.density
    else:
        # the clump's own compliance (rotation included) is in its contact mass, so the
        # sphere's rolling factor is not applied again below
        m_eff = pt.grain.contact_mass() if pt.rotation else pt.grain.mass
        sizes = [(float(r), m_eff) for r in np.unique(pt.grain.radii)]
        density = pt.grain.density
    if not pt.types:
        auto, limit = math.inf, math.inf
        for radius, mass in sizes:
            a, b = timestep_limits(
                law, radius, density, impact_speed, rotation=pt.rotation and mass is None,
                pairs=grains > 1, mass=mass,
            )  # fmt: skip
            auto, limit = min(auto, a), min(limit, b)
    period = 2.0 * math.pi / case.drive.omega
    auto = period / math.ceil(period / auto)
    user = timestep if timestep is not None else case.run.timestep
    if user is not None:
        if user > limit and check_limit:
            raise InputError(
                "run.timestep",
                user,
                f"<= {limit:.4g} s, the stability limit of this contact "
                f"({config.DEM_DT_STABILITY_FRACTION} of the critical step; 'auto' gives "
                f"{auto:.4g} s){hardest}",
                source=str(case.source),
            )
        return Timestep(float(user), auto, limit, impact_speed)
    return Timestep(auto, auto, limit, impact_speed)
