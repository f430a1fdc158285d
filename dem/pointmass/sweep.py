"""Parameter sweeps of the point-mass model and the optimum vibration angle or throw number.

An optimum only means something with a statement of what is held fixed while the angle or
the throw number changes (README, The point-mass model). The conveying velocity in m/s is

    v = v_norm(Gamma, phi) * A omega cos(phi),   Gamma = A omega^2 sin(phi) / (g cos(alpha)),

so the same normalised curve gives different optima:

=====================  ==================  ==============================================
optimum over           hold                what changes, and the objective
=====================  ==================  ==============================================
angle phi              throw_number        the normalised velocity v_norm(Gamma, phi)
                                           (Figs. 7, 8): in m/s, v ~ v_norm cot(phi) grows
                                           without bound as phi -> 0 because
                                           A = Gamma g cos(a) / (omega^2 sin phi) does
angle phi              amplitude           A, f fixed; Gamma grows with sin(phi);
                                           v = v_norm(Gamma(phi), phi) A omega cos(phi)
angle phi              acceleration        peak trough acceleration A omega^2 = K g and f
                                           fixed: the same optimum as holding A at that f
throw number Gamma     frequency           A grows with Gamma: v ~ Gamma v_norm(Gamma)
throw number Gamma     amplitude           omega grows as sqrt(Gamma): v ~ sqrt(Gamma) v_norm
throw number Gamma     drive_velocity      A omega fixed: v ~ v_norm(Gamma) (Fig. 6)
=====================  ==================  ==============================================
"""

import math
from dataclasses import dataclass, field
from typing import IO

import numpy as np

from dem import config
from dem.errors import InputError
from dem.physics import drive
from dem.physics.search import golden_section
from dem.pointmass.model import REGIMES, velocities
from dem.pointmass.validate import check_angle, check_positive, check_throw_number

#: Inputs that a sweep can vary, in output column order.
SWEEPABLE = ("throw_number", "angle", "friction", "inclination", "eps_t", "eps_n")

#: What may be held fixed for each kind of optimum.
HOLDS = {
    "angle": ("throw_number", "amplitude", "acceleration"),
    "throw_number": ("frequency", "amplitude", "drive_velocity"),
}

_COLUMNS = SWEEPABLE + (
    "velocity_norm",
    "regime",
    "periodic",
    "period",
    "spread",
    "velocity_min",
    "velocity_max",
    "stick",
    "slide_forward",
    "slide_backward",
    "flight",
    "impact",
)


#: Most points one sweep (or one axis of it) computes: 1e6 points take minutes and their
#: arrays a few hundred MB; 7e7 ran out of memory.
MAX_SWEEP_POINTS = 1_000_000


def sweep(
    throw_number,
    angle,
    friction,
    inclination=0.0,
    eps_t=0.8,
    eps_n=0.0,
    impact="paper",
) -> dict[str, np.ndarray]:
    """Velocities over the Cartesian product of the given values (scalars or 1-D sequences).

    ``impact``: the landing law, ``"paper"`` or ``"coulomb"``
    (:data:`dem.pointmass.model.IMPACT_LAWS`), also written as a column.

    Returns flat arrays keyed like :func:`dem.pointmass.velocities`, plus ``regime`` (labels),
    ordered with the first varying input slowest.
    """
    axes = [np.atleast_1d(np.asarray(v, dtype=float)) for v in (throw_number, angle, friction)]
    axes += [np.atleast_1d(np.asarray(v, dtype=float)) for v in (inclination, eps_t, eps_n)]
    for name, axis in zip(SWEEPABLE, axes, strict=True):
        if axis.ndim != 1 or axis.size == 0:
            raise InputError(name, axis.tolist(), "a number or a non-empty 1-D list of numbers")
    points = math.prod(axis.size for axis in axes)
    if points > MAX_SWEEP_POINTS:
        sizes = " x ".join(
            f"{name} {axis.size}" for name, axis in zip(SWEEPABLE, axes, strict=True)
        )
        raise InputError(
            ", ".join(SWEEPABLE), points, f"a sweep of at most {MAX_SWEEP_POINTS} points "
            f"({sizes}): sweep fewer values, or in parts",
        )  # fmt: skip
    grid = np.meshgrid(*axes, indexing="ij")
    gamma, phi, mu, alpha, e_t, e_n = (g.ravel() for g in grid)
    result = velocities(gamma, phi, mu, alpha, e_t, e_n, impact=impact)
    result["regime"] = np.array([REGIMES[c] for c in result["regime_code"]])
    result["impact"] = np.full(result["regime"].shape, impact)
    return result


