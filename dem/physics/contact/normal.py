"""The normal sub-models: Hertz (E, nu) and linear (k_n) springs.

Each knows its coefficients and what the layers above ask of a normal law: its keyword
arguments for the kernels' parameters (:func:`dem.kernels.contact.make_params`), its tangent
stiffness, collision and Rayleigh times, the stiffness of a bed under a load, a stiffer copy,
its case key and its LAMMPS and LIGGGHTS words.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar

from dem.kernels import contact


@dataclass(frozen=True)
class Hertz:
    """Hertz-Mindlin: S_n = 2 Y* sqrt(R* delta), Y* = E / (2 (1 - nu^2)) of one material.

    Attributes:
        youngs_modulus: E, Pa.
        poisson_ratio: nu.

    """

    youngs_modulus: float
    poisson_ratio: float

    name: ClassVar[str] = "hertz_mindlin"
    #: The case key of its stiffness, and the LIGGGHTS ``pair_style gran`` model it maps to.
    key: ClassVar[str] = "contact.youngs_modulus"
    liggghts: ClassVar[str] = "model hertz tangential history"
    #: What a LIGGGHTS deck's tangential spring is when it keeps dem's own k_t / k_n.
    liggghts_spring_note: ClassVar[str] = ", with Mindlin's k_t = 8 G* sqrt(R* d)"

    @property
    def y_star(self) -> float:
        """Effective Young's modulus Y* = E / (2 (1 - nu^2)), Pa."""
        return contact.youngs_star(self.youngs_modulus, self.poisson_ratio)

    @property
    def stiffness_value(self) -> float:
        """The value of :attr:`key`: E, Pa."""
        return self.youngs_modulus

    def kernel_args(self) -> dict:
        """The keyword arguments of :func:`dem.kernels.contact.make_params` it decides."""
        return {"model": self.name, "stiffness": 0.0, "youngs_modulus": self.youngs_modulus,
                "poisson_ratio": self.poisson_ratio}  # fmt: skip

    def impact_overlap(self, r_eff: float, m_eff: float, speed: float) -> float:
        """Largest overlap of an elastic impact at ``speed``, m."""
        return contact.hertz_max_overlap(self.y_star, r_eff, m_eff, speed)

    def collision_time(self, r_eff: float, m_eff: float, speed: float, beta: float) -> float:
        """Elastic contact duration at ``speed`` (the damping does not enter), s."""
        return contact.hertz_collision_time(self.y_star, r_eff, m_eff, speed)

    def rayleigh_time(self, radius: float, density: float) -> float:
        """Rayleigh time of a grain of this material, s."""
        return contact.rayleigh_time(radius, density, self.youngs_modulus, self.poisson_ratio)

    def bed_stiffness(self, load: float, radius: float) -> float:
        """S_n = 2 Y* sqrt(R delta) of a grain of radius R resting on a plane under ``load`` N."""
        y_star = self.y_star
        delta = (load / (4.0 / 3.0 * y_star * math.sqrt(radius))) ** (2.0 / 3.0)
        return 2.0 * y_star * math.sqrt(radius * delta)

    def scaled(self, factor: float) -> Hertz:
        """The law whose bed stiffness under a fixed load is ``factor`` times this one's.

        S_n grows as E^(2/3) at a fixed load, so E takes factor^1.5.
        """
        return replace(self, youngs_modulus=self.youngs_modulus * factor**1.5)

    def stiffer(self, ratio: float) -> Hertz:
        """The law whose impact overlaps are 1 / ``ratio`` of this one's (delta ~ E^(-2/5))."""
        return replace(self, youngs_modulus=self.youngs_modulus * ratio**2.5)

    def equivalent_youngs_modulus(self, mass: float, radius: float, speed: float) -> float:
        """E, Pa (the axis of the stiffness studies)."""
        return float(self.youngs_modulus)

    def lammps_words(self, restitution: float, c_kt: float) -> tuple[str, str, list[str]]:
        """LAMMPS normal words ``hertz/material E e nu``, tangential model ``mindlin``, notes.

        LAMMPS forms E_eff = E / (2 (1 - nu^2)) from E and nu: the E written is 2 (1 - nu^2) Y*;
        ``mindlin`` takes k_t = C_kt a.
        """
        nu = self.poisson_ratio
        e_mod = 2.0 * (1.0 - nu * nu) * self.y_star
        note = (f"hertz/material E = 2 (1 - nu^2) Y* = {e_mod:.6g} Pa (LAMMPS's E_eff is dem's "
                f"Y* = {self.y_star:.6g} Pa); mindlin k_t = {c_kt:.6g} a (dem's C_kt)")  # fmt: skip
        return f"hertz/material {e_mod:.17g} {restitution:.17g} {nu:.17g}", "mindlin", [note]

    def report(self) -> dict:
        """Its coefficients for summary.json."""
        return {"model": self.name, "youngs_modulus": self.youngs_modulus,
                "poisson_ratio": self.poisson_ratio}  # fmt: skip


