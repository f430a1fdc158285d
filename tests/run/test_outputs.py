"""What a run leaves for people to open: cycles.csv, and the ParaView time series' datasets."""

import csv
import json

import numpy as np
import pytest
from small_case import SMALL_CASE, write_case

from dem.physics import measure
from dem.run.runner import run_case
from dem.scene.case import load_case


@pytest.fixture(scope="module")
def sphere_run(tmp_path_factory):
    """The small sphere case: 2 settling and 3 measured cycles, 3 frames a cycle."""
    tmp = tmp_path_factory.mktemp("spheres")
    case = load_case(write_case(tmp / "case", SMALL_CASE.replace("cycles = 6", "cycles = 3")))
    out = tmp / "out"
    summary = run_case(case, out, progress=False, threads=1)
    return case, out, summary


@pytest.mark.integration
def test_cycles_csv_has_one_row_per_measured_cycle_and_the_summary_mean(sphere_run):
    case, out, summary = sphere_run
    text = (out / "cycles.csv").read_text()
    assert not any(line.startswith("#") for line in text.splitlines())
    with (out / "cycles.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == summary["cycles"] == 3
    assert [int(r["cycle"]) for r in rows] == [2, 3, 4]  # after the 2 settling cycles
    v = np.array([float(r["mean_velocity_m_s"]) for r in rows])
    assert np.allclose(v, summary["per_cycle_velocity"], rtol=1e-5, atol=1e-9)
    scale = np.max(np.abs(summary["per_cycle_velocity"]))
    assert v.mean() == pytest.approx(summary["mean_velocity"], abs=1e-5 * scale)
    norm = np.array([float(r["velocity_norm"]) for r in rows])
    assert np.allclose(norm, v / case.drive.velocity_scale, rtol=1e-5)
    period = 1.0 / case.drive.frequency
    assert np.allclose([float(r["time_s"]) for r in rows], [3 * period, 4 * period, 5 * period])
    table = np.genfromtxt(out / "cycles.csv", delimiter=",", names=True, dtype=None,
                          encoding="utf-8")  # fmt: skip
    assert {"cycle", "time_s", "mean_velocity_m_s", "velocity_norm"} <= set(table.dtype.names)
    side = json.loads((out / "cycles.json").read_text())
    assert side["settle_cycles_left_out"] == 2 and side["measured_cycles"] == 3


SCREWS = """
[trough]
length = 0.04
width = 0.03

[drive]
frequency = 60.0
angle = 25.0
throw_number = 1.8

[material]
friction = 0.35
restitution_normal = 0.3

[contact]
model = "hertz_mindlin"
youngs_modulus = 5.0e7

[particles]
shape = "screw"
count = 12
length = 0.016
shank_radius = 0.0014
head_radius = 0.0028
mass = 0.0025

[run]
settle_cycles = 1
cycles = 1
seed = 2

[output]
frames_per_cycle = 2
"""


def _drive_velocity(case, t):
    """s'(t) = A omega cos(omega t) (cos phi, 0, sin phi): the line drive without a ramp."""
    assert case.drive.ramp_cycles == 0 and case.drive.second_amplitude == 0
    omega = 2 * np.pi * case.drive.frequency
    phi = np.radians(case.drive.angle)
    return (
        case.drive.amplitude * omega * np.cos(omega * t) * np.array([np.cos(phi), 0, np.sin(phi)])
    )


def _names(pvd):
    import xml.etree.ElementTree as ET

    sets = ET.parse(pvd).getroot().findall("./Collection/DataSet")
    return sorted({(int(d.get("part")), d.get("name")) for d in sets})


def test_sphere_frames_carry_the_lab_velocity(sphere_run):
    import pyvista as pv

    case, out, _ = sphere_run
    assert _names(out / "particles.pvd") == [(0, "spheres"), (1, "trough")]
    reader = pv.get_reader(str(out / "particles.pvd"))
    for t in (reader.time_values[0], reader.time_values[4], reader.time_values[-1]):
        reader.set_active_time_value(t)
        spheres = reader.read()[0]
        assert spheres.field_data["time"][0] == pytest.approx(t)
        lab = spheres["velocity_trough"] + _drive_velocity(case, t)
        assert np.allclose(spheres["velocity_lab"], lab, atol=1e-6)
        assert np.allclose(spheres["velocity"], spheres["velocity_trough"])  # the trough frame
        assert np.allclose(spheres["speed_lab"], np.linalg.norm(lab, axis=1), atol=1e-6)


@pytest.mark.integration
def test_screw_frames_have_a_grains_block(tmp_path):
    import pyvista as pv

    case = load_case(write_case(tmp_path / "case", SCREWS))
    out = tmp_path / "out"
    run_case(case, out, progress=False, threads=1, lab_frame=True)
    assert _names(out / "particles.pvd") == [(0, "spheres"), (1, "trough"), (2, "grains")]
    reader = pv.get_reader(str(out / "particles.pvd"))
    t = reader.time_values[3]
    reader.set_active_time_value(t)
    spheres, _, grains = reader.read()
    assert grains.n_points == 12 and list(grains["spheres"]) == [case.particles.grain.count] * 12
    drive_v = _drive_velocity(case, t)
    assert np.allclose(grains["velocity_lab"], grains["velocity_trough"] + drive_v, atol=1e-6)
    assert np.allclose(grains["velocity"], grains["velocity_lab"])  # the lab frame
    assert np.allclose(spheres["velocity_lab"], spheres["velocity_trough"] + drive_v, atol=1e-6)
    assert np.allclose(np.linalg.norm(grains["axis"], axis=1), 1.0, atol=1e-6)
    # the axis points from the centre of mass along the shank: the farthest member lies on it
    for g in range(12):
        members = spheres.points[spheres["clump_id"] == g] - grains.points[g]
        members[:, 0] -= case.trough.length * np.round(members[:, 0] / case.trough.length)
        along = members @ grains["axis"][g]
        assert along.max() > -along.min()
    # the centres of mass lie among their members (lab frame: shifted alike)
    for g in range(12):
        d = spheres.points[spheres["clump_id"] == g] - grains.points[g]
        d[:, 0] -= case.trough.length * np.round(d[:, 0] / case.trough.length)
        assert np.max(np.linalg.norm(d, axis=1)) < 0.016


@pytest.mark.integration
def test_a_feeder_run_prints_its_discharge_and_tables_it_per_cycle(tmp_path, capsys):
    from test_feeder import FEEDER

    from dem.cli import main

    case_dir = write_case(tmp_path / "case", FEEDER)
    out = tmp_path / "out"
    assert main(["run", str(case_dir), "--out", str(out), "--threads", "1", "--no-frames"]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    f = summary["feeder"]
    line = [x for x in printed.splitlines() if x.startswith("discharge")]
    shown = measure.with_error(f["discharge_rate"], f["discharge_rate_stderr"], "kg/s")
    assert len(line) == 1 and shown in line[0]  # the digits its error allows
    with (out / "cycles.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == summary["cycles"]
    rate = np.mean([float(r["discharge_rate_kg_s"]) for r in rows])
    assert rate == pytest.approx(f["discharge_rate"], rel=1e-5, abs=1e-9)
    assert {"mass_in_trough_kg", "grains_in_trough", "feed_backlog"} <= set(rows[0])
