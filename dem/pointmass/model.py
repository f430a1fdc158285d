"""Mean conveying velocity of the point-mass model over its periodic steady state.

The public functions check their inputs, allocate, and call the event-driven kernels of
:mod:`dem.pointmass._kernel`. A grain starts at rest on the floor at drive phase 0 and is
followed until its state at phase 0 repeats (a periodic orbit of one or more cycles). Motion
that never repeats (chaotic hopping at high throw numbers, bouncing with eps_n > 0) is reported
as non-periodic: the velocity is then the mean over ``PM_SPREAD_STARTS`` starting phases, each
averaged over ``PM_AVERAGE_CYCLES`` cycles, and ``spread`` is their standard deviation.

Velocities are normalised by the drive velocity ``A omega cos(phi)`` (the paper's Fig. 6).
"""

from dataclasses import asdict, dataclass

import numpy as np

from dem import config
from dem.physics import drive
from dem.pointmass import _kernel
from dem.pointmass.validate import (
    check_angle,
    check_inclination,
    check_restitution,
    check_throw_number,
    check_transport_friction,
    checked_arrays,
    drive_inputs,
)

#: Regime labels, indexed by the integer codes returned by :func:`velocities`.
REGIMES = (
    "rest",
    "forward sliding",
    "backward sliding",
    "forward and backward sliding",
    "hopping",
    "hopping with backward sliding",
    "non-periodic",
)
NON_PERIODIC = REGIMES.index("non-periodic")
_PHASE_TIME_FLOOR = 1e-9  # fraction of a cycle below which a phase counts as absent


@dataclass(frozen=True)
class VelocityResult:
    """Steady motion of the point mass for one set of parameters.

    Attributes:
        velocity_norm: mean conveying velocity / (A omega cos phi).
        regime: one of :data:`REGIMES`.
        periodic: whether the motion settled into a periodic orbit.
        period: the orbit's length in drive cycles (0 when non-periodic).
        spread: standard deviation of velocity_norm over starting phases (0 when periodic).
        velocity_min, velocity_max: range over starting phases (equal when periodic).
        stick, slide_forward, slide_backward, flight: fractions of the cycle in each phase.
        cycles: drive cycles integrated until the orbit closed (or the limit).
        impact: the landing law, ``"paper"`` or ``"coulomb"`` (:data:`IMPACT_LAWS`).

    """

    throw_number: float
    angle: float
    friction: float
    inclination: float
    eps_t: float
    eps_n: float
    velocity_norm: float
    regime: str
    periodic: bool
    period: int
    spread: float
    velocity_min: float
    velocity_max: float
    stick: float
    slide_forward: float
    slide_backward: float
    flight: float
    cycles: int
    impact: str = "paper"

    def velocity_scale(self, frequency: float) -> float:
        """A omega cos(phi) in m/s at ``frequency`` (Hz), the amplitude following from Gamma."""
        return velocity_scale(self.throw_number, frequency, self.angle, self.inclination)

    def velocity(self, frequency: float) -> float:
        """Mean conveying velocity in m/s at ``frequency`` (Hz)."""
        return self.velocity_norm * self.velocity_scale(frequency)

    def as_dict(self) -> dict:
        """Plain dictionary (for JSON)."""
        return asdict(self)


# The drive relations in the point-mass argument order (Gamma or A, phi, alpha, f); the
# physics is dem.physics.drive's.


def amplitude_from_throw_number(throw_number, frequency, angle, inclination=0.0):
    """A = Gamma g cos(alpha) / (omega^2 sin(phi)), m (:func:`dem.physics.drive.amplitude`).

    Arguments in :mod:`dem.physics.drive`'s order: Gamma, f (Hz), phi and alpha (degrees).
    """
    return drive.amplitude(throw_number, frequency, angle, inclination)


def throw_number_from_amplitude(amplitude, frequency, angle, inclination=0.0):
    """Gamma = A omega^2 sin(phi) / (g cos(alpha)) (Eq. 3; ``drive.throw_number``)."""
    return drive.throw_number(amplitude, frequency, angle, inclination)


