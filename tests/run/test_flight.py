"""The grains in flight by phase (dem.run.flight): counted right, sampled after the measurement."""

import math
from pathlib import Path

import numpy as np
import pytest
from small_case import SMALL_CASE, write_case

from dem.engine import setup
from dem.run import flight
from dem.run.runner import run_case
from dem.scene.case import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"


def test_a_grain_touching_nothing_is_in_flight_and_one_on_the_floor_is_not():
    case = load_case(CASES / "single-sphere", {"particles.count": 2})
    r = case.particles.radius
    sim = setup.from_grains(case, [[0.3 * case.trough.length, 0.0, r],
                                   [0.7 * case.trough.length, 0.0, 6 * r]])  # fmt: skip
    sim.run(1)
    assert flight.in_flight(sim) == 0.5


def test_a_screw_is_in_flight_only_when_every_member_is_free(monkeypatch):
    case = load_case(CASES / "screw-trough", {"particles.count": 2})
    length = case.trough.length
    sim = setup.from_grains(case, [[0.25 * length, 0.0, 0.05], [0.75 * length, 0.0, 0.05]])
    sim.run(1)
    assert flight.in_flight(sim) == 1.0  # both in the air
    counts = np.zeros(sim.spheres.n, dtype=np.int64)
    counts[np.flatnonzero(sim.spheres.body == 0)[-1]] = 1  # one member of screw 0 touches
    monkeypatch.setattr(sim, "contact_counts", lambda: counts)
    assert flight.in_flight(sim) == 0.5


@pytest.mark.integration
def test_sampling_the_flight_leaves_the_measured_velocity_bit_for_bit(tmp_path):
    d = write_case(tmp_path / "case", SMALL_CASE)
    with_flight = run_case(load_case(d, {"output.flight_phases": 8}), tmp_path / "a",
                           progress=False, frames=False, threads=1)  # fmt: skip
    plain = run_case(load_case(d), tmp_path / "b", progress=False, frames=False, threads=1)
    assert with_flight["mean_velocity"] == plain["mean_velocity"]
    assert with_flight["per_cycle_velocity"] == plain["per_cycle_velocity"]
    assert plain["flight"] is None
    f = with_flight["flight"]
    assert f["phase_deg"] == [45.0 * (k + 1) for k in range(8)] and f["cycles"] == 2
    assert all(0.0 <= x <= 1.0 for x in f["fraction"])
    assert max(f["fraction"]) > 0.0  # Gamma 3.06: the bed leaves the floor
    assert not any(math.isnan(x) for x in f["fraction"])
