"""What a run leaves for people to open: cycles.csv, and the ParaView time series' datasets."""

import csv
import json

import numpy as np
import pytest
from small_case import SMALL_CASE, write_case

from dem.case import load_case
from dem.runner import run_case


@pytest.fixture(scope="module")
def sphere_run(tmp_path_factory):
    """The small sphere case: 2 settling and 3 measured cycles, 3 frames a cycle."""
    tmp = tmp_path_factory.mktemp("spheres")
    case = load_case(write_case(tmp / "case", SMALL_CASE.replace("cycles = 6", "cycles = 3")))
    out = tmp / "out"
    summary = run_case(case, out, progress=False, threads=1)
    return case, out, summary


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
