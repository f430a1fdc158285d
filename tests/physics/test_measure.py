"""Per-cycle statistics (dem.physics.measure) and the damping relation shared with the LIGGGHTS
export."""

import math

import numpy as np
import pytest

from dem.io.liggghts import damping_ratio
from dem.kernels.contact import damping_beta
from dem.physics import drive, measure


def test_mean_and_stderr_is_std_ddof1_over_sqrt_n():
    v = np.random.default_rng(5).normal(0.03, 0.004, 17)
    mean, stderr = measure.mean_and_stderr(v)
    assert mean == pytest.approx(v.sum() / v.size, rel=1e-14)
    direct = math.sqrt(np.sum((v - v.mean()) ** 2) / (v.size - 1)) / math.sqrt(v.size)
    assert stderr == pytest.approx(direct, rel=1e-12)
    assert math.isnan(measure.mean_and_stderr(v[:1])[1])


def test_running_statistics_end_at_the_summary_values():
    v = np.random.default_rng(6).normal(0.03, 0.004, 23)
    mean, stderr = measure.running_mean_and_stderr(v)
    stat = measure.conveying_velocity(v, scale=drive.velocity_scale(0.5e-3, 60.0, 25.0))
    assert (mean[-1], stderr[-1]) == (stat.mean, stat.stderr)
    assert math.isnan(stderr[0]) and mean[0] == v[0]


def test_liggghts_damping_ratio_is_minus_the_kernels_beta():
    for e in np.linspace(0.0, 1.0, 41):
        assert damping_ratio(e) == -damping_beta(e)


def _ar1(rng, rho, n, replicas):
    """AR(1) series x_t = rho x_{t-1} + e_t, stationary start, unit innovation variance."""
    x = np.empty((replicas, n))
    x[:, 0] = rng.normal(0.0, 1.0 / math.sqrt(1.0 - rho**2), replicas)
    e = rng.normal(0.0, 1.0, (replicas, n))
    for t in range(1, n):
        x[:, t] = rho * x[:, t - 1] + e[:, t]
    return x


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.8])
def test_correlated_stderr_recovers_the_known_ar1_answer(rho):
    # var(mean) of n AR(1) samples: s^2 / n [(1 + r) / (1 - r) - 2 r (1 - r^n) / (n (1 - r)^2)]
    n, replicas = 400, 300
    x = _ar1(np.random.default_rng(11), rho, n, replicas)
    s2 = 1.0 / (1.0 - rho**2)
    exact = math.sqrt(
        s2 / n * ((1 + rho) / (1 - rho) - 2 * rho * (1 - rho**n) / (n * (1 - rho) ** 2))
    )
    # the spread of the replicas' means is the truth the estimate stands for
    assert np.std(x.mean(axis=1)) == pytest.approx(exact, rel=0.15)
    estimates = np.array([measure.correlated_stderr(row)[0] for row in x])
    naive = np.array([measure.mean_and_stderr(row)[1] for row in x])
    # Sokal's window is biased low by a few per cent at n = 400 (8 % at rho = 0.8)
    assert 0.88 * exact < np.mean(estimates) < 1.05 * exact
    if rho > 0:  # the plain formula misses the correlation: 58 % of the truth at 0.5, 33 % at 0.8
        assert np.mean(naive) < 0.6 * exact
    tau = np.mean([measure.integrated_autocorrelation_time(row) for row in x])
    assert tau == pytest.approx(0.5 * (1 + rho) / (1 - rho), rel=0.12)


def test_independent_cycles_keep_the_plain_error_bar():
    white = np.random.default_rng(12).normal(0.03, 0.004, 200)
    stat = measure.conveying_velocity(white, scale=drive.velocity_scale(0.5e-3, 60.0, 25.0))
    assert stat.stderr == pytest.approx(stat.stderr_independent, rel=0.25)
    assert stat.autocorrelation_time < 1.0
    assert measure.integrated_autocorrelation_time(np.full(10, 0.3)) == 0.5


def test_transient_end_finds_where_an_exponential_start_up_dies_out():
    rng = np.random.default_rng(13)
    t = np.arange(80)
    noise = 0.01 * _ar1(rng, 0.3, t.size, 1)[0]
    x = 0.3 + 0.5 * np.exp(-t / 4.0) + noise  # below the noise after about 4 ln(50) = 16 cycles
    d = measure.transient_end(x)
    assert 8 <= d <= 30
    assert measure.steady(x)
    assert not measure.steady(x[:12])  # still falling: the minimum sits at the bound


def test_a_drifting_series_is_never_steady():
    x = np.linspace(0.2, 0.4, 40) + 1e-4 * np.random.default_rng(14).normal(size=40)
    assert measure.transient_end(x) == 20
    assert not measure.steady(x)
    stationary = 0.3 + 0.01 * np.random.default_rng(15).normal(size=40)
    assert measure.steady(stationary)


def test_a_noiseless_geometric_approach_is_steady_within_the_tolerance():
    """One grain settling onto its orbit: MSER alone calls it drifting for ever."""
    x = 0.99 - 0.3 * 0.8 ** np.arange(80)
    assert not measure.steady(x)  # no noise: the drift always outweighs it
    assert not measure.steady(x[:20], tolerance=1e-4)  # second half still spans 3e-3
    assert measure.steady(x, tolerance=1e-4)  # second half spans < 1e-6