#: Column names of the CSV (:func:`write_csv`), units in the name, by result key.
CSV_COLUMNS = {
    "throw_number": "throw_number",
    "angle": "angle_deg",
    "friction": "friction",
    "inclination": "inclination_deg",
    "eps_t": "eps_t",
    "eps_n": "eps_n",
    "velocity_norm": "velocity_norm",
    "regime": "regime",
    "periodic": "periodic",
    "period": "period_cycles",
    "spread": "spread",
    "velocity_min": "velocity_norm_min",
    "velocity_max": "velocity_norm_max",
    "stick": "stick",
    "slide_forward": "slide_forward",
    "slide_backward": "slide_backward",
    "flight": "flight",
    "impact": "impact",
}


def write_csv(result: dict[str, np.ndarray], stream: IO[str]) -> None:
    """Write a sweep result as CSV: one header line, units in the names, 6 significant digits.

    Columns (:data:`CSV_COLUMNS`): the inputs ``throw_number``, ``angle_deg``, ``friction``,
    ``inclination_deg``, ``eps_t``, ``eps_n``; the normalised velocity v / (A omega cos phi)
    ``velocity_norm``; the regime and landing law as words; ``periodic`` (true/false) and the
    orbit's period in drive cycles ``period_cycles``; for a non-periodic point the ``spread``
    and range ``velocity_norm_min`` .. ``velocity_norm_max`` over starting phases; the phase
    fractions of a cycle ``stick``, ``slide_forward``, ``slide_backward``, ``flight``.
    """
    from dem.io.tables import csv_text

    keys = list(_COLUMNS)
    n = len(result["velocity_norm"])
    rows = ([result[k][i] for k in keys] for i in range(n))
    stream.write(csv_text([CSV_COLUMNS[k] for k in keys], rows))


@dataclass(frozen=True)
class Optimum:
    """The best angle or throw number under a stated constraint.

    ``objective`` is what was maximised (``velocity`` in m/s, or ``velocity_norm``).
    ``plateau`` is the interval where the objective is at least 90% of its optimum: narrow
    means a sharply defined optimum. ``curve`` holds the scanned values.
    """

    over: str
    hold: str
    objective: str
    held: dict
    value: float
    velocity: float
    velocity_norm: float
    throw_number: float
    angle: float
    amplitude: float
    frequency: float
    regime: str
    plateau: tuple[float, float]
    curve: dict = field(repr=False)

    def as_dict(self, with_curve: bool = False) -> dict:
        """Plain dictionary (for JSON)."""
        out = {
            "over": self.over,
            "hold": self.hold,
            "objective": self.objective,
            "held": self.held,
            "value": self.value,
            "velocity": self.velocity,
            "velocity_norm": self.velocity_norm,
            "throw_number": self.throw_number,
            "angle": self.angle,
            "amplitude": self.amplitude,
            "frequency": self.frequency,
            "regime": self.regime,
            "plateau_90": list(self.plateau),
        }
        if with_curve:
            out["curve"] = {k: np.asarray(v).tolist() for k, v in self.curve.items()}
        return out


