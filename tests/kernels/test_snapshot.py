"""Every contact of a frame (dem.kernels.snapshot): the forces the step applies, state untouched."""

from pathlib import Path

import numpy as np
import pytest
from small_case import SMALL_CASE, write_case

from dem.config import GRAVITY
from dem.engine import setup
from dem.errors import InputError
from dem.scene.case import load_case
from dem.scene.resolved import resolve

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.fixture(scope="module")
def rested(tmp_path_factory):
    case = load_case(write_case(tmp_path_factory.mktemp("snap") / "case", SMALL_CASE))
    sim = setup.from_case(resolve(case))
    sim.settle()
    return sim


def test_a_resting_beds_contacts_carry_its_weight_and_leave_the_state_alone(rested):
    """Newton at rest: the wall contacts hold the bed's weight; on every sphere the contacts
    sum to the force the step applied less its weight (within the one-step spring advance)."""
    sim = rested
    before = [a.copy() for a in (sim.pairs.hist, sim.spheres.wall_hist, sim.spheres.x,
                                 sim.spheres.v, sim.spheres.force)]  # fmt: skip
    snap = sim.contact_snapshot()
    after = (sim.pairs.hist, sim.spheres.wall_hist, sim.spheres.x, sim.spheres.v,
             sim.spheres.force)  # fmt: skip
    assert all(np.array_equal(a, b) for a, b in zip(before, after, strict=True))
    force = snap["normal_force"][:, None] * snap["normal"] + snap["tangential_force"]
    walls = snap["kind"] > 0
    weight = sim.total_mass * GRAVITY
    assert force[walls, 2].sum() == pytest.approx(weight, rel=1e-3)
    per = np.zeros((sim.spheres.n, 3))
    np.add.at(per, snap["i"], force)
    pairs = snap["kind"] == 0
    np.add.at(per, snap["j"][pairs], -force[pairs])
    body = sim.spheres.force - per  # what is left is m g (drive off, level trough)
    mg = sim.spheres.mass * GRAVITY
    assert np.allclose(body[:, 2] / mg, -1.0, atol=2e-3)
    assert np.abs(body[:, :2]).max() < 2e-3 * mg.max()
    # every listed contact touches, every touching pair is listed
    assert np.all(snap["overlap"] > 0) and pairs.sum() == int(sim.contact_counts().sum() -
                                                              walls.sum()) // 2  # fmt: skip
    # the friction law holds on the floor
    floor = snap["kind"] == 1
    ratio = np.linalg.norm(snap["tangential_force"][floor], axis=1) / snap["normal_force"][floor]
    assert np.all(ratio <= 0.35 + 1e-9)  # SMALL_CASE's friction, the floor's too


def test_contacts_are_refused_where_they_are_not_listed():
    with pytest.raises(InputError, match=r"output\.contacts.*a mesh trough"):
        load_case(CASES / "u-trough", {"output.contacts": True})
    with pytest.raises(InputError, match=r"output\.contacts.*the GPU engine"):
        load_case(CASES / "sphere-bed", {"output.contacts": True, "run.device": "cuda"})


def test_contacts_without_frames_say_that_nothing_is_written(tmp_path):
    from dem.run.runner import run_case

    text = SMALL_CASE.replace("count = 120", "count = 20").replace("cycles = 6", "cycles = 1")
    case = load_case(write_case(tmp_path / "case", text), {"output.contacts": True})
    with pytest.warns(UserWarning, match=r"output\.contacts = true writes nothing without frames"):
        run_case(case, tmp_path / "out", progress=False, frames=False, threads=1)
    assert not list((tmp_path / "out").glob("frames/contacts_*"))


def test_the_walls_carry_the_weight_of_a_conveyed_bed_over_a_cycle(tmp_path):
    """results.h5 keeps every frame's contacts and the trough's loads (the floor's normal force
    over a cycle is one column). Sliding at Gamma = 0.8 (no flight), 16 frames a cycle: the walls'
    force on the grains averages to the bed's weight over whole cycles (the drive's inertial force
    averages to zero, the momentum returns), the floor carrying nearly all of it; each frame's
    rows are the ones the contact counts of its spheres give; a resumed file is trimmed back to
    its frames, contacts included."""
    from dem.io.hdf5 import ResultsWriter, read_results
    from dem.run.runner import run_case

    amplitude = 0.8 * GRAVITY / (2 * np.pi * 60.0) ** 2
    text = (SMALL_CASE.replace("amplitude = 0.0005", f"amplitude = {amplitude!r}")
            .replace("cycles = 6", "cycles = 4").replace("frames_per_cycle = 3",
                                                         "frames_per_cycle = 16"))  # fmt: skip
    case = load_case(write_case(tmp_path / "case", text), {"output.contacts": True})
    summary = run_case(case, tmp_path / "out", progress=False, threads=1)
    res = read_results(tmp_path / "out" / "results.h5")
    loads = res["wall_loads"]
    count = res["frame_count"]
    assert loads is not None and loads["floor_normal_force"].shape == (count,)
    assert loads["wall_force_on_grains"].shape == (count, 3)
    last = slice(count - 64, count)  # the last 4 cycles, 16 evenly spaced frames each
    mass = 120 * 7800.0 * 4.0 / 3.0 * np.pi * 0.002**3
    mean = loads["wall_force_on_grains"][last].mean(axis=0)
    assert mean[2] == pytest.approx(mass * GRAVITY, rel=0.03)
    assert abs(mean[0]) < 0.03 * mass * GRAVITY and abs(mean[1]) < 0.03 * mass * GRAVITY
    assert loads["floor_normal_force"][last].mean() == pytest.approx(mass * GRAVITY, rel=0.05)
    assert np.ptp(loads["floor_normal_force"][last]) > 0.2 * mass * GRAVITY  # it swings
    frame = res["frames"][count - 1]
    rows = frame["contacts"]
    pairs = rows["kind"] == 0
    assert 2 * pairs.sum() + (~pairs).sum() == frame["contact_count"].sum()
    assert np.all(rows["overlap"] > 0) and summary["grains"] == 120
    # a resumed run trims the file back to the frames its checkpoint counted
    ResultsWriter(tmp_path / "out" / "results.h5", case={}, versions={}, seed=0, timestep=1.0,
                  resume_at=(2, 5))  # fmt: skip
    res = read_results(tmp_path / "out" / "results.h5")
    assert res["frame_count"] == 5 and res["wall_loads"]["floor_normal_force"].shape == (5,)
    assert len(res["frames"][4]["contacts"]["kind"]) > 0
    with pytest.raises(IndexError):
        res["frames"][5]
