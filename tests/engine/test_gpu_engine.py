"""The GPU engine (device = "cuda") against the CPU engine, step for step.

Run with ``NUMBA_ENABLE_CUDASIM=1 pytest -m cuda`` (the variable must be set before numba.cuda is
first imported, hence on the command line). In numba's CUDA simulator the kernels run as Python
and the contact law as the CPU's compiled code, with the CPU engine's operations in its order:
positions, velocities, spins, forces, the pair list and every spring must be the CPU engine's
to the bit after many steps and several neighbour rebuilds. The per-step momentum sum is summed
per sphere over the steps on the GPU and per step over the spheres on the CPU, a different order
of the same terms: equal to 1e-12. On a GPU the compiler fuses multiplies and adds (FMA): there
the trajectories are compared after few steps to ``GPU_RTOL`` (not yet run on a GPU in CI).
"""

import math
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from dem.engine.simulation import Simulation
from dem.engine.state import Bodies, Spheres
from dem.physics import drive
from dem.scene import shapes
from dem.scene.trough import Trough

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "kernels"))
from test_contacts import LENGTH, WIDTH, _coefficients, _law, _packing  # noqa: E402

SIMULATOR = os.environ.get("NUMBA_ENABLE_CUDASIM") == "1"
GPU_RTOL = 1e-9

pytestmark = pytest.mark.cuda


@pytest.fixture(scope="module", autouse=True)
def _needs_cuda():
    from numba import cuda

    if not (SIMULATOR or cuda.is_available()):
        pytest.skip("no GPU, and NUMBA_ENABLE_CUDASIM=1 (numba's CUDA simulator) is not set")


def _pair(model, e, mu, mu_roll, limit, tangential, arm, dt, seed=3, angle=30.0, incline=0.1):
    """Two simulations of one 40-sphere periodic packing, driven and inclined, with random
    velocities and spins: the first on the CPU, the second on the GPU."""
    rng = np.random.default_rng(seed)
    x, r = _packing(rng)
    v = rng.normal(0, 0.4, (len(r), 3))
    w = rng.normal(0, 200.0, (len(r), 3))
    law = _law(model, _coefficients(model, e, mu, mu_roll, limit, tangential, arm))
    motion = drive.Motion(2 * math.pi * 50.0, (drive.Component(2e-3, math.radians(angle)),))
    sims = []
    for device in ("cpu", "cuda"):
        spheres = Spheres.create(x, r, 2500.0)
        spheres.v[:] = v
        spheres.omega[:] = w
        trough = Trough(LENGTH, WIDTH, inclination=incline, motion=motion)
        sim = Simulation(spheres, trough, law, dt)
        sim.device = device
        sim.start_drive()
        sims.append(sim)
    return sims


def _same(gpu, cpu, scale=1.0):
    if SIMULATOR:
        np.testing.assert_array_equal(gpu, cpu)
    else:
        np.testing.assert_allclose(gpu, cpu, rtol=0, atol=GPU_RTOL * max(scale, 1e-300))


def _compare(cpu, gpu):
    a, b = cpu.spheres, gpu.spheres
    for name in ("x", "v", "omega", "force", "torque", "wall_hist"):
        ref = getattr(a, name)
        _same(getattr(b, name), ref, np.max(np.abs(ref)))
    k = cpu.pairs.n_pairs
    assert gpu.pairs.n_pairs == k
    assert gpu.pairs.builds == cpu.pairs.builds
    for name in ("pair_i", "pair_j"):
        np.testing.assert_array_equal(getattr(gpu.pairs, name)[:k], getattr(cpu.pairs, name)[:k])
    _same(gpu.pairs.hist[:k], cpu.pairs.hist[:k], np.max(np.abs(cpu.pairs.hist[:k])))
    np.testing.assert_array_equal(gpu.pairs.x_ref, cpu.pairs.x_ref)
    np.testing.assert_array_equal(gpu.pairs.part_start, cpu.pairs.part_start)
    np.testing.assert_array_equal(gpu.pairs.part_slot[: 2 * k], cpu.pairs.part_slot[: 2 * k])
    np.testing.assert_allclose(gpu.stats[:2], cpu.stats[:2], rtol=1e-12)


