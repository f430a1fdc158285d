"""A case's contact law: one :class:`Interaction` for grain-grain, one for grain-wall contacts.

:meth:`ContactLaw.from_case` builds the named sub-models and packs them once into the kernels'
parameter array (two rows of :data:`dem.kernels.contact.N_PARAMS` floats, grain-grain then
grain-wall); the layers above ask the law (its time scales, its stiffer copy, its damping, its
deck words, :meth:`ContactLaw.report`) and never read a slot. A law built straight from a
kernel array (``ContactLaw(model, params)``: engine tests) decodes its sub-models from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from dem import config
from dem.kernels import contact
from dem.physics.contact.damping import Damping, restitution_for_beta
from dem.physics.contact.normal import Hertz, Linear, normal_from_case
from dem.physics.contact.tangential import (
    Coulomb,
    Impact,
    Liggghts,
    tangential_from_case,
)


def _key(table: dict, value: float) -> str:
    """The name whose code in ``table`` (:data:`dem.kernels.contact.TANGENTIAL`...) is ``value``."""
    return next(k for k, v in table.items() if v == value)


@dataclass(frozen=True)
class Interaction:
    """The law of one kind of contact (grain-grain or grain-wall): its sub-models.

    Attributes:
        normal: :class:`Hertz` or :class:`Linear`.
        damping: The normal dashpot from eps_n (:class:`Damping`).
        tangential: :class:`Coulomb`, :class:`Liggghts` or :class:`Impact`.
        friction: Coulomb friction mu.
        rolling_friction: Rolling resistance mu_r (LIGGGHTS ``cdt``; 0: off).
        restitution_tangential: eps_t, the case's (nan when decoded from a kernel array that
            does not hold it).
        limit_force: True keeps F_n >= 0 (LIGGGHTS ``limitForce``).
        wall_lever_arm: A key of :data:`dem.kernels.contact.WALL_LEVER_ARMS`.
        slip_lever_arm: A key of :data:`dem.kernels.contact.SLIP_LEVER_ARMS`.

    """

    normal: Hertz | Linear
    damping: Damping
    tangential: Coulomb | Liggghts | Impact
    friction: float
    rolling_friction: float
    restitution_tangential: float
    limit_force: bool = False
    wall_lever_arm: str = "surface"
    slip_lever_arm: str = "contact"

    @classmethod
    def from_case(cls, case, material) -> Interaction:
        """The law of ``case``'s ``[contact]`` with ``material`` (the grains', or the wall's).

        Raises:
            ValueError: "coulomb" cannot reach the material's eps_t (:mod:`dem.physics.tangential`).

        """
        c = case.contact
        return cls(
            normal=normal_from_case(c),
            damping=Damping(material.restitution_normal),
            tangential=tangential_from_case(c, material, case.particles),
            friction=material.friction,
            rolling_friction=material.rolling_friction,
            restitution_tangential=material.restitution_tangential,
            limit_force=c.limit_force,
            wall_lever_arm=c.wall_lever_arm,
            slip_lever_arm=c.slip_lever_arm,
        )

    @classmethod
    def from_row(cls, model: str, p: np.ndarray) -> Interaction:
        """The sub-models a kernel row ``p`` holds (the inverse of :meth:`pack`, up to rounding).

        Hertz's nu follows from q = Y* / G* = 2 (2 - nu) / (1 - nu): nu = (4 - q) / (2 - q);
        linear's nu is not in the row (nan), and eps_t only in an "impact" row (else nan).
        """
        normal: Hertz | Linear
        tangential: Coulomb | Liggghts | Impact
        if model == Hertz.name:
            y_star, g_star = float(p[contact.P_YSTAR]), float(p[contact.P_GSTAR])
            q = y_star / g_star if g_star else math.nan
            nu = (4.0 - q) / (2.0 - q)
            normal = Hertz(contact.youngs_modulus_from_star(y_star, nu) if g_star else 0.0, nu)
        else:
            normal = Linear(float(p[contact.P_KN]), math.nan)
        beta = float(p[contact.P_BETA])
        name = _key(contact.TANGENTIAL, p[contact.P_TANGENTIAL])
        eps_t = math.nan
        if name == Impact.name:
            tangential = Impact(float(p[contact.P_MASS_T]), float(p[contact.P_MASS_N]))
            eps_t = 1.0 - p[contact.P_IMPACT_RATIO] * (1.0 + p[contact.P_NORMAL_E])
        elif name == Liggghts.name:
            tangential = Liggghts(float(p[contact.P_KT_RATIO]))
        else:
            tangential = Coulomb(
                float(p[contact.P_KT_RATIO]), float(p[contact.P_ZETA_T]), float(p[contact.P_MASS_T])
            )
        return cls(
            normal=normal,
            damping=Damping(restitution_for_beta(beta), beta_override=beta),
            tangential=tangential,
            friction=float(p[contact.P_MU]),
            rolling_friction=float(p[contact.P_MU_ROLL]),
            restitution_tangential=float(eps_t),
            limit_force=bool(p[contact.P_LIMIT_FORCE]),
            wall_lever_arm=_key(contact.WALL_LEVER_ARMS, p[contact.P_WALL_ARM]),
            slip_lever_arm=_key(contact.SLIP_LEVER_ARMS, p[contact.P_SLIP_ARM]),
        )

    def pack(self) -> np.ndarray:
        """Its row of kernel parameters (:func:`dem.kernels.contact.make_params`)."""
        return contact.make_params(
            **self.normal.kernel_args(),
            **self.damping.kernel_args(),
            friction=self.friction,
            rolling_friction=self.rolling_friction,
            limit_force=self.limit_force,
            tangential=self.tangential.name,
            wall_lever_arm=self.wall_lever_arm,
            slip_lever_arm=self.slip_lever_arm,
            restitution_tangential=self.restitution_tangential,
            **self.tangential.kernel_args(),
        )

    @property
    def damping_ratio(self) -> float:
        """zeta_n against the tangent stiffness S_n."""
        return self.damping.ratio(self.normal.name)

    def report(self, coefficients: dict) -> dict:
        """E (or k_n), nu, eps_n, eps_t, mu, mu_r and the tangential law's ``coefficients``."""
        return {
            **self.normal.report(),
            "restitution_normal": self.damping.restitution,
            "restitution_tangential": self.restitution_tangential,
            "friction": self.friction,
            "rolling_friction": self.rolling_friction,
            "limit_force": self.limit_force,
            **coefficients,
        }


