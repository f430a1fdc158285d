"""The GPU sphere-force kernel against the CPU engine, in numba's CUDA simulator or on a GPU.

Run with ``NUMBA_ENABLE_CUDASIM=1 pytest -m cuda`` (the variable must be set before numba.cuda is
first imported, hence on the command line). In the simulator the kernel runs as Python and the
contact law as the CPU's compiled code, with the CPU engine's terms in the CPU engine's order:
the forces, torques and history must be the CPU engine's to the bit. On a GPU the compiler fuses
multiplies and adds (FMA), which moves the last bits: there the tolerance is ``GPU_RTOL`` of the
largest force (not yet run on a GPU).
"""

import os

import numpy as np
import pytest
from test_contacts import LENGTH, WIDTH, _coefficients, _law, _packing

from dem.engine.simulation import Simulation
from dem.engine.state import Spheres
from dem.kernels.integrate import body_acceleration
from dem.scene.trough import Trough

SIMULATOR = os.environ.get("NUMBA_ENABLE_CUDASIM") == "1"
#: On a GPU: FMA contraction changes rounding, ~1e-16 per operation, and a contact's history
#: carries it into the second step; 1e-12 of the largest force leaves room for that.
GPU_RTOL = 1e-12

pytestmark = pytest.mark.cuda


@pytest.fixture(scope="module")
def gpu_forces():
    """:func:`dem.kernels.cuda.forces.sphere_forces`, or a skip without a GPU or the simulator."""
    from numba import cuda

    if not (SIMULATOR or cuda.is_available()):
        pytest.skip("no GPU, and NUMBA_ENABLE_CUDASIM=1 (numba's CUDA simulator) is not set")
    from dem.kernels.cuda.forces import sphere_forces

    return sphere_forces


def _assert_same(gpu, cpu, scale):
    if SIMULATOR:
        np.testing.assert_array_equal(gpu, cpu)
    else:
        np.testing.assert_allclose(gpu, cpu, rtol=0, atol=GPU_RTOL * scale)


@pytest.mark.parametrize("arm", ["surface", "lammps"])
@pytest.mark.parametrize("tangential", ["coulomb", "liggghts", "impact"])
@pytest.mark.parametrize(
    ("model", "e", "mu", "mu_roll", "limit", "dt"),
    [
        ("linear", 0.5, 0.3, 0.0, False, 1e-5),
        ("linear", 0.0, 0.3, 0.1, True, 1e-3),
        ("hertz_mindlin", 0.3, 0.5, 0.05, False, 1e-5),
        ("hertz_mindlin", 0.9, 0.2, 0.0, True, 1e-3),
    ],
)
def test_gpu_forces_equal_the_cpu_engine(
    gpu_forces, model, e, mu, mu_roll, limit, dt, tangential, arm
):
    """Forces, torques and the new pair and wall history of a 40-sphere periodic packing with
    walls equal ``Simulation.compute_forces``'s, twice: the second time after a move and a
    rebuild, from the history both carried over. The laws and lever arms of
    test_contacts.py's brute-force comparison, plus "impact" (five floats of history)."""
    rng = np.random.default_rng(7)
    x, r = _packing(rng)
    law = _law(model, _coefficients(model, e, mu, mu_roll, limit, tangential, arm))
    spheres = Spheres.create(x, r, 2500.0)
    sim = Simulation(spheres, Trough(LENGTH, WIDTH, inclination=0.1), law, dt)
    touching = 0
    for _ in range(2):
        spheres.v[:] = rng.normal(0, 0.3, (len(r), 3))
        spheres.omega[:] = rng.normal(0, 300.0, (len(r), 3))
        sim.engine.build()  # the pair list the CPU step will use (a rebuild is deterministic)
        pairs = sim.pairs
        n_pairs = pairs.n_pairs
        pair_i, pair_j = pairs.pair_i[:n_pairs].copy(), pairs.pair_j[:n_pairs].copy()
        a_body = np.array(body_acceleration(sim.drive_time, sim.gravity, sim.drive_array()))
        force, torque, hist, wall_hist = gpu_forces(
            law.model_id, law.params, spheres.x.copy(), spheres.v.copy(), spheres.omega.copy(),
            spheres.radius, spheres.mass, pair_i, pair_j, n_pairs, pairs.hist[:n_pairs].copy(),
            spheres.wall_hist.copy(), LENGTH, WIDTH, sim.geom.back, dt, a_body,
        )  # fmt: skip
        sim.compute_forces()
        assert pairs.n_pairs == n_pairs
        np.testing.assert_array_equal(pairs.pair_i[:n_pairs], pair_i)
        np.testing.assert_array_equal(pairs.pair_j[:n_pairs], pair_j)
        scale = np.max(np.abs(spheres.force))
        _assert_same(force, spheres.force, scale)
        _assert_same(torque, spheres.torque, scale * r.max())
        _assert_same(hist, pairs.hist[:n_pairs], np.max(np.abs(pairs.hist[:n_pairs])))
        _assert_same(wall_hist, spheres.wall_hist, np.max(np.abs(spheres.wall_hist)))
        touching += np.count_nonzero(np.any(hist != 0.0, axis=1))
        spheres.x += rng.normal(0, 1e-4, spheres.x.shape)
    assert touching > 20  # many contacts carry history into the second call
    assert np.any(wall_hist != 0.0)  # and walls


def test_slots_hold_the_compact_list_in_key_order():
    """The CPU engine's compact list (sorted by key i n + j) goes to per-sphere slots and back
    unchanged: slot order is key order."""
    from dem.kernels.cuda.forces import compact_to_slots, slots_to_compact

    pair_i = np.array([0, 0, 1, 2, 3, 3])
    pair_j = np.array([1, 3, 3, 3, 4, 5])
    hist = np.arange(18.0).reshape(6, 3)
    nbr, count, slot_hist, slots = compact_to_slots(pair_i, pair_j, hist, 6, 6)
    assert slots == 16
    assert count.tolist() == [2, 1, 1, 2, 0, 0]
    assert nbr[3 * slots : 3 * slots + 2].tolist() == [4, 5]
    pi, pj, back = slots_to_compact(nbr, count, slot_hist, slots)
    assert pi.tolist() == pair_i.tolist() and pj.tolist() == pair_j.tolist()
    np.testing.assert_array_equal(back, hist)
    with pytest.raises(ValueError, match="2 pairs, more than the 1 slots"):
        compact_to_slots(pair_i, pair_j, hist, 6, 6, slots=1)