@pytest.mark.parametrize(
    ("model", "e", "mu", "mu_roll", "limit", "tangential", "arm", "dt"),
    [
        ("linear", 0.5, 0.3, 0.0, False, "coulomb", "surface", 2e-5),
        ("linear", 0.0, 0.3, 0.1, True, "liggghts", "lammps", 2e-5),
        ("hertz_mindlin", 0.3, 0.5, 0.05, False, "impact", "surface", 2e-5),
        ("hertz_mindlin", 0.9, 0.2, 0.0, True, "coulomb", "lammps", 2e-5),
    ],
)
def test_gpu_steps_equal_the_cpu_engine(model, e, mu, mu_roll, limit, tangential, arm, dt):
    """Three calls of 40 steps each (the state goes to the host and back between them) through
    several neighbour rebuilds, the drive on, walls, periodic in x: the same bits."""
    cpu, gpu = _pair(model, e, mu, mu_roll, limit, tangential, arm, dt)
    steps = 40 if SIMULATOR else 5
    springs = False  # whether the history held a spring at a comparison
    for _ in range(3):
        cpu.advance(steps)
        gpu.advance(steps)
        springs |= bool(np.any(cpu.pairs.hist[: cpu.pairs.n_pairs] != 0.0))
        # the instability check's deepest overlap, from the pairs kept on the GPU
        assert gpu.engine.pairs_on_device
        deep_gpu, deep_cpu = gpu._deepest(), cpu._deepest()
        assert gpu.engine.pairs_on_device  # the check did not copy the pairs back
        assert deep_gpu[1:3] == deep_cpu[1:3]
        _same(np.array(deep_gpu[0]), np.array(deep_cpu[0]))
        _same(deep_gpu[3], deep_cpu[3])
        _compare(cpu, gpu)
    assert cpu.pairs.builds >= 3  # the history went through rebuilds
    # and held springs while it was compared (the drive scatters the bed: by the last call the
    # linear coulomb bed's few contacts are new, and since the spring's reset stores no force
    # along the slip, a new contact's spring can be zero)
    assert springs
    # steps queued after a rebuild's trip did nothing and were relaunched after the rebuild
    assert gpu.engine.skipped > 0


@pytest.mark.parametrize("keep", [16, 1])
def test_gpu_compact_step_gives_the_same_bits(keep):
    """The step that gathers each block's touching candidates before the law (one pass a
    block, or with ``keep`` 1 a pass for every touching candidate of the most crowded sphere)
    against the CPU engine, spheres (through rebuilds with 16), walls touched: the same bits."""
    cpu, gpu = _pair("hertz_mindlin", 0.3, 0.5, 0.05, False, "impact", "surface", 2e-5)
    engine = gpu.engine
    engine.compact = True
    engine.compact_keep = keep
    steps = (40 if keep > 1 else 6) if SIMULATOR else 5  # the simulator's barriers are slow
    for _ in range(2):
        cpu.advance(steps)
        gpu.advance(steps)
        _compare(cpu, gpu)
    assert keep == 1 or cpu.pairs.builds >= 2
    assert np.any(cpu.pairs.hist[: cpu.pairs.n_pairs] != 0.0)
    assert np.any(cpu.spheres.wall_hist != 0.0)
    assert keep > 1 or np.max(cpu.contact_counts()) > 1  # spheres that took several passes


