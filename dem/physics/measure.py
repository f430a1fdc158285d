"""Measurements of a driven run (README, A DEM run): conveying velocity and mass flow.

- Mean conveying velocity v: the mass-weighted mean x-velocity of all grains in the trough frame,
  sum_i m_i v_x,i / sum_i m_i, averaged over each whole drive cycle; v is the mean of the
  per-cycle means. Per-cycle means of a bed are correlated (a slow bed remembers its last
  cycle: lag-1 correlation up to +0.8), so its standard error is not std / sqrt(cycles) but
  std sqrt(2 tau_int / cycles), with tau_int the integrated autocorrelation time of the
  per-cycle means (:func:`integrated_autocorrelation_time`; 1/2 for independent cycles).
- Normalised velocity v / (A omega cos phi) (the paper's Fig. 6; the scale is
  :attr:`dem.scene.spec.DriveSpec.velocity_scale`, :func:`dem.physics.drive.velocity_scale`).
- Mass flow rate through a cross-section of the periodic section: M v / L, kg/s (M total grain
  mass, L the section length); per metre of width: M v / (L W), kg/(s m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike


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

    def summary_fields(self) -> dict:
        """The velocity fields of a run's summary.json (``dem run``'s and an exported deck's)."""
        return {
            "mean_velocity": self.mean,
            "mean_velocity_stderr": self.stderr,
            "mean_velocity_norm": self.norm,
            "mean_velocity_norm_stderr": self.norm_stderr,
            "cycle_autocorrelation_time": self.autocorrelation_time,
            "mean_velocity_stderr_independent": self.stderr_independent,
        }


