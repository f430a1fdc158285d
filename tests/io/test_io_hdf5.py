import json
import shutil
import subprocess
import sys

import h5py
import numpy as np
import pytest

from dem.io.hdf5 import ResultsWriter, package_versions, read_results

CASE = {
    "name": "spheres",
    "trough": {"length": 0.1, "width": 0.04, "inclination": 0.0, "mesh": None},
    "drive": {"frequency": 60.0, "angle": 25.0, "throw_number": 1.8},
    "particles": {"shape": "sphere", "count": 40, "radius": 0.002},
    "run": {"seed": 7, "cycles": 3},
}


def _writer(path, **kw):
    return ResultsWriter(
        path, case=CASE, versions=package_versions(), seed=7, timestep=2.5e-6, **kw
    )


def _frame(rng, n):
    return (
        rng.uniform(0.0, 0.04, (n, 3)),
        rng.normal(0.0, 0.05, (n, 3)),
        rng.integers(0, 9, n),
    )


def test_metadata_round_trip(tmp_path):
    path = tmp_path / "results.h5"
    _writer(path).close()
    res = read_results(path)
    assert res["case"] == CASE
    assert res["seed"] == 7 and res["timestep"] == 2.5e-6 and res["format_version"] == 2
    assert res["complete"] is True
    assert set(res["versions"]) == {"dem", "numpy", "numba", "h5py", "python"}
    assert res["frame_count"] == 0 and res["cycles"] == {}
    with h5py.File(path, "r") as f:
        assert json.loads(f.attrs["case_json"]) == CASE
        assert f["case/drive"].attrs["angle"] == 25.0
        assert f["case/particles"].attrs["shape"] == "sphere"
        assert "mesh" not in f["case/trough"].attrs  # None left out of the tree


