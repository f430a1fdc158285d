"""Measurements of a driven run (DESIGN.md section 3): conveying velocity and mass flow.

- Mean conveying velocity v: the mass-weighted mean x-velocity of all grains in the trough frame,
  sum_i m_i v_x,i / sum_i m_i, averaged over each whole drive cycle; v is the mean of the
  per-cycle means. Per-cycle means of a bed are correlated (a slow bed remembers its last
  cycle: lag-1 correlation up to +0.8), so its standard error is not std / sqrt(cycles) but
  std sqrt(2 tau_int / cycles), with tau_int the integrated autocorrelation time of the
  per-cycle means (:func:`integrated_autocorrelation_time`; 1/2 for independent cycles).
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
        stderr: Standard error of v from the per-cycle means, their correlation accounted for
            (:func:`correlated_stderr`), m/s (nan for one cycle).
        norm: v / (A omega cos phi).
        norm_stderr: stderr / (A omega cos phi).
        cycles: Number of cycles.
        autocorrelation_time: tau_int of the per-cycle means, cycles (1/2: independent).
        stderr_independent: std / sqrt(cycles), the error bar if the cycles were independent, m/s.

    """

    mean: float
    stderr: float
    norm: float
    norm_stderr: float
    cycles: int
    autocorrelation_time: float = 0.5
    stderr_independent: float = math.nan


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


def integrated_autocorrelation_time(samples: np.ndarray, window_factor: float = 5.0) -> float:
    """Integrated autocorrelation time tau_int = 1/2 + sum_{k=1}^{M} rho_k of a series, in samples.

    rho_k is the biased estimate sum_t (x_t - m)(x_{t+k} - m) / sum_t (x_t - m)^2, and the sum
    is cut at the smallest window M >= ``window_factor`` tau_int(M) (Sokal's automatic window,
    A. Sokal, "Monte Carlo methods in statistical mechanics", 1997, section 3). The variance of
    the mean of n samples is then var 2 tau_int / n. Never below 1/2, the independent value: a
    short series cannot tell anti-correlation from noise, and an error bar must not shrink on it.
    A constant series gives 1/2.
    """
    u = np.asarray(samples, dtype=np.float64)
    n = u.size
    d = u - np.mean(u)
    c0 = float(np.dot(d, d))
    # a constant series leaves only rounding in d: no correlation to measure
    if n < 3 or c0 <= n * (16.0 * np.finfo(float).eps * float(np.max(np.abs(u)))) ** 2:
        return 0.5
    tau = 0.5
    for m in range(1, n):
        tau += float(np.dot(d[:-m], d[m:])) / c0
        if m >= window_factor * tau:
            break
    return max(tau, 0.5)


def correlated_stderr(samples: np.ndarray) -> tuple[float, float]:
    """Standard error of the mean of a correlated series and its tau_int: (stderr, tau_int).

    stderr = std(samples, ddof=1) sqrt(2 tau_int / n) (:func:`integrated_autocorrelation_time`);
    for independent samples it is std / sqrt(n). nan for a single sample.

    A short series underestimates a strong correlation. For an AR(1) series with lag-1
    correlation 0.8 (400 replicas each), the mean estimate recovers 46 %, 66 %, 88 % and 92 % of
    the true standard error at 20, 50, 200 and 400 samples; std / sqrt(n) recovers 31-32 % at
    every length. Runs that need a trustworthy error bar at strong correlation need more cycles.
    """
    u = np.asarray(samples, dtype=np.float64)
    if u.ndim != 1 or u.size == 0:
        raise ValueError("samples must be a non-empty 1-d array")
    if u.size == 1:
        return math.nan, 0.5
    tau = integrated_autocorrelation_time(u)
    return float(np.std(u, ddof=1) * math.sqrt(2.0 * tau / u.size)), tau