def test_trend_recovers_a_known_slope_and_its_error():
    """The slope of a line under AR(1) noise: the estimate, and z near N(0, 1) without a line."""
    rng = np.random.default_rng(21)
    n, rho = 200, 0.5
    zs, slopes = [], []
    for _ in range(300):
        noise = _ar1(rng, rho, n, 1)[0]
        zs.append(measure.trend(noise).z)
        slopes.append(measure.trend(noise + 0.01 * np.arange(n)).slope)
    # the slope's error: sqrt(var 2 tau / sum t^2) = sqrt(4 / 666650) = 0.0025 a series
    assert np.mean(slopes) == pytest.approx(0.01, abs=3 * 0.0025 / math.sqrt(300))
    zs = np.array(zs)
    # the autocorrelated error makes z a unit normal: its spread within 20 % of 1, its mean near 0
    assert abs(np.std(zs) - 1.0) < 0.2
    assert abs(np.mean(zs)) < 0.2
    line = measure.trend(2.0 + 0.5 * np.arange(10.0))
    assert (line.slope, line.change, line.z) == (pytest.approx(0.5), pytest.approx(4.5), 0.0)
    assert measure.trend([1.0, 2.0, 3.0]).z == 0.0  # too short to tell


def test_steady_with_the_trend_test_waits_for_a_slow_rise():
    """A rise slow against the noise: MSER alone stops inside it, the trend test does not."""
    rng = np.random.default_rng(22)
    n = 40
    rise = 0.5 + 0.05 * (1.0 - np.exp(-np.arange(n) / 30.0))  # still rising at 40 cycles
    x = rise + 0.004 * rng.normal(size=n)
    ends_mser = [k for k in range(6, n + 1) if measure.steady(x[:k])]
    ends_trend = [k for k in range(6, n + 1) if measure.steady(x[:k], trend_z=2.0)]
    assert ends_mser and ends_mser[0] < 20  # MSER calls it steady early
    assert len(ends_trend) < len(ends_mser)
    assert not ends_trend or ends_trend[0] > ends_mser[0]
    flat = 0.5 + 0.004 * rng.normal(size=n)
    assert measure.steady(flat, trend_z=2.0)


@pytest.mark.parametrize("replicas", [2, 3, 5, 10])
@pytest.mark.parametrize("spread", [0.0, 1.0, 4.0])
def test_pooled_interval_covers_the_true_mean_at_95_percent(replicas, spread):
    """Synthetic replicas with a known fill-to-fill spread tau (in units of the runs' own
    errors, which differ run to run): the 95 % interval covers the true mean in 93-99.5 % of
    3000 sets, whether the spread is absent, equal to or four times the runs' errors."""
    rng = np.random.default_rng(replicas * 10 + int(spread))
    hits = 0
    sets = 3000
    for _ in range(sets):
        s = rng.uniform(0.5, 1.5, replicas)
        m = 2.0 + spread * rng.normal(size=replicas) + s * rng.normal(size=replicas)
        p = measure.pooled(m, s)
        hits += abs(p.mean - 2.0) <= p.half_width
    assert 0.93 <= hits / sets <= 0.995


def test_pooled_one_run_is_its_own_error_and_many_recover_the_spread():
    one = measure.pooled([1.5], [0.1])
    assert (one.mean, one.stderr, one.replicas) == (1.5, 0.1, 1)
    assert one.half_width == pytest.approx(1.96 * 0.1, rel=1e-3)
    assert math.isnan(one.between)
    rng = np.random.default_rng(1)
    m = 1.0 + 0.3 * rng.normal(size=4000) + 0.1 * rng.normal(size=4000)
    many = measure.pooled(m, np.full(4000, 0.1))
    assert many.between == pytest.approx(0.3, rel=0.05)
    assert many.stderr == pytest.approx(math.sqrt(0.3**2 + 0.1**2) / math.sqrt(4000), rel=0.05)
    # equal errors and no spread: the plain mean
    same = measure.pooled([1.0, 2.0, 3.0], [0.5, 0.5, 0.5])
    assert same.mean == pytest.approx(2.0)
    with pytest.raises(ValueError):
        measure.pooled([1.0, 2.0], [0.1])


def test_student_t95_against_the_table_and_the_normal_limit():
    assert measure.student_t95(1) == pytest.approx(12.706, abs=1e-3)
    assert measure.student_t95(60) == pytest.approx(2.0003, abs=2e-4)
    assert measure.student_t95(120) == pytest.approx(1.9799, abs=2e-4)
    assert measure.student_t95(10**7) == pytest.approx(1.95996, abs=1e-5)


@pytest.mark.parametrize(
    ("value", "error", "unit", "text"),
    [
        (0.045712, 0.00081, "m/s", "0.0457 +- 0.0008 m/s"),
        (0.76123, 0.0112, "", "0.761 +- 0.011"),
        (0.76123, 0.0096, "", "0.761 +- 0.010"),
        (-0.0021, 0.00019, "m/s", "-0.00210 +- 0.00019 m/s"),
        (12345.6, 234.0, "N", "12300 +- 200 N"),
        (0.5, 0.0, "kg/s", "0.5 kg/s"),
        (0.123456, math.nan, "", "0.1235"),
    ],
)
def test_with_error_keeps_the_digits_the_error_allows(value, error, unit, text):
    assert measure.with_error(value, error, unit) == text


def test_distinct_shows_the_digits_that_tell_a_value_from_its_bound():
    """Issue 48, item 5: "TOO SOFT ... 0.0089 > 0.0089" for 0.008948 against 0.008937."""
    assert measure.distinct(0.008948, 0.008937) == ("0.00895", "0.00894")
    assert measure.distinct(0.0123, 0.0089) == ("0.012", "0.0089")
    assert measure.distinct(0.5, 0.5) == ("0.5", "0.5")