def velocity_scale(throw_number, frequency, angle, inclination=0.0):
    """A omega cos(phi), m/s, of a drive given by Gamma (broadcasts).

    :func:`dem.physics.drive.velocity_scale` of the amplitude that Eq. 3 gives.
    """
    a = drive.amplitude(throw_number, frequency, angle, inclination)
    return drive.velocity_scale(a, frequency, angle)


def _regime_codes(stick, forward, backward, flight, periodic):
    codes = np.zeros(stick.shape, dtype=np.int64)
    has_f = forward > _PHASE_TIME_FLOOR
    has_b = backward > _PHASE_TIME_FLOOR
    has_flight = flight > _PHASE_TIME_FLOOR
    codes[has_f & ~has_b] = REGIMES.index("forward sliding")
    codes[~has_f & has_b] = REGIMES.index("backward sliding")
    codes[has_f & has_b] = REGIMES.index("forward and backward sliding")
    codes[has_flight & ~has_b] = REGIMES.index("hopping")
    codes[has_flight & has_b] = REGIMES.index("hopping with backward sliding")
    codes[~periodic] = NON_PERIODIC
    return codes


#: Landing laws: ``"paper"`` multiplies the relative tangential velocity by eps_t at every
#: landing (Eq. 12); ``"coulomb"`` caps that change at mu (1 + eps_n) times the landing's
#: normal speed, since no friction can take more: the reference of the DEM, whose contacts obey
#: Coulomb. The two differ only at grazing landings (Gamma about 1.1-1.55 and 4.55-4.7 at
#: phi 25 deg, mu 0.35) and at low eps_t.
IMPACT_LAWS = {"paper": 0.0, "coulomb": 1.0}


def check_impact(impact: str) -> str:
    """Return ``impact`` if it names a landing law (:data:`IMPACT_LAWS`), else ValueError."""
    if impact not in IMPACT_LAWS:
        raise ValueError(f"impact must be one of {sorted(IMPACT_LAWS)}, got {impact!r}")
    return impact


def velocities(
    throw_number,
    angle,
    friction,
    inclination=0.0,
    eps_t: float | np.ndarray = 0.8,
    eps_n: float | np.ndarray = 0.0,
    impact: str = "paper",
) -> dict[str, np.ndarray]:
    """Vectorised :func:`velocity`: inputs broadcast together; returns a dict of flat arrays.

    ``impact`` is a key of :data:`IMPACT_LAWS`.

    Keys: the six inputs, ``velocity_norm``, ``periodic``, ``period``, ``spread``,
    ``velocity_min``, ``velocity_max``, ``regime_code`` (index into :data:`REGIMES`), the phase
    fractions ``stick``, ``slide_forward``, ``slide_backward``, ``flight`` and ``cycles``.
    The points run in parallel (numba prange); non-periodic points are rerun from
    ``PM_SPREAD_STARTS`` starting phases to give their mean and spread.
    """
    g, phi, mu, alpha, et, en = checked_arrays(
        drive_inputs(throw_number, angle, friction, inclination, eps_t, eps_n)
    )
    bounded = np.full(g.shape, IMPACT_LAWS[check_impact(impact)])
    params = np.column_stack(
        [g, np.tan(np.radians(phi)), np.tan(np.radians(alpha)), mu, et, en, bounded]
    ).astype(np.float64)
    n = params.shape[0]
    run = _run_batch(params, np.zeros(n))
    velocity, period, cycles, times = run
    periodic = period > 0
    spread = np.zeros(n)
    vmin = velocity.copy()
    vmax = velocity.copy()
    chaotic = np.flatnonzero(~periodic)
    if chaotic.size:
        k = config.PM_SPREAD_STARTS
        starts = np.tile(2.0 * np.pi * np.arange(k) / k, chaotic.size)
        vel_k, _, _, times_k = _run_batch(np.repeat(params[chaotic], k, axis=0), starts)
        vel_k = vel_k.reshape(chaotic.size, k)
        velocity[chaotic] = vel_k.mean(axis=1)
        spread[chaotic] = vel_k.std(axis=1)
        vmin[chaotic] = vel_k.min(axis=1)
        vmax[chaotic] = vel_k.max(axis=1)
        times[chaotic] = times_k.reshape(chaotic.size, k, 4).mean(axis=1)
    codes = _regime_codes(times[:, 0], times[:, 1], times[:, 2], times[:, 3], periodic)
    return {
        "throw_number": g,
        "angle": phi,
        "friction": mu,
        "inclination": alpha,
        "eps_t": et,
        "eps_n": en,
        "velocity_norm": velocity,
        "periodic": periodic,
        "period": period,
        "spread": spread,
        "velocity_min": vmin,
        "velocity_max": vmax,
        "regime_code": codes,
        "stick": times[:, 0],
        "slide_forward": times[:, 1],
        "slide_backward": times[:, 2],
        "flight": times[:, 3],
        "cycles": cycles,
    }


