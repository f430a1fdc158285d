"""``dem atlas``: a grid of bulk runs to a target error, resumable, refusing stale points."""

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from small_case import SMALL_CASE, write_case

from dem.cli import main
from dem.errors import InputError
from dem.studies import atlas

#: 30 spheres (layers set by the grid), one settling and two measured cycles a fill.
TINY = SMALL_CASE.replace("settle_cycles = 2", "settle_cycles = 1").replace(
    "cycles = 6", "cycles = 2"
)

GRID = """
[atlas]
target_error = 0.5
max_replicas = 3
cycles = 2

[atlas.cases]
sphere = "case"

[[grid]]
shape = "sphere"
"drive.angle" = [20.0, 30.0]
"particles.layers" = [0.5]
"""


def read_csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


def write_grid(tmp_path, text=GRID, case=TINY):
    write_case(tmp_path / "case", case)
    path = tmp_path / "grid.toml"
    path.write_text(text)
    return path


def test_a_grid_file_is_read_and_checked_before_anything_runs(tmp_path):
    path = write_grid(tmp_path)
    g = atlas.read_grid(path)
    assert g.target_error == 0.5 and g.max_replicas == 3 and g.cycles == 2
    assert g.points == [("sphere", {"drive.angle": 20.0, "particles.layers": 0.5}),
                        ("sphere", {"drive.angle": 30.0, "particles.layers": 0.5})]  # fmt: skip
    bad = {
        '"run.cycles" = [3]': r"grid\[0\]\.run\.cycles.*the run and output keys are the atlas",
        'shape = "screw"': r"grid\[0\]\.shape = 'screw'.*a shape of \[atlas\.cases\]: sphere",
        '"material.friction" = []': r"grid\[0\]\.material\.friction.*one value at least",
    }
    for line, match in bad.items():
        text = GRID.replace('shape = "sphere"', line) if "shape" in line else GRID + line + "\n"
        with pytest.raises(InputError, match=match):
            atlas.read_grid(write_grid(tmp_path, text))
    with pytest.raises(InputError, match=r"atlas\.target_error.*\[1e-4, 0\.5\]"):
        atlas.read_grid(write_grid(tmp_path, GRID.replace("0.5\nmax", "0.9\nmax")))
    seeded = atlas.read_grid(
        write_grid(tmp_path, GRID.replace("cycles = 2", "cycles = 2\nseed = 1001"))
    )
    case = atlas.point_case(seeded, "sphere", seeded.points[0][1])
    assert seeded.seed == 1001 and case.run.seed == 1001  # a refill of the same points
    assert atlas.point_case(g, "sphere", g.points[0][1]).run.seed == 3  # the base case's
    with pytest.raises(InputError, match=r"atlas\.seed.*whole number"):
        atlas.read_grid(write_grid(tmp_path, GRID.replace("cycles = 2", "cycles = 2\nseed = -1")))
    with pytest.raises(InputError, match=r"atlas\.spead.*a key of \[atlas\]"):
        atlas.read_grid(write_grid(tmp_path, GRID.replace("cycles = 2", "spead = 2")))
    # a point's case is checked at the door, named
    out = tmp_path / "out"
    with pytest.raises(InputError, match=r"drive\.angle.*atlas point sphere"):
        atlas.run_atlas(write_grid(tmp_path, GRID.replace("30.0]", "95.0]")), out, progress=False)
    assert not out.exists()


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The tiny grid, built once."""
    tmp = tmp_path_factory.mktemp("atlas")
    path = write_grid(tmp)
    out = tmp / "out"
    report = atlas.run_atlas(path, out, threads=2, progress=False)
    return path, out, report


@pytest.mark.integration
def test_an_atlas_records_the_bulk_the_point_masses_their_ratio_and_the_cost(built):
    path, out, report = built
    assert report["done"] == 2 and not report["failed"]
    rows = read_csv(out / "atlas.csv")
    assert len(rows) == 2 and {r["status"] for r in rows} == {"done"}
    for r in rows:
        v, pm = float(r["mean_velocity_norm"]), float(r["pointmass_bounded_velocity_norm"])
        assert float(r["ratio_bounded"]) == pytest.approx(v / pm, rel=1e-5)
        assert int(r["fills"]) == 3 and r["target_reached"] == "true"
        assert r["pointmass_regime"].startswith("hopping") and int(r["pointmass_period"]) >= 1
        assert float(r["layers"]) == pytest.approx(0.5, rel=0.1)
        assert float(r["cpu_s"]) > 0 and float(r["particle_steps"]) > 0
    meta = json.loads((out / "atlas.json").read_text())
    assert meta["command"] == "dem atlas" and meta["target_error"] == 0.5
    assert (out / "atlas.h5").is_file() and (out / "atlas.png").is_file()


@pytest.mark.integration
def test_a_rerun_runs_no_finished_point_and_a_changed_case_is_refused(built, tmp_path):
    path, out, _ = built
    summaries = sorted(out.glob("points/*/*/summary.json"))
    stamps = [p.stat().st_mtime_ns for p in summaries]
    report = atlas.run_atlas(path, out, threads=2, progress=False)
    assert report["done"] == 2
    assert [p.stat().st_mtime_ns for p in summaries] == stamps
    # the base case changes: its points are stale, refused by name before anything runs
    case = path.parent / "case" / "case.toml"
    original = case.read_text()
    case.write_text(original.replace("friction = 0.35", "friction = 0.4"))
    try:
        with pytest.raises(InputError, match=r"point sphere/drive\.angle=20.*\(and 1 more\).*"
                           r"material\.friction = 0\.35 \(now 0\.4\).*--rerun-stale"):  # fmt: skip
            atlas.run_atlas(path, out, threads=2, progress=False)
        assert [p.stat().st_mtime_ns for p in summaries] == stamps
        assert atlas.run_atlas(path, out, progress=False, dry_run=True, rerun_stale=True) == {
            "points": 2, "done": 0, "todo": 2, "stale": 2}  # fmt: skip
    finally:
        case.write_text(original)


@pytest.mark.integration
@pytest.mark.parametrize("threads", ["1", "2"])  # fills in process, and in a process pool
def test_sigterm_stops_the_atlas_and_the_same_command_finishes_it(tmp_path, threads):
    """The command is stopped by SIGTERM once its first point has finished; it exits 143 with
    the table of that point; run again it runs the second point only."""
    path = write_grid(tmp_path)
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "support"))
    cmd = [sys.executable, "-m", "dem.cli", "atlas", str(path), "--out", str(out), "--threads",
           threads]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    folder = out / "points" / "sphere" / "drive.angle=20_particles.layers=0.5"
    first, record = folder / "summary.json", folder / atlas.RECORD

    def finished():
        try:
            return json.loads(record.read_text())["finished"]
        except (OSError, ValueError, KeyError):
            return False

    deadline = time.monotonic() + 600
    while not finished() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
    assert finished(), proc.communicate()[1][-2000:]
    time.sleep(1.0)  # into the second point's fills
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 128 + signal.SIGTERM, err[-2000:]
    assert "SIGTERM" in err and "the same command continues" in err and "failed" not in err
    rows = read_csv(out / "atlas.csv")
    assert rows[0]["status"] == "done" and rows[1]["status"] in ("not run", "interrupted")
    stamp = first.stat().st_mtime_ns
    assert main(["atlas", str(path), "--out", str(out), "--threads", threads]) == 0
    assert first.stat().st_mtime_ns == stamp
    assert [r["status"] for r in read_csv(out / "atlas.csv")] == ["done", "done"]


def test_a_second_atlas_into_the_same_folder_is_refused_before_it_moves_anything(tmp_path):
    from dem.run.output import lock_output

    path = write_grid(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    held = lock_output(out)  # an atlas running there
    try:
        with pytest.raises(InputError, match="--out"):
            atlas.run_atlas(path, out, progress=False)
    finally:
        held.close()
    assert not (out / "points").exists()


def test_a_second_signal_does_not_break_off_the_atlas_stop():
    """A signal to the process group arrives twice (directly and forwarded): only the first
    raises, so the stop that follows (the workers, the table) runs to its end."""
    import os
    import time

    from dem.studies import atlas

    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(atlas.AtlasStopped):
        with atlas._StopOnSignals():
            try:
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(5.0)
            except atlas.AtlasStopped:
                os.kill(os.getpid(), signal.SIGTERM)  # the forwarded copy: noted, not raised
                time.sleep(0.05)
                raise
    assert signal.getsignal(signal.SIGTERM) == before
