"""A short run of two sphere types, one of a size distribution: per-type velocities everywhere.

summary.json reports each type (what the fill placed, its velocity as the bulk's), results.h5 a
``mean_velocity_<type>`` column per cycle, and the VTK frames a ``grain_type`` field; the
types' velocities, weighted by their mass, give the bulk's per-cycle velocity (the bulk from
the momentum after every step, the types from the displacements over the cycle).
"""

import json

import numpy as np
import pytest
from small_case import write_case
from test_sizes import TWO_TYPES

from dem.io.hdf5 import read_results
from dem.run.runner import run_case
from dem.scene.case import load_case


@pytest.mark.integration
def test_a_two_type_run_reports_each_types_velocity(tmp_path):
    import pyvista as pv

    short = {"run.cycles": 3, "run.settle_cycles": 1, "output.frames_per_cycle": 1}
    case = load_case(write_case(tmp_path / "case", TWO_TYPES), short)
    summary = run_case(case, tmp_path / "out", overwrite=True, progress=False, frames=True)
    on_disk = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert on_disk["per_type"] == summary["per_type"]
    glass, steel = summary["per_type"]
    assert (glass["name"], glass["count"], steel["name"], steel["count"]) == (
        "glass",
        60,
        "steel",
        60,
    )
    assert 0.0012 <= glass["radius_min"] <= glass["radius_mean"] <= glass["radius_max"] <= 0.0018
    assert steel["radius_min"] == steel["radius_max"] == 0.002
    assert glass["mass_fraction"] + steel["mass_fraction"] == pytest.approx(1.0)
    scale = summary["velocity_scale"]
    for t in (glass, steel):
        assert len(t["per_cycle_velocity"]) == 3 and np.isfinite(t["mean_velocity"])
        assert t["mean_velocity_norm"] == pytest.approx(t["mean_velocity"] / scale)
    weighted = (glass["mass_fraction"] * np.array(glass["per_cycle_velocity"])
                + steel["mass_fraction"] * np.array(steel["per_cycle_velocity"]))  # fmt: skip
    np.testing.assert_allclose(weighted, summary["per_cycle_velocity"], rtol=0, atol=2e-3 * scale)
    cycles = read_results(tmp_path / "out" / "results.h5")["cycles"]
    measured = cycles["measured"] == 1
    np.testing.assert_array_equal(
        cycles["mean_velocity_glass"][measured], glass["per_cycle_velocity"]
    )
    frame = pv.read(sorted((tmp_path / "out" / "frames").glob("particles_*.vtp"))[-1])
    kind = np.asarray(frame.point_data["grain_type"])
    assert np.bincount(kind).tolist() == [60, 60]
    np.testing.assert_array_equal(
        np.asarray(frame.point_data["radius"])[kind == 1], np.float32(0.002)
    )