def test_gpu_times_the_plain_and_compact_steps_and_keeps_the_faster(monkeypatch):
    """With ``compact`` None (the opt-in trial) a scene of ``tune_min`` spheres or more runs its
    chunks alternately with the plain and the compact step, times them (here on a clock that charges
    each launch by its kernel, the compact one a tenth) and keeps the faster for the rest of the
    run, across calls, until the trial runs again (the costs swapped: the plain wins): every
    chunk, whichever step ran it, gives the CPU engine's bits."""
    from dem.engine.gpu import schemes as gpu_module

    faster = "compact"  # then "plain", in the second trial
    cpu, gpu = _pair("hertz_mindlin", 0.3, 0.5, 0.05, False, "impact", "surface", 2e-5)
    engine = gpu.engine
    assert engine.compact is False  # the plain step unless a run opts in
    engine.compact = None
    engine.tune_min = 1  # the 40 spheres: below the default, which would not time them
    monkeypatch.setattr(gpu_module, "TUNE_CHUNKS", 2)  # fewer of the simulator's slow compact
    monkeypatch.setattr(gpu_module, "TUNE_LAUNCHES", 8)  # steps (its barriers run as threads)
    names = {"plain": "step_kernel", "compact": "compact_step_kernel"}
    cost = {"compact_step_kernel": 0.1, "step_kernel": 1.0}
    launched = {name: 0 for name in cost}
    real_step = engine._step

    def counted_step(*args):
        launched[engine._chosen[0].py_func.__name__] += 1
        real_step(*args)

    engine._step = counted_step
    engine._clock = lambda: sum(cost[k] * launched[k] for k in cost)
    per_call = 20 if SIMULATOR else 5
    calls = 0
    while engine.tuned is None:
        assert calls < 8, f"no decision after {calls} calls: {engine._trial}"
        cpu.advance(per_call)
        gpu.advance(per_call)
        _compare(cpu, gpu)
        calls += 1
    assert engine.tuned["chose"] == faster, (engine.tuned, engine._trial, launched)
    us = engine.tuned["us_per_step"]
    assert us[faster] == pytest.approx(1e5) and us[next(n for n in us if n != faster)] == 1e6
    assert min(launched.values()) >= gpu_module.TUNE_LAUNCHES
    before = dict(launched)
    cpu.advance(per_call)
    gpu.advance(per_call)
    _compare(cpu, gpu)
    assert launched[names[faster]] > before[names[faster]]
    slower = next(k for k in launched if k != names[faster])
    assert launched[slower] == before[slower]  # the decision held in the next call
    assert engine.step_scheme() == {"kernel": names[faster], "trial_us_per_step": us,
                                    "trials": 1}  # fmt: skip
    # TUNE_EVERY launches on, the trial runs again: the costs swapped, the other step wins
    monkeypatch.setattr(gpu_module, "TUNE_EVERY", 10)
    cost = {k: 1.1 - c for k, c in cost.items()}
    calls = 0
    while engine.tuned["trials"] < 2:
        assert calls < 8, f"no second decision after {calls} calls: {engine._trial}"
        cpu.advance(per_call)
        gpu.advance(per_call)
        _compare(cpu, gpu)
        calls += 1
    assert engine.tuned["chose"] == "plain"
    assert engine.step_scheme()["kernel"] == "step_kernel"


@pytest.mark.parametrize(("compact", "tune_min"), [(False, 1), (None, 20_000)])
def test_gpu_runs_the_plain_step_untimed_unless_a_trial_is_asked_for(compact, tune_min):
    """The default (``compact`` False) runs the plain step, untimed whatever the scene's size;
    with the trial asked for (None), a scene below ``tune_min`` spheres is not timed either."""
    cpu, gpu = _pair("linear", 0.5, 0.3, 0.0, False, "coulomb", "surface", 2e-5)
    engine = gpu.engine
    engine.compact, engine.tune_min = compact, tune_min
    gpu.advance(3)
    assert engine.tuned is None and engine._trial is None
    assert engine.step_scheme() == {"kernel": "step_kernel"}


def test_gpu_compact_step_refuses_what_it_cannot_do():
    cpu, gpu = _pair("linear", 0.5, 0.3, 0.0, False, "coulomb", "surface", 2e-5)
    engine = gpu.engine
    engine.compact, engine.compact_keep = True, 0
    with pytest.raises(ValueError, match="1 to 16"):
        gpu.advance(2)


