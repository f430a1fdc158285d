"""Replicas stepped together on the GPU (dem.engine.gpu_replicas) against each replica alone.

Run with ``NUMBA_ENABLE_CUDASIM=1 pytest -m cuda``. Every replica has a cell grid of its own, so
a replica in a batch meets only its own spheres and is stepped by the single scene's code; the
batch rebuilds the pair lists whenever any replica needs it. Identical replicas rebuild on the
same steps as one alone: the same bits. Different replicas rebuild more often than alone, which
changes when a sphere's x is wrapped into the period, hence the last bits of the positions (a
wrap x - L is exact, x + L is not): equal to 1e-9 of the largest value.
"""

import os

import numpy as np
import pytest
from test_gpu_engine import _pair

from dem.engine.gpu_replicas import GpuReplicas

SIMULATOR = os.environ.get("NUMBA_ENABLE_CUDASIM") == "1"
pytestmark = pytest.mark.cuda
LAW = ("hertz_mindlin", 0.3, 0.5, 0.05, False, "impact", "surface", 2e-5)


@pytest.fixture(scope="module", autouse=True)
def _needs_cuda():
    from numba import cuda

    if not (SIMULATOR or cuda.is_available()):
        pytest.skip("no GPU, and NUMBA_ENABLE_CUDASIM=1 (numba's CUDA simulator) is not set")


def _close(batch, alone, exact):
    for name in ("x", "v", "omega", "force", "torque", "wall_hist"):
        got, ref = getattr(batch, name), getattr(alone, name)
        if exact and SIMULATOR:
            np.testing.assert_array_equal(got, ref)
        else:
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * np.max(np.abs(ref)))


def test_identical_replicas_are_the_single_run_to_the_bit():
    """Two copies of a driven 40-sphere packing stepped together: each is the scene stepped
    alone on the GPU, every array and the velocity."""
    alone = _pair(*LAW)[1]
    copies = [_pair(*LAW)[1] for _ in range(2)]
    batch = GpuReplicas(copies)
    for _ in range(2):
        v = batch.advance(40)
        alone.stats[:] = 0.0
        alone._advance(40)
        for r in range(2):
            part = batch.spheres(r)
            for name in ("x", "v", "omega", "force", "torque"):
                got = getattr(batch.sim.spheres, name)[part]
                ref = getattr(alone.spheres, name)
                if SIMULATOR:
                    np.testing.assert_array_equal(got, ref)
                else:
                    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * np.abs(ref).max())
            np.testing.assert_allclose(v[r], alone.cycle_velocity(), rtol=1e-12)
    assert batch.engine.builds >= 2


def test_different_replicas_each_as_alone():
    """Two different packings (seeds 3 and 4) stepped together: each as stepped alone."""
    singles = [_pair(*LAW, seed=seed)[1] for seed in (3, 4)]
    batch = GpuReplicas([_pair(*LAW, seed=seed)[1] for seed in (3, 4)])
    batch.advance(60)
    for r, sim in enumerate(singles):
        sim._advance(60)
        part = batch.spheres(r)
        for name in ("x", "v", "omega"):
            ref = getattr(sim.spheres, name)
            got = getattr(batch.sim.spheres, name)[part]
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * np.abs(ref).max())
    # no pair joins two replicas
    pairs = batch.sim.pairs
    k = pairs.n_pairs
    scene = batch.scene
    assert k > 0 and np.all(scene[pairs.pair_i[:k]] == scene[pairs.pair_j[:k]])


def test_replicas_must_share_the_scene():
    a = _pair(*LAW)[1]
    b = _pair(*LAW[:-1], 1e-5)[1]
    with pytest.raises(ValueError, match="replica 1 differs from replica 0 in its time step"):
        GpuReplicas([a, b])
