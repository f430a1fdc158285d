"""The contact-law registry: one row per sub-model, and a case's law resolved once.

A contact law is a normal law (``[contact] model``) with a tangential law (``[contact]
tangential``), a damping law that follows from eps_n, and rolling resistance (``[material]
rolling_friction``), as LAMMPS's ``pair granular`` composes its sub-models. Each row of
:data:`NORMAL_LAWS` and :data:`TANGENTIAL_LAWS` says everything the rest of dem asks of a law:

- the case keys it reads (the keys of another law are refused at load, :mod:`dem.scene.case`);
- its sub-model, which builds its coefficients (:mod:`dem.physics.contact`);
- the floats of contact history it needs (the contact's width is the sum over its sub-models);
- the stiffness the time step must resolve (:func:`dem.scene.timestep.timestep_limits`);
- its LIGGGHTS mapping: the deck's law, or the nearest one with the note the deck carries;
- whether ``dem calibrate`` applies, and what it fits.

The kernels' side of the same sub-models (scalar functions) is :mod:`dem.kernels.contact`.
A new tangential law is a function there and one row here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from dem.kernels import contact

#: Default k_t / k_n of the linear model under ``tangential = "liggghts"``: 2/7 makes the
#: tangential and normal oscillations of a solid sphere equally fast (Shaefer et al. 1996).
DEFAULT_TANGENTIAL_STIFFNESS_RATIO = 2.0 / 7.0


@dataclass(frozen=True)
class NormalLaw:
    """One normal law (with its damping sub-model, which follows from eps_n).

    Attributes:
        name: The ``[contact] model`` value.
        keys: ``[contact]`` keys it reads.
        history_width: Floats of contact history it needs (0: none).
        liggghts: The LIGGGHTS ``pair_style gran`` model it maps to.

    """

    name: str
    keys: tuple[str, ...]
    history_width: int
    liggghts: str


@dataclass(frozen=True)
class TangentialLaw:
    """One tangential law.

    Attributes:
        name: The ``[contact] tangential`` value.
        keys: ``[contact]`` keys it reads, by normal law.
        history_width: Floats of contact history it needs.
        step_spring: The tangential spring the time step must resolve: (params, normal law,
            tangent normal stiffness S_n, size factor a, normal damping ratio zeta_n, rotation
            factor) -> (effective k_t, N/m, its damping ratio); k_t = 0 when it has none.
        liggghts_as: The tangential law of the exported LIGGGHTS deck (itself when exact).
        liggghts_note: The note the deck carries when ``liggghts_as`` is another law.
        calibrates: ``[contact]`` keys ``dem calibrate`` fits (empty: nothing to fit).
        calibration: Why it fits nothing, or why calibration is refused (empty when it fits).
        calibration_refused: True: ``dem calibrate`` refuses the law (InputError).
        liggghts_keeps: True: a LIGGGHTS deck keeps the law's own tangential coefficients
            (k_t / k_n, zeta_t) under ``liggghts_as``; False: the case switches to that law.
        lammps_refusal: Why a LAMMPS deck cannot express it (empty: LAMMPS's ``mindlin`` or
            ``linear_history`` is the law, term for term).
        defaults: ``[contact]`` values it takes when the case omits them, by normal law.

    """

    name: str
    keys: dict[str, tuple[str, ...]]
    history_width: int
    step_spring: Callable[..., tuple[float, float]]
    liggghts_as: str
    liggghts_note: str = ""
    calibrates: tuple[str, ...] = ()
    calibration: str = ""
    calibration_refused: bool = False
    liggghts_keeps: bool = False
    lammps_refusal: str = ""
    defaults: dict[str, dict[str, float]] = field(default_factory=dict)


NORMAL_LAWS = {
    "hertz_mindlin": NormalLaw(
        "hertz_mindlin", ("youngs_modulus", "poisson_ratio"), 0, "model hertz tangential history"
    ),
    "linear": NormalLaw(
        "linear", ("stiffness", "poisson_ratio"), 0, "model hooke/stiffness tangential history"
    ),
}


def _spring_step(p, model, s_n, a, zeta_n, rotation_factor) -> tuple[float, float]:
    """k_t = kappa S_n (kappa k_n linear) times the rotation factor, damping ratio zeta_t."""
    kt = p[contact.P_KT_RATIO] * s_n
    return rotation_factor * kt, float(p[contact.P_ZETA_T])


def _liggghts_step(p, model, s_n, a, zeta_n, rotation_factor) -> tuple[float, float]:
    """Linear kappa k_n; Hertz Mindlin's S_t = 8 G* a; and the tangential damping ratio.

    The tangential oscillator has stiffness k_t and mass m* / f (f: the rotation factor, 7/2
    for a rolling sphere), so its damping ratio is gamma_t sqrt(f) / (2 sqrt(k_t m*)). Hertz:
    gamma_t = -2 sqrt(5/6) beta sqrt(S_t m*), so zeta_t = zeta_n sqrt(f); linear:
    gamma_t = gamma_n = 2 zeta_n sqrt(k_n m*), so zeta_t = zeta_n sqrt(f k_n / k_t). With
    eps_n = 0 and rotation that is 3.5 zeta_n (linear, kappa = 2/7): an overdamped dashpot whose
    explicit step is stable only below 0.28 / omega_t, where an undamped one allows 2 / omega_t.
    """
    if model == "linear":
        kt = p[contact.P_KT_RATIO] * s_n
    else:
        kt = 8.0 * p[contact.P_GSTAR] * a
    if kt <= 0:
        return 0.0, 0.0
    ratio = rotation_factor * (s_n / kt if model == "linear" else 1.0)
    return rotation_factor * kt, zeta_n * math.sqrt(ratio)


def _impact_step(p, model, s_n, a, zeta_n, rotation_factor) -> tuple[float, float]:
    """None: the stick spring is sized by the step itself (alpha = stick_rate rad a step)."""
    return 0.0, 0.0


_SPRING_KEYS = ("tangential_stiffness_ratio", "tangential_damping_ratio")

TANGENTIAL_LAWS = {
    "impact": TangentialLaw(
        "impact",
        keys={"hertz_mindlin": (), "linear": ()},
        history_width=contact.HISTORY_WIDTH["impact"],
        step_spring=_impact_step,
        liggghts_as="liggghts",
        liggghts_note=(
            "the case's impact-aware tangential law ([contact] tangential = 'impact': "
            "eps_t per impact, then a rigid stick; with eps_n = 0 a perfectly plastic normal "
            "contact that never pulls) has no LIGGGHTS equivalent; this deck uses LIGGGHTS's "
            "history law, as dem's tangential = 'liggghts'"
        ),
        lammps_refusal=(
            "the impact-aware law (eps_t per impact, then a rigid stick) has no LAMMPS equivalent"
        ),
        calibration=(
            "contact.tangential = 'impact' delivers eps_t by construction (each impact "
            "takes the impulse eps_t asks for, capped by Coulomb); it has no spring to fit"
        ),
    ),
    "coulomb": TangentialLaw(
        "coulomb",
        keys={"hertz_mindlin": _SPRING_KEYS, "linear": _SPRING_KEYS},
        history_width=contact.HISTORY_WIDTH["coulomb"],
        step_spring=_spring_step,
        liggghts_as="liggghts",
        liggghts_note=(
            "the case caps the total tangential force at mu F_n ([contact] tangential = "
            "'coulomb'); LIGGGHTS caps the spring alone and adds the dashpot while sticking, as "
            "dem's tangential = 'liggghts'"
        ),
        calibrates=("tangential_stiffness_ratio",),
        liggghts_keeps=True,
    ),
    "liggghts": TangentialLaw(
        "liggghts",
        keys={"hertz_mindlin": (), "linear": ("tangential_stiffness_ratio",)},
        history_width=contact.HISTORY_WIDTH["liggghts"],
        step_spring=_liggghts_step,
        liggghts_as="liggghts",
        calibration=(
            "a tangential law for deck equivalence: its tangential spring is LIGGGHTS's (Hertz: "
            "Mindlin's k_t; linear: the given k_t / k_n); calibrate under 'coulomb'"
        ),
        calibration_refused=True,
        lammps_refusal=(
            "LIGGGHTS's law caps the spring alone and adds the dashpot only while sticking; "
            "LAMMPS's mindlin and linear_history cap spring and dashpot together"
        ),
        defaults={"linear": {"tangential_stiffness_ratio": DEFAULT_TANGENTIAL_STIFFNESS_RATIO}},
    ),
}

#: Every tangential key some law reads (the others of the case's law are refused).
TANGENTIAL_KEYS = ("tangential_stiffness_ratio", "tangential_damping_ratio")
#: Every normal-law key some law reads.
NORMAL_KEYS = ("youngs_modulus", "stiffness", "poisson_ratio")


def foreign_keys(model: str, tangential: str) -> tuple[str, ...]:
    """``[contact]`` keys of other laws, which a case with this law must not set."""
    own = set(NORMAL_LAWS[model].keys) | set(TANGENTIAL_LAWS[tangential].keys[model])
    return tuple(k for k in (*NORMAL_KEYS, *TANGENTIAL_KEYS) if k not in own)


def history_width(tangential: str, model: str = "hertz_mindlin") -> int:
    """Floats of contact history per contact: the sum over the law's sub-models."""
    return NORMAL_LAWS[model].history_width + TANGENTIAL_LAWS[tangential].history_width


__all__ = [
    "DEFAULT_TANGENTIAL_STIFFNESS_RATIO",
    "NORMAL_KEYS",
    "NORMAL_LAWS",
    "TANGENTIAL_KEYS",
    "TANGENTIAL_LAWS",
    "NormalLaw",
    "TangentialLaw",
    "foreign_keys",
    "history_width",
]
