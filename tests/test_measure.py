"""Per-cycle statistics (dem.measure) and the damping relation shared with the LIGGGHTS export."""

import math

import numpy as np
import pytest

from dem import measure
from dem.io.liggghts import damping_ratio
from dem.kernels.contacts import damping_beta


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
    stat = measure.conveying_velocity(v, amplitude=0.5e-3, omega=2 * math.pi * 60, angle=25.0)
    assert (mean[-1], stderr[-1]) == (stat.mean, stat.stderr)
    assert math.isnan(stderr[0]) and mean[0] == v[0]


def test_liggghts_damping_ratio_is_minus_the_kernels_beta():
    for e in np.linspace(0.0, 1.0, 41):
        assert damping_ratio(e) == -damping_beta(e)