@dataclass(frozen=True)
class Linear:
    """The linear spring k_n (LIGGGHTS ``hooke/stiffness``).

    Attributes:
        stiffness: k_n, N/m.
        poisson_ratio: nu (the case's; the linear law does not use it).

    """

    stiffness: float
    poisson_ratio: float

    name: ClassVar[str] = "linear"
    key: ClassVar[str] = "contact.stiffness"
    liggghts: ClassVar[str] = "model hooke/stiffness tangential history"
    liggghts_spring_note: ClassVar[str] = ""

    @property
    def stiffness_value(self) -> float:
        """The value of :attr:`key`: k_n, N/m."""
        return self.stiffness

    def kernel_args(self) -> dict:
        """The keyword arguments of :func:`dem.kernels.contact.make_params` it decides."""
        return {"model": self.name, "stiffness": self.stiffness, "youngs_modulus": 0.0,
                "poisson_ratio": self.poisson_ratio}  # fmt: skip

    def impact_overlap(self, r_eff: float, m_eff: float, speed: float) -> float:
        """0: the linear law's stiffness does not depend on the overlap."""
        return 0.0

    def collision_time(self, r_eff: float, m_eff: float, speed: float, beta: float) -> float:
        """Damped contact duration pi / omega_d, s (the linear collision time)."""
        return contact.linear_collision_time(self.stiffness, m_eff, beta)

    def rayleigh_time(self, radius: float, density: float) -> float:
        """No Rayleigh time: the linear law has no modulus (inf)."""
        return math.inf

    def bed_stiffness(self, load: float, radius: float) -> float:
        """k_n, whatever the load, N/m."""
        return float(self.stiffness)

    def scaled(self, factor: float) -> Linear:
        """The law whose bed stiffness is ``factor`` times this one's."""
        return replace(self, stiffness=self.stiffness * factor)

    def stiffer(self, ratio: float) -> Linear:
        """The law whose impact overlaps are 1 / ``ratio`` of this one's (delta ~ k^(-1/2))."""
        return replace(self, stiffness=self.stiffness * ratio**2)

    def equivalent_youngs_modulus(self, mass: float, radius: float, speed: float) -> float:
        """The E whose Hertz impact at ``speed`` lasts as long as pi sqrt(m / k_n), Pa."""
        t_c = math.pi * math.sqrt(mass / self.stiffness)
        y_star = contact.hertz_youngs_star_for_time(t_c, radius, mass, speed)
        return contact.youngs_modulus_from_star(y_star, self.poisson_ratio)

    def lammps_words(self, restitution: float, c_kt: float) -> tuple[str, str, list[str]]:
        """LAMMPS normal words ``hooke k_n e``, tangential model ``linear_history``, no note."""
        return f"hooke {self.stiffness:.17g} {restitution:.17g}", "linear_history", []

    def report(self) -> dict:
        """Its coefficients for summary.json."""
        return {"model": self.name, "stiffness": self.stiffness,
                "poisson_ratio": self.poisson_ratio}  # fmt: skip


#: The normal sub-models by their ``[contact] model`` name.
NORMALS = {"hertz_mindlin": Hertz, "linear": Linear}


def normal_from_case(contact_spec) -> Hertz | Linear:
    """The normal sub-model of a case's ``[contact]`` (:class:`dem.scene.spec.ContactSpec`)."""
    if contact_spec.model == Hertz.name:
        return Hertz(contact_spec.youngs_modulus or 0.0, contact_spec.poisson_ratio)
    return Linear(contact_spec.stiffness or 0.0, contact_spec.poisson_ratio)