def _pan():
    """A pan across the section: flat bottom, 34-degree slopes, vertical sides (14 triangles
    along three segments in x, the mesh periodic in x)."""
    from dem.scene.mesh import TriangleMesh, extrude

    h = 0.5 * WIDTH
    profile = [[-h, 0.012], [-h, 0.002], [-0.002, 0.0], [0.002, 0.0], [h, 0.002], [h, 0.012]]
    m = extrude(profile, LENGTH, 3)
    return TriangleMesh(m.points[m.cells[0].data], period=LENGTH, source="pan")


def _mesh_pair(model, e, mu, tangential, seed=5):
    """Two simulations of the 40-sphere packing lifted 2 mm into :func:`_pan`, driven and
    inclined, with random velocities and spins: CPU, then GPU."""
    rng = np.random.default_rng(seed)
    x, r = _packing(rng)
    x[:, 2] += 2e-3
    v = rng.normal(0, 0.4, (len(r), 3))
    w = rng.normal(0, 200.0, (len(r), 3))
    law = _law(model, _coefficients(model, e, mu, 0.0, False, tangential, "surface"))
    motion = drive.Motion(2 * math.pi * 50.0, (drive.Component(2e-3, math.radians(30.0)),))
    sims = []
    for device in ("cpu", "cuda"):
        spheres = Spheres.create(x, r, 2500.0)
        spheres.v[:] = v
        spheres.omega[:] = w
        trough = Trough(LENGTH, WIDTH, inclination=0.1, motion=motion)
        sim = Simulation(spheres, trough, law, 2e-5, mesh=_pan())
        sim.device = device
        sim.start_drive()
        sims.append(sim)
    return sims


def test_gpu_steps_in_a_mesh_equal_the_cpu_engine():
    """Spheres in a triangle-mesh pan (the closest points, the rule against counting a contact
    twice, the slots that carry a spring from one triangle to the next) through a rebuild: the
    same bits as the CPU, the mesh springs and their normals included."""
    cpu, gpu = _mesh_pair("hertz_mindlin", 0.3, 0.5, "impact")
    gpu.engine.compact, gpu.engine.tune_min = None, 1  # no trial all the same: one mesh step
    steps = 15 if SIMULATOR else 5  # the simulator runs the mesh's Python: slow
    on_mesh = 0
    for _ in range(2):
        cpu.advance(steps)
        gpu.advance(steps)
        _compare(cpu, gpu)
        for name in ("mesh_hist", "mesh_normal"):
            ref = getattr(cpu.spheres, name)
            _same(getattr(gpu.spheres, name), ref, np.max(np.abs(ref)))
        slots = np.any(cpu.spheres.mesh_normal != 0.0, axis=1).reshape(cpu.spheres.n, -1)
        on_mesh = max(on_mesh, int(np.count_nonzero(slots.any(axis=1))))
        assert np.any(cpu.spheres.mesh_hist != 0.0)  # springs on the mesh
    assert on_mesh >= 5
    assert cpu.pairs.builds >= 2
    assert gpu.engine._trial is None
    assert gpu.engine.step_scheme() == {"kernel": "mesh_step_kernel"}
    with pytest.raises(ValueError, match="mesh step has one thread a sphere"):
        gpu.engine.compact = True
        gpu.advance(1)


def test_gpu_takes_up_a_state_the_host_changed():
    """A change to the host's arrays between calls (a restart, a refill) is uploaded, pair list
    and springs included, and the GPU goes on as the CPU does."""
    cpu, gpu = _pair("hertz_mindlin", 0.3, 0.5, 0.0, False, "coulomb", "surface", 2e-5)
    for sim in (cpu, gpu):
        sim.advance(20)
        sim.spheres.v[:, 0] += 0.05
    for sim in (cpu, gpu):
        sim.advance(20)
    _compare(cpu, gpu)


