"""The rolling sphere: the point mass's reference for a round grain that is free to roll.

A grain that can roll is not the point mass: a sphere on the driven trough rolls where the point
mass sticks, and its rolling carries it along (Gamma 0.8, phi 25 deg, mu 0.35: v_norm 0.823 for a
solid sphere, 0.341 for the Coulomb-bounded point mass). This is the rigid sphere of radius r,
mass m and moment of inertia I = k m r^2 (k = 2/5 a solid sphere, 2/3 a thin shell, any k > 0
for another round grain rolling on a radius r) on the paper's trough, in the trough's
accelerating frame, with the point mass's drive conventions (:mod:`dem.pointmass.model`): the
trough moves by s(t) = A sin(omega t) (cos phi, 0, sin phi), x along the trough (conveying
direction, uphill for an incline alpha > 0), z normal to the floor, y = z x x across, and
Gamma = A omega^2 sin(phi) / (g cos(alpha)).

**Unknowns and signs.** v (m/s): the centre's velocity along x relative to the trough;
omega_y (rad/s): the spin about +y, positive when the top of the sphere moves towards +x. The
contact point (at -r z from the centre) slips over the floor at

    sigma = v - r omega_y                                                          (m/s)

(sigma = 0: rolling; sigma > 0: the contact point slides forward). A friction force F along x on
the contact point gives

    m dv/dt = m a(t) + F,   I d(omega_y)/dt = -r F,   a(t) = A omega^2 cos(phi) sin(omega t)
                                                              - g sin(alpha)     (m/s^2)

and on the floor the normal force is N = m (g cos(alpha) - A omega^2 sin(phi) sin(omega t)).

**Phases.** *Rolling*: sigma = 0 needs F = -m_t a with m_t = 1 / (1/m + r^2/I) = m k / (1 + k),
the contact point's reduced tangential mass; it holds while |F| <= mu N, and the centre then
moves with dv/dt = a / (1 + k) (5/7 a for a solid sphere). *Slipping*: F = -mu N sgn(sigma)
(kinetic friction opposing the slip). *Flight* (N would be negative, Gamma > 1): F = 0, the
spin is carried unchanged and the centre moves ballistically in the accelerating frame.
*Landing*: a normal impulse J_n = (1 + eps_n) m |v_n| (eps_n = 0: the sphere stays on the floor)
and a tangential impulse J on the contact point, by one of two landing laws (:data:`LANDINGS`):

- ``"centre"`` (the default): the paper's eps_t, the ratio of the centre's tangential velocity
  after a landing to before it (the README's definition, which the DEM's impact-aware contact
  law delivers): J = -m (1 - eps_t) sigma, but never past rolling, |J| <= m_t |sigma| (so a
  sphere landing without spin keeps at least 1 / (1 + k) of its centre's velocity, 5/7 for a
  solid one);
- ``"contact"``: eps_t on the contact point's slip, sigma -> eps_t sigma: J = -m_t (1 - eps_t)
  sigma (Walton's tangential restitution).

Under ``impact="coulomb"`` (the default; :data:`dem.pointmass.model.IMPACT_LAWS`) |J| <= mu J_n,
as in the Coulomb-bounded point mass, the DEM's reference; ``"paper"`` leaves J uncapped. A
landing with eps_n > 0 starts a Zeno sequence of ever smaller bounces, handled as the point mass
handles it (the cap then applies to their summed normal impulse).

**Two exact consequences.** (1) J and F act at the contact, so they change v by J/m and r omega_y
by -J / (k m): the combination

    L = v + k r omega_y,   dL/dt = a(t)                  (units of velocity; m r L is the
                                                          angular momentum about the contact line)

does not feel friction or impacts at all. In the laboratory, L_lab = L + s'_x(t) is constant on
a level trough: P = L_lab / (A omega cos phi) is set when the grain starts (P = 1 for a grain at
rest on the trough when a line drive switches on at phase 0, as the point mass starts; P = 0 for
one at rest when a ramped drive starts) and never changes. On an incline L loses g sin(alpha) per
second, so a free round grain has no steady state there: on average it rolls downhill at
g sin(alpha) / (1 + k) (5/7 g sin(alpha)), whatever the drive. (2) The slip obeys

    d(sigma)/dt = a(t) + F / m_t,

the point mass's equation with friction mu' = mu (1 + 1/k) (3.5 mu for a solid sphere): rolling
is the point mass's stick, slipping its sliding, flight its flight, and each landing law above is
the point mass's landing with eps_t' (``"contact"``: eps_t' = eps_t; ``"centre"``:
eps_t' = max(0, 1 - (1 - eps_t)(1 + 1/k))) and the Coulomb cap mu' (1 + eps_n) |v_n|. So the
event-driven kernel of :mod:`dem.pointmass.model` integrates sigma exactly (phase changes to about
1e-15 rad), and with v = (L + k sigma) / (1 + k) the mean conveying velocity on a level trough is

    v_norm = (P + k <sigma>_norm) / (1 + k),     velocities over A omega cos(phi),

with <sigma>_norm the point mass's v_norm at mu', eps_t' (periodic orbit detected on the Poincare
section at phase 0; motion that never repeats is reported ``non-periodic``, with the mean and
spread over starting phases, as the point mass reports it). k -> infinity (the spin locked,
``inertia_factor=math.inf``) is the point mass: mu' = mu, eps_t' = eps_t and v = sigma. k -> 0
(no rotational inertia) is a frictionless grain, v_norm = P: I -> 0 does not give the point mass.

Checked against a brute-force time-stepped twin of the sphere's own equations (tests/oracles) and
against the DEM's free sphere (validation/rolling-sphere).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from dem.errors import InputError
from dem.pointmass import model
from dem.pointmass.validate import (
    check_angle,
    check_inclination,
    check_restitution,
    check_throw_number,
    check_transport_friction,
    checked_arrays,
    drive_inputs,
)
from dem.quantities import QUANTITIES

#: k = I / (m r^2) of a solid sphere (uniform density).
SOLID_SPHERE = 0.4
#: k of a thin spherical shell.
THIN_SHELL = 2.0 / 3.0
#: Landing laws of the rolling sphere (module docstring): ``"centre"``, eps_t of the centre's
#: tangential velocity, never past rolling (the paper's eps_t, the DEM's impact-aware law);
#: ``"contact"``, eps_t of the contact point's slip velocity.
LANDINGS = ("centre", "contact")
#: The slip's friction mu (1 + 1/k) is capped here: from 1e9 the point mass treats a contact as
#: ideal adhesion (:data:`dem.quantities.QUANTITIES` ``friction``), so nothing changes.
SLIP_FRICTION_MAX = 1.0e12
#: Regimes in the words of a rolling grain, indexed like :data:`dem.pointmass.model.REGIMES`
#: (the slip's regime: the point mass's stick is rolling, its sliding is slipping), then
#: :data:`DOWNHILL`.
REGIMES = (
    "rolling",
    "slipping forward",
    "slipping backward",
    "slipping both ways",
    "hopping",
    "hopping with backward slip",
    "non-periodic",
)
#: The regime of a free round grain on an inclined trough: no steady state.
DOWNHILL = "rolling downhill (no steady state)"


@dataclass(frozen=True)
class RollingResult:
    """Steady motion of the rolling sphere for one set of parameters.

    Attributes:
        velocity_norm: mean conveying velocity of the centre / (A omega cos phi); NaN where
            there is none (an inclined trough and a finite k: the grain rolls downhill).
        slip_norm: mean slip velocity of the contact point, sigma / (A omega cos phi).
        regime: one of :data:`REGIMES` or :data:`DOWNHILL`.
        periodic: whether the motion settled into a periodic orbit.
        period: the orbit's length in drive cycles (0 when non-periodic).
        spread: standard deviation of velocity_norm over starting phases (0 when periodic).
        velocity_min, velocity_max: range over starting phases (equal when periodic).
        rolling, slip_forward, slip_backward, flight: fractions of the cycle in each phase.
        cycles: drive cycles integrated until the orbit closed (or the limit).
        drift_per_cycle: change of the mean velocity_norm per drive cycle: 0 on a level trough,
            -2 pi tan(phi) tan(alpha) / (Gamma (1 + k)) on an incline (g sin(alpha) / (1 + k)
            downhill).
        inertia_factor: k = I / (m r^2) (inf: the spin locked, the point mass).
        momentum: P, the angular momentum about the contact line in the laboratory over
            m r A omega cos(phi) (module docstring).
        landing: one of :data:`LANDINGS`.
        impact: ``"coulomb"`` (landings capped by friction) or ``"paper"``.

    """

    throw_number: float
    angle: float
    friction: float
    inclination: float
    eps_t: float
    eps_n: float
    inertia_factor: float
    momentum: float
    landing: str
    impact: str
    velocity_norm: float
    slip_norm: float
    regime: str
    periodic: bool
    period: int
    spread: float
    velocity_min: float
    velocity_max: float
    rolling: float
    slip_forward: float
    slip_backward: float
    flight: float
    cycles: int
    drift_per_cycle: float

    def velocity_scale(self, frequency: float) -> float:
        """A omega cos(phi) in m/s at ``frequency`` (Hz), the amplitude following from Gamma."""
        return model.velocity_scale(self.throw_number, frequency, self.angle, self.inclination)

    def velocity(self, frequency: float) -> float:
        """Mean conveying velocity in m/s at ``frequency`` (Hz); NaN where there is none."""
        return self.velocity_norm * self.velocity_scale(frequency)

    def as_dict(self) -> dict:
        """Plain dictionary (for JSON: an infinite k is the string "inf", NaN is None)."""
        out = asdict(self)
        for key, value in out.items():
            if isinstance(value, float) and math.isnan(value):
                out[key] = None
        if math.isinf(self.inertia_factor):
            out["inertia_factor"] = "inf"
        return out


def check_inertia_factor(value, key: str = "inertia_factor") -> float:
    """The factor k = I / (m r^2) in (0, 1e6], or inf (the spin locked); else InputError."""
    if isinstance(value, int | float) and not isinstance(value, bool) and value == math.inf:
        return math.inf
    return QUANTITIES["inertia_factor"].check(value, key)


def check_landing(value: str, key: str = "landing") -> str:
    """``value`` if it names a landing law (:data:`LANDINGS`); InputError naming ``key``."""
    if value not in LANDINGS:
        raise InputError(key, value, "one of " + ", ".join(repr(v) for v in LANDINGS))
    return value


def check_momentum(value, key: str = "momentum") -> float:
    """A finite number (P of the module docstring); InputError naming ``key`` otherwise."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(key, value, "a finite number (1: at rest as the drive starts)") from None
    if isinstance(value, bool) or not math.isfinite(number):
        raise InputError(key, value, "a finite number (1: at rest as the drive starts)")
    return number


