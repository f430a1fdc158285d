"""Mesh troughs: closest points, contacts without double counting, and the flat walls reproduced."""

import math

import meshio
import numba
import numpy as np
import pytest

from dem.engine import setup
from dem.errors import InputError
from dem.kernels.mesh import EDGE, FACE, VERTEX, closest_point
from dem.scene.case import load_case
from dem.scene.mesh import extrude, load_mesh

LENGTH, WIDTH, WALL = 0.03, 0.02, 0.012

CASE = """
[trough]
length = {length}
width = {width}
inclination = {inclination}
{mesh}

[drive]
frequency = 60.0
angle = 25.0
throw_number = {throw}

[material]
density = 7800.0
friction = 0.35
restitution_normal = 0.0
restitution_tangential = 0.8

[contact]
model = "hertz_mindlin"
youngs_modulus = 5.0e8

[particles]
shape = "sphere"
count = {count}
radius = 0.002
rotation = {rotation}

[run]
settle_cycles = 1
cycles = 2
seed = 2

[output]
frames_per_cycle = 4
"""


def _case(tmp_path, *, mesh=None, count=1, rotation="false", inclination=0.0, throw=0.5,
          name="case", width=WIDTH):  # fmt: skip
    folder = tmp_path / name
    folder.mkdir(parents=True, exist_ok=True)
    line = "" if mesh is None else f'mesh = "{mesh}"'
    (folder / "case.toml").write_text(CASE.format(
        length=LENGTH, width=width, inclination=inclination, mesh=line, throw=throw, count=count,
        rotation=rotation))  # fmt: skip
    return load_case(folder)


def _box_mesh(path, x_segments=1):
    """Floor and side walls of the flat trough as triangles (normals into the trough)."""
    h = 0.5 * WIDTH
    profile = [[-h, WALL], [-h, 0.0], [h, 0.0], [h, WALL]]
    meshio.write(path, extrude(profile, LENGTH, x_segments), binary=False)
    return path


@numba.njit
def _closest(p, tri):
    return closest_point(p[0], p[1], p[2], tri, 0)


@pytest.mark.validation
def test_closest_point_matches_brute_force_and_names_the_feature():
    rng = np.random.default_rng(0)
    uv = np.array([(a, b) for a in np.linspace(0, 1, 301) for b in np.linspace(0, 1, 301)
                   if a + b <= 1.0])  # fmt: skip
    seen = set()
    for _ in range(60):
        tri = rng.normal(size=(1, 3, 3))
        p = rng.normal(size=3) * 2.0
        qx, qy, qz, feature = _closest(p, tri)
        a, b, c = tri[0]
        samples = a + uv[:, :1] * (b - a) + uv[:, 1:] * (c - a)
        best = np.min(np.linalg.norm(samples - p, axis=1))
        got = math.dist((qx, qy, qz), p)
        assert got <= best + 1e-12 and got >= best - 0.02 * np.ptp(tri)  # no sample is closer
        seen.add(feature)
        # the feature: a vertex is a corner; an edge point lies on a side; a face point inside
        corners = np.linalg.norm(tri[0] - [qx, qy, qz], axis=1)
        if feature == VERTEX:
            assert corners.min() < 1e-12
        elif feature == FACE:
            assert corners.min() > 0.0
    assert seen == {FACE, EDGE, VERTEX}


def test_mesh_file_errors_name_the_key(tmp_path):
    (tmp_path / "bad.stl").write_text("solid nothing\nendsolid\n")
    with pytest.raises(InputError, match="trough.mesh"):
        load_mesh(tmp_path / "bad.stl", length=LENGTH)
    short = tmp_path / "short.stl"
    meshio.write(short, extrude([[-0.01, 0.0], [0.01, 0.0]], 0.5 * LENGTH), binary=False)
    with pytest.raises(InputError, match="spanning x from 0 to trough.length"):
        load_mesh(short, length=LENGTH)
    _box_mesh(tmp_path / "box.stl")
    with pytest.raises(InputError, match="trough.width"):
        _case(tmp_path, mesh=tmp_path / "box.stl", width=2 * WIDTH)