def _drive(over, hold, x, fixed):
    """Throw number, angle, amplitude and frequency along the scanned variable x (physics.drive)."""
    alpha = fixed["inclination"]
    if over == "angle":
        phi = x
        f = np.full_like(x, fixed["frequency"])
        if hold == "throw_number":
            gamma = np.full_like(x, fixed["throw_number"])
            amp = drive.amplitude(gamma, f, phi, alpha)
        else:
            if hold == "amplitude":
                amp = np.full_like(x, fixed["amplitude"])
            else:  # acceleration: A omega^2 = K g
                peak = fixed["peak_acceleration"] * config.GRAVITY
                amp = np.full_like(x, peak) / drive.omega(f) ** 2
            gamma = drive.throw_number(amp, f, phi, alpha)
    else:
        gamma = x
        phi = np.full_like(x, fixed["angle"])
        if hold == "frequency":
            f = np.full_like(x, fixed["frequency"])
            amp = drive.amplitude(gamma, f, fixed["angle"], alpha)
        elif hold == "amplitude":
            amp = np.full_like(x, fixed["amplitude"])
            f = drive.frequency_for_amplitude(gamma, amp, fixed["angle"], alpha)
        else:  # drive_velocity: the peak trough speed A omega = V
            v_drive = fixed["drive_velocity"]
            f = drive.frequency_for_peak_speed(gamma, v_drive, fixed["angle"], alpha)
            amp = v_drive / drive.omega(f)
    return gamma, phi, amp, f


def _objective(over, hold):
    """What an optimum maximises: the velocity in m/s, or v_norm when Gamma is held."""
    return "velocity_norm" if (over, hold) == ("angle", "throw_number") else "velocity"


def _velocity_along(over, hold, x, fixed):
    """Objective, velocities and drive along x: (objective, result, Gamma, phi, A, f)."""
    gamma, phi, amp, f = _drive(over, hold, x, fixed)
    r = velocities(
        gamma, phi, fixed["friction"], fixed["inclination"], fixed["eps_t"], fixed["eps_n"],
        impact=fixed.get("impact", "paper"),
    )  # fmt: skip
    r["velocity"] = r["velocity_norm"] * drive.velocity_scale(amp, f, phi)
    return r[_objective(over, hold)], r, gamma, phi, amp, f