def test_gpu_grows_its_slots_and_keeps_the_springs():
    """A build that overflows the slots (one start slot a sphere) regrows them and keeps the
    history: the same bits as the CPU engine."""
    import dem.engine.gpu.buffers as gpu_engine

    start = gpu_engine.START_SLOTS, gpu_engine.START_CELL
    gpu_engine.START_SLOTS, gpu_engine.START_CELL = 1, 1
    try:
        cpu, gpu = _pair("linear", 0.5, 0.3, 0.0, False, "liggghts", "surface", 2e-5, seed=5)
        for _ in range(2):
            cpu.advance(30)
            gpu.advance(30)
            _compare(cpu, gpu)
        assert gpu.engine.slots > 1 and gpu.engine.cell_cap > 1
    finally:
        gpu_engine.START_SLOTS, gpu_engine.START_CELL = start


def _screws(rng, template, n, depth=3e-5):
    """Up to n screws at random in the section, no two overlapping by more than ``depth``."""
    x, q, members = [], [], []
    for _ in range(5000):
        if len(x) == n:
            break
        xi = rng.uniform([0.0, -0.003, 0.0012], [LENGTH, 0.003, 0.005])
        qi = rng.normal(size=4)
        bodies, spheres = Bodies.create(template, xi[None], qi[None])
        ok = np.all(spheres.x[:, 2] > 0.8 * spheres.radius)
        for other in members if ok else ():
            d = spheres.x[:, None, :] - other.x[None, :, :]
            d[..., 0] -= LENGTH * np.round(d[..., 0] / LENGTH)
            gap = np.linalg.norm(d, axis=2) - spheres.radius[:, None] - other.radius[None, :]
            if gap.min() < -depth:
                ok = False
                break
        if ok:
            x.append(xi)
            q.append(qi)
            members.append(spheres)
    return np.array(x), np.array(q)


def _clump_pair(model, e, mu, tangential, rotation=True, seed=4, mesh=False):
    """Two simulations of 20 small screws (a head and shank spheres) thrown into one periodic
    section with random velocities and angular momenta, driven and inclined: CPU, then GPU.
    With ``mesh`` they are lifted 2 mm into :func:`_pan`."""
    rng = np.random.default_rng(seed)
    template = shapes.screw(0.006, 0.0006, 0.0011, density=7800.0)
    x, q = _screws(rng, template, 20)
    x[:, 2] += 2e-3 if mesh else 0.0
    n = len(x)
    v = rng.normal(0, 0.3, (n, 3))
    law = _law(model, _coefficients(model, e, mu, 0.0, False, tangential, "surface"))
    motion = drive.Motion(2 * math.pi * 50.0, (drive.Component(2e-3, math.radians(30.0)),))
    sims = []
    for device in ("cpu", "cuda"):
        bodies, spheres = Bodies.create(template, x, q)
        bodies.v[:] = v
        bodies.ang_mom[:] = rng.normal(0, 1.0, (n, 3)) * 100.0 * bodies.moments if not sims else (
            sims[0].bodies.ang_mom
        )  # fmt: skip
        bodies.place(spheres)
        trough = Trough(LENGTH, WIDTH, inclination=0.1, motion=motion)
        sim = Simulation(spheres, trough, law, 2e-5, rotation=rotation, bodies=bodies,
                         mesh=_pan() if mesh else None)  # fmt: skip
        sim.device = device
        sim.start_drive()
        sims.append(sim)
    return sims


def _compare_bodies(cpu, gpu):
    _compare(cpu, gpu)
    for name in ("x", "v", "q", "ang_mom", "omega", "force", "torque"):
        ref = getattr(cpu.bodies, name)
        _same(getattr(gpu.bodies, name), ref, np.max(np.abs(ref)))


