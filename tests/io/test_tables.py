"""CSV conventions: one plain header line, units in the names, rounded values, a JSON sidecar."""

import csv
import io
import json

import numpy as np
import pytest

from dem.io.tables import (
    column_name,
    csv_text,
    format_value,
    summary_column,
    write_csv,
)


def _no_comments(text: str) -> None:
    assert not any(line.startswith("#") for line in text.splitlines())


def test_values_are_rounded_and_undefined_values_empty():
    assert format_value(0.1 + 0.05) == "0.15"  # 0.15000000000000002
    assert format_value(np.float64(1) / 3) == "0.333333"
    assert format_value(1 / 3, digits=9) == "0.333333333"
    assert format_value(12) == "12" and format_value(np.int64(7)) == "7"
    assert format_value(True) == "true" and format_value(np.bool_(False)) == "false"
    assert format_value(None) == "" and format_value(float("nan")) == ""
    assert format_value(float("inf")) == "inf" and format_value(-0.0) == "0"
    assert format_value("hopping") == "hopping"


def test_column_names_carry_units():
    assert column_name("angle", "deg") == "angle_deg"
    assert column_name("velocity", "m/s") == "velocity_m_s"
    assert column_name("throw_number") == "throw_number"
    assert summary_column("mean_velocity") == "mean_velocity_m_s"
    assert summary_column("mass_flow_rate") == "mass_flow_rate_kg_s"
    assert summary_column("wall_time_s") == "wall_time_s"  # not wall_time_s_s
    assert summary_column("mean_velocity_norm") == "mean_velocity_norm"
    assert summary_column("drive.angle") == "drive.angle_deg"
    assert summary_column("material.friction") == "material.friction"
    assert summary_column("material.density") == "material.density_kg_m3"


def test_write_csv_reads_with_csv_numpy_and_has_a_sidecar(tmp_path):
    path = write_csv(
        tmp_path / "t.csv", ["angle_deg", "velocity_m_s", "regime"],
        [{"angle_deg": 10 + 0.1 * k, "velocity_m_s": 0.1 + 0.05 * k, "regime": "hopping"}
         for k in range(3)],
        meta={"columns": {"angle_deg": "vibration angle"}}, command="test",
    )  # fmt: skip
    text = path.read_text()
    _no_comments(text)
    assert text.splitlines()[3] == "10.2,0.2,hopping"
    rows = list(csv.DictReader(io.StringIO(text)))
    assert [float(r["velocity_m_s"]) for r in rows] == [0.1, 0.15, 0.2]
    table = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert table.dtype.names == ("angle_deg", "velocity_m_s", "regime")
    assert np.allclose(table["angle_deg"], [10.0, 10.1, 10.2])
    side = json.loads((tmp_path / "t.json").read_text())
    assert side["file"] == "t.csv" and side["command"] == "test"
    assert side["provenance"]["versions"]["dem"]
    assert side["columns"]["angle_deg"] == "vibration angle"


def test_rows_must_match_the_columns():
    with pytest.raises(ValueError, match="2 values for 3 columns"):
        csv_text(["a", "b", "c"], [[1, 2]])


def test_pointmass_sweep_csv_reads_with_numpy(tmp_path, capsys):
    from dem.cli import main

    out = tmp_path / "fig6.csv"
    assert main(["pointmass", "sweep", "--throw-number", "0.1:0.4:0.05", "--angle", "25",
                 "--friction", "0.35", "--out", str(out)]) == 0  # fmt: skip
    text = out.read_text()
    _no_comments(text)
    assert "0.15000000000000002" not in text and "\n0.15,25," in text
    table = np.genfromtxt(out, delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert {"throw_number", "angle_deg", "inclination_deg", "velocity_norm"} <= set(
        table.dtype.names
    )
    assert np.allclose(table["throw_number"], [0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4])
    assert np.all(table["angle_deg"] == 25.0)


def test_optimum_csv_has_units_in_its_header(tmp_path):
    from dem.studies.optimum import _write_csv

    samples = [(10.0, 0, 0.71732348874, 0.0043689807), (22.5, 1, 0.8 + 1e-17, 0.004)]
    _write_csv(tmp_path / "optimum.csv", samples, "drive.angle", "velocity_norm")
    text = (tmp_path / "optimum.csv").read_text()
    assert text.splitlines() == [
        "angle_deg,fill,velocity_norm,velocity_norm_stderr",
        "10,0,0.717323,0.00436898",
        "22.5,1,0.8,0.004",
    ]
    _write_csv(tmp_path / "o2.csv", samples, "drive.throw_number", "velocity")
    assert (tmp_path / "o2.csv").read_text().splitlines()[0] == (
        "throw_number,fill,velocity_m_s,velocity_stderr_m_s"
    )


def test_cycles_csv_holds_the_measured_cycles_of_results_h5(tmp_path):
    from dem.io.hdf5 import ResultsWriter
    from dem.io.tables import write_cycles_csv

    w = ResultsWriter(tmp_path / "results.h5", case={}, versions={}, seed=0, timestep=1e-5)
    velocities = [0.001, 0.002, 0.0101, 0.0102, 0.0097]
    for k, v in enumerate(velocities):
        w.append_cycle(cycle=k, time=(k + 1) / 60.0, mean_velocity=v, kinetic_energy=1e-6 * k,
                       contacts=100 + k, measured=int(k >= 2))  # fmt: skip
    w.close()
    summary = {"case": "x", "velocity_scale": 0.1, "settle_cycles": 2, "mean_velocity": 0.01}
    path = write_cycles_csv(tmp_path, summary)
    assert path == tmp_path / "cycles.csv"
    text = path.read_text()
    _no_comments(text)
    table = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert table.dtype.names == ("cycle", "time_s", "mean_velocity_m_s", "velocity_norm",
                                 "kinetic_energy_J", "contacts")  # fmt: skip
    assert list(table["cycle"]) == [2, 3, 4]
    assert np.allclose(table["time_s"], [3 / 60, 4 / 60, 5 / 60], rtol=1e-9)
    assert np.allclose(table["mean_velocity_m_s"], velocities[2:])
    assert np.allclose(table["velocity_norm"], np.array(velocities[2:]) / 0.1)
    side = json.loads((tmp_path / "cycles.json").read_text())
    assert side["settle_cycles_left_out"] == 2 and side["measured_cycles"] == 3
    assert side["columns"]["time_s"]["unit"] == "s"
