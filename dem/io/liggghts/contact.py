"""The material and contact-law block of a LIGGGHTS deck: dem's laws mapped one-to-one.

- ``hertz_mindlin`` -> ``model hertz tangential history`` with the same Young's modulus Y and
  Poisson ratio nu (one material for grains and walls), friction mu and normal restitution e.
  LIGGGHTS computes k_n = (4/3) Y* sqrt(R* d_n) and damping from
  beta = ln(e) / sqrt(ln(e)^2 + pi^2); it refuses e <= 0.05, so e is clamped to
  :data:`MIN_HERTZ_RESTITUTION` and the deck says so.
- ``linear`` -> ``model hooke/stiffness`` with ``absolute_damping on``: k_n (N/m),
  k_t = kappa k_n, and the damping coefficients (N s/m)

      gamma_n = 2 zeta sqrt(k_n m*),   zeta = -ln(e) / sqrt(ln(e)^2 + pi^2)   (1 for e = 0),

  with m* = m/2 for grain-grain (atom types 1-1) and m* = m for grain-wall contacts (1-2), so the
  restitution is exact for both and e = 0 needs no clamp; gamma_t = gamma_n as dem's
  ``tangential = "liggghts"`` uses it, or 2 zeta_t sqrt(k_t f_t m*) for ``"coulomb"``.

LIGGGHTS has one tangential convention, the spring capped at mu F_n with the dashpot added while
sticking: dem's ``tangential = "liggghts"``. A case with ``"coulomb"`` is written
with the same coefficients and a NOTE in the deck; use ``"liggghts"`` on both sides of a
comparison.

``limitForce`` is written out (on or off as ``[contact] limit_force``), and so is
``tangential_damping on`` (the LIGGGHTS default). Grains are atom type 1, walls type 2.
"""

from __future__ import annotations

import math

from dem.errors import InputError
from dem.io.liggghts.text import fmt
from dem.kernels.contact import damping_beta
from dem.physics.contact import Hertz, Liggghts
from dem.physics.laws import TANGENTIAL_LAWS
from dem.scene.resolved import Scene

#: LIGGGHTS refuses coefficientRestitution <= 0.05; Hertz decks use at least this value.
MIN_HERTZ_RESTITUTION = 0.06


def damping_ratio(restitution: float) -> float:
    """Return the damping ratio zeta of a linear spring-dashpot with restitution e in [0, 1].

    zeta = -beta = -ln(e) / sqrt(ln(e)^2 + pi^2) (:func:`dem.kernels.contact.damping_beta`, the
    kernels' value), from e = exp(-zeta pi / sqrt(1 - zeta^2)); e = 0 gives critical damping,
    zeta = 1.
    """
    return -damping_beta(restitution)


