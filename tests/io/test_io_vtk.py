import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import pyvista as pv

from dem.io.vtk import (
    GRAIN_ARRAYS,
    PARTICLE_ARRAYS,
    VELOCITY_ARRAYS,
    VTKSeriesWriter,
    long_axis,
    read_frame,
    rotate,
)

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


@pytest.mark.integration
def test_the_collection_is_rewritten_on_a_schedule_not_after_every_frame(tmp_path, monkeypatch):
    """Rewriting particles.pvd (O(frames)) after each frame made a long run O(frames^2)."""
    from dem.io import vtk

    now = [0.0]
    monkeypatch.setattr(vtk, "_clock", lambda: now[0])
    rewrites = []
    real = VTKSeriesWriter._write_pvd
    monkeypatch.setattr(VTKSeriesWriter, "_write_pvd", lambda self: (rewrites.append(
        len(self._entries)), real(self)))  # fmt: skip
    w = VTKSeriesWriter(tmp_path, L, W, 0.0)
    rng = np.random.default_rng(3)
    for k in range(300):
        now[0] += 0.02  # a frame every 20 ms: a rewrite at most once a second
        w.write_frame(0.001 * k, **_frame(rng, 4))
    assert rewrites[0] == 1 and 5 <= len(rewrites) <= 8
    w.close()
    root = ET.parse(tmp_path / "particles.pvd").getroot()
    assert len(root.findall("./Collection/DataSet")) == 2 * 300  # all frames once closed