def slip_friction(friction, inertia_factor):
    """The slip's friction coefficient mu' = mu (1 + 1/k), capped at SLIP_FRICTION_MAX.

    Rolling needs |F| = m_t |a| <= mu N, i.e. |a| <= mu' N / m, and slipping decelerates the
    slip at mu N / m_t = mu' N / m: the point mass's friction is mu' (broadcasts).
    """
    k = np.asarray(inertia_factor, dtype=float)
    out = np.minimum(np.asarray(friction, dtype=float) * (1.0 + 1.0 / k), SLIP_FRICTION_MAX)
    return float(out) if out.ndim == 0 else out


def slip_restitution(eps_t, inertia_factor, landing: str):
    """The slip's tangential restitution eps_t' of a landing law (broadcasts).

    ``"contact"``: eps_t. ``"centre"``: the centre keeps eps_t of its velocity change by the
    slip, J = -m (1 - eps_t) sigma, which moves the slip by J / m_t = (1 + 1/k) J / m, stopped
    at rolling: eps_t' = max(0, 1 - (1 - eps_t)(1 + 1/k)).
    """
    check_landing(landing)
    e, k = np.broadcast_arrays(np.asarray(eps_t, dtype=float), np.asarray(inertia_factor, float))
    out = e.copy() if landing == "contact" else np.maximum(0.0, 1.0 - (1.0 - e) * (1.0 + 1.0 / k))
    return float(out) if out.ndim == 0 else out