def test_incremental_readable_without_close(tmp_path):
    path = tmp_path / "results.h5"
    rng = np.random.default_rng(0)
    n = 40
    w = _writer(path)
    written = []
    for k in range(3):
        pos, vel, cc = _frame(rng, n)
        w.append_frame(0.01 * k, pos, vel, np.full(n, 0.002), np.arange(n) // 2, cc)
        w.append_cycle(cycle=k, time=0.0167 * k, mean_velocity=0.01 + 0.001 * k, contacts=10 * k)
        written.append((pos, vel, cc))
        # a second read-only handle while the writer is alive, and a copy of the file
        res = read_results(path)
        assert res["frame_count"] == k + 1 and res["complete"] is False
        assert np.array_equal(res["cycles"]["cycle"], np.arange(k + 1))
    copy = tmp_path / "copy.h5"
    shutil.copy(path, copy)
    for res in (read_results(path), read_results(copy)):
        assert np.allclose(res["cycles"]["mean_velocity"], [0.01, 0.011, 0.012])
        assert res["cycles"]["contacts"].dtype.kind == "i"
        frames = res["frames"]
        assert len(frames) == 3 and np.allclose(frames.time, [0.0, 0.01, 0.02])
        for k, (pos, vel, cc) in enumerate(written):
            fr = frames[k]
            assert np.array_equal(fr["positions"], pos) and np.array_equal(fr["velocity"], vel)
            assert np.array_equal(fr["contact_count"], cc)
            assert np.array_equal(fr["grain_id"], np.arange(n) // 2)
            assert np.allclose(fr["radius"], 0.002)
        assert np.array_equal(frames[-1]["positions"], written[-1][0])
        with pytest.raises(IndexError):
            frames[3]
    with h5py.File(path, "r") as f:
        d = f["frames/positions"]
        assert d.shape == (3, n, 3) and d.chunks == (1, n, 3) and d.compression == "gzip"
        assert f["cycles/time"].maxshape == (None,)
    w.close()
    assert read_results(path)["complete"] is True
    with pytest.raises(ValueError, match="closed"):
        w.append_cycle(cycle=3, time=0.05, mean_velocity=0.0, contacts=0)


def test_readable_after_kill(tmp_path):
    path = tmp_path / "results.h5"
    code = (
        "import os, signal, numpy as np\n"
        "from dem.io.hdf5 import ResultsWriter\n"
        f"w = ResultsWriter({str(path)!r}, case={{'a': 1}}, versions={{}}, seed=1, timestep=1e-5)\n"
        "n = 30\n"
        "for k in range(4):\n"
        "    w.append_frame(0.1 * k, np.full((n, 3), k), np.zeros((n, 3)), np.ones(n), None,\n"
        "                   np.zeros(n, int))\n"
        "    w.append_cycle(cycle=k, mean_velocity=0.5 * k)\n"
        "os.kill(os.getpid(), signal.SIGKILL)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True)
    assert proc.returncode == -9, proc.stderr.decode()
    res = read_results(path)
    assert res["complete"] is False and res["frame_count"] == 4
    assert np.allclose(res["cycles"]["mean_velocity"], [0.0, 0.5, 1.0, 1.5])
    assert np.all(res["frames"][3]["positions"] == 3.0)


def test_cycle_keys_fixed_and_checked(tmp_path):
    w = _writer(tmp_path / "results.h5")
    w.append_cycle(cycle=0, mean_velocity=0.1)
    with pytest.raises(ValueError, match="differ"):
        w.append_cycle(cycle=1, kinetic_energy=0.1)
    with pytest.raises(ValueError, match="scalar"):
        w.append_cycle(cycle=1, mean_velocity=[0.1, 0.2])


def test_frame_shapes_checked(tmp_path):
    w = _writer(tmp_path / "results.h5")
    with pytest.raises(ValueError, match="radius"):
        w.append_frame(0.0, np.zeros((4, 3)), np.zeros((4, 3)))
    w.append_frame(0.0, np.zeros((4, 3)), np.zeros((4, 3)), np.ones(4))
    with pytest.raises(ValueError, match="spheres"):
        w.append_frame(0.1, np.zeros((5, 3)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="velocity"):
        w.append_frame(0.1, np.zeros((4, 3)), np.zeros((4, 2)))


def test_bytes_per_sphere_frame(tmp_path):
    # a settled bed: grain-scale positions, velocities of a few cm/s (random mantissas, worst case)
    path = tmp_path / "results.h5"
    n, nf = 1500, 4
    rng = np.random.default_rng(1)
    w = _writer(path)
    for k in range(nf):
        pos, vel, cc = _frame(rng, n)
        w.append_frame(0.004 * k, pos, vel, np.full(n, 0.002), None, cc)
    w.close()
    empty = tmp_path / "empty.h5"
    _writer(empty).close()
    per = (path.stat().st_size - empty.stat().st_size) / (n * nf)
    print(f"HDF5 bytes per sphere-frame: {per:.1f}")
    # raw float64 positions + velocities + int32 contacts = 52 B; 1500 x 120 frames -> < 10 MB
    assert per < 56, per
    assert path.stat().st_size / nf * 120 < 20e6


def test_viewer_holding_the_file_does_not_stop_appends(tmp_path):
    path = tmp_path / "results.h5"
    w = _writer(path)
    w.append_cycle(cycle=0, mean_velocity=0.1)
    code = (
        "import sys, time, h5py\n"
        f"f = h5py.File({str(path)!r}, 'r')\n"  # default locking, as a viewer would
        "print('open', flush=True)\n"
        "sys.stdin.read()\n"
    )
    viewer = subprocess.Popen(
        [sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE
    )
    try:
        assert viewer.stdout.readline().strip() == b"open"
        w.append_cycle(cycle=1, mean_velocity=0.2)
        w.append_frame(0.0, np.zeros((3, 3)), np.zeros((3, 3)), np.ones(3))
    finally:
        viewer.communicate(b"")
    w.close()
    res = read_results(path)
    assert np.allclose(res["cycles"]["mean_velocity"], [0.1, 0.2]) and res["frame_count"] == 1


def test_resolved_case_from_case_file(tmp_path):
    from pathlib import Path

    from dem.scene.case import load_case

    case = load_case(Path(__file__).parents[2] / "cases" / "sphere-bed").as_dict()
    path = tmp_path / "results.h5"
    ResultsWriter(path, case=case, versions={}, seed=1, timestep=1e-5).close()
    assert read_results(path)["case"] == json.loads(json.dumps(case))
    with h5py.File(path, "r") as f:
        assert f["case/drive"].attrs["amplitude"] == case["drive"]["amplitude"]
        assert f["case/contact"].attrs["limit_force"] == case["contact"]["limit_force"]


def _unit_quaternions(rng, b):
    q = rng.normal(size=(b, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


def test_clump_orientations_round_trip(tmp_path):
    path = tmp_path / "results.h5"
    rng = np.random.default_rng(2)
    bodies, members = 3, 2
    n = bodies * members
    grain_id = np.arange(n) // members
    w = _writer(path)
    written = []
    for k in range(3):
        pos, vel, cc = _frame(rng, n)
        q = _unit_quaternions(rng, bodies)
        w.append_frame(0.01 * k, pos, vel, np.full(n, 0.002), grain_id, cc, orientation=q)
        written.append(q)
    with pytest.raises(ValueError, match="orientation"):
        w.append_frame(0.03, pos, vel)  # a file with orientations needs them in every frame
    with pytest.raises(ValueError, match="orientation"):
        w.append_frame(0.03, pos, vel, orientation=_unit_quaternions(rng, bodies + 1))
    w.close()
    res = read_results(path)
    assert res["format_version"] == 2 and res["frame_count"] == 3
    for k, q in enumerate(written):
        assert np.array_equal(res["frames"][k]["orientation"], q)
        assert np.array_equal(res["frames"][k]["grain_id"], grain_id)
    with h5py.File(path, "r") as f:
        d = f["frames/orientation"]
        assert d.shape == (3, bodies, 4) and d.dtype == np.float64 and d.chunks == (1, bodies, 4)
    # a resumed run trims the orientations with the other frame data and goes on appending
    w = _writer(path, resume_at=(0, 2))
    w.append_frame(0.02, pos, vel, orientation=written[0])
    w.close()
    res = read_results(path)
    assert res["frame_count"] == 3
    assert np.array_equal(res["frames"][1]["orientation"], written[1])
    assert np.array_equal(res["frames"][2]["orientation"], written[0])
    # plain spheres: no orientation dataset, None in every frame; a clump index must exist
    spheres = tmp_path / "spheres.h5"
    w = _writer(spheres)
    w.append_frame(0.0, pos, vel, np.full(n, 0.002), None, cc)
    with pytest.raises(ValueError, match="orientation"):
        w.append_frame(0.01, pos, vel, orientation=written[0])
    w.close()
    assert read_results(spheres)["frames"][0]["orientation"] is None
    with pytest.raises(ValueError, match="grain_id"):
        _writer(tmp_path / "bad.h5").append_frame(
            0.0, pos, vel, np.full(n, 0.002), np.arange(n), cc, orientation=written[0]
        )


def test_format_versions_one_to_three_are_read_and_others_refused(tmp_path):
    from dem.errors import InputError
    from dem.provenance import git_commit

    old = tmp_path / "v1.h5"
    w = _writer(old, format_version=1)
    w.append_frame(0.0, np.zeros((4, 3)), np.zeros((4, 3)), np.ones(4))
    w.close()
    res = read_results(old)
    assert res["format_version"] == 1 and res["frames"][0]["orientation"] is None
    commit = git_commit()  # None outside a git checkout; "+" marks edits to dem/ (may change)
    assert (res["git_commit"] or "").rstrip("+") == (commit or "").rstrip("+")
    for version in (0, 4):
        path = tmp_path / f"v{version}.h5"
        _writer(path, format_version=version).close()
        with pytest.raises(InputError) as info:
            read_results(path)
        message = str(info.value)
        assert str(path) in message and f"format_version = {version}" in message
        assert "versions 1, 2, 3" in message
    # a run is never continued into a file of another version
    with pytest.raises(InputError, match="format_version = 1"):
        _writer(old, resume_at=(0, 1))


def test_ragged_frames_of_a_changing_grain_count_round_trip_and_resume(tmp_path):
    """Format 3: each frame its own count; a reopened file is trimmed to the frames it keeps."""
    rng = np.random.default_rng(5)
    path = tmp_path / "r.h5"
    w = _writer(path, ragged=True)
    written = []
    for k, n in enumerate((5, 7, 3, 6)):
        pos, vel, cc = _frame(rng, n)
        gid = np.arange(10 * k, 10 * k + n)
        q = rng.normal(size=(n, 4))
        balance = {"grains_in_trough": np.int64(n), "mass_in_trough": np.float64(0.1 * n)}
        w.append_frame(0.01 * k, pos, vel, radius=np.full(n, 1e-3 * (k + 1)), grain_id=gid,
                       contact_count=cc, orientation=q, grain_index=np.arange(n),
                       per_frame=balance)  # fmt: skip
        written.append((pos, vel, cc, gid, q))
    w.append_cycle(cycle=0, mean_velocity=0.1)
    w.close()
    r = read_results(path)
    assert r["format_version"] == 3 and r["frame_count"] == 4
    for k, (pos, vel, cc, gid, q) in enumerate(written):
        f = r["frames"][k]
        np.testing.assert_array_equal(f["positions"], pos)
        np.testing.assert_array_equal(f["velocity"], vel)
        np.testing.assert_array_equal(f["contact_count"], cc)
        np.testing.assert_array_equal(f["grain_id"], gid)
        np.testing.assert_array_equal(f["orientation"], q)
        assert f["radius"].shape == (len(pos),) and f["radius"][0] == 1e-3 * (k + 1)
        assert f["grains_in_trough"] == len(pos) and f["time"] == 0.01 * k
    # an interrupted run resumes after frame 2: frames 2 and 3 are dropped, then rewritten
    w = _writer(path, ragged=True, resume_at=(1, 2))
    pos, vel, cc = _frame(rng, 4)
    w.append_frame(0.5, pos, vel, radius=np.full(4, 1e-3), grain_id=np.arange(4),
                   contact_count=cc, orientation=rng.normal(size=(4, 4)),
                   per_frame={"grains_in_trough": np.int64(4),
                              "mass_in_trough": np.float64(0.4)})  # fmt: skip
    w.close()
    r = read_results(path)
    assert r["frame_count"] == 3
    np.testing.assert_array_equal(r["frames"][1]["positions"], written[1][0])
    np.testing.assert_array_equal(r["frames"][2]["positions"], pos)
    assert r["frames"][2]["grains_in_trough"] == 4 and r["frames"][2]["orientation"].shape == (4, 4)
    # a fixed-count writer cannot resume a ragged file
    with pytest.raises(Exception, match="format version 2"):
        _writer(path, resume_at=(1, 2))
