"""Replicas stepped together on the GPU (dem.engine.gpu.replicas) against each replica alone.

Run with ``NUMBA_ENABLE_CUDASIM=1 pytest -m cuda``. Every replica has a cell grid of its own, so
a replica in a batch meets only its own spheres and is stepped by the single scene's code; the
batch rebuilds the pair lists whenever any replica needs it. Identical replicas rebuild on the
same steps as one alone: the same bits. Different replicas rebuild more often than alone, which
changes when a sphere's x is wrapped into the period, hence the last bits of the positions (a
wrap x - L is exact, x + L is not): equal to 1e-9 of the largest value.
"""

import copy
import os

import numpy as np
import pytest
from test_gpu_engine import _clump_pair, _mesh_pair, _pair

from dem.engine.gpu.replicas import GpuReplicas
from dem.errors import SimulationError

SIMULATOR = os.environ.get("NUMBA_ENABLE_CUDASIM") == "1"
pytestmark = pytest.mark.cuda
LAW = ("hertz_mindlin", 0.3, 0.5, 0.05, False, "impact", "surface", 2e-5)


@pytest.fixture(scope="module", autouse=True)
def _needs_cuda():
    from numba import cuda

    if not (SIMULATOR or cuda.is_available()):
        pytest.skip("no GPU, and NUMBA_ENABLE_CUDASIM=1 (numba's CUDA simulator) is not set")


def _close(batch, alone, exact, names=("x", "v", "omega", "force", "torque", "wall_hist")):
    for name in names:
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
        alone.advance(40)
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
    assert batch.step_scheme() == {"kernel": "step_kernel"}  # 80 spheres: nothing to time


def test_different_replicas_each_as_alone():
    """Two different packings (seeds 3 and 4) stepped together: each as stepped alone."""
    singles = [_pair(*LAW, seed=seed)[1] for seed in (3, 4)]
    batch = GpuReplicas([_pair(*LAW, seed=seed)[1] for seed in (3, 4)])
    batch.advance(60)
    for r, sim in enumerate(singles):
        sim.advance(60)
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


def test_replicas_of_other_drives_and_inclines_each_as_alone():
    """A sweep as one batch: the same packing under drive angles of 20 and 50 deg and inclines
    of 0 and 0.1 rad, each replica with its own body acceleration: each as stepped alone (to
    1e-9, the wraps of a superset of rebuilds), its momentum too."""
    sweep = [(20.0, 0.0), (50.0, 0.1)]
    singles = [_pair(*LAW, angle=a, incline=i)[1] for a, i in sweep]
    batch = GpuReplicas([_pair(*LAW, angle=a, incline=i)[1] for a, i in sweep])
    assert batch.run(50) == 50
    for r, sim in enumerate(singles):
        sim.run(50)
        _close(batch.sims[r].spheres, sim.spheres, exact=False)
        np.testing.assert_allclose(batch.sims[r].stats[0], sim.stats[0], rtol=1e-9)
    a, b = (s.spheres.v for s in singles)
    assert np.max(np.abs(a - b)) > 1e-3  # the drives did differ


def test_replicas_must_share_the_scene():
    a = _pair(*LAW)[1]
    b = _pair(*LAW[:-1], 1e-5)[1]
    with pytest.raises(ValueError, match="replica 1 differs from replica 0 in its time step"):
        GpuReplicas([a, b])
    import dataclasses
    import math

    from dem.physics import drive

    c = _pair(*LAW)[1]
    faster = drive.Motion(2 * math.pi * 60.0, c.trough.motion.components)
    c.trough = dataclasses.replace(c.trough, motion=faster)
    with pytest.raises(ValueError, match="replica 1 differs from replica 0 in its drive period"):
        GpuReplicas([a, c])


def test_run_scatters_each_replica_into_its_own_simulation():
    """``run`` (with the checks) leaves every replica's Simulation as if it had run alone: its
    spheres, pair list, springs, CSR index, step and momentum sums (the sums in another order:
    1e-12)."""
    alone = _pair(*LAW)[1]
    copies = [_pair(*LAW)[1] for _ in range(2)]
    batch = GpuReplicas(copies)
    for _ in range(2):
        assert batch.run(30) == 30
        alone.run(30)
        for rs in copies:
            _close(rs.spheres, alone.spheres, exact=True)
            k = alone.pairs.n_pairs
            assert rs.pairs.n_pairs == k and rs.pairs.builds == alone.pairs.builds
            for name in ("pair_i", "pair_j", "hist", "part_slot"):
                np.testing.assert_array_equal(
                    getattr(rs.pairs, name)[:k], getattr(alone.pairs, name)[:k]
                )
            np.testing.assert_array_equal(rs.pairs.part_start, alone.pairs.part_start)
            np.testing.assert_array_equal(rs.pairs.x_ref, alone.pairs.x_ref)
            assert rs.step_index == alone.step_index
            np.testing.assert_allclose(rs.stats[:2], alone.stats[:2], rtol=1e-12)
            assert rs.cycle_velocity() == pytest.approx(alone.cycle_velocity(), rel=1e-12)


def _resting(seed, speed):
    """Four spheres apart on the floor of a still trough, sliding at ``speed`` along x (rolling
    friction stops them once they roll)."""
    from test_contacts import LENGTH, WIDTH, _coefficients, _law

    from dem.engine.simulation import Simulation
    from dem.engine.state import Spheres
    from dem.scene.trough import Trough

    rng = np.random.default_rng(seed)
    r = np.full(4, 1.0e-3)
    x = np.column_stack([(np.arange(4) + 0.5) * LENGTH / 4, rng.uniform(-0.003, 0.003, 4), r])
    spheres = Spheres.create(x, r, 2500.0)
    spheres.v[:, 0] = speed
    law = _law("linear", _coefficients("linear", 0.3, 0.5, 0.3, False, "coulomb", "surface"))
    return Simulation(spheres, Trough(LENGTH, WIDTH), law, 2e-5)