def optimum(
    over: str,
    hold: str,
    *,
    friction: float,
    angle: float | None = None,
    throw_number: float | None = None,
    amplitude: float | None = None,
    peak_acceleration: float | None = None,
    drive_velocity: float | None = None,
    frequency: float = 60.0,
    inclination: float = 0.0,
    eps_t: float = 0.8,
    eps_n: float = 0.0,
    bounds: tuple[float, float] | None = None,
    points: int = 321,
    impact: str = "paper",
) -> Optimum:
    """Optimum vibration angle (``over="angle"``) or throw number (``over="throw_number"``).

    The velocity in m/s is scanned on ``points`` values within ``bounds`` (default 1-89 deg or
    Gamma 0.05-8) and the best point refined by golden-section search between its neighbours.
    ``hold`` names what stays fixed (see the module table); it needs its value:
    ``throw_number``, ``amplitude`` (m), ``peak_acceleration`` (in g), ``frequency`` (Hz),
    or ``drive_velocity`` (A omega, m/s). Angles are in degrees.
    """
    if over not in HOLDS:
        raise InputError("over", over, "one of " + ", ".join(HOLDS))
    if hold not in HOLDS[over]:
        raise InputError("hold", hold, f"for an optimum over {over}: one of {HOLDS[over]}")
    fixed = {
        "friction": friction,
        "inclination": inclination,
        "eps_t": eps_t,
        "eps_n": eps_n,
        "impact": impact,
        "frequency": check_positive(frequency, "frequency"),
    }
    needs = {
        "throw_number": throw_number,
        "amplitude": amplitude,
        "acceleration": peak_acceleration,
        "drive_velocity": drive_velocity,
    }
    if hold in needs:
        key = "peak_acceleration" if hold == "acceleration" else hold
        held = needs[hold]
        if held is None:
            raise InputError(key, None, f"required when holding {hold} fixed")
        fixed[key] = check_positive(held, key)
    if over == "throw_number":
        if angle is None:
            raise InputError("angle", None, "required for an optimum over throw_number")
        fixed["angle"] = check_angle(angle)
    lo, hi = bounds if bounds is not None else ((1.0, 89.0) if over == "angle" else (0.05, 8.0))
    if over == "angle":
        check_angle(lo, "bounds")
        check_angle(hi, "bounds")
    else:
        check_throw_number(lo, "bounds")
        check_throw_number(hi, "bounds")
    if not lo < hi:
        raise InputError("bounds", (lo, hi), "lower bound must be below the upper bound")
    if points < 5:
        raise InputError("points", points, "at least 5")

    x = np.linspace(lo, hi, points)
    obj, r, gamma, phi, amp, f = _velocity_along(over, hold, x, fixed)
    best = int(np.argmax(obj))
    a, b = x[max(best - 1, 0)], x[min(best + 1, points - 1)]
    x_best, o_best = golden_section(
        lambda t: _velocity_along(over, hold, np.array([t]), fixed)[0][0],
        a,
        b,
        iterations=40,
        maximize=True,
    )
    if o_best < obj[best]:
        x_best, o_best = x[best], obj[best]
    _, rb, gb, pb, ab, fb = _velocity_along(over, hold, np.array([x_best]), fixed)
    above = obj >= 0.9 * o_best if o_best > 0 else np.zeros_like(obj, dtype=bool)
    return Optimum(
        over=over,
        hold=hold,
        objective=_objective(over, hold),
        held=dict(fixed),
        value=float(x_best),
        velocity=float(rb["velocity"][0]),
        velocity_norm=float(rb["velocity_norm"][0]),
        throw_number=float(gb[0]),
        angle=float(pb[0]),
        amplitude=float(ab[0]),
        frequency=float(fb[0]),
        regime=REGIMES[int(rb["regime_code"][0])],
        plateau=_plateau(x, above, best),
        curve={
            over: x,
            "velocity": r["velocity"],
            "velocity_norm": r["velocity_norm"],
            "throw_number": gamma,
            "angle": phi,
            "amplitude": amp,
            "frequency": f,
        },
    )


def _plateau(x, above, best):
    """The contiguous interval around ``best`` where ``above`` holds."""
    if not above[best]:
        return (float(x[best]), float(x[best]))
    i = best
    while i > 0 and above[i - 1]:
        i -= 1
    j = best
    while j < len(x) - 1 and above[j + 1]:
        j += 1
    return (float(x[i]), float(x[j]))


def parse_values(text: str, key: str) -> list[float]:
    """Parse ``"1.8"``, ``"0.25,0.35,0.6"`` or ``"start:stop:step"`` (stop included)."""
    count = 0
    try:
        if ":" in text:
            parts = [float(p) for p in text.split(":")]
            if len(parts) != 3 or parts[2] <= 0 or parts[1] < parts[0]:
                raise ValueError
            if not all(math.isfinite(v) for v in parts):
                raise ValueError
            start, stop, step = parts
            count = int(math.floor((stop - start) / step + 1e-9)) + 1
        else:
            return [float(p) for p in text.split(",")]
    except ValueError:
        raise InputError(
            key, text, "a number, a comma list, or start:stop:step with step > 0"
        ) from None
    if count > MAX_SWEEP_POINTS:
        raise InputError(
            key, text, f"at most {MAX_SWEEP_POINTS} values ({count} asked: a larger step, or "
            "a narrower range)",
        )  # fmt: skip
    return [start + i * step for i in range(count)]


__all__ = [
    "HOLDS",
    "Optimum",
    "SWEEPABLE",
    "optimum",
    "parse_values",
    "sweep",
    "write_csv",
]