def transient_end(samples: np.ndarray) -> int:
    """Where the start-up transient of a series ends: the MSER truncation point d*.

    d* minimises the marginal standard error of what is kept,
    MSER(d) = sum_{i >= d} (x_i - mean(x_d..x_{n-1}))^2 / (n - d)^2, over d <= n/2 (White 1997;
    White, Cobb and Spratt 2000, "A comparison of five steady-state truncation heuristics").
    A series still drifting at its end has its minimum at the bound n/2; one whose transient has
    died out early has it inside. Returns 0 for fewer than 3 samples.
    """
    u = np.asarray(samples, dtype=np.float64)
    n = u.size
    if n < 3:
        return 0
    best, best_d = math.inf, 0
    for d in range(n // 2 + 1):
        tail = u[d:]
        value = float(np.sum((tail - np.mean(tail)) ** 2)) / (n - d) ** 2
        if value < best:
            best, best_d = value, d
    return best_d


def steady(samples: np.ndarray, min_samples: int = 6, tolerance: float = 0.0) -> bool:
    """True when the transient of a growing series has ended: its MSER point lies inside.

    With n >= ``min_samples`` samples, the series is steady when :func:`transient_end` is below
    n/2 - 1: the kept part is not still drifting, and at least half of the series is past the
    transient. A series without noise that converges geometrically (one grain settling onto
    its periodic orbit) drifts forever by that rule; it is steady once the second half of the
    series spans no more than ``tolerance``. Cost O(n^2) per call.
    """
    u = np.asarray(samples, dtype=np.float64)
    n = u.size
    if n < min_samples:
        return False
    tail = u[n // 2 :]
    if float(np.max(tail) - np.min(tail)) <= tolerance:
        return True
    return transient_end(u) < n // 2 - 1


def running_mean_and_stderr(samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and :func:`correlated_stderr` of the first k samples, k = 1..n: (mean, stderr), (n,).

    The last entries are those of all n samples, bit for bit (a run's summary values). Cost
    O(n^2) for n cycles (a few hundred at most).
    """
    u = np.asarray(samples, dtype=np.float64)
    mean = np.full(u.size, np.nan)
    stderr = np.full(u.size, np.nan)
    for k in range(1, u.size + 1):
        mean[k - 1] = float(np.mean(u[:k]))
        stderr[k - 1] = correlated_stderr(u[:k])[0]
    return mean, stderr


def conveying_velocity(
    per_cycle: np.ndarray,
    *,
    amplitude: float | None = None,
    omega: float | None = None,
    angle: float | None = None,
    scale: float | None = None,
) -> VelocityStatistics:
    """Mean and standard error of per-cycle mean x-velocities, shape (cycles,), m/s.

    The standard error accounts for the correlation of successive cycles
    (:func:`correlated_stderr`); the independent-cycle value is kept beside it. Velocities are
    normalised by A omega cos(phi) (``amplitude``, ``omega``, ``angle``) or by ``scale`` (m/s;
    an elliptical drive's :attr:`dem.case.DriveSpec.velocity_scale`).
    """
    if scale is None:
        scale = drive_velocity_scale(amplitude, omega, angle)
    u = np.asarray(per_cycle, dtype=np.float64)
    if u.ndim != 1 or u.size == 0:
        raise ValueError("per_cycle must be a non-empty 1-d array")
    mean, naive = mean_and_stderr(u)
    stderr, tau = correlated_stderr(u)
    return VelocityStatistics(mean, stderr, mean / scale, stderr / scale, int(u.size), tau, naive)


def mass_flow_rate(total_mass: float, velocity: float, length: float) -> float:
    """Mass flow rate M v / L through a cross-section of the periodic section, kg/s."""
    return total_mass * velocity / length


def mass_weighted_mean(mass: np.ndarray, values: np.ndarray) -> float:
    """sum_i m_i q_i / sum_i m_i for masses (n,) and values (n,)."""
    return float(np.dot(mass, values) / np.sum(mass))
