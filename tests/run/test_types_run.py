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


def test_replicas_pool_each_types_velocity_as_the_bulks():
    """Two fills' per-type rows: velocities pooled as the bulk's, counts and sizes over both."""
    from dem.physics import measure
    from dem.run.replicas import pool_summaries

    def fill(seed, v, count, lo):
        row = {"name": "glass", "fraction": 0.5, "density": 2500.0, "distribution": "uniform",
               "count": count, "radius_mean": 0.0015, "radius_min": lo, "radius_max": 0.0018,
               "mass_fraction": 0.1, "mean_velocity": v, "mean_velocity_stderr": 0.001,
               "mean_velocity_norm": v / 0.17,
               "mean_velocity_norm_stderr": 0.001 / 0.17}  # fmt: skip
        return {"seed": seed, "mean_velocity": v, "mean_velocity_stderr": 0.001,
                "mean_velocity_norm": v / 0.17, "mean_velocity_norm_stderr": 0.001 / 0.17,
                "mass_flow_rate": 1.0, "mass_flow_rate_per_width": 10.0, "settle_cycles": 2,
                "cycles": 3, "wall_time_s": 1.0, "spheres": 10, "steps": 100,
                "per_type": [row]}  # fmt: skip

    out = pool_summaries([fill(1, 0.15, 60, 0.0012), fill(2, 0.16, 61, 0.0013)])
    (glass,) = out["per_type"]
    p = measure.pooled([0.15, 0.16], [0.001, 0.001])
    assert (glass["mean_velocity"], glass["mean_velocity_stderr"]) == (p.mean, p.stderr)
    assert (glass["count"], glass["radius_min"]) == (60.5, 0.0012)
    assert [r["per_type_velocity"] for r in out["per_replica"]] == [[0.15], [0.16]]


@pytest.mark.integration
def test_a_stopped_two_type_run_resumes_bit_for_bit(tmp_path, monkeypatch, capsys):
    """The cycle edge's positions that each type's velocity is measured from travel in the
    checkpoint's arrays (binary, O(n)), not in its JSON record; a run stopped by a signal and
    resumed reports every type's per-cycle velocity as the run that went straight through."""
    import signal

    from small_case import sigterm_at_check

    from dem.cli import main

    case_dir = write_case(tmp_path / "case", TWO_TYPES)
    short = ["--set", "run.cycles=3", "--set", "run.settle_cycles=1", "--no-frames",
             "--threads", "1"]  # fmt: skip
    assert main(["run", str(case_dir), "--out", str(tmp_path / "straight"), *short]) == 0
    out = tmp_path / "stopped"
    sigterm_at_check(monkeypatch, 40)
    code = main(["run", str(case_dir), "--out", str(out), *short])
    monkeypatch.undo()
    assert code == 128 + signal.SIGTERM, capsys.readouterr().err
    with np.load(out / "checkpoint.npz") as saved:
        assert saved["sim.type_mark"].shape == (120,)
        assert "type_mark" not in str(saved["loop.json"])
    assert main(["run", str(case_dir), "--out", str(out), *short, "--resume"]) == 0
    straight = json.loads((tmp_path / "straight" / "summary.json").read_text())["per_type"]
    resumed = json.loads((out / "summary.json").read_text())["per_type"]
    assert [t["per_cycle_velocity"] for t in resumed] == [t["per_cycle_velocity"] for t in straight]
