"""validation/_lib: the studies' shared statistics and cycle edges, and setup's ``spins``."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from dem.engine import setup
from dem.kernels.rigid import quat_to_matrix
from dem.physics import measure
from dem.scene.case import load_case

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import cycles, replicas  # noqa: E402

CASES = Path(__file__).resolve().parents[2] / "cases"


def test_replica_and_series_errors():
    v = np.array([0.101, 0.097, 0.104, 0.099, 0.1005])
    mean, se = replicas.replica_mean(v)
    assert mean == float(v.mean())
    assert se == float(v.std(ddof=1) / math.sqrt(v.size))  # bit for bit, as the studies had it
    assert replicas.replica_stderr(v) == se
    mean, se = replicas.series_mean(v)
    assert se == measure.correlated_stderr(v)[0]


def test_difference():
    d = replicas.difference(1.1, 0.03, 1.0, 0.04)
    assert d["dem_minus_liggghts"] == pytest.approx(0.1)
    assert d["combined_stderr"] == pytest.approx(0.05)
    assert d["sigma"] == pytest.approx(2.0)
    assert d["percent_of_liggghts"] == pytest.approx(10.0)


def test_cycle_edges_and_means():
    case = load_case(CASES / "sphere-bed")
    edges = cycles.cycle_edges(case, 3)
    per = cycles.steps_per_cycle(case)
    assert edges == [round(c * per) for c in range(4)]
    steps = np.arange(1, edges[-1] + 1)
    values = steps.astype(float)
    means = cycles.cycle_means(steps, values, edges, range(3))
    assert means[1] == pytest.approx(0.5 * (edges[1] + 1 + edges[2]))
    with pytest.raises(SystemExit, match="cycle 2"):
        cycles.cycle_means(steps[:-1], values[:-1], edges, range(3))
    assert math.isnan(cycles.cycle_means(steps[:0], values[:0], edges, [0], strict=False)[0])


@pytest.mark.validation
def test_from_grains_spins():
    case = load_case(CASES / "screw-trough")
    w = np.array([[3.0, -2.0, 5.0]])
    q = np.array([[0.9, 0.1, 0.3, -0.2]])
    q /= np.linalg.norm(q)
    sim = setup.from_grains(case, [[0.05, 0.0, 0.01]], orientations=q, spins=w)
    b = sim.bodies
    assert np.allclose(b.omega[0], w[0], rtol=1e-12, atol=0.0)
    r = quat_to_matrix(b.q[0])
    assert np.allclose(b.ang_mom[0], r @ (b.moments[0] * (r.T @ w[0])), rtol=1e-14, atol=0.0)
    sphere = load_case(CASES / "sphere-bed")
    sim = setup.from_grains(sphere, [[0.05, 0.0, 0.01]], spins=w)
    assert np.array_equal(sim.spheres.omega[0], w[0])
