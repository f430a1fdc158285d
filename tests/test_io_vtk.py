import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import pyvista as pv

from dem.io.vtk import PARTICLE_ARRAYS, VTKSeriesWriter

L, W = 0.1, 0.04


def _frame(rng, n):
    pos = np.column_stack(
        [rng.uniform(0, L, n), rng.uniform(-W / 2, W / 2, n), rng.uniform(0, 0.02, n)]
    )
    return {
        "positions": pos,
        "radius": rng.uniform(0.0015, 0.0025, n),
        "velocity": rng.normal(0.0, 0.05, (n, 3)),
        "grain_id": np.arange(n),
        "clump_id": np.arange(n) // 2,
        "contact_count": rng.integers(0, 9, n),
    }


def _write(out, times, n=50, lab_frame=False, shifts=None, close=True, seed=0):
    rng = np.random.default_rng(seed)
    w = VTKSeriesWriter(out, L, W, 2.5, lab_frame=lab_frame)
    frames = []
    for k, t in enumerate(times):
        f = _frame(rng, n)
        shift = None if shifts is None else shifts[k]
        w.write_frame(t, **f, drive_displacement=shift)
        frames.append(f)
    if close:
        w.close()
    return frames


def test_pvd_time_series_reads_back_with_arrays(tmp_path):
    times = [0.0, 0.0041666, 0.0083333, 0.0125]
    frames = _write(tmp_path, times)
    first = pv.read(tmp_path / "particles.pvd")  # pyvista 0.49: the first time step
    assert isinstance(first, pv.MultiBlock) and first[0].n_points == 50
    reader = pv.get_reader(tmp_path / "particles.pvd")
    assert np.allclose(reader.time_values, times)
    for t, f in zip(times, frames, strict=True):
        reader.set_active_time_value(t)
        blocks = reader.read()
        assert len(blocks) == 2
        spheres, trough = blocks[0], blocks[1]
        assert spheres.n_points == 50 and spheres.n_verts == 50
        for name in PARTICLE_ARRAYS:
            assert name in spheres.point_data, name
        assert np.allclose(spheres.points, f["positions"], atol=1e-7)
        assert np.allclose(spheres["radius"], f["radius"], rtol=1e-6)
        assert np.allclose(spheres["velocity"], f["velocity"], atol=1e-7)
        assert np.array_equal(spheres["clump_id"], f["clump_id"])
        assert np.array_equal(spheres["contact_count"], f["contact_count"])
        assert np.isclose(spheres.field_data["time"][0], t)
        # trough frame: floor z = 0 from x = 0 to L, walls at y = +-W/2
        assert np.allclose(trough.bounds[:5], [0, L, -W / 2, W / 2, 0])
        assert trough.n_cells == 3


def test_glyph_scaled_by_radius(tmp_path):
    frames = _write(tmp_path, [0.0], n=5)
    mesh = pv.read(tmp_path / "frames" / "particles_000000.vtp")
    glyphs = mesh.glyph(scale="radius", geom=pv.Sphere(radius=1.0), orient=False)
    pos, r = frames[0]["positions"], frames[0]["radius"]
    assert np.isclose(glyphs.bounds[0], np.min(pos[:, 0] - r), atol=1e-5)
    assert np.isclose(glyphs.bounds[5], np.max(pos[:, 2] + r), atol=1e-5)


def test_lab_frame_shifts_spheres_and_trough(tmp_path):
    shifts = [np.zeros(3), np.array([4e-4, 0.0, 2e-4]), np.array([-3e-4, 0.0, -1e-4])]
    frames = _write(tmp_path, [0.0, 0.01, 0.02], lab_frame=True, shifts=shifts)
    reader = pv.get_reader(tmp_path / "particles.pvd")
    for t, s, f in zip(reader.time_values, shifts, frames, strict=True):
        reader.set_active_time_value(t)
        spheres, trough = reader.read()
        assert np.allclose(spheres.points, f["positions"] + s, atol=1e-7)
        assert np.allclose(trough.bounds[::2], np.array([0, -W / 2, 0]) + s, atol=1e-12)
    # the default trough frame ignores the displacement
    out = tmp_path / "trough_frame"
    frames = _write(out, [0.0, 0.01], shifts=shifts[1:])
    spheres = pv.read(out / "frames" / "particles_000001.vtp")
    assert np.allclose(spheres.points, frames[1]["positions"], atol=1e-7)