@pytest.mark.parametrize(
    ("model", "e", "mu", "tangential", "rotation"),
    [
        ("linear", 0.3, 0.35, "coulomb", True),
        ("hertz_mindlin", 0.0, 0.5, "impact", True),
        ("linear", 0.6, 0.3, "liggghts", False),
    ],
)
def test_gpu_clumps_equal_the_cpu_engine(model, e, mu, tangential, rotation):
    """Rigid screws (members' forces, reduction to the body, kicks, free rotation, members
    placed, no contacts inside a clump) through several rebuilds: the same bits as the CPU."""
    cpu, gpu = _clump_pair(model, e, mu, tangential, rotation)
    steps = 40 if SIMULATOR else 5
    springs = False  # whether the history held a spring at a comparison
    for _ in range(3):
        cpu.advance(steps)
        gpu.advance(steps)
        springs |= bool(np.any(cpu.pairs.hist[: cpu.pairs.n_pairs] != 0.0))
        _compare_bodies(cpu, gpu)
        k = cpu.pairs.n_pairs
        assert np.any(cpu.pairs.hist[:k] != 0.0)  # screws in contact
        assert np.any(cpu.spheres.wall_hist != 0.0)
    body = cpu.spheres.body
    assert k > 0 and np.all(body[cpu.pairs.pair_i[:k]] != body[cpu.pairs.pair_j[:k]])
    assert cpu.pairs.builds >= 3
    assert rotation == np.any(cpu.bodies.ang_mom != 0.0)


def test_gpu_clumps_with_the_compact_step_equal_the_cpu_engine():
    """Screws' member spheres through the compact step, two touching candidates a pass: the same
    bits as the CPU engine."""
    cpu, gpu = _clump_pair("hertz_mindlin", 0.0, 0.5, "impact")
    engine = gpu.engine
    engine.compact, engine.compact_keep = True, 2
    for _ in range(2):
        cpu.advance(25 if SIMULATOR else 5)
        gpu.advance(25 if SIMULATOR else 5)
        _compare_bodies(cpu, gpu)
    assert np.any(cpu.pairs.hist[: cpu.pairs.n_pairs] != 0.0)


def test_gpu_clumps_in_a_mesh_equal_the_cpu_engine():
    """Screws in the triangle-mesh pan: the same bits as the CPU engine, mesh springs included."""
    cpu, gpu = _clump_pair("hertz_mindlin", 0.0, 0.5, "impact", mesh=True)
    for _ in range(2):  # the simulator runs the mesh's Python for 160 spheres: few steps
        cpu.advance(8 if SIMULATOR else 5)
        gpu.advance(8 if SIMULATOR else 5)
        _compare_bodies(cpu, gpu)
        for name in ("mesh_hist", "mesh_normal"):
            ref = getattr(cpu.spheres, name)
            _same(getattr(gpu.spheres, name), ref, np.max(np.abs(ref)))
    assert np.any(cpu.spheres.mesh_hist != 0.0)


def test_gpu_clumps_evaluate_and_take_up_a_host_change():
    """``compute_forces`` (the bodies' force and torque at rest) and a host change to the bodies
    between calls (a restart): the same bits as the CPU."""
    cpu, gpu = _clump_pair("hertz_mindlin", 0.3, 0.5, "coulomb", seed=7)
    for sim in (cpu, gpu):
        sim.compute_forces()
    _compare_bodies(cpu, gpu)
    for sim in (cpu, gpu):
        sim.advance(25)
        sim.bodies.v[:, 0] += 0.05
        sim.bodies.place(sim.spheres)
        sim.advance(25)
    _compare_bodies(cpu, gpu)


def test_gpu_takes_up_a_law_changed_between_calls():
    """A contact law replaced between calls (a study changing the friction) is the one the next
    call uses, as on the CPU."""
    cpu, gpu = _pair("linear", 0.5, 0.3, 0.0, False, "coulomb", "surface", 2e-5)
    for sim in (cpu, gpu):
        sim.advance(20)
        sim.law = _law("linear", _coefficients("linear", 0.5, 0.8, 0.0, False, "coulomb"))
        sim.advance(20)
    _compare(cpu, gpu)
