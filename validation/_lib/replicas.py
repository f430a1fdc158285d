"""Statistics of a study's results: independent replicas, per-cycle series, and differences.

Two kinds of error bar, kept apart on purpose:

- independent replicas (fills drawn from different seeds): the mean and its standard error
  std(ddof=1) / sqrt(n), :func:`replica_mean` (:func:`dem.physics.measure.mean_and_stderr`);
- per-cycle means of one run, which are correlated from cycle to cycle (a bed remembers its
  last cycle): the mean and the correlated standard error std(ddof=1) sqrt(2 tau_int / n),
  :func:`series_mean` (:func:`dem.physics.measure.correlated_stderr`). std / sqrt(n) would
  understate it.

:func:`difference` sets one result against another in percent and in combined standard errors.
"""

from __future__ import annotations

import math

import numpy as np

from dem.physics import measure


def replica_mean(values) -> tuple[float, float]:
    """Mean of independent replicas (n,) and its standard error std(ddof=1) / sqrt(n).

    nan standard error for one replica.
    """
    return measure.mean_and_stderr(np.asarray(values, dtype=float))


def replica_stderr(values) -> float:
    """The standard error of :func:`replica_mean`: std(ddof=1) / sqrt(n) of independent replicas."""
    return replica_mean(values)[1]


def series_mean(per_cycle) -> tuple[float, float]:
    """Mean of a run's per-cycle values (n,) and its correlated standard error (same units)."""
    u = np.asarray(per_cycle, dtype=float)
    return float(u.mean()), float(measure.correlated_stderr(u)[0])


def difference(value: float, stderr: float, reference: float, reference_stderr: float) -> dict:
    """``value`` - ``reference``, its combined standard error, in sigmas and in % of reference.

    Keys: dem_minus_liggghts (the difference), combined_stderr (sqrt(se^2 + se_ref^2)), sigma
    (difference / combined_stderr), percent_of_liggghts (100 difference / reference).
    """
    diff = value - reference
    sigma = math.hypot(stderr, reference_stderr)
    return {
        "dem_minus_liggghts": diff,
        "combined_stderr": sigma,
        "sigma": diff / sigma,
        "percent_of_liggghts": 100.0 * diff / reference,
    }
