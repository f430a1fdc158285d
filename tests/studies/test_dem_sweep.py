"""``dem sweep``: a grid of DEM cases on a local Dask cluster, gathered into one table."""

import csv
import json

import h5py
import numpy as np
import pytest
from small_case import SMALL_CASE, write_case

from dem.cli import main
from dem.errors import InputError
from dem.run.output import SUMMARY
from dem.studies.sweep import folder_name, grid, parse_set, run_sweep

pytest.importorskip("distributed")

#: 30 spheres, one settling and two measured cycles: a point takes well under a second.
TINY = SMALL_CASE.replace("count = 120", "count = 30").replace(
    "settle_cycles = 2", "settle_cycles = 1"
)


def read_csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


def test_parse_set_takes_ranges_lists_words_and_whole_numbers():
    assert parse_set("drive.angle=10:30:10") == ("drive.angle", [10.0, 20.0, 30.0])
    assert parse_set("material.friction=0.25,0.6") == ("material.friction", [0.25, 0.6])
    assert parse_set("contact.model=linear,hertz_mindlin") == (
        "contact.model", ["linear", "hertz_mindlin"])  # fmt: skip
    assert parse_set("run.seed=1:3:1") == ("run.seed", [1, 2, 3])
    assert parse_set("particles.rotation=false") == ("particles.rotation", [False])
    for bad in ("drive.angle", "angle=10", "drive.angle=30:10:5", "run.seed=1.5"):
        with pytest.raises(InputError):
            parse_set(bad)
    assert grid([("a.x", [1, 2]), ("b.y", [3])]) == [{"a.x": 1, "b.y": 3}, {"a.x": 2, "b.y": 3}]
    assert folder_name(7, {"drive.angle": 25.0}) == "007_drive.angle=25"


def test_a_bad_point_is_refused_before_anything_runs(tmp_path):
    case = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    with pytest.raises(InputError, match=r"drive\.angle.*sweep point"):
        run_sweep(case, [("drive.angle", [20.0, 95.0])], out, progress=False)
    assert not out.exists()


@pytest.mark.integration
def test_two_points_run_on_dask_and_a_rerun_recomputes_nothing(tmp_path, capsys):
    case = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    args = ["sweep", str(case), "--set", "drive.angle=20,30", "--out", str(out), "--workers", "2"]
    assert main(args) == 0
    rows = read_csv(out / "sweep.csv")
    assert [float(r["drive.angle_deg"]) for r in rows] == [20.0, 30.0]
    for r in rows:
        summary = json.loads((out / r["point"] / SUMMARY).read_text())
        assert summary["angle"] == float(r["drive.angle_deg"])
        assert float(r["mean_velocity_norm"]) == pytest.approx(summary["mean_velocity_norm"],
                                                               rel=1e-5)  # fmt: skip
        assert float(r["mean_velocity_m_s"]) == pytest.approx(summary["mean_velocity"], rel=1e-5)
        assert r["status"] == "done"
    with open(out / "sweep.csv") as fh:
        assert not any(line.startswith("#") for line in fh)
    table = np.genfromtxt(out / "sweep.csv", delimiter=",", names=True, dtype=None,
                          encoding="utf-8")  # fmt: skip
    assert list(table["mean_velocity_m_s"]) == [float(r["mean_velocity_m_s"]) for r in rows]
    side = json.loads((out / "sweep.json").read_text())
    assert side["provenance"]["versions"]["dem"] and side["command"] == "dem sweep"
    assert side["columns"]["mean_velocity_m_s"]["unit"] == "m/s"
    assert side["columns"]["drive.angle_deg"]["unit"] == "deg"
    with h5py.File(out / "sweep.h5") as h5:
        assert np.array_equal(h5["sweep/drive.angle_deg"][:], [20.0, 30.0])
        assert h5["sweep/mean_velocity_m_s"].attrs["unit"] == "m/s"
    assert (out / "sweep.png").stat().st_size > 0
    # every name written is one the sweep checks for links at the door (hardening round 4)
    from dem.studies.sweep import SweepPoint, written_names

    walked = set(written_names([SweepPoint(0, {}, out / r["point"]) for r in rows]))
    assert {str(f.relative_to(out)) for f in out.rglob("*")} <= walked
    stamps = {r["point"]: (out / r["point"] / SUMMARY).stat().st_mtime_ns for r in rows}
    capsys.readouterr()
    assert main(args + ["--json"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["skipped"] == 2 and again["failed"] == {}
    assert stamps == {r: (out / r / SUMMARY).stat().st_mtime_ns for r in stamps}


@pytest.mark.integration
def test_a_failed_point_is_reported_while_the_other_finishes(tmp_path, capsys):
    """E = 1e3 Pa passes the checks at load; the guard stops it at the first impacts."""
    case = write_case(tmp_path / "case", TINY)
    out = tmp_path / "out"
    code = main(["sweep", str(case), "--set", "contact.youngs_modulus=5e7,1e3",
                 "--out", str(out), "--workers", "2"])  # fmt: skip
    assert code == 1
    err = capsys.readouterr().err
    assert "001_contact.youngs_modulus=1000 failed: SimulationError: overlap" in err
    rows = {r["point"]: r for r in read_csv(out / "sweep.csv")}
    assert rows["000_contact.youngs_modulus=5e+07"]["status"] == "done"
    failed = rows["001_contact.youngs_modulus=1000"]
    assert failed["status"] == "failed" and "guard" not in failed["error"]
    assert "DEM_MAX_OVERLAP_FRACTION" in failed["error"]