def mean_and_stderr(samples: np.ndarray) -> tuple[float, float]:
    """Mean of samples (n,) and its standard error std(samples, ddof=1) / sqrt(n).

    The value if the samples were independent: a run keeps it beside its error bar
    (:attr:`VelocityStatistics.stderr_independent`); the error bar itself is
    :func:`correlated_stderr`, the cycles' correlation accounted for. The standard error is nan
    for a single sample.
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


_Z95 = 1.959963984540054  # two-sided 95 % quantile of the normal distribution


class Pooled(NamedTuple):
    """Replicas pooled: the estimate, its standard error and its 95 % interval.

    Attributes:
        mean: Pooled mean.
        stderr: Its standard error, the 95 % half-width over 1.96 (fill-to-fill spread
            included when there are replicas).
        half_width: Half-width of the 95 % interval.
        between: tau, the fill-to-fill standard deviation estimated beyond the runs' own errors
            (0 when the replicas agree within their errors; nan for N = 1).
        replicas: N.

    """

    mean: float
    stderr: float
    half_width: float
    between: float
    replicas: int


def pooled(means, stderrs) -> Pooled:
    """Pool N independent runs (replicas: other fills) of one case into one estimate.

    A random-effects model: run i measures mu + b_i + e_i, b_i the fill's own offset (variance
    tau^2, the fill-to-fill spread), e_i its within-run error (variance s_i^2, the run's
    autocorrelated standard error, :func:`correlated_stderr`). tau^2 is the DerSimonian-Laird
    moment estimate (DerSimonian and Laird 1986, Control. Clin. Trials 7: 177),
    tau^2 = max(0, (Q - (N - 1)) / (S1 - S2 / S1)), Q = sum w_i (m_i - m_w)^2, w_i = 1 / s_i^2,
    S1 = sum w_i, S2 = sum w_i^2; the pooled mean weighs run i by w*_i = 1 / (s_i^2 + tau^2).
    The 95 % interval is the wider of the model's, 1.96 sqrt(1 / sum w*_i), and the
    Hartung-Knapp-Sidik-Jonkman interval, t_{N-1} sqrt(sum w*_i (m_i - m)^2 / ((N - 1) sum w*_i))
    (Student's t with N - 1 degrees of freedom): the plain DerSimonian-Laird interval covers
    too little for few replicas, the HKSJ one alone too little when they agree by chance
    (IntHout, Ioannidis and Borm 2014, BMC Med. Res. Methodol. 14: 25; Roever, Knapp and Friede
    2015, ibid. 15: 99). ``stderr`` is its half-width over 1.96. On synthetic replicas (2-10
    runs, spread 0-4 times the runs' errors) it covers the true mean in 94.5-99.3 % of sets
    (tests/physics/test_measure.py). One run: its own error, 1.96 s_1,
    which excludes the fill-to-fill spread. Runs without a finite error (one cycle) count with
    the spread of the others alone (s_i = 0).
    """
    m = np.asarray(means, dtype=np.float64).ravel()
    s = np.asarray(stderrs, dtype=np.float64).ravel()
    if m.size == 0 or m.size != s.size:
        raise ValueError("means and stderrs must be non-empty and of equal length")
    n = m.size
    s = np.where(np.isfinite(s), s, 0.0)
    if n == 1:
        return Pooled(float(m[0]), float(s[0]), _Z95 * float(s[0]), math.nan, 1)
    tiny = np.finfo(float).tiny
    w = 1.0 / np.maximum(s * s, tiny)
    m_w = float(np.sum(w * m) / np.sum(w))
    q = float(np.sum(w * (m - m_w) ** 2))
    s1, s2 = float(np.sum(w)), float(np.sum(w * w))
    tau2 = max(0.0, (q - (n - 1)) / (s1 - s2 / s1)) if s1 > 0.0 else 0.0
    if not np.all(s > 0.0):  # a run without an error of its own: the spread alone
        tau2 = max(tau2, float(np.var(m, ddof=1)))
    w_star = 1.0 / np.maximum(s * s + tau2, tiny)
    mean = float(np.sum(w_star * m) / np.sum(w_star))
    model = math.sqrt(1.0 / float(np.sum(w_star)))
    hksj = math.sqrt(float(np.sum(w_star * (m - mean) ** 2)) / ((n - 1) * float(np.sum(w_star))))
    half = max(_Z95 * model, student_t95(n - 1) * hksj)
    return Pooled(mean, half / _Z95, half, math.sqrt(tau2), n)


#: Two-sided 95 % quantiles of Student's t for 1..30 degrees of freedom (standard tables).
_T95 = (12.7062, 4.3027, 3.1824, 2.7764, 2.5706, 2.4469, 2.3646, 2.3060, 2.2622, 2.2281,
        2.2010, 2.1788, 2.1604, 2.1448, 2.1314, 2.1199, 2.1098, 2.1009, 2.0930, 2.0860,
        2.0796, 2.0739, 2.0687, 2.0639, 2.0595, 2.0555, 2.0518, 2.0484, 2.0452, 2.0423)  # fmt: skip


def student_t95(dof: int) -> float:
    """Two-sided 95 % quantile of Student's t with ``dof`` >= 1 degrees of freedom.

    A table to 30; beyond it the Cornish-Fisher expansion about z = 1.95996 (Abramowitz and
    Stegun 26.7.5), within 1e-5 of the exact value there.
    """
    if dof < 1:
        raise ValueError(f"dof must be >= 1, got {dof}")
    if dof <= len(_T95):
        return _T95[dof - 1]
    z = 1.959963984540054
    g1 = (z**3 + z) / 4.0
    g2 = (5.0 * z**5 + 16.0 * z**3 + 3.0 * z) / 96.0
    g3 = (3.0 * z**7 + 19.0 * z**5 + 17.0 * z**3 - 15.0 * z) / 384.0
    return z + g1 / dof + g2 / dof**2 + g3 / dof**3


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


def steady(samples: ArrayLike, min_samples: int = 6, tolerance: float = 0.0,
           trend_z: float | None = None) -> bool:  # fmt: skip
    """True when the transient of a growing series has ended: its MSER point lies inside.

    With n >= ``min_samples`` samples, the series is steady when :func:`transient_end` d* is
    below n/2 - 1: the kept part is not still drifting, and at least half of the series is past
    the transient; with ``trend_z``, the kept part x[d*:] must also show no :func:`trend`
    beyond ``trend_z`` of its error (MSER alone stops on a bed still speeding up when the rise
    is slow against the noise: validation/steadiness). A series without noise that converges
    geometrically (one grain settling onto its periodic orbit) drifts forever by that rule; it
    is steady once the second half of the series spans no more than ``tolerance``. Cost O(n^2)
    per call.
    """
    u = np.asarray(samples, dtype=np.float64)
    n = u.size
    if n < min_samples:
        return False
    tail = u[n // 2 :]
    if float(np.max(tail) - np.min(tail)) <= tolerance:
        return True
    d = transient_end(u)
    if d >= n // 2 - 1:
        return False
    return trend_z is None or abs(trend(u[d:]).z) <= trend_z


class Trend(NamedTuple):
    """A series' least-squares trend against its error (:func:`trend`).

    Attributes:
        slope: Fitted change per sample (units of the series per cycle).
        change: slope (n - 1): the fitted change from the first sample to the last.
        z: slope over its standard error, the residuals' autocorrelation accounted for.
        samples: n.

    """

    slope: float
    change: float
    z: float
    samples: int


def trend(samples: ArrayLike) -> Trend:
    """The least-squares slope of a series against its autocorrelated standard error.

    slope = sum t (x_t - m) / sum t^2 (t centred); its error std(res, ddof=2)
    sqrt(2 tau_int / sum t^2), with tau_int of the residuals
    (:func:`integrated_autocorrelation_time`).
    z = 0 for a series without spread (a single grain on its orbit) or of fewer than 4 samples.
    On one short run the test is weak (validation/steadiness: at 20-30 cycles of lag-1 0.8 a
    steady series gives |z| > 3 in 22-28 % of runs, a drift of 6 of the run's errors is seen in
    62-91 %); on the longer series of a settle it is what tells a bed still speeding up.
    """
    u = np.asarray(samples, dtype=np.float64)
    n = u.size
    if n < 4:
        return Trend(0.0, 0.0, 0.0, n)
    t = np.arange(n) - (n - 1) / 2.0
    tt = float(np.dot(t, t))
    slope = float(np.dot(t, u - u.mean()) / tt)
    res = u - u.mean() - slope * t
    spread = float(np.std(res, ddof=2))
    if spread <= 16.0 * np.finfo(float).eps * max(float(np.max(np.abs(u))), 1e-300):
        return Trend(slope, slope * (n - 1), 0.0, n)
    tau = integrated_autocorrelation_time(res)
    se = spread * math.sqrt(2.0 * tau / tt)
    return Trend(slope, slope * (n - 1), slope / se, n)


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


def conveying_velocity(per_cycle: np.ndarray, *, scale: float) -> VelocityStatistics:
    """Mean and standard error of per-cycle mean x-velocities, shape (cycles,), m/s.

    The standard error accounts for the correlation of successive cycles
    (:func:`correlated_stderr`); the independent-cycle value is kept beside it. Velocities are
    normalised by ``scale``, m/s: the case's :attr:`dem.scene.spec.DriveSpec.velocity_scale`
    (A omega cos(phi) for the paper's drive, :func:`dem.physics.drive.velocity_scale`).
    """
    u = np.asarray(per_cycle, dtype=np.float64)
    if u.ndim != 1 or u.size == 0:
        raise ValueError("per_cycle must be a non-empty 1-d array")
    mean, naive = mean_and_stderr(u)
    stderr, tau = correlated_stderr(u)
    return VelocityStatistics(mean, stderr, mean / scale, stderr / scale, int(u.size), tau, naive)


def mass_flow_rate(total_mass: float, velocity: float, length: float) -> float:
    """Mass flow rate M v / L through a cross-section of the periodic section, kg/s."""
    return total_mass * velocity / length


def group_velocities(
    x_start: np.ndarray,
    x_end: np.ndarray,
    mass: np.ndarray,
    group: np.ndarray,
    groups: int,
    duration: float,
    length: float,
) -> list[float]:
    """Mass-weighted mean x-velocity of each group of grains over an interval, m/s.

    v_g = sum_{i in g} m_i dx_i / (M_g T), dx_i = x_end - x_start taken as the minimum image
    over the periodic ``length`` (so a grain must move less than length / 2 in ``duration``: a
    drive cycle moves the shipped beds a few mm), T = ``duration`` s. Over a cycle this is the
    time mean of the group's mass-weighted velocity, the bulk's measure
    (:meth:`dem.engine.simulation.Simulation.cycle_velocity`, from the momentum after every
    step) taken per group from the positions at the cycle's two edges; the two differ by the
    step's half kick at the edges, O(dt / T). nan for an empty group.
    """
    dx = np.asarray(x_end, dtype=np.float64) - np.asarray(x_start, dtype=np.float64)
    dx -= length * np.round(dx / length)
    mass = np.asarray(mass, dtype=np.float64)
    momentum = np.bincount(group, weights=mass * dx, minlength=groups)
    total = np.bincount(group, weights=mass, minlength=groups)
    with np.errstate(invalid="ignore", divide="ignore"):
        return [float(v) for v in momentum / (total * duration)]


def mass_weighted_mean(mass: np.ndarray, values: np.ndarray) -> float:
    """sum_i m_i q_i / sum_i m_i for masses (n,) and values (n,)."""
    return float(np.dot(mass, values) / np.sum(mass))


def distinct(a: float, b: float, digits: int = 2) -> tuple[str, str]:
    """Two numbers with the fewest significant digits that tell them apart.

    At least ``digits``, at most 8: "0.008948 > 0.008937", never "0.0089 > 0.0089".
    """
    for n in range(digits, 9):
        sa, sb = f"{a:.{n}g}", f"{b:.{n}g}"
        if sa != sb or a == b:
            return sa, sb
    return sa, sb


def with_error(value: float | None, error: float | None, unit: str = "") -> str:
    """``value +- error unit`` with the digits the error allows: 0.0457 +- 0.0008 m/s.

    The error keeps two significant digits when its first is 1 (0.011: rounding it to 0.01
    would change it by 10 %), else one; the value is rounded to the same decimal place. A
    missing or zero error leaves four significant digits and no error part.
    """
    unit = f" {unit}" if unit else ""
    if value is None or not math.isfinite(value):
        return f"{value}{unit}"
    if error is None or not math.isfinite(error) or error <= 0.0:
        return f"{value:.4g}{unit}"
    exponent = math.floor(math.log10(error))
    digits = 2 if f"{error:.1e}".startswith("1") else 1
    place = exponent - digits + 1  # decimal place of the last digit kept
    rounded_error = round(error, -place)  # 0.0096 -> 0.010: two digits, the first a 1
    decimals = max(-place, 0)
    return f"{round(value, -place):.{decimals}f} +- {rounded_error:.{decimals}f}{unit}"