def velocities(
    throw_number,
    angle,
    friction,
    inclination=0.0,
    eps_t=0.8,
    eps_n=0.0,
    inertia_factor=SOLID_SPHERE,
    momentum=1.0,
    landing: str = "centre",
    impact: str = "coulomb",
) -> dict[str, np.ndarray]:
    """Vectorised :func:`velocity`: the numeric inputs broadcast together; a dict of flat arrays.

    Keys: the eight numeric inputs, ``velocity_norm``, ``slip_norm``, ``periodic``, ``period``,
    ``spread``, ``velocity_min``, ``velocity_max``, ``regime_code`` (index into :data:`REGIMES`;
    ``len(REGIMES)`` for :data:`DOWNHILL`), ``rolling``, ``slip_forward``, ``slip_backward``,
    ``flight``, ``cycles`` and ``drift_per_cycle``.
    """
    check_landing(landing)
    model.check_impact(impact)
    g, phi, mu, alpha, et, en, k, p = checked_arrays({
        **drive_inputs(throw_number, angle, friction, inclination, eps_t, eps_n),
        "inertia_factor": (inertia_factor, check_inertia_factor),
        "momentum": (momentum, check_momentum),
    })  # fmt: skip
    # the slip is the point mass at mu' and eps_t' (module docstring)
    slip = model.velocities(
        g, phi, slip_friction(mu, k), alpha, slip_restitution(et, k, landing), en, impact
    )
    share = 1.0 / (1.0 + 1.0 / k)  # k / (1 + k): the slip's share of v; 1 for a locked spin
    velocity = (1.0 - share) * p + share * slip["velocity_norm"]
    c = np.tan(np.radians(phi)) * np.tan(np.radians(alpha)) / g
    drift = -2.0 * math.pi * c * (1.0 - share) + 0.0  # + 0.0: no -0.0 on a level trough
    downhill = drift != 0.0
    codes = slip["regime_code"].copy()
    codes[downhill] = len(REGIMES)
    return {
        "throw_number": g,
        "angle": phi,
        "friction": mu,
        "inclination": alpha,
        "eps_t": et,
        "eps_n": en,
        "inertia_factor": k,
        "momentum": p,
        "velocity_norm": np.where(downhill, np.nan, velocity),
        "slip_norm": slip["velocity_norm"],
        "periodic": slip["periodic"] & ~downhill,
        "period": np.where(downhill, 0, slip["period"]),
        "spread": share * slip["spread"],
        "velocity_min": np.where(
            downhill, np.nan, (1.0 - share) * p + share * slip["velocity_min"]
        ),
        "velocity_max": np.where(
            downhill, np.nan, (1.0 - share) * p + share * slip["velocity_max"]
        ),
        "regime_code": codes,
        "rolling": slip["stick"],
        "slip_forward": slip["slide_forward"],
        "slip_backward": slip["slide_backward"],
        "flight": slip["flight"],
        "cycles": slip["cycles"],
        "drift_per_cycle": drift,
    }