def contact_block(scene: Scene, sphere_mass: float) -> tuple[list[str], str, str]:
    """Return the property/global lines, the model string and the model settings."""
    case = scene.case
    lines = [
        "# grains are atom type 1, walls type 2; each matrix below is (1-1 1-2 2-1 2-2): "
        "grain-grain the material, grain-wall [wall] (the material's where it gives nothing)",
    ]
    row = TANGENTIAL_LAWS[case.contact.tangential]
    if row.liggghts_as != row.name:
        note = row.liggghts_note
        if row.liggghts_keeps:
            note += scene.law.normal.liggghts_spring_note
        lines.append("# NOTE: " + note)
        if not row.liggghts_keeps:
            case = case.with_tangential(row.liggghts_as)
    # the scene's law, or the law of the case switched to the deck's tangential law above
    law = case.law
    contact, material, wall = case.contact, case.material, case.wall_material
    limit = "on" if contact.limit_force else "off"

    def pair(grains: float, walls: float) -> str:
        return " ".join(fmt(x) for x in (grains, walls, walls, walls))

    mu = pair(material.friction, wall.friction)
    if contact.wall_lever_arm != "midpoint":
        arm = "r - delta" if contact.wall_lever_arm == "surface" else "r"
        lines.append(
            f"# NOTE: the case's wall contacts act at {arm} (contact.wall_lever_arm = "
            f"'{contact.wall_lever_arm}'); LIGGGHTS's walls at r - delta/2, as dem's "
            "wall_lever_arm = 'midpoint'"
        )
    if contact.slip_lever_arm == "radius":
        lines.append(
            "# NOTE: the case takes the slip velocity at the full radii (contact.slip_lever_arm "
            "= 'radius'); LIGGGHTS at r - delta/2, as dem's slip_lever_arm = 'contact'"
        )
    lines += [
        f"fix m_mu all property/global coefficientFriction peratomtypepair 2 {mu}",
    ]
    if isinstance(law.normal, Hertz):
        es = []
        for e_case in (material.restitution_normal, wall.restitution_normal):
            e = max(e_case, MIN_HERTZ_RESTITUTION)
            if e != e_case and e_case not in es:
                lines.append(
                    f"# NOTE: restitution_normal = {e_case} in the case; LIGGGHTS refuses "
                    f"e <= 0.05, so e = {e} is used here (use the same value on both sides of a "
                    "comparison)"
                )  # fmt: skip
            es.append(e)
        assert contact.youngs_modulus is not None  # Hertz-Mindlin's key
        y, nu = fmt(contact.youngs_modulus), fmt(contact.poisson_ratio)
        lines += [
            f"fix m_Y all property/global youngsModulus peratomtype {y} {y}",
            f"fix m_nu all property/global poissonsRatio peratomtype {nu} {nu}",
            f"fix m_e all property/global coefficientRestitution peratomtypepair 2 {pair(*es)}",
        ]
        model = law.normal.liggghts
        settings = f"limitForce {limit} tangential_damping on"
    else:
        if case.particles.types:
            raise InputError(
                "contact.model", contact.model, "'hertz_mindlin' for a LIGGGHTS deck of grain "
                "types or sizes (particles.types): the linear deck's damping is one absolute "
                "gamma for every pair, dem's 2 zeta sqrt(k m*) takes each pair's m*",
                source=str(case.source),
            )  # fmt: skip
        kn = law.normal.stiffness
        rows = (law.grain_grain.tangential, law.grain_wall.tangential)
        kts = [rows[0].stiffness_ratio * kn] + [rows[1].stiffness_ratio * kn] * 3
        zetas = [damping_ratio(material.restitution_normal)]
        zetas += [damping_ratio(wall.restitution_normal)] * 3
        # m* = m/2 grain-grain (1-1), m for grain-wall (1-2 and 2-1); type 2-2 never meets
        meff = (0.5 * sphere_mass, sphere_mass, sphere_mass, sphere_mass)
        gn = [2.0 * z * math.sqrt(kn * m) for z, m in zip(zetas, meff, strict=True)]
        if isinstance(rows[0], Liggghts):
            gt, gt_text = gn, "gamma_t = gamma_n (as dem's liggghts convention)"
        else:
            gt = [
                2.0 * row.damping_ratio * math.sqrt(kt * row.mass_factor * m)
                for row, kt, m in zip((rows[0],) + (rows[1],) * 3, kts, meff, strict=True)
            ]
            zeta_t, f_t = rows[0].damping_ratio, rows[0].mass_factor
            gt_text = f"gamma_t = 2 zeta_t sqrt(k_t f_t m*), zeta_t = {zeta_t:.6g}, f_t = {f_t:.6g}"
        lines += [
            f"# linear spring-dashpot: zeta = {zetas[0]:.6g} (grain-wall {zetas[1]:.6g}) from e = "
            f"{material.restitution_normal} (wall {wall.restitution_normal}), "
            "gamma_n = 2 zeta sqrt(k m*), m* = m/2 (1-1) or m (1-2); " + gt_text,
            f"fix m_kn all property/global kn peratomtypepair 2 {' '.join([fmt(kn)] * 4)}",
            "fix m_kt all property/global kt peratomtypepair 2 " + " ".join(map(fmt, kts)),
            "fix m_gn all property/global gamman_abs peratomtypepair 2 " + " ".join(map(fmt, gn)),
            "fix m_gt all property/global gammat_abs peratomtypepair 2 " + " ".join(map(fmt, gt)),
        ]
        model = law.normal.liggghts
        settings = f"absolute_damping on limitForce {limit} tangential_damping on"
    if material.rolling_friction > 0.0 or wall.rolling_friction > 0.0:
        mr = pair(material.rolling_friction, wall.rolling_friction)
        lines.append(
            f"fix m_mur all property/global coefficientRollingFriction peratomtypepair 2 {mr}"
        )
        model += " rolling_friction cdt"
    return lines, model, settings
