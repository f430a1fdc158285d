"""The tangential sub-models: "coulomb", "liggghts" and "impact" with their coefficients.

Each is built from a case's ``[contact]``, ``[material]`` (or the wall's) and the grain, and
gives the keyword arguments of :func:`dem.kernels.contact.make_params` it decides. "coulomb"
derives an omitted k_t / k_n from eps_t (:mod:`dem.physics.tangential`): the root search runs
once per set of inputs (:func:`spring_ratio` is cached), so the check at load, the law's two
rows and every later build share one search.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import ClassVar

from dem.config import DEM_TANGENTIAL_DAMPING_RATIO
from dem.kernels import contact
from dem.physics import tangential as fit


@functools.lru_cache(maxsize=256)  # a pure function of five scalars: one root search each
def spring_ratio(eps_t: float, eps_n: float, model: str, zeta_t: float, f_t: float) -> float:
    """Kappa = k_t / k_n (Hertz: k_t / S_n) that gives eps_t in a sticking impact.

    zeta_n follows from eps_n and the normal law (:func:`dem.kernels.contact.damping_ratio`);
    :func:`dem.physics.tangential.tangential_stiffness_ratio` does the search.

    Raises:
        ValueError: eps_t is out of reach (the message gives the reachable range).

    """
    zeta_n = contact.damping_ratio(model, contact.damping_beta(eps_n))
    return fit.tangential_stiffness_ratio(eps_t, zeta_n, zeta_t, f_t, model)


@dataclass(frozen=True)
class Coulomb:
    """One spring-dashpot whose total force is capped at mu F_n (LAMMPS ``mindlin``, Luding).

    Attributes:
        stiffness_ratio: kappa = k_t / k_n (Hertz: k_t / S_n).
        damping_ratio: zeta_t, the tangential dashpot's damping ratio.
        mass_factor: f_t, the tangential effective mass over m*.
        derived: True when kappa was derived from eps_t (not given in the case).

    """

    stiffness_ratio: float
    damping_ratio: float
    mass_factor: float
    derived: bool = False

    name: ClassVar[str] = "coulomb"
    history_width: ClassVar[int] = contact.HISTORY_WIDTH["coulomb"]

    @classmethod
    def from_case(cls, spec, material, particles) -> Coulomb:
        """Given kappa and zeta_t, else derived from the material's eps_t (and the default zeta_t).

        Raises:
            ValueError: eps_t is out of reach of the derivation.

        """
        f_t = fit.tangential_mass_factor(particles.shape, particles.rotation, particles.grain)
        zeta_t = spec.tangential_damping_ratio
        if zeta_t is None:
            zeta_t = DEM_TANGENTIAL_DAMPING_RATIO
        kappa = spec.tangential_stiffness_ratio
        if kappa is not None:
            return cls(kappa, zeta_t, f_t)
        eps_t, eps_n = material.restitution_tangential, material.restitution_normal
        return cls(spring_ratio(eps_t, eps_n, spec.model, zeta_t, f_t), zeta_t, f_t, derived=True)

    def kernel_args(self) -> dict:
        """kappa, zeta_t and f_t."""
        return {
            "tangential_stiffness_ratio": self.stiffness_ratio or 0.0,
            "tangential_damping_ratio": self.damping_ratio,
            "tangential_mass_factor": self.mass_factor,
        }


@dataclass(frozen=True)
class Liggghts:
    """LIGGGHTS's ``tangential_model history``: the spring capped, the dashpot added on top.

    Attributes:
        stiffness_ratio: kappa = k_t / k_n of the linear law (0 with Hertz: Mindlin's k_t).

    """

    stiffness_ratio: float

    name: ClassVar[str] = "liggghts"
    history_width: ClassVar[int] = contact.HISTORY_WIDTH["liggghts"]
    damping_ratio: ClassVar[float] = 0.0
    mass_factor: ClassVar[float] = 1.0

    @classmethod
    def from_case(cls, spec, material, particles) -> Liggghts:
        """The given kappa (linear); LIGGGHTS's own damping (gamma_t = gamma_n, or Mindlin's)."""
        return cls(spec.tangential_stiffness_ratio or 0.0)

    def kernel_args(self) -> dict:
        """kappa; no zeta_t, f_t = 1."""
        return {
            "tangential_stiffness_ratio": self.stiffness_ratio,
            "tangential_damping_ratio": self.damping_ratio,
            "tangential_mass_factor": self.mass_factor,
        }


@dataclass(frozen=True)
class Impact:
    """The impact-aware law: eps_t delivered by each impact, then a rigid Coulomb stick.

    Attributes:
        mass_factor: f_t, the tangential effective mass over m*.
        normal_mass_factor: f_n, the plastic contact's normal stick mass over m*.

    """

    mass_factor: float
    normal_mass_factor: float

    name: ClassVar[str] = "impact"
    history_width: ClassVar[int] = contact.HISTORY_WIDTH["impact"]
    stiffness_ratio: ClassVar[float] = 0.0
    damping_ratio: ClassVar[float] = 0.0

    @classmethod
    def from_case(cls, spec, material, particles) -> Impact:
        """f_t and f_n of the grain; the rest follows from eps_n, eps_t and dt."""
        pt = particles
        return cls(
            fit.tangential_mass_factor(pt.shape, pt.rotation, pt.grain),
            fit.normal_mass_factor(pt.shape, pt.rotation, pt.grain),
        )

    def kernel_args(self) -> dict:
        """f_t and f_n; no spring."""
        return {
            "tangential_stiffness_ratio": self.stiffness_ratio,
            "tangential_damping_ratio": self.damping_ratio,
            "tangential_mass_factor": self.mass_factor,
            "normal_mass_factor": self.normal_mass_factor,
        }


#: The tangential sub-models by their ``[contact] tangential`` name.
TANGENTIALS: dict[str, type[Coulomb] | type[Liggghts] | type[Impact]] = {
    "coulomb": Coulomb,
    "liggghts": Liggghts,
    "impact": Impact,
}


def tangential_from_case(spec, material, particles) -> Coulomb | Liggghts | Impact:
    """The tangential sub-model of a case's ``[contact]`` with ``material`` and its grain."""
    return TANGENTIALS[spec.tangential].from_case(spec, material, particles)
