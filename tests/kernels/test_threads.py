"""1 and 2 numba threads step a bed bit for bit: plain spheres, and screws (clumps).

The parallel loops are race-free by construction (each sphere sums its own
contacts), so the thread count must not change a single bit of the state. A case's seeded fill is
given random velocities, so that grains meet in the air and on the floor within a few hundred
steps; after a common start, copies of that bed are driven on 1 and on 2 threads and compared
with ``np.array_equal``: positions, velocities, the angular state and the contact history (pair
keys and tangential elongations, grain-grain and grain-wall).
"""

import copy

import numba
import numpy as np
import pytest
from small_case import SMALL_CASE, write_case

from dem import config
from dem.engine import setup
from dem.scene.case import load_case

pytestmark = pytest.mark.skipif(
    numba.config.NUMBA_NUM_THREADS < 2,
    reason=f"needs 2 numba threads, NUMBA_NUM_THREADS is {numba.config.NUMBA_NUM_THREADS}",
)

START_STEPS = 400  # common start: contacts and their history exist when the comparison begins
STEPS = 400  # compared
SPEED = 0.5  # m/s, spread of the random initial velocities

SCREW_CASE = SMALL_CASE.replace("density = 7800.0\n", "").replace(
    """shape = "sphere"
count = 120
radius = 0.002""",
    """shape = "screw"
count = 24
length = 0.016
shank_radius = 0.0014
head_radius = 0.0028
mass = 0.0025""",
)


def _started(tmp_path, text):
    """The case's fill with random velocities, driven for START_STEPS steps."""
    case = load_case(write_case(tmp_path / "case", text))
    filled = setup.from_case(case)
    b = filled.bodies
    grains = filled.spheres.x if b is None else b.x
    velocities = np.random.default_rng(5).normal(0.0, SPEED, grains.shape)
    sim = setup.from_grains(
        case, grains, orientations=None if b is None else b.q, velocities=velocities
    )
    sim.start_drive()
    sim.run(START_STEPS)
    return sim


def _run(start, threads):
    sim = copy.deepcopy(start)
    before = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        sim.run(STEPS)
    finally:
        numba.set_num_threads(before)
    return _snapshot(sim)


def _snapshot(sim):
    s, p = sim.spheres, sim.pairs
    n = p.n_pairs
    out = {
        "sphere x": s.x,
        "sphere v": s.v,
        "sphere omega": s.omega,
        "wall history": s.wall_hist,
        "pair keys": p.pair_key[:n],
        "pair history": p.hist[:n],
        "step and pair count": np.array([sim.step_index, n]),
    }
    if sim.bodies is not None:
        b = sim.bodies
        out |= {"body x": b.x, "body v": b.v, "body q": b.q, "body ang_mom": b.ang_mom}
    return {k: np.copy(v) for k, v in out.items()}


@pytest.mark.validation
@pytest.mark.parametrize("text", [SMALL_CASE, SCREW_CASE], ids=["spheres", "screws"])
def test_one_and_two_threads_give_identical_trajectories(tmp_path, monkeypatch, text):
    monkeypatch.setattr(config, "DEM_PARALLEL_MIN_SPHERES", 0)  # small beds run parallel too
    start = _started(tmp_path, text)
    before = _snapshot(start)
    one = _run(start, 1)
    two = _run(start, 2)
    # the compared steps had contacts with history, and every grain moved and turned
    assert np.count_nonzero(np.any(one["pair history"] != 0.0, axis=1)) >= 3
    assert np.count_nonzero(np.any(one["wall history"] != 0.0, axis=1)) >= 1
    assert np.all(np.any(one["sphere x"] != before["sphere x"], axis=1))
    spin = one["body ang_mom"] if "body ang_mom" in one else one["sphere omega"]
    assert np.any(spin != 0.0)
    for name in one:
        assert np.array_equal(one[name], two[name]), f"{name} differs between 1 and 2 threads"


def test_thread_guard_probes_one_thread_and_keeps_the_faster(monkeypatch):
    from dem.engine import threads

    chosen = []
    monkeypatch.setattr(threads.numba, "set_num_threads", chosen.append)
    guard = threads.ThreadGuard(2, period=4)
    slow = {2: 3.0, 1: 1.0}  # seconds per 1000 steps: a busy machine, one thread is faster
    for _ in range(16):
        n = config.DEM_THREAD_GUARD_TRY_STEPS if guard.trying else 1000
        k = guard.choose()
        guard.record(k, n, slow[k] * n / 1000)
    # N threads first (untimed) and second, one thread third (it wins: the next try 4 chunks
    # after it), then one thread; the try at chunk 7 confirms it: the next waits 8 chunks
    assert chosen == [2, 2, 1, 1, 1, 1, 1, 2, 1, 1, 1, 1, 1, 1, 1, 1]
    try_steps = config.DEM_THREAD_GUARD_TRY_STEPS
    on_one = try_steps + 12 * 1000  # the short try at chunk 2, then 12 full chunks
    on_two = 2 * 1000 + try_steps  # the first two chunks, the short try at chunk 7
    share = guard.as_dict()["fraction_on_one_thread"]
    assert guard.best == 1 and share == on_one / (on_one + on_two)
    chosen.clear()
    fast = threads.ThreadGuard(2, period=4)
    for _ in range(40):
        n = config.DEM_THREAD_GUARD_TRY_STEPS if fast.trying else 1000
        k = fast.choose()
        fast.record(k, n, {2: 1.0, 1: 1.8}[k] * n / 1000)
    # tries of one thread at chunks 2, 11, 28: the wait doubles (8, 16, ...) while two hold
    assert [c for c, k in enumerate(chosen) if k == 1] == [2, 11, 28] and fast.best == 2
    chosen.clear()
    turn = threads.ThreadGuard(2, period=4)  # two threads win, then the machine gets busy
    for c in range(20):
        k = turn.choose()
        turn.record(k, 1000, ({2: 1.0, 1: 1.8} if c < 6 else {2: 3.0, 1: 1.0})[k])
    # chunk 6 on two threads is slow: the guard leaves at once (no wait for a try)
    assert chosen[:10] == [2, 2, 1, 2, 2, 2, 2, 1, 1, 1]
    chosen.clear()
    busy = threads.ThreadGuard(2, period=4)  # two threads 20x slower: tries wait for their cost
    for _ in range(400):
        n = config.DEM_THREAD_GUARD_TRY_STEPS if busy.trying else config.DEM_CHECK_INTERVAL
        k = busy.choose()
        busy.record(k, n, {2: 20.0, 1: 1.0}[k] * n)
    tries = [c for c, k in enumerate(chosen) if k == 2][2:]  # after the first two chunks
    lost = sum(19.0 * config.DEM_THREAD_GUARD_TRY_STEPS for _ in tries)
    assert len(tries) >= 2 and lost / (400 * config.DEM_CHECK_INTERVAL) < 0.05


