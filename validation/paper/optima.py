"""The optimum vibration angle of the point mass under each hold, and the drive along a hold.

What is held fixed while the angle changes decides where the optimum lies (README, The
point-mass model): the throw number Gamma, the amplitude A, or the peak trough acceleration
A omega^2 = K g; a fourth reading holds Gamma and measures v / (A omega) = v_norm cos(phi).
The drive at the paper's 60 Hz comes from :mod:`dem.physics.drive`.
"""

import math

import numpy as np

from dem.config import GRAVITY
from dem.physics import drive
from dem.pointmass import REGIMES, velocities
from dem.pointmass.sweep import optimum

FREQUENCY = 60.0  # Hz, the paper's experiments
OMEGA = drive.omega(FREQUENCY)
REFERENCE_ANGLE = 25.0  # deg: the paper's "practical vibration angle" (Fig. 6)


def m_per_s(v_norm, angle, amplitude):
    """Conveying velocity in m/s: v_norm times the drive velocity A omega cos(phi) at 60 Hz."""
    return v_norm * drive.velocity_scale(amplitude, FREQUENCY, angle)


def amplitude_for(gamma: float, angle: float = REFERENCE_ANGLE, inclination: float = 0.0):
    """A (m) at 60 Hz giving throw number ``gamma`` at ``angle`` (Eq. 3)."""
    return drive.amplitude(gamma, FREQUENCY, angle, inclination)


def peak_acceleration(amplitude):
    """K = A omega^2 / g at 60 Hz: the peak trough acceleration in units of g."""
    return amplitude * OMEGA**2 / GRAVITY


def amplitude_at_acceleration(k):
    """A = K g / omega^2 at 60 Hz, m: the amplitude of peak acceleration K g."""
    return k * GRAVITY / OMEGA**2


def held_drive(angle, hold: str, value: float):
    """Throw number and amplitude along ``angle`` (alpha = 0) for a hold at 60 Hz.

    ``hold``: ``throw_number`` (value = Gamma), ``amplitude`` (value = A in m) or
    ``acceleration`` (value = K, peak trough acceleration A omega^2 = K g).
    """
    if hold == "throw_number":
        gamma = np.full_like(angle, value)
        return gamma, drive.amplitude(gamma, FREQUENCY, angle)
    if hold == "amplitude":
        amp = np.full_like(angle, value)
    else:
        amp = np.full_like(angle, amplitude_at_acceleration(value))
    return drive.throw_number(amp, FREQUENCY, angle), amp


def plateau(x, y, level, top=None):
    """Contiguous interval (lo, hi) around the maximum of y where y >= level * top (max y)."""
    best = int(np.argmax(y))
    above = y >= level * (y[best] if top is None else top)
    i = j = best
    while i > 0 and above[i - 1]:
        i -= 1
    while j < len(x) - 1 and above[j + 1]:
        j += 1
    return float(x[i]), float(x[j])


def v_over_a_omega_row(friction, gamma, points):
    """Optimum angle at fixed Gamma of v / (A omega) = v_norm cos(phi).

    No hold of ``dem.pointmass.sweep.optimum`` has this objective, so its recipe is done here:
    ``points`` angles on 1-89 deg, the best refined on 201 points between its neighbours (which
    include it); the 90% plateau is relative to the refined maximum.
    """
    x = np.linspace(1.0, 89.0, points)

    def objective(phi):
        return velocities(gamma, phi, friction)["velocity_norm"] * np.cos(np.radians(phi))

    y = objective(x)
    best = int(np.argmax(y))
    fine = np.linspace(x[max(best - 1, 0)], x[min(best + 1, points - 1)], 201)
    y_fine = objective(fine)
    phi, top = fine[np.argmax(y_fine)], y_fine.max()
    at = velocities(gamma, np.array([phi]), friction)
    lo, hi = plateau(x, y, 0.9, top)
    amp = amplitude_for(gamma, phi)
    return {
        "friction": friction,
        "hold": "throw_number",
        "reading": "v_over_A_omega",
        "held_value": gamma,
        "optimum_angle": float(phi),
        "plateau_90": [lo, hi],
        "plateau_width": hi - lo,
        "plateau_95_width": float(np.ptp(plateau(x, y, 0.95))),
        "mu_tan_phi_at_optimum": friction * math.tan(math.radians(phi)),
        "tail_ratio_89deg": float(y[-1] / top),
        "throw_number_at_optimum": gamma,
        "velocity_norm_at_optimum": float(at["velocity_norm"][0]),
        "velocity_m_per_s_at_optimum": float(top * amp * OMEGA),
        "v_over_A_omega_at_optimum": float(top),
        "regime_at_optimum": REGIMES[int(at["regime_code"][0])],
        "at_scan_bound": bool(min(abs(phi - 1.0), abs(phi - 89.0)) < 1e-6),
        "plateau_covers_scan": bool(lo <= 1.0 and hi >= 89.0),
    }


def optimum_row(friction, hold, value, points):
    """Optimum angle under one hold; value = Gamma, A (m) or K (g)."""
    key = {"throw_number": "throw_number", "amplitude": "amplitude"}.get(hold, "peak_acceleration")
    opt = optimum(
        "angle", hold, friction=friction, frequency=FREQUENCY, points=points, **{key: value}
    )
    return {
        "friction": friction,
        "hold": hold,
        "reading": hold,
        "held_value": value,
        "optimum_angle": opt.value,
        "plateau_90": list(opt.plateau),
        "plateau_width": opt.plateau[1] - opt.plateau[0],
        "plateau_95_width": float(
            np.ptp(plateau(opt.curve["angle"], opt.curve[opt.objective], 0.95))
        ),
        "mu_tan_phi_at_optimum": friction * math.tan(math.radians(opt.value)),
        "tail_ratio_89deg": float(opt.curve[opt.objective][-1] / max(opt.curve[opt.objective])),
        "throw_number_at_optimum": opt.throw_number,
        "velocity_norm_at_optimum": opt.velocity_norm,
        "velocity_m_per_s_at_optimum": opt.velocity,
        "v_over_A_omega_at_optimum": opt.velocity_norm * math.cos(math.radians(opt.value)),
        "regime_at_optimum": opt.regime,
        "at_scan_bound": bool(min(abs(opt.value - 1.0), abs(opt.value - 89.0)) < 1e-6),
        "plateau_covers_scan": bool(opt.plateau[0] <= 1.0 and opt.plateau[1] >= 89.0),
    }


# panels and optima rows, in this order, and what each panel plots at the optimum


def sweep_along(gamma, angle, friction):
    """Velocities along paired (Gamma, phi) arrays (not a Cartesian product)."""
    return velocities(gamma, angle, friction)