class KernelCoefficients(NamedTuple):
    """The packed coefficients of one row that a deck writes (:mod:`dem.io.lammps`).

    Attributes:
        beta: The damping parameter (-1: critical).
        normal_damping: C_dn sqrt(B_n): gamma_n = this sqrt(a m*) (:func:`law_coefficients`).
        tangential_damping: C_dt sqrt(B_t): gamma_t = this sqrt(a m*).
        tangential_stiffness: C_kt: k_t = C_kt a.
        tangential_damping_ratio: zeta_t ("coulomb").

    """

    beta: float
    normal_damping: float
    tangential_damping: float
    tangential_stiffness: float
    tangential_damping_ratio: float


def wall_params(params: np.ndarray) -> np.ndarray:
    """The grain-wall row of a law's parameters: the second row, or the only one."""
    n = contact.N_PARAMS
    return params[n : 2 * n] if params.shape[0] >= 2 * n else params


@dataclass(frozen=True)
class ContactLaw:
    """A contact law: its normal model's name and its kernel parameters, from its sub-models.

    Attributes:
        model: ``"linear"`` or ``"hertz_mindlin"`` (:data:`dem.kernels.contact.MODELS`).
        params: Kernel parameter array (:func:`dem.kernels.contact.make_params`): the
            grain-grain row, then the grain-wall row (or one row for both).
        interactions: (grain-grain, grain-wall) :class:`Interaction`; None decodes them from
            ``params`` (:meth:`Interaction.from_row`).

    """

    model: str
    params: np.ndarray
    interactions: tuple[Interaction, Interaction] | None = None

    @classmethod
    def from_case(cls, case) -> ContactLaw:
        """Law of a :class:`dem.scene.case.Case`: grain-grain, then grain-wall (``[wall]``).

        The grain-grain law takes the material, the grain-wall law the material with
        ``[wall]``'s friction and restitutions (:attr:`dem.scene.case.Case.wall_material`); the
        pair kernels read the first row, the wall kernels the second (:func:`wall_params`). With
        ``"coulomb"`` an omitted ``tangential_stiffness_ratio`` is derived from each row's own
        eps_t, one cached root search per distinct eps_t (:func:`.tangential.spring_ratio`).

        Raises:
            ValueError: "coulomb" cannot reach an eps_t.

        """
        pair = Interaction.from_case(case, case.material)
        wall = pair if case.wall is None else Interaction.from_case(case, case.wall_material)
        params = np.concatenate([pair.pack(), wall.pack()])
        return cls(model=case.contact.model, params=params, interactions=(pair, wall))

    @property
    def grain_grain(self) -> Interaction:
        """The grain-grain :class:`Interaction`."""
        if self.interactions is not None:
            return self.interactions[0]
        return Interaction.from_row(self.model, self.params[: contact.N_PARAMS])

    @property
    def grain_wall(self) -> Interaction:
        """The grain-wall :class:`Interaction`."""
        if self.interactions is not None:
            return self.interactions[1]
        return Interaction.from_row(self.model, self.wall_params)

    @property
    def normal(self) -> Hertz | Linear:
        """The grain-grain normal sub-model (both rows share E or k_n and nu)."""
        return self.grain_grain.normal

    @property
    def wall_params(self) -> np.ndarray:
        """The grain-wall row of ``params`` (:func:`wall_params`)."""
        return wall_params(self.params)

    @property
    def tangential(self) -> str:
        """Tangential law, a key of :data:`dem.physics.laws.TANGENTIAL_LAWS`."""
        return _key(contact.TANGENTIAL, self.params[contact.P_TANGENTIAL])

    @property
    def critically_damped(self) -> bool:
        """True when the grain-grain dashpot is critical or beyond (eps_n = 0: beta = -1)."""
        return not self.params[contact.P_BETA] > -1.0 + 1e-12

    @property
    def rolling_friction(self) -> float:
        """The grain-grain rolling resistance mu_r (0: off)."""
        return float(self.params[contact.P_MU_ROLL])

    @property
    def history_width(self) -> int:
        """Floats of contact history per contact (:func:`dem.physics.laws.history_width`)."""
        return contact.HISTORY_WIDTH[self.tangential]

    @property
    def model_id(self) -> int:
        """Integer id used by the kernels."""
        return contact.MODELS[self.model]

    def kernel_coefficients(self, wall: bool = False) -> KernelCoefficients:
        """The grain-grain (or grain-wall) row's packed coefficients, by name."""
        p = self.wall_params if wall else self.params
        return KernelCoefficients(
            beta=float(p[contact.P_BETA]),
            normal_damping=float(p[contact.P_DAMP_N] * math.sqrt(p[contact.P_DAMP_N_SCALE])),
            tangential_damping=float(p[contact.P_DAMP_T] * math.sqrt(p[contact.P_DAMP_T_SCALE])),
            tangential_stiffness=float(p[contact.P_KT_COEF]),
            tangential_damping_ratio=float(p[contact.P_ZETA_T]),
        )

    def stiffer(self, ratio: float) -> tuple[str, float]:
        """The case key and value that make impact overlaps 1 / ``ratio`` of this law's."""
        normal = self.normal.stiffer(ratio)
        return normal.key, float(normal.stiffness_value)

    def tangential_coefficients(self, wall: bool = False) -> dict:
        """The tangential coefficients in use: convention, kappa, zeta_t and f_t ("coulomb")."""
        p = self.wall_params if wall else self.params
        name = self.tangential
        out: dict[str, str | float | bool] = {"tangential": name}
        if name == "coulomb" or (self.model == "linear" and name != "impact"):
            out["tangential_stiffness_ratio"] = float(p[contact.P_KT_RATIO])
        if name == "coulomb":
            out["tangential_damping_ratio"] = float(p[contact.P_ZETA_T])
            out["tangential_mass_factor"] = float(p[contact.P_MASS_T])
        if name == "impact":
            out["tangential_mass_factor"] = float(p[contact.P_MASS_T])
            out["stick_rate"] = float(p[contact.P_STICK_RATE])
            out["stick_damping_ratio"] = float(p[contact.P_STICK_ZETA])
            out["normal_law_restitution"] = float(p[contact.P_NORMAL_E])
            out["plastic"] = bool(p[contact.P_PLASTIC])
            if out["plastic"]:
                out["normal_stick_rate"] = float(p[contact.P_NORMAL_STICK_RATE])
        out["wall_lever_arm"] = _key(contact.WALL_LEVER_ARMS, p[contact.P_WALL_ARM])
        out["slip_lever_arm"] = _key(contact.SLIP_LEVER_ARMS, p[contact.P_SLIP_ARM])
        return out

    def report(self) -> dict:
        """The law for summary.json: per interaction E (or k_n), nu, eps_n, eps_t, mu, mu_r, ...

        ``{"grain_grain": {...}, "grain_wall": {...}}``, each with the normal model and its
        coefficients, the restitutions, friction, rolling friction and the tangential law's
        coefficients (:meth:`tangential_coefficients`).
        """
        return {
            "grain_grain": self.grain_grain.report(self.tangential_coefficients()),
            "grain_wall": self.grain_wall.report(self.tangential_coefficients(wall=True)),
        }

    def contact_times(
        self, m_eff: float, r_eff: float, impact_speed: float, rotation_factor: float, wall: bool
    ) -> tuple[float, float]:
        """(collision time, critical step) of one contact of the law, s.

        The collision time: linear pi / omega_d, Hertz the elastic time at ``impact_speed``.
        The critical step: velocity Verlet's limit for the stiffest oscillator of the contact,
        normal (tangent stiffness S_n at the impact's overlap, damping ratio zeta_n) and
        tangential (the tangential law's spring times ``rotation_factor``, 7/2 for a rolling
        sphere; :data:`dem.physics.laws.TANGENTIAL_LAWS` ``step_spring``).
        """
        from dem.physics.laws import TANGENTIAL_LAWS

        p = self.wall_params if wall else self.params
        normal = self.normal
        beta = p[contact.P_BETA]
        zeta = contact.damping_ratio(self.model, beta)
        if self.model == "linear":
            delta, t_c = 0.0, contact.linear_collision_time(p[contact.P_KN], m_eff, beta)
        else:
            y_star = p[contact.P_YSTAR]
            delta = contact.hertz_max_overlap(y_star, r_eff, m_eff, impact_speed)
            t_c = contact.hertz_collision_time(y_star, r_eff, m_eff, impact_speed)
        kn, root = contact.tangent_stiffness(normal.name, p, r_eff, delta)
        step_spring = TANGENTIAL_LAWS[self.tangential].step_spring
        kt_eff, zeta_t = step_spring(p, self.model, kn, root, zeta, rotation_factor)
        limit = contact.critical_timestep(kn, m_eff, zeta)
        if kt_eff > 0:
            limit = min(limit, contact.critical_timestep(kt_eff, m_eff, zeta_t))
        return t_c, limit

    def automatic_step(self, collision_time: float, radius: float, density: float) -> float:
        """The automatic step from the shortest collision time of the law's contacts, s.

        Linear: ``DEM_DT_COLLISION_FRACTION`` of it. Hertz: the smaller of
        ``DEM_DT_HERTZ_FRACTION`` of it and ``DEM_DT_RAYLEIGH_FRACTION`` of the Rayleigh time of a
        grain of ``radius`` m and ``density`` kg/m^3.
        """
        if self.model == "linear":
            return collision_time * config.DEM_DT_COLLISION_FRACTION
        rayleigh = self.normal.rayleigh_time(radius, density)
        return min(
            collision_time * config.DEM_DT_HERTZ_FRACTION,
            config.DEM_DT_RAYLEIGH_FRACTION * rayleigh,
        )
