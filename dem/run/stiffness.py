"""Is the contact stiff enough? The resting bed's lowest vertical mode against the drive.

A DEM contact is a spring, so a resting bed is a column of masses on springs. Its lowest vertical
mode omega_bed rides the drive; where omega_bed is not far above the drive's omega the bed's
response to the normal acceleration is amplified (a single grain: 1 / (1 - (omega /
omega_n)^2), validation/impact-law) and the bed conveys differently from the rigid material it
stands for. validation/bulk-convergence measured how far the bed velocity is from its rigid
limit against c = (omega / omega_bed)^2; :func:`advice` warns where c is above the largest value
at which that study measured less than 2 % (``dem/data/stiffness_convergence.json``), naming the
stiffness that brings it below.

The estimate (an order of magnitude, which the study's threshold absorbs):

- bed height H = N V_grain / (phi L W), phi = :data:`PACKING` (the section's floor area L W);
- layers n = max(1, H / d), d the diameter of the grain's largest member sphere;
- the bottom contact carries the grains above it: F = n m g cos(alpha);
- its tangent stiffness S: Hertz 2 Y* sqrt(R delta) at the overlap delta that carries F (R the
  member radius, a grain on the floor), linear k_n;
- omega_c = sqrt(S / m), and the lowest mode of a fixed-free chain of n equal masses and springs,
  omega_bed = 2 omega_c sin(pi / (2 (2 n + 1))) (omega_c for one grain).

It scales with E as omega_bed ~ E^(1/3) (Hertz), so c ~ E^(-2/3).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from importlib import resources

from dem.config import GRAVITY
from dem.kernels import contact
from dem.physics.mass import sphere_volume

#: Solid fraction of a resting bed assumed for its height.
PACKING = 0.6


@dataclass(frozen=True)
class BedMode:
    """The resting bed's estimated lowest vertical mode.

    Attributes:
        layers: n, grain layers in the bed.
        contact_stiffness: S of the bottom contact, N/m.
        omega_bed: The bed's lowest vertical mode, rad/s.
        compliance: c = (omega / omega_bed)^2, omega the drive's angular frequency.

    """

    layers: float
    contact_stiffness: float
    omega_bed: float
    compliance: float


def bed_mode(scene, youngs_modulus: float | None = None, stiffness: float | None = None) -> BedMode:
    """The :class:`BedMode` of a :class:`dem.scene.resolved.Scene` (another E or k_n if given)."""
    case = scene.case
    c, pt = case.contact, case.particles
    mass, radius = scene.grain_mass, scene.max_radius
    volume = mass / scene.grain.density if pt.clumps else sphere_volume(radius)
    area = case.trough.length * case.trough.width
    height = pt.count * volume / (PACKING * area)
    layers = max(1.0, height / (2.0 * radius))
    load = layers * mass * GRAVITY * math.cos(math.radians(case.trough.inclination))
    if c.model == "linear":
        s = float(stiffness if stiffness is not None else c.stiffness)
    else:
        youngs = youngs_modulus if youngs_modulus is not None else c.youngs_modulus
        y_star = contact.youngs_star(youngs, c.poisson_ratio)
        delta = (load / (4.0 / 3.0 * y_star * math.sqrt(radius))) ** (2.0 / 3.0)
        s = 2.0 * y_star * math.sqrt(radius * delta)
    omega_c = math.sqrt(s / mass)
    omega_bed = 2.0 * omega_c * math.sin(math.pi / (2.0 * (2.0 * layers + 1.0)))
    return BedMode(layers, s, omega_bed, (case.drive.omega / omega_bed) ** 2)


def study() -> dict | None:
    """validation/bulk-convergence's summary, ``dem/data/stiffness_convergence.json``, or None."""
    try:
        text = resources.files("dem").joinpath("data", "stiffness_convergence.json").read_text()
    except FileNotFoundError:
        return None
    return json.loads(text)


def stiffness_for(scene, compliance: float) -> tuple[str, float]:
    """The contact key and the value at which the bed's compliance c falls to ``compliance``.

    c ~ S^-1 and S ~ E^(2/3) at a fixed load (Hertz), S = k_n (linear).
    """
    mode = bed_mode(scene)
    factor = mode.compliance / compliance
    c = scene.case.contact
    if c.model == "linear":
        return "contact.stiffness", float(c.stiffness * factor)
    return "contact.youngs_modulus", float(c.youngs_modulus * factor**1.5)


def advice(scene):
    """A "warn" :class:`dem.run.accuracy.Advice` where the study finds the bed too compliant.

    One grain (no bed) gets none: validation/impact-law covers it.
    """
    from dem.run.accuracy import Advice, round_up

    data = study()
    if data is None or scene.case.particles.count < 2:
        return None
    limit = data["compliance_limit"]
    mode = bed_mode(scene)
    if mode.compliance <= limit:
        return None
    key, value = stiffness_for(scene, limit)
    return Advice(
        "warn",
        key,
        f"the resting bed's lowest vertical mode ({mode.omega_bed / (2 * math.pi):.0f} Hz, "
        f"{mode.layers:.1f} layers) is close enough to the drive that the bed conveys unlike "
        f"the rigid material: (omega / omega_bed)^2 = {mode.compliance:.3f} > {limit:.3f}, where "
        f"validation/bulk-convergence measured more than 2 % from the rigid limit "
        f"({data['evidence']}); set {key} >= {round_up(value):.3g}",
        round_up(value),
    )


def assessment(scene) -> dict | None:
    """Whether the bed is stiff enough for the rigid material's answer, for summary.json.

    None for one grain or without the study's data; else the bed's compliance c, the study's
    limit, ``converged`` (c <= limit), and where it is not, the key and the value to set.
    """
    data = study()
    if data is None or scene.case.particles.count < 2:
        return None
    from dem.run.accuracy import round_up

    limit = data["compliance_limit"]
    mode = bed_mode(scene)
    out = {
        "converged": mode.compliance <= limit,
        "compliance": mode.compliance,
        "compliance_limit": limit,
        "bed_mode_hz": mode.omega_bed / (2 * math.pi),
    }
    if not out["converged"]:
        key, value = stiffness_for(scene, limit)
        out |= {"key": key, "value": round_up(value)}
    out["measured"] = measured_near(data, mode.compliance)
    return out


def measured_near(data: dict, compliance: float, within: float = 1.5) -> list[dict]:
    """What the bulk study measured near this compliance: per bed, its point of closest c.

    Only points within a factor ``within`` of ``compliance``: each row has the bed, its Young's
    modulus, c, and the velocity's relative error against that bed's rigid limit with its
    standard error.
    """
    best: dict[str, dict] = {}
    for row in data.get("rows", []):
        ratio = abs(math.log(row["compliance"] / compliance))
        if ratio <= math.log(within) and (
            row["bed"] not in best or ratio < abs(math.log(best[row["bed"]]["compliance"]
                                                           / compliance))
        ):  # fmt: skip
            best[row["bed"]] = row
    keys = ("bed", "youngs_modulus_pa", "compliance", "error_vs_rigid", "error_stderr")
    return [{k: r[k] for k in keys} for r in best.values()]