def _run_batch(params: np.ndarray, starts: np.ndarray):
    n = params.shape[0]
    velocity = np.empty(n)
    period = np.empty(n, dtype=np.int64)
    cycles = np.empty(n, dtype=np.int64)
    status = np.empty(n, dtype=np.int64)
    times = np.zeros((n, 4))
    _kernel.mean_velocity_many(
        params,
        starts,
        config.PM_MAX_CYCLES,
        config.PM_AVERAGE_CYCLES,
        config.PM_MAX_ORBIT_PERIOD,
        config.PM_PERIODIC_TOL,
        velocity,
        period,
        cycles,
        status,
        times,
    )
    if np.any(status != 0):
        i = int(np.flatnonzero(status != 0)[0])
        raise RuntimeError(
            "point-mass integration exceeded the event limit per cycle at "
            f"Gamma={params[i, 0]}, tan(phi)={params[i, 1]}, mu={params[i, 3]}; "
            "this indicates a degenerate input (e.g. exact tangency) -- perturb it slightly"
        )
    return velocity, period, cycles, times


def velocity(
    throw_number: float,
    angle: float,
    friction: float,
    inclination: float = 0.0,
    eps_t: float = 0.8,
    eps_n: float = 0.0,
    impact: str = "paper",
) -> VelocityResult:
    """Mean conveying velocity of a point mass (the paper's model), normalised.

    ``impact = "coulomb"`` bounds each landing by Coulomb (:data:`IMPACT_LAWS`).

    Args:
        throw_number: Gamma = A omega^2 sin(phi) / (g cos(alpha)), > 0.
        angle: vibration angle phi in degrees, in (0, 90).
        friction: Coulomb coefficient mu >= 0 (static = kinetic, as in the paper).
        inclination: trough inclination alpha in degrees (> 0: conveying uphill).
        eps_t: tangential restitution at landing (relative velocity multiplied by eps_t).
        eps_n: normal restitution at landing.

    Example: ``velocity(1.8, 25, 0.35).velocity_norm`` is the normalised velocity of the
    paper's Fig. 6 at Gamma = 1.8.

    """
    check_throw_number(throw_number)
    check_angle(angle)
    check_transport_friction(friction)
    check_inclination(inclination)
    check_restitution(eps_t, "eps_t")
    check_restitution(eps_n, "eps_n")
    r = velocities(throw_number, angle, friction, inclination, eps_t, eps_n, impact)
    return VelocityResult(
        throw_number=float(throw_number),
        angle=float(angle),
        friction=float(friction),
        inclination=float(inclination),
        eps_t=float(eps_t),
        eps_n=float(eps_n),
        velocity_norm=float(r["velocity_norm"][0]),
        regime=REGIMES[int(r["regime_code"][0])],
        periodic=bool(r["periodic"][0]),
        period=int(r["period"][0]),
        spread=float(r["spread"][0]),
        velocity_min=float(r["velocity_min"][0]),
        velocity_max=float(r["velocity_max"][0]),
        stick=float(r["stick"][0]),
        slide_forward=float(r["slide_forward"][0]),
        slide_backward=float(r["slide_backward"][0]),
        flight=float(r["flight"][0]),
        cycles=int(r["cycles"][0]),
        impact=impact,
    )
