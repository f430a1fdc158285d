"""Measurements of a driven run (DESIGN.md section 3): conveying velocity and mass flow.

- Mean conveying velocity v: the mass-weighted mean x-velocity of all grains in the trough frame,
  sum_i m_i v_x,i / sum_i m_i, averaged over each whole drive cycle; v is the mean of the
  per-cycle means and its standard error is std(per-cycle means, ddof=1) / sqrt(cycles).
- Normalised velocity v / (A omega cos phi) (the paper's Fig. 6; the scale is
  :func:`dem.drive.drive_velocity_from_omega`).
- Mass flow rate through a cross-section of the periodic section: M v / L, kg/s (M total grain
  mass, L the section length); per metre of width: M v / (L W), kg/(s m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dem import drive


@dataclass(frozen=True)
class VelocityStatistics:
    """Conveying velocity over measured cycles.

    Attributes:
        mean: v, m/s.
        stderr: Standard error of v from the per-cycle means, m/s (nan for one cycle).
        norm: v / (A omega cos phi).
        norm_stderr: stderr / (A omega cos phi).
        cycles: Number of cycles.

    """

    mean: float
    stderr: float
    norm: float
    norm_stderr: float
    cycles: int


def drive_velocity_scale(amplitude: float, omega: float, angle: float) -> float:
    """A omega cos phi, m/s (omega in rad/s, angle phi in degrees; :mod:`dem.drive`)."""
    return drive.drive_velocity_from_omega(amplitude, omega, angle)


def mean_and_stderr(samples: np.ndarray) -> tuple[float, float]:
    """Mean of samples (n,) and its standard error std(samples, ddof=1) / sqrt(n).

    The statistics of per-cycle means: the cycles of a steady run are taken as independent
    samples. The standard error is nan for a single sample.
    """
    u = np.asarray(samples, dtype=np.float64)
    if u.ndim != 1 or u.size == 0:
        raise ValueError("samples must be a non-empty 1-d array")
    mean = float(np.mean(u))
    stderr = float(np.std(u, ddof=1) / math.sqrt(u.size)) if u.size > 1 else math.nan
    return mean, stderr


def running_mean_and_stderr(samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`mean_and_stderr` of the first k samples for k = 1..n: (mean (n,), stderr (n,)).

    The last entries are those of all n samples, bit for bit (a run's summary values).
    """
    u = np.asarray(samples, dtype=np.float64)
    mean = np.full(u.size, np.nan)
    stderr = np.full(u.size, np.nan)
    for k in range(1, u.size + 1):  # n is a few hundred cycles at most
        mean[k - 1], stderr[k - 1] = mean_and_stderr(u[:k])
    return mean, stderr


def conveying_velocity(
    per_cycle: np.ndarray, *, amplitude: float, omega: float, angle: float
) -> VelocityStatistics:
    """Mean and standard error of per-cycle mean x-velocities, shape (cycles,), m/s."""
    u = np.asarray(per_cycle, dtype=np.float64)
    if u.ndim != 1 or u.size == 0:
        raise ValueError("per_cycle must be a non-empty 1-d array")
    mean, stderr = mean_and_stderr(u)
    scale = drive_velocity_scale(amplitude, omega, angle)
    return VelocityStatistics(mean, stderr, mean / scale, stderr / scale, int(u.size))


def mass_flow_rate(total_mass: float, velocity: float, length: float) -> float:
    """Mass flow rate M v / L through a cross-section of the periodic section, kg/s."""
    return total_mass * velocity / length


def mass_weighted_mean(mass: np.ndarray, values: np.ndarray) -> float:
    """sum_i m_i q_i / sum_i m_i for masses (n,) and values (n,)."""
    return float(np.dot(mass, values) / np.sum(mass))
