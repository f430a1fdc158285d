"""Measurements of a driven run (DESIGN.md section 3): conveying velocity and mass flow.

- Mean conveying velocity v: the mass-weighted mean x-velocity of all grains in the trough frame,
  sum_i m_i v_x,i / sum_i m_i, averaged over each whole drive cycle; v is the mean of the
  per-cycle means and its standard error is std(per-cycle means, ddof=1) / sqrt(cycles).
- Normalised velocity v / (A omega cos phi) (the paper's Fig. 6).
- Mass flow rate through a cross-section of the periodic section: M v / L, kg/s (M total grain
  mass, L the section length); per metre of width: M v / (L W), kg/(s m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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
    """A omega cos phi, m/s (angle phi in degrees)."""
    return amplitude * omega * math.cos(math.radians(angle))


def conveying_velocity(
    per_cycle: np.ndarray, *, amplitude: float, omega: float, angle: float
) -> VelocityStatistics:
    """Mean and standard error of per-cycle mean x-velocities, shape (cycles,), m/s."""
    u = np.asarray(per_cycle, dtype=np.float64)
    if u.ndim != 1 or u.size == 0:
        raise ValueError("per_cycle must be a non-empty 1-d array")
    mean = float(np.mean(u))
    stderr = float(np.std(u, ddof=1) / math.sqrt(u.size)) if u.size > 1 else math.nan
    scale = drive_velocity_scale(amplitude, omega, angle)
    return VelocityStatistics(mean, stderr, mean / scale, stderr / scale, int(u.size))


def mass_flow_rate(total_mass: float, velocity: float, length: float) -> float:
    """Mass flow rate M v / L through a cross-section of the periodic section, kg/s."""
    return total_mass * velocity / length


def mass_weighted_mean(mass: np.ndarray, values: np.ndarray) -> float:
    """sum_i m_i q_i / sum_i m_i for masses (n,) and values (n,)."""
    return float(np.dot(mass, values) / np.sum(mass))
