"""A full disk ends a run in one line, with every file dem wrote whole (issue 15, items 1 and 5).

Measured on a 300 kB tmpfs before these guards: pyvista's ``save`` left a truncated frame and
printed VTK's error without raising; HDF5 failed inside a flush, h5py printed "Exception
ignored" tracebacks and the process segfaulted at exit; the collection's temporary file stayed
behind. The first test repeats that run on a real full file system where the machine lets the
test mount one (root, as CI runs); the others check each guard without one.
"""

import errno
import os
import shutil
import subprocess
import sys
import uuid
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv
from small_case import SMALL_CASE, write_case

from dem.io import hdf5_guard
from dem.io.files import replace_text
from dem.io.hdf5 import ResultsWriter, read_results
from dem.io.vtk import save_vtp


def _mount_tmpfs(size: str) -> Path | None:
    """A fresh tmpfs of ``size`` (e.g. "2500k"), or None where the machine does not allow it."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0 or shutil.which("mount") is None:
        return None
    where = Path("/tmp") / f"dem-full-{uuid.uuid4().hex[:8]}"
    where.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
                          capture_output=True)  # fmt: skip
    if done.returncode != 0:
        where.rmdir()
        return None
    return where


@pytest.fixture
def tiny_disk():
    where = _mount_tmpfs("2500k")
    if where is None:
        pytest.skip("needs root and a mountable tmpfs to fill a real file system")
    yield where
    subprocess.run(["umount", str(where)], check=False)
    where.rmdir()


@pytest.mark.integration
@pytest.mark.parametrize("filler", [1_100_000, 800_000])
def test_a_really_full_disk_ends_in_one_line_with_readable_files(tmp_path, tiny_disk, filler):
    (tiny_disk / "filler").write_bytes(b"\0" * filler)
    case_dir = write_case(tmp_path / "case", SMALL_CASE.replace("cycles = 6", "cycles = 300"))
    out = tiny_disk / "out"
    done = subprocess.run(
        [sys.executable, "-m", "dem.cli", "run", str(case_dir), "--out", str(out),
         "--threads", "1"],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 1, done.stderr[-2000:]
    lines = [x for x in done.stderr.replace("\r", "\n").splitlines() if x.startswith("dem: error")]
    assert len(lines) == 1 and "No space left on device" in lines[0] and str(out) in lines[0]
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr
    r = read_results(out / "results.h5")  # whole: every cycle and frame written before
    assert r["frame_count"] >= 1
    leftovers = [p.name for p in out.rglob("*") if ".tmp" in p.name]
    assert leftovers == []
    for frame in (out / "frames").glob("*.vtp"):
        pv.read(frame)  # no truncated frame


def test_results_file_refuses_a_write_without_room_and_stays_readable(tmp_path, monkeypatch):
    path = tmp_path / "results.h5"
    w = ResultsWriter(path, case={"name": "x"}, versions={}, seed=1, timestep=1e-5)
    w.append_cycle(cycle=0, time=0.1, mean_velocity=0.01, kinetic_energy=1.0, contacts=1,
                   measured=1)  # fmt: skip
    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(hdf5_guard.shutil, "disk_usage",
                        lambda _: usage._replace(free=hdf5_guard.HDF5_FREE_MARGIN - 1))  # fmt: skip
    with pytest.raises(OSError) as info:
        w.append_cycle(cycle=1, time=0.2, mean_velocity=0.02, kinetic_energy=1.0, contacts=1,
                       measured=1)  # fmt: skip
    assert info.value.errno == errno.ENOSPC and info.value.filename == str(path)
    assert len(read_results(path)["cycles"]["mean_velocity"]) == 1


def test_a_frame_vtk_cannot_write_raises_and_leaves_no_file(tmp_path):
    """pyvista's save returns quietly when VTK's writer fails; save_vtp raises and names it."""
    mesh = pv.PolyData(np.random.default_rng(1).random((50, 3)))
    target = tmp_path / "gone" / "frame.vtp"  # a missing folder: VTK's writer fails
    with pytest.raises(OSError) as info:
        save_vtp(mesh, target)
    assert info.value.filename == str(target)
    assert not target.exists() and not target.with_name("frame.vtp.tmp").exists()
    save_vtp(mesh, tmp_path / "frame.vtp")
    assert pv.read(tmp_path / "frame.vtp").n_points == 50


def test_a_failed_replacement_keeps_the_old_file_and_removes_the_temporary(tmp_path, monkeypatch):
    path = tmp_path / "particles.pvd"
    path.write_text("old")

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")  # as close() raises it: no name

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(OSError) as info:
        replace_text(path, "new")
    monkeypatch.undo()
    assert info.value.filename == str(path) and info.value.errno == errno.ENOSPC
    assert path.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == [path.name]
