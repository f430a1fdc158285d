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