def test_settle_rests_every_replica_and_starts_the_drive_together():
    """The batch settles until its last replica rests (friction stops the slower replica
    first), then starts the drive in all at once; a replica that does not rest in time is
    named."""
    import math

    from dem import config

    copies = [_resting(1, 0.002), _resting(2, 0.01)]
    batch = GpuReplicas(copies)
    threshold = config.DEM_SETTLE_SPEED_FRACTION * math.sqrt(config.GRAVITY * 1.0e-3)
    assert copies[1].rms_speed() > threshold
    rested = batch.settle(chunk_time=2e-4, max_time=0.05)
    assert 0 < rested < 0.05
    assert all(rs.rms_speed() < threshold for rs in copies)
    batch.start_drive()
    assert all(rs.drive_on and rs.drive_start_step == batch.sim.step_index for rs in copies)
    moving = GpuReplicas([_resting(1, 0.0), _resting(2, 0.5)])
    with pytest.raises(SimulationError, match=r"replicas \[1\] did not come to rest"):
        moving.settle(chunk_time=2e-4, max_time=4e-4)


def test_clump_replicas_are_the_single_run_to_the_bit():
    """Two copies of 20 driven screws stepped together and scattered: each replica's bodies,
    members, pairs and momentum sums are the scene stepped alone on the GPU."""
    # eps_n = 0.3: the scene's random placement starts screw 12 1.95 radii into the side wall;
    # the plastic contact of eps_n = 0 keeps such an overlap as a dent (it pushes only against
    # an approach), so its centre stays past the wall and the replicas' overlap check stops
    # the batch; the dashpot of eps_n = 0.3 pushes it out. The other clump tests compare the
    # plastic contact's bits by raw steps, which do not check
    law = ("hertz_mindlin", 0.3, 0.5, "impact", True)
    alone = _clump_pair(*law)[1]
    copies = [_clump_pair(*law)[1] for _ in range(2)]
    batch = GpuReplicas(copies)
    assert batch.sim.bodies.n == 2 * alone.bodies.n
    for _ in range(2):
        assert batch.run(30) == 30
        alone.run(30)
        for rs in copies:
            _close(rs.spheres, alone.spheres, exact=True)
            _close(rs.bodies, alone.bodies, True, ("x", "v", "q", "ang_mom", "omega", "force",
                                                   "torque"))  # fmt: skip
            _same_pairs(rs, alone)
    v = batch.advance(20)
    alone.stats[:] = 0.0
    alone.advance(20)
    np.testing.assert_allclose(v, alone.cycle_velocity(), rtol=1e-12)


def _same_pairs(rs, alone):
    """A scattered replica's pair list, springs and momentum sums against the scene alone."""
    k = alone.pairs.n_pairs
    assert rs.pairs.n_pairs == k
    np.testing.assert_array_equal(rs.pairs.pair_j[:k], alone.pairs.pair_j[:k])
    np.testing.assert_array_equal(rs.pairs.hist[:k], alone.pairs.hist[:k])
    np.testing.assert_allclose(rs.stats[:2], alone.stats[:2], rtol=1e-12)


def test_replicas_in_a_trough_mesh_are_the_single_run_to_the_bit():
    """Two copies of 40 spheres that fell into a triangle pan on the CPU (so that they start on
    the mesh with springs), stepped together through the GPU's mesh step and scattered: each
    replica's spheres, mesh springs and their normals, pairs and momentum sums are the scene
    stepped on alone by the CPU engine (the GPU's mesh step is the CPU's to the bit in the
    simulator: tests/engine/test_gpu_engine.py)."""
    alone = _mesh_pair("hertz_mindlin", 0.3, 0.5, "impact")[0]
    alone.run(60)  # onto the pan
    on_mesh = np.any(alone.spheres.mesh_normal != 0.0, axis=1).reshape(alone.spheres.n, -1)
    assert np.count_nonzero(on_mesh.any(axis=1)) >= 5
    copies = [copy.deepcopy(alone) for _ in range(2)]
    for rs in copies:
        rs.device = "cuda"
    batch = GpuReplicas(copies)
    assert batch.sim.mesh is not alone.mesh and batch.sim.spheres.mesh_hist.shape[0] == (
        2 * alone.spheres.mesh_hist.shape[0]
    )  # fmt: skip
    steps = 12 if SIMULATOR else 40
    assert batch.run(steps) == steps
    alone.run(steps)
    assert batch.step_scheme() == {"kernel": "mesh_step_kernel"}
    for rs in copies:
        _close(rs.spheres, alone.spheres, exact=True)
        _close(rs.spheres, alone.spheres, True, ("mesh_hist", "mesh_normal"))
        _same_pairs(rs, alone)
    assert np.any(copies[1].spheres.mesh_hist != 0.0)


def test_replicas_must_share_the_trough_mesh():
    flat = _pair(*LAW)[1]
    pan = _mesh_pair("hertz_mindlin", 0.3, 0.5, "impact")[1]
    with pytest.raises(ValueError, match="replica 1 differs from replica 0 in its trough mesh"):
        GpuReplicas([flat, pan])