def test_positions_wrapped_into_periodic_section(tmp_path):
    w = VTKSeriesWriter(tmp_path, L, W, 0.0)
    f = _frame(np.random.default_rng(1), 3)
    f["positions"][:, 0] = [-0.01, 0.05, 0.13]
    w.write_frame(0.0, **f)
    mesh = pv.read(tmp_path / "frames" / "particles_000000.vtp")
    assert np.allclose(mesh.points[:, 0], [0.09, 0.05, 0.03], atol=1e-7)


def test_pvd_valid_after_kill(tmp_path):
    # a child process writes three frames and is killed without close()
    code = (
        "import os, signal, numpy as np\n"
        "from dem.io.vtk import VTKSeriesWriter\n"
        f"w = VTKSeriesWriter({str(tmp_path)!r}, {L}, {W}, 0.0)\n"
        "n = 20\n"
        "for k in range(3):\n"
        "    w.write_frame(0.01 * k, np.random.rand(n, 3) * 0.02, np.full(n, 1e-3),\n"
        "                  np.zeros((n, 3)), np.arange(n), np.arange(n), np.zeros(n, int))\n"
        "os.kill(os.getpid(), signal.SIGKILL)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True)
    assert proc.returncode == -9, proc.stderr.decode()
    pvd = tmp_path / "particles.pvd"
    root = ET.parse(pvd).getroot()  # well-formed XML
    sets = root.findall("./Collection/DataSet")
    assert len(sets) == 6
    for ds in sets:
        assert (tmp_path / ds.get("file")).is_file()
    reader = pv.get_reader(pvd)
    assert np.allclose(reader.time_values, [0.0, 0.01, 0.02])
    reader.set_active_time_value(0.02)
    assert reader.read()[0].n_points == 20
    assert not list(tmp_path.glob("*.tmp"))


def test_orientation_mapped_through_clump_id(tmp_path):
    w = VTKSeriesWriter(tmp_path, L, W, 0.0)
    f = _frame(np.random.default_rng(2), 6)  # clump_id 0,0,1,1,2,2
    q = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])
    w.write_frame(0.0, **f, orientation=q)
    mesh = pv.read(tmp_path / "frames" / "particles_000000.vtp")
    assert np.allclose(mesh["orientation"], q[f["clump_id"]])
    with pytest.raises(ValueError, match="orientation"):
        w.write_frame(0.1, **f, orientation=q[:2])


def test_bad_shapes_rejected(tmp_path):
    w = VTKSeriesWriter(tmp_path, L, W, 0.0)
    f = _frame(np.random.default_rng(3), 4)
    f["radius"] = f["radius"][:3]
    with pytest.raises(ValueError, match="radius"):
        w.write_frame(0.0, **f)


def test_bytes_per_sphere_frame(tmp_path):
    # realistic content: a settled bed moving at a few cm/s
    n, nf = 1500, 3
    _write(tmp_path, [0.004 * k for k in range(nf)], n=n)
    size = sum(p.stat().st_size for p in tmp_path.rglob("*") if p.is_file())
    per = size / (n * nf)
    # 1500 spheres x 120 frames must stay well under 100 MB: < 60 B per sphere-frame -> < 11 MB
    print(f"VTK bytes per sphere-frame: {per:.1f}")
    assert per < 60, per
    assert per * 1500 * 120 < 20e6
