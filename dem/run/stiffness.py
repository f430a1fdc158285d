"""Is the contact stiff enough? The resting bed's lowest vertical mode against the drive.

For a lone grain the same c = (omega / omega_c)^2 sets its error against the rigid reference,
measured linear in c (:func:`single_grain`).

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
from typing import Any

from dem.config import BED_PACKING, GRAVITY
from dem.physics import measure
from dem.physics.mass import sphere_volume

#: Solid fraction of a resting bed assumed for its height (the one of the depth keys).
PACKING = BED_PACKING


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


def bed_mode(scene, normal=None) -> BedMode:
    """The :class:`BedMode` of a :class:`dem.scene.resolved.Scene`.

    ``normal``: another normal sub-model (:class:`dem.physics.contact.Hertz` or ``Linear``)
    than the scene's law's.
    """
    case = scene.case
    pt = case.particles
    mass, radius = scene.grain_mass, scene.max_radius
    volume = mass / scene.grain.density if pt.clumps else sphere_volume(radius)
    area = case.trough.length * case.trough.width
    height = pt.count * volume / (PACKING * area)
    layers = max(1.0, height / (2.0 * radius))
    load = layers * mass * GRAVITY * math.cos(math.radians(case.trough.inclination))
    s = (normal or scene.law.normal).bed_stiffness(load, radius)
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
    normal = scene.law.normal.scaled(factor)
    return normal.key, float(normal.stiffness_value)


#: A lone grain's error against its rigid reference, per unit compliance: |v_norm(DEM) -
#: v_norm(rigid)| <= K c. validation/single-grain-stiffness measured 0.01-0.49 c over 7 sliding
#: drives (level and uphill near the threshold) at E = 5e7-2e10 Pa under the plastic contact of
#: eps_n = 0 (growing as c^0.66-0.9; 0.21-0.99 c, linear, under the dashpot before it); K is
#: the worst, rounded up (a lone grain is one layer: omega_bed = omega_c).
SINGLE_GRAIN_ERROR_PER_COMPLIANCE = 0.5
#: ... and what a lone grain's answer may be off by: 2 % of its reference v_norm, and 0.002 in
#: v_norm below a reference of 0.1 (near a threshold a relative error means nothing).
SINGLE_GRAIN_TOLERANCE = 0.02
SINGLE_GRAIN_FLOOR = 0.1
#: Where the grain flies, its error also follows the reference's sensitivity to the contact:
#: |v_norm(DEM) - v_norm(rigid)| <= K_h |v(Gamma (1 + c)) - v(Gamma (1 - c))| / 2, the bounded
#: point mass at a throw number moved by the compliance c either way. validation/hopping-bias
#: (part ``rule``, rule.csv) measured the ratio on Figs. 6 and 7's 64 drives at 2e9 Pa and the
#: misses at 2e10 and 2e11 Pa: 0.51-7.8 where the error exceeds the sliding rule by more than a
#: run resolves (0.001), the largest at Gamma 3.8 and 4.4, beside the paper's fall (+0.7 % and
#: +7.7 % at 2e9 Pa, converging with E); K_h is the worst, rounded up, and covers all 74 rows.
HOPPING_ERROR_PER_SENSITIVITY = 8.0


def single_grain(scene) -> dict | None:
    """Whether one grain's contact is stiff enough for its rigid reference, for summary.json.

    The reference is the one the summary names (the rolling sphere for a sphere free to roll,
    else the Coulomb-bounded point mass; None on a two-component drive or where no steady state
    exists). The expected error is :data:`SINGLE_GRAIN_ERROR_PER_COMPLIANCE` c; it is allowed
    :data:`SINGLE_GRAIN_TOLERANCE` max(|reference|, :data:`SINGLE_GRAIN_FLOOR`). Where it is
    more, the key and the value that bring it within (c ~ E^(-2/3) for Hertz, 1/k_n linear).
    """
    from dem.run.advice import round_up
    from dem.run.summary import grains_roll, pointmass_bounded, pointmass_rolling

    case = scene.case
    reference = pointmass_rolling(case) if grains_roll(case) else pointmass_bounded(case)
    if reference is None:
        return None
    mode = bed_mode(scene)
    c = mode.compliance
    allowed = SINGLE_GRAIN_TOLERANCE * max(abs(reference), SINGLE_GRAIN_FLOOR)
    sliding = SINGLE_GRAIN_ERROR_PER_COMPLIANCE * c
    hopping = None if grains_roll(case) else hopping_error(case, c)
    expected = max(sliding, hopping or 0.0)
    # both terms grow about linearly in c: the compliance at which the larger meets the bound
    limit = c * allowed / expected if expected > 0.0 else math.inf
    out: dict[str, Any] = {
        "single_grain": True,
        "converged": expected <= allowed,
        "compliance": c,
        "compliance_limit": limit,
        "grain_mode_hz": mode.omega_bed / (2 * math.pi),
        "expected_error": expected,
        "expected_error_sliding": sliding,
        "expected_error_hopping": hopping,
        "allowed_error": allowed,
        "reference_velocity_norm": reference,
    }
    if not out["converged"]:
        key, value = stiffness_for(scene, limit)
        out |= {"key": key, "value": round_up(value)}
    return out


def hopping_error(case, compliance: float) -> float | None:
    """A flying lone grain's expected error from the rigid point mass's sensitivity, v_norm.

    :data:`HOPPING_ERROR_PER_SENSITIVITY` times half the change of the Coulomb-bounded point
    mass when the throw number moves by the compliance c either way: large next to a
    bifurcation (the paper's fall at Gamma 4.5), where the finite contact's landing phase
    matters. None where the grain does not fly (Gamma <= 1: the sliding rule alone) or on a
    two-component drive.
    """
    from dem import pointmass

    d, m = case.drive, case.wall_material
    if not d.is_single or d.throw_number <= 1.0:
        return None

    def v(gamma):
        return pointmass.velocity(
            gamma, d.angle, m.friction, case.trough.inclination, m.restitution_tangential,
            m.restitution_normal, impact="coulomb",
        ).velocity_norm  # fmt: skip

    lo, hi = v(d.throw_number * (1.0 - compliance)), v(d.throw_number * (1.0 + compliance))
    return HOPPING_ERROR_PER_SENSITIVITY * abs(hi - lo) / 2.0


def why_expected(one: dict) -> str:
    """Which rule set a lone grain's expected error, in words with its evidence."""
    if (one.get("expected_error_hopping") or 0.0) > one.get("expected_error_sliding", 0.0):
        return (f"{HOPPING_ERROR_PER_SENSITIVITY:g} times the bounded point mass's change when "
                f"Gamma moves by c either way: a flying grain's landing phase, large beside a "
                f"bifurcation; validation/hopping-bias")  # fmt: skip
    return f"{SINGLE_GRAIN_ERROR_PER_COMPLIANCE:g} c, validation/single-grain-stiffness"


def advice(scene):
    """A "warn" :class:`dem.run.advice.Advice` where a study finds the contact too compliant.

    A bed: validation/bulk-convergence's limit on c; one grain: :func:`single_grain`.
    """
    from dem.run.advice import Advice, round_up

    if scene.case.particles.count < 2:
        one = single_grain(scene)
        if one is None or one["converged"]:
            return None
        return Advice(
            "warn", one["key"],
            f"one grain's contact is soft against the drive: (omega / omega_c)^2 = "
            f"{one['compliance']:.3g} (the grain bounces at {one['grain_mode_hz']:.0f} Hz on "
            f"the floor), where a lone grain departs from its rigid reference by up to "
            f"{one['expected_error']:.2g} in v_norm ({why_expected(one)}), more than the "
            f"{one['allowed_error']:.2g} allowed (2 % of the reference "
            f"{one['reference_velocity_norm']:.3g}); set {one['key']} >= {one['value']:.3g}",
            one["value"],
        )  # fmt: skip
    data = study()
    if data is None:
        return None
    limit = data["compliance_limit"]
    mode = bed_mode(scene)
    if mode.compliance <= limit:
        return None
    key, value = stiffness_for(scene, limit)
    shown, bound = measure.distinct(mode.compliance, limit, 3)
    return Advice(
        "warn",
        key,
        f"the resting bed's lowest vertical mode ({mode.omega_bed / (2 * math.pi):.0f} Hz, "
        f"{mode.layers:.1f} layers) is close enough to the drive that the bed conveys unlike "
        f"the rigid material: (omega / omega_bed)^2 = {shown} > {bound}, where "
        f"validation/bulk-convergence measured more than 2 % from the rigid limit "
        f"({data['evidence']}); set {key} >= {round_up(value):.3g}",
        round_up(value),
    )


def assessment(scene) -> dict | None:
    """Whether the bed is stiff enough for the rigid material's answer, for summary.json.

    One grain: :func:`single_grain`. None without the study's data; else the bed's compliance
    c, the study's limit, ``converged`` (c <= limit), and where it is not, the key and the value
    to set.
    """
    if scene.case.particles.count < 2:
        return single_grain(scene)
    data = study()
    if data is None:
        return None
    from dem.run.advice import round_up

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