@pytest.mark.integration
def test_pvd_valid_after_kill(tmp_path):
    # a child process writes three frames and is killed without close()
    code = (
        "import os, signal, numpy as np\n"
        "from dem.io import vtk\n"
        "from dem.io.vtk import VTKSeriesWriter\n"
        "vtk.PVD_REWRITE_MIN_S = vtk.PVD_REWRITE_FACTOR = 0.0\n"  # rewritten after every frame
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
    # realistic content: a settled bed moving at a few cm/s, the drive velocity given as a run
    # gives it (the velocity in the lab and relative to the trough, and both speeds: ~44 B of
    # the ~86, random velocities barely compress)
    n, nf = 1500, 3
    rng = np.random.default_rng(0)
    w = VTKSeriesWriter(tmp_path, L, W, 2.5)
    for k in range(nf):
        w.write_frame(0.004 * k, **_frame(rng, n), drive_velocity=np.array([0.1, 0.0, 0.05]))
    w.close()
    size = sum(p.stat().st_size for p in tmp_path.rglob("*") if p.is_file())
    per = size / (n * nf)
    # 1500 spheres x 120 frames must stay well under 100 MB: < 90 B per sphere-frame -> < 17 MB
    print(f"VTK bytes per sphere-frame: {per:.1f}")
    assert per < 90, per
    assert per * 1500 * 120 < 20e6


def _blocks(pvd):
    """(part, name, file) of every DataSet of the collection."""
    root = ET.parse(pvd).getroot()
    return [(int(d.get("part")), d.get("name"), d.get("file"))
            for d in root.findall("./Collection/DataSet")]  # fmt: skip


def test_blocks_are_named_and_velocities_given_in_both_frames(tmp_path):
    rng = np.random.default_rng(4)
    drive_v = np.array([0.12, 0.0, 0.056])
    w = VTKSeriesWriter(tmp_path, L, W, 0.0)
    f = _frame(rng, 8)
    w.write_frame(0.01, **f, drive_velocity=drive_v)
    w.close()
    assert [(p, n) for p, n, _ in _blocks(tmp_path / "particles.pvd")] == [
        (0, "spheres"), (1, "trough")]  # fmt: skip
    mesh = pv.read(tmp_path / "frames" / "particles_000000.vtp")
    for name in PARTICLE_ARRAYS + VELOCITY_ARRAYS:
        assert name in mesh.point_data, name
    v = f["velocity"]
    assert np.allclose(mesh["velocity"], v, atol=1e-7)  # the trough frame: relative, as before
    assert np.allclose(mesh["velocity_trough"], v, atol=1e-7)
    assert np.allclose(mesh["velocity_lab"], v + drive_v, atol=1e-7)
    assert np.allclose(mesh["speed_lab"], np.linalg.norm(v + drive_v, axis=1), atol=1e-7)
    assert np.allclose(mesh["speed_trough"], np.linalg.norm(v, axis=1), atol=1e-7)
    assert np.allclose(mesh.field_data["drive_velocity"], drive_v)
    # the lab frame: velocity is the lab velocity, velocity_trough the relative one
    out = tmp_path / "lab"
    w = VTKSeriesWriter(out, L, W, 0.0, lab_frame=True)
    w.write_frame(0.01, **f, drive_displacement=np.array([1e-4, 0, 5e-5]), drive_velocity=drive_v)
    mesh = pv.read(out / "frames" / "particles_000000.vtp")
    assert np.allclose(mesh["velocity"], v + drive_v, atol=1e-7)
    assert np.allclose(mesh["velocity_trough"], v, atol=1e-7)
    assert mesh.field_data["velocity_frame"][0] == "lab"


class _Bodies:
    """Two dumbbells of a head sphere and a tip sphere along the body x axis."""

    def __init__(self, q):
        self.q = np.asarray(q, dtype=float)
        self.x = np.array([[0.02, 0.0, 0.004], [L + 0.01, 0.005, 0.004]])  # the 2nd wraps
        self.v = np.array([[0.01, 0.0, 0.0], [-0.02, 0.003, 0.001]])
        self.omega = np.array([[0.0, 0.0, 1.0], [0.0, 2.0, 0.0]])
        self.mass = np.array([2.5e-3, 2.5e-3])
        self.moments = np.tile([1e-8, 5e-8, 5e-8], (2, 1))  # least about the body x axis
        # head at -2 mm (heavier side: nearer the centre), tip at +6 mm along body x
        self.offsets = np.tile([[-0.002, 0, 0], [0.006, 0, 0]], (2, 1))
        self.body_of = np.array([0, 0, 1, 1])


def test_grains_dataset_of_clumps(tmp_path):
    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
    q = np.array([[1.0, 0, 0, 0], [c, 0, 0, s]])  # identity; 90 deg about z (x -> y)
    bodies = _Bodies(q)
    f = _frame(np.random.default_rng(5), 4)
    f["clump_id"] = bodies.body_of
    f["grain_id"] = np.array([7, 7, 9, 9])
    f["contact_count"] = np.array([1, 2, 0, 3])
    drive_v = np.array([0.1, 0.0, 0.05])
    w = VTKSeriesWriter(tmp_path, L, W, 0.0)
    w.write_frame(0.0, **f, orientation=q, drive_velocity=drive_v, bodies=bodies)
    w.close()
    assert [n for _, n, _ in _blocks(tmp_path / "particles.pvd")] == ["spheres", "trough",
                                                                      "grains"]  # fmt: skip
    blocks = pv.get_reader(tmp_path / "particles.pvd").read()
    assert len(blocks) == 3
    grains = blocks[2]
    for name in GRAIN_ARRAYS:
        assert name in grains.point_data, name
    assert np.allclose(grains.points, [[0.02, 0.0, 0.004], [0.01, 0.005, 0.004]], atol=1e-7)
    assert list(grains["grain_id"]) == [7, 9] and list(grains["spheres"]) == [2, 2]
    assert list(grains["contact_count"]) == [3, 3]
    assert np.allclose(grains["axis"], [[1, 0, 0], [0, 1, 0]], atol=1e-7)  # towards the tip
    assert np.allclose(grains["velocity_trough"], bodies.v, atol=1e-7)
    assert np.allclose(grains["velocity_lab"], bodies.v + drive_v, atol=1e-7)
    assert np.allclose(grains["speed_lab"], np.linalg.norm(bodies.v + drive_v, axis=1))
    assert np.allclose(grains["angular_velocity"], bodies.omega)
    assert np.allclose(grains["mass"], 2.5e-3)
    # pyvista's own reader names them Block-00..02; read_frame by the collection's names
    assert blocks.keys() == ["Block-00", "Block-01", "Block-02"]
    t, named = read_frame(tmp_path)
    assert t == 0.0 and named.keys() == ["spheres", "trough", "grains"]
    assert np.array_equal(named["grains"]["grain_id"], grains["grain_id"])
    assert named["spheres"].n_points == 4


def test_long_axis_points_to_the_farthest_member():
    rng = np.random.default_rng(6)
    q = rng.normal(size=(5, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    offsets = np.tile([[0.004, 0, 0], [-0.001, 0, 0], [-0.003, 0, 0]], (5, 1))
    axis = long_axis(q, np.tile([1.0, 2.0, 2.0], (5, 1)), offsets, np.repeat(np.arange(5), 3))
    # R(q) e_x by the rotation matrix of each quaternion, written out
    w, x, y, z = q.T
    expected = np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])
    assert np.allclose(axis, expected)
    flipped = long_axis(q, np.tile([1.0, 2.0, 2.0], (5, 1)), -offsets, np.repeat(np.arange(5), 3))
    assert np.allclose(flipped, -expected)
    assert np.allclose(rotate(q, np.tile([1.0, 0, 0], (5, 1))), expected)


def test_a_resumed_writer_keeps_its_grains_and_a_new_one_drops_stale_ones(tmp_path):
    bodies = _Bodies(np.tile([1.0, 0, 0, 0], (2, 1)))
    f = _frame(np.random.default_rng(7), 4)
    f["clump_id"] = bodies.body_of
    w = VTKSeriesWriter(tmp_path, L, W, 0.0)
    w.write_frame(0.0, **f, orientation=bodies.q, bodies=bodies)
    again = VTKSeriesWriter(tmp_path, L, W, 0.0, entries=w.entries)  # a resumed run
    again.write_frame(0.01, **f, orientation=bodies.q, bodies=bodies)
    files = [name for _, _, name in _blocks(tmp_path / "particles.pvd")]
    assert files.count("frames/grains_000000.vtp") == 1
    assert files.count("frames/grains_000001.vtp") == 1
    # a new run of spheres in the same folder: the earlier grains files are gone
    VTKSeriesWriter(tmp_path, L, W, 0.0).write_frame(0.0, **_frame(np.random.default_rng(8), 4))
    assert not list((tmp_path / "frames").glob("grains_*.vtp"))
    assert len(_blocks(tmp_path / "particles.pvd")) == 2


def test_a_frames_contacts_are_a_named_block_with_the_walls_loads(tmp_path):
    snap = {
        "kind": np.array([0, 1, 1]), "i": np.array([0, 0, 1]), "j": np.array([1, -1, -1]),
        "point": np.array([[0.01, 0.0, 0.004], [0.01, 0.0, 0.0], [0.02, 0.0, 0.0]]),
        "normal": np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]),
        "normal_force": np.array([0.5, 1.0, 2.0]),
        "tangential_force": np.array([[0.1, 0.0, 0.0], [0.0, 0.2, 0.0], [0.0, 0.0, 0.0]]),
        "overlap": np.array([1e-6, 2e-6, 3e-6]),
    }  # fmt: skip
    f = _frame(np.random.default_rng(2), 2)
    w = VTKSeriesWriter(tmp_path, L, W, 0.0)
    w.write_frame(0.0, **f, contacts=snap)
    w.write_frame(0.01, **f)  # a frame without contacts lists none
    w.close()
    t, blocks = read_frame(tmp_path, 0)
    assert blocks.keys() == ["spheres", "trough", "contacts"]
    c = blocks["contacts"]
    assert c.n_points == 3 and list(c["kind"]) == [0, 1, 1]
    assert c.field_data["floor_normal_force"][0] == pytest.approx(3.0)
    assert np.allclose(c.field_data["wall_force_on_grains"], [0.0, 0.2, 3.0])
    assert np.allclose(c["normal_force_vector"][0], [0.0, 0.0, 0.5])
    assert read_frame(tmp_path, 1)[1].keys() == ["spheres", "trough"]