def velocity(
    throw_number: float,
    angle: float,
    friction: float,
    inclination: float = 0.0,
    eps_t: float = 0.8,
    eps_n: float = 0.0,
    inertia_factor: float = SOLID_SPHERE,
    momentum: float = 1.0,
    landing: str = "centre",
    impact: str = "coulomb",
) -> RollingResult:
    """Mean conveying velocity of a rolling sphere (module docstring), normalised.

    Args:
        throw_number: Gamma = A omega^2 sin(phi) / (g cos(alpha)), > 0.
        angle: vibration angle phi in degrees, in (0, 90).
        friction: Coulomb coefficient mu >= 0 between grain and floor (static = kinetic).
        inclination: trough inclination alpha in degrees (> 0: conveying uphill). Any alpha != 0
            with a finite k has no steady state (the grain rolls downhill): velocity_norm NaN.
        eps_t: tangential restitution of a landing, read by ``landing``.
        eps_n: normal restitution of a landing.
        inertia_factor: k = I / (m r^2): 0.4 a solid sphere (:data:`SOLID_SPHERE`), 2/3 a thin
            shell (:data:`THIN_SHELL`); ``math.inf`` locks the spin (the point mass).
        momentum: P, the grain's angular momentum about its contact line in the laboratory over
            m r A omega cos(phi); 1 (a grain at rest on the trough as a line drive switches on
            at phase 0, as the point mass starts); 0 for one at rest as a ramped drive starts.
        landing: ``"centre"`` or ``"contact"`` (:data:`LANDINGS`).
        impact: ``"coulomb"`` (each landing's tangential impulse at most mu times its normal
            impulse: the DEM's reference) or ``"paper"`` (uncapped).

    Example: ``velocity(0.8, 25, 0.35).velocity_norm`` is 0.823 (the point mass: 0.341).

    """
    check_throw_number(throw_number)
    check_angle(angle)
    check_transport_friction(friction)
    check_inclination(inclination)
    check_restitution(eps_t, "eps_t")
    check_restitution(eps_n, "eps_n")
    k = check_inertia_factor(inertia_factor)
    p = check_momentum(momentum)
    r = velocities(throw_number, angle, friction, inclination, eps_t, eps_n, k, p, landing, impact)
    code = int(r["regime_code"][0])
    return RollingResult(
        throw_number=float(throw_number),
        angle=float(angle),
        friction=float(friction),
        inclination=float(inclination),
        eps_t=float(eps_t),
        eps_n=float(eps_n),
        inertia_factor=k,
        momentum=p,
        landing=landing,
        impact=impact,
        velocity_norm=float(r["velocity_norm"][0]),
        slip_norm=float(r["slip_norm"][0]),
        regime=DOWNHILL if code == len(REGIMES) else REGIMES[code],
        periodic=bool(r["periodic"][0]),
        period=int(r["period"][0]),
        spread=float(r["spread"][0]),
        velocity_min=float(r["velocity_min"][0]),
        velocity_max=float(r["velocity_max"][0]),
        rolling=float(r["rolling"][0]),
        slip_forward=float(r["slip_forward"][0]),
        slip_backward=float(r["slip_backward"][0]),
        flight=float(r["flight"][0]),
        cycles=int(r["cycles"][0]),
        drift_per_cycle=float(r["drift_per_cycle"][0]),
    )