def _run_single(case, position, velocity, steps):
    sim = setup.from_grains(case, np.array([position]), velocities=np.array([velocity]))
    out = []
    for _ in range(steps // 50):
        sim.run(50)
        out.append(np.concatenate([sim.spheres.x[0], sim.spheres.v[0]]))
    return sim, np.array(out)


@pytest.mark.validation
@pytest.mark.parametrize("where", ["face", "shared vertex", "shared edge"])
def test_a_flat_mesh_reproduces_the_flat_walls(tmp_path, where):
    """A sphere on a floor cut into many triangles moves as on the flat floor: no contact twice."""
    mesh = _box_mesh(tmp_path / "box.stl", x_segments=6)
    flat = _case(tmp_path, name="flat")
    meshed = _case(tmp_path, mesh=mesh, name="meshed")
    r = 0.002
    x0 = {"face": 0.0031, "shared vertex": 0.005, "shared edge": 0.0075}[where]
    y0 = {"face": 0.0013, "shared vertex": 0.0, "shared edge": 0.0}[where]
    # x0 = 0.005 is a vertex row of the 6 x-segments (every 5 mm); y = 0 the shared edge line
    start, vel = [x0, y0, 0.98 * r], [0.0, 0.0, 0.0]
    a, ta = _run_single(flat, start, vel, 600)
    b, tb = _run_single(meshed, start, vel, 600)
    np.testing.assert_allclose(tb, ta, rtol=0, atol=1e-9)
    # and it came to rest on the floor with the overlap of its weight (one contact, not two)
    assert abs(b.spheres.v[0]).max() < 1e-3


@pytest.mark.validation
def test_sliding_down_a_tilted_mesh_follows_coulomb(tmp_path):
    """A block on a plane tilted by a = 30 deg slides with g (sin a - mu cos a)."""
    a = math.radians(30.0)
    mu = 0.35
    # a plane through the origin rising in +y: z = tan(a) (y + w/2), spanning the section
    ys = np.linspace(-0.5 * WIDTH, 0.5 * WIDTH, 2)
    profile = np.column_stack([ys, np.tan(a) * (ys + 0.5 * WIDTH)])
    path = tmp_path / "ramp.stl"
    meshio.write(path, extrude(profile, LENGTH, 3), binary=False)
    case = _case(tmp_path, mesh=path, width=WIDTH)
    r = 0.002
    y0 = 0.003
    z0 = np.tan(a) * (y0 + 0.5 * WIDTH) + r / math.cos(a) - 1e-6
    sim = setup.from_grains(case, np.array([[0.01, y0, z0]]))
    sim.run(2000)  # come to the plane, start sliding
    t0, v0 = sim.time, sim.spheres.v[0].copy()
    sim.run(4000)
    dv = (sim.spheres.v[0] - v0) / (sim.time - t0)
    along = -np.array([0.0, math.cos(a), math.sin(a)])  # down the slope
    expected = 9.81 * (math.sin(a) - mu * math.cos(a))
    assert np.dot(dv, along) == pytest.approx(expected, rel=0.01)


@pytest.mark.validation
def test_a_grain_rests_in_the_u_trough(tmp_path):
    from dem.scene.mesh import extrude as ext

    theta = np.linspace(np.pi, 2 * np.pi, 49)
    radius = 0.5 * WIDTH
    profile = np.column_stack([radius * np.cos(theta), radius + radius * np.sin(theta)])
    path = tmp_path / "u.stl"
    meshio.write(path, ext(profile, LENGTH), binary=False)
    case = _case(tmp_path, mesh=path, rotation="true")
    r = 0.002
    sim = setup.from_grains(case, np.array([[0.012, 0.0, r + 1e-5]]))
    sim.run(3000)
    x1 = sim.spheres.x[0].copy()
    sim.run(6000)
    assert np.linalg.norm(sim.spheres.x[0] - x1) < 1e-6
    assert np.linalg.norm(sim.spheres.v[0]) < 1e-4
    assert sim.mesh.gaps(sim.spheres.x)[0] > 0.95 * r


@pytest.mark.validation
def test_a_fast_grain_does_not_tunnel(tmp_path):
    mesh = _box_mesh(tmp_path / "box.stl", x_segments=2)
    case = _case(tmp_path, mesh=mesh, rotation="true")
    r = 0.002
    sim = setup.from_grains(case, np.array([[0.01, 0.0, 3 * r]]), velocities=[[0.0, 0.0, -5.0]],
                            impact_speed=5.0)  # fmt: skip
    lowest = np.inf
    for _ in range(200):
        sim.run(10)
        lowest = min(lowest, sim.spheres.x[0, 2])
    # it struck at 5 m/s (eps_n = 0: no rebound) and rests on the floor, never below half a radius
    assert lowest > 0.5 * r
    assert sim.spheres.x[0, 2] == pytest.approx(r, rel=0.05)
    assert np.linalg.norm(sim.spheres.v[0]) < 1e-3


@pytest.mark.validation
def test_a_bed_in_the_u_trough_stays_above_the_mesh_in_every_frame(tmp_path):
    """dem run on a U-trough mesh: every sphere of every frame lies inside the pan, clear of it."""
    import h5py

    from dem.run.runner import run_case

    theta = np.linspace(np.pi, 2 * np.pi, 33)
    radius = 0.5 * WIDTH
    arc = np.column_stack([radius * np.cos(theta), radius + radius * np.sin(theta)])
    profile = np.vstack([[[-radius, radius + WALL]], arc, [[radius, radius + WALL]]])
    path = tmp_path / "u.stl"
    meshio.write(path, extrude(profile, LENGTH), binary=False)
    case = _case(tmp_path, mesh=path, count=40, rotation="true", throw=1.8)
    summary = run_case(case, tmp_path / "out", progress=False)
    assert np.isfinite(summary["mean_velocity"])
    mesh = load_mesh(path, length=LENGTH)
    mesh.index(0.01)
    with h5py.File(tmp_path / "out" / "results.h5") as f:
        frames = f["frames/positions"][:]
        r = f["frames/radius"][:]
    assert len(frames) >= 8
    for x in frames:
        assert np.all(mesh.sides(x) > 0.0)  # on the grains' side
        assert np.all(mesh.gaps(x) > 0.8 * r)  # never deeper than the overlap bound
    # the trough drawn for ParaView is the mesh
    import pyvista as pv

    drawn = pv.read(tmp_path / "out" / "frames" / "trough.vtp")
    assert drawn.n_cells == mesh.count


@pytest.mark.parametrize("name", ["u_trough.stl", "v_trough.stl"])
def test_dems_stl_reader_gives_meshios_triangles_bit_for_bit(tmp_path, name):
    """dem reads STL itself (sizes and grammar checked); the triangles are meshio's, so runs of
    the shipped mesh troughs are unchanged, in ASCII and in binary."""
    from pathlib import Path

    shipped = Path(__file__).parents[2] / "cases" / "geometry" / name
    for path in (shipped, tmp_path / name):
        mesh = meshio.read(shipped)
        if path != shipped:
            meshio.write(path, mesh, binary=True)
            mesh = meshio.read(path)
        expected = mesh.points[mesh.cells[0].data].astype(np.float64)
        np.testing.assert_array_equal(load_mesh(path).tri, expected)