def test_the_guard_starts_on_one_thread_where_the_load_leaves_no_core_free(monkeypatch):
    from dem.engine import threads

    assert threads.starting_threads(2, cores=2, busy=0.3) == 2
    assert threads.starting_threads(2, cores=2, busy=0.6) == 1  # a core half busy is not free
    assert threads.starting_threads(2, cores=2, busy=3.0) == 1
    assert threads.starting_threads(4, cores=16, busy=3.0) == 4
    chosen, notes = [], []
    monkeypatch.setattr(threads.numba, "set_num_threads", chosen.append)
    guard = threads.ThreadGuard(2, period=4, start=1, note=notes.append)
    assert len(notes) == 1 and "starting on one thread" in notes[0]
    for _ in range(6):
        k = guard.choose()
        guard.record(k, 1000, {2: 1.0, 1: 1.8}[k])  # the machine was free after all
    assert chosen == [1, 1, 2, 2, 2, 2] and guard.best == 2 and len(notes) == 1
    with pytest.raises(ValueError, match="start"):
        threads.ThreadGuard(4, start=2)


def test_the_guard_notes_the_move_to_one_thread_once(monkeypatch):
    from dem.engine import threads

    notes = []
    monkeypatch.setattr(threads.numba, "set_num_threads", lambda k: None)
    guard = threads.ThreadGuard(2, period=2, note=notes.append)
    for _ in range(30):
        k = guard.choose()
        guard.record(k, 1000, {2: 3.0, 1: 1.0}[k])
    assert len(notes) == 1 and "2 threads ran slower than one" in notes[0]


@pytest.mark.validation
def test_a_try_of_the_other_thread_count_runs_a_short_chunk(tmp_path, monkeypatch):
    """The guard's try may be the slow choice: Simulation.run gives it a short chunk."""
    from dem.engine import threads

    monkeypatch.setattr(threads.numba, "set_num_threads", lambda k: None)
    sim = setup.from_case(load_case(write_case(tmp_path / "case")))
    sim.guard = threads.ThreadGuard(2, period=4)
    sizes = []
    real = sim.advance
    monkeypatch.setattr(sim, "advance", lambda n: (sizes.append(n), real(n)))
    sim.run(6 * config.DEM_CHECK_INTERVAL)
    assert sizes[2] == config.DEM_THREAD_GUARD_TRY_STEPS  # the third chunk tries one thread
    assert sizes[:2] == [config.DEM_CHECK_INTERVAL] * 2
    assert sum(sizes) == 6 * config.DEM_CHECK_INTERVAL


@pytest.mark.validation
def test_the_guard_changes_the_wall_time_only(tmp_path, monkeypatch):
    """Momentum sums in fixed chunks: the same bits on one thread and on two."""
    import numba
    from small_case import write_case

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs two numba threads")

    from dem import config
    from dem.run.runner import run_case
    from dem.scene.case import load_case

    case = load_case(write_case(tmp_path / "case"))
    guarded = run_case(case, tmp_path / "a", threads=2, progress=False, frames=False)
    assert "thread_guard" in guarded
    monkeypatch.setattr(config, "DEM_THREAD_GUARD", False)
    two = run_case(case, tmp_path / "b", threads=2, progress=False, frames=False)
    one = run_case(case, tmp_path / "c", threads=1, progress=False, frames=False)
    assert guarded["per_cycle_velocity"] == two["per_cycle_velocity"] == one["per_cycle_velocity"]


def test_busy_cores_are_sampled_now_not_the_minutes_average(monkeypatch):
    """A core spinning in another process shows within the sample; once it stops, the next
    sample is idle again (the 1-minute load average would still hold it)."""
    import multiprocessing
    import os
    import time

    from dem.engine import threads

    if threads.cpu_times() is None:
        pytest.skip("no /proc/stat here: the load average is the fallback")
    samples = iter([[(0, 0), (0, 0)], [(50, 100), (0, 100)]])  # CPU 0 half idle, CPU 1 busy
    monkeypatch.setattr(threads, "cpu_times", lambda: next(samples))
    assert threads.busy_cores(0.01) == pytest.approx(1.5)
    monkeypatch.undo()
    spinner = multiprocessing.get_context("spawn").Process(target=_spin, args=(2.0,))
    spinner.start()
    try:
        time.sleep(0.6)  # the spawned interpreter starts
        busy = threads.busy_cores(0.5)
    finally:
        spinner.join()
    assert busy >= 0.7  # the spinner's core, whatever else runs
    assert os.cpu_count() >= 1


def _spin(seconds):
    import time

    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass
