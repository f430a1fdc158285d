"""Neighbour lists: the pair set of a brute-force search, sorted keys, CSR, history carry-over."""

import numpy as np
import pytest

from dem.engine.simulation import ContactLaw, Simulation
from dem.engine.state import PairList, Spheres
from dem.kernels import contact
from dem.scene.trough import Trough


def _sim(n, length, width, seed, capacity=None):
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.8e-3, 1.2e-3, n)
    x = np.column_stack(
        [rng.uniform(0, length, n), rng.uniform(-width / 2, width / 2, n), rng.uniform(0, 0.02, n)]
    )
    law = ContactLaw(
        "linear", contact.make_params(model="linear", stiffness=1e3, restitution=0.5, friction=0.3)
    )
    sim = Simulation(Spheres.create(x, r, 2500.0), Trough(length, width), law, 1e-6)
    if capacity is not None:
        sim.pairs = PairList(n, capacity=capacity, cell_capacity=2)
    return sim, rng


def _brute_force_keys(sim):
    x, r, n = sim.spheres.x, sim.spheres.radius, sim.spheres.n
    length = sim.trough.length
    keys = []
    for i in range(n):
        d = x[i] - x[i + 1 :]
        d[:, 0] -= length * np.round(d[:, 0] / length)
        dist = np.sqrt(np.sum(d * d, axis=1))
        for j in np.flatnonzero(dist < r[i] + r[i + 1 :] + sim.skin):
            keys.append(i * n + i + 1 + j)
    return np.array(sorted(keys), dtype=np.int64)


@pytest.mark.parametrize(
    ("n", "length", "width"),
    [(400, 0.03, 0.02), (150, 0.007, 0.02), (200, 0.03, 0.002)],  # many cells; one x column
)
def test_pair_list_equals_brute_force(n, length, width):
    sim, _ = _sim(n, length, width, seed=n)
    sim.spheres.x[:5, 0] += np.array([-0.5, 1.0, 2.3, -3.1, 0.7]) * length  # outside the box
    sim.engine.build()
    p = sim.pairs
    k = p.n_pairs
    expected = _brute_force_keys(sim)
    np.testing.assert_array_equal(p.pair_key[:k], expected)
    np.testing.assert_array_equal(p.pair_key[:k], p.pair_i[:k] * n + p.pair_j[:k])
    assert np.all((sim.spheres.x[:, 0] >= 0) & (sim.spheres.x[:, 0] < length))
    # CSR: every sphere owns the slots of exactly the pair ends it is, in increasing pair index
    slots = p.part_slot[: 2 * k]
    assert sorted(slots) == list(range(2 * k))  # every slot used once
    for s in range(0, n, 7):
        own = range(p.part_start[s], p.part_start[s + 1])
        ends = [e for e in range(2 * k) if slots[e] in own]
        assert [e // 2 for e in ends] == sorted(e // 2 for e in ends)
        assert sorted(slots[ends]) == list(own)
        assert [e // 2 for e in ends if e % 2 == 0] == list(np.flatnonzero(p.pair_i[:k] == s))
        assert [e // 2 for e in ends if e % 2 == 1] == list(np.flatnonzero(p.pair_j[:k] == s))


def test_overflow_regrows_to_the_same_list():
    sim, _ = _sim(300, 0.03, 0.02, seed=5, capacity=3)
    sim.engine.build()
    assert sim.pairs.capacity >= sim.pairs.n_pairs > 3
    np.testing.assert_array_equal(sim.pairs.pair_key[: sim.pairs.n_pairs], _brute_force_keys(sim))


def test_history_survives_rebuild_by_pair_key():
    sim, rng = _sim(300, 0.03, 0.02, seed=11)
    sim.engine.build()
    p, n = sim.pairs, sim.spheres.n
    k = p.n_pairs
    old = {int(key): np.array([key, -key, 0.5 * key], dtype=float) for key in p.pair_key[:k]}
    for m in range(k):
        p.hist[m] = old[int(p.pair_key[m])]
    sim.spheres.x += rng.normal(0, 4e-4, sim.spheres.x.shape)
    sim.engine.build()
    k2 = p.n_pairs
    kept = new = 0
    for m in range(k2):
        key = int(p.pair_key[m])
        if key in old:
            np.testing.assert_array_equal(p.hist[m], old[key])
            kept += 1
        else:
            np.testing.assert_array_equal(p.hist[m], 0.0)
            new += 1
    assert kept > 50 and new > 5 and n > 0


def test_overflow_inside_the_step_loop_resumes_the_step_exactly():
    """A rebuild that overflows mid-run is regrown and the step resumed: same state bit for bit."""
    runs = []
    for small_lists in (False, True):
        sim, rng = _sim(300, 0.03, 0.02, seed=4)
        sim.spheres.x[:, 2] *= 0.3  # a dense layer: many contacts
        sim.spheres.v[:] = rng.normal(0, 0.05, sim.spheres.v.shape)
        sim.advance(20)  # (no instability checks: the random start overlaps deeply)
        if small_lists:  # same list, but every capacity of the next build overflows
            k = sim.pairs.n_pairs
            small = PairList(sim.spheres.n, capacity=k, cell_capacity=2, slots=2)
            small.counters[:] = sim.pairs.counters
            for name in ("pair_i", "pair_j", "pair_key", "hist"):
                getattr(small, name)[:k] = getattr(sim.pairs, name)[:k]
            for name in ("part_start", "part_slot", "inbox"):
                getattr(small, name)[:] = getattr(sim.pairs, name)[: len(getattr(small, name))]
            small.x_ref[:] = sim.pairs.x_ref
            sim.pairs = small
        sim.pairs.x_ref[:] = np.inf  # force a build in the next step
        sim.advance(30)
        runs.append((sim.spheres.x.copy(), sim.spheres.v.copy(), sim.pairs.n_pairs))
        assert sim.pairs.n_pairs > 0
    assert sim.pairs.cell_capacity > 2 and sim.pairs.slots > 2  # it did regrow
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    assert runs[0][2] == runs[1][2]
