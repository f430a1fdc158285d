"""The contact counts of frames and summaries: the force kernels' own tests against a brute
force over every pair and wall, for spheres, clumps, meshes and a feeder's back wall."""

import math

import meshio
import numpy as np
import pytest
from naive_contacts import contact_counts as naive_counts

from dem.engine.simulation import ContactLaw, Simulation
from dem.engine.state import Bodies, Spheres
from dem.kernels import contact
from dem.scene import shapes
from dem.scene.mesh import extrude, load_mesh
from dem.scene.trough import Trough

RADIUS, DENSITY = 2.0e-3, 7800.0
LENGTH, WIDTH = 0.03, 0.02
KN = 1.0e5


def _law():
    return ContactLaw(
        "linear", contact.make_params(model="linear", stiffness=KN, restitution=0.3, friction=0.35)
    )


def _dt():
    mass = DENSITY * 4 / 3 * math.pi * RADIUS**3
    return contact.linear_collision_time(KN, mass / 2, _law().params[contact.P_BETA]) / 50


def _jittered_bed(seed, rows=3):
    """Spheres on a lattice of pitch just under 2 r, jittered: many contacts, walls included."""
    rng = np.random.default_rng(seed)
    pitch = 1.95 * RADIUS
    xs = np.arange(0.5 * pitch, LENGTH, pitch)
    ys = np.arange(-0.5 * WIDTH + 0.98 * RADIUS, 0.5 * WIDTH - 0.9 * RADIUS, pitch)
    zs = 0.98 * RADIUS + pitch * np.arange(rows)
    x = np.array(np.meshgrid(xs, ys, zs, indexing="ij")).reshape(3, -1).T
    return x + rng.uniform(-0.02, 0.02, x.shape) * RADIUS


def _check(sim, body=None, back=-np.inf):
    s = sim.spheres
    body = np.arange(s.n) if body is None else body
    want = naive_counts(s.x, s.radius, body, sim.trough.length, sim.trough.width, back=back)
    got = sim.contact_counts()
    np.testing.assert_array_equal(got, want)
    return got


@pytest.mark.parametrize("seed", [0, 1])
def test_sphere_counts_match_the_brute_force_before_and_after_steps(seed):
    sim = Simulation(Spheres.create(_jittered_bed(seed), RADIUS, DENSITY), Trough(LENGTH, WIDTH),
                     _law(), _dt())  # fmt: skip
    sim.compute_forces()
    before = _check(sim)
    assert before.sum() > 3 * sim.spheres.n  # a packed bed: pairs, the floor and side walls
    sim.run(400)  # the bed moves: pairs open and close, some across the periodic boundary
    after = _check(sim)
    assert not np.array_equal(before, after)


def test_clump_counts_leave_out_a_clumps_own_spheres():
    rng = np.random.default_rng(3)
    template = shapes.screw(length=0.016, shank_radius=0.0014, head_radius=0.0028, mass=2.5e-3)
    centres = np.array([[0.008, -0.004, 0.004], [0.012, 0.004, 0.005], [0.024, 0.0, 0.004],
                        [0.0285, 0.002, 0.009]])  # fmt: skip
    quats = rng.normal(size=(len(centres), 4))
    quats /= np.linalg.norm(quats, axis=1)[:, None]
    bodies, spheres = Bodies.create(template, centres, quats)
    sim = Simulation(spheres, Trough(LENGTH, WIDTH), _law(), _dt(), bodies=bodies)
    sim.compute_forces()
    body = np.repeat(np.arange(len(centres)), template.count)
    got = _check(sim, body)
    assert got.sum() > 0


def test_a_feeder_counts_its_back_wall():
    x = np.array([[0.5 * RADIUS, 0.0, 3 * RADIUS], [0.9 * RADIUS, 0.0, 0.9 * RADIUS],
                  [0.01, 0.0, 0.9 * RADIUS]])  # fmt: skip
    trough = Trough(LENGTH, WIDTH, discharge=0.02)
    sim = Simulation(Spheres.create(x, RADIUS, DENSITY), trough, _law(), _dt())
    sim.compute_forces()
    got = _check(sim, back=0.0)
    np.testing.assert_array_equal(got, [1, 2, 1])  # the back wall; back wall and floor; floor


def _mesh(tmp_path, profile, x_segments=1):
    path = tmp_path / "pan.vtk"
    meshio.write(path, extrude(profile, LENGTH, x_segments), binary=False)
    return load_mesh(path, length=LENGTH)


def test_a_box_mesh_counts_what_the_flat_walls_count(tmp_path):
    """The floor and side walls as triangles (cut three times along x, so spheres lie over the
    shared edges): the same counts as the flat walls, no contact counted twice."""
    h = 0.5 * WIDTH
    mesh = _mesh(tmp_path, [[-h, 0.012], [-h, 0.0], [h, 0.0], [h, 0.012]], x_segments=3)
    x = _jittered_bed(4, rows=2)
    flat = Simulation(Spheres.create(x, RADIUS, DENSITY), Trough(LENGTH, WIDTH), _law(), _dt())
    pan = Simulation(Spheres.create(x, RADIUS, DENSITY), Trough(LENGTH, WIDTH), _law(), _dt(),
                     mesh=mesh)  # fmt: skip
    for sim in (flat, pan):
        sim.compute_forces()
    np.testing.assert_array_equal(pan.contact_counts(), _check(flat))


def test_a_sphere_in_the_bottom_of_a_v_touches_both_faces(tmp_path):
    """Two faces at 90 degrees: the force kernel adds two contacts, and so does the count."""
    mesh = _mesh(tmp_path, [[-0.01, 0.01], [0.0, 0.0], [0.01, 0.01]], x_segments=2)
    z = RADIUS * math.sqrt(2) * 0.99  # both faces overlapped by 1 % of the radius
    x = np.array([[0.01, 0.0, z], [0.02, 0.005, 0.005 + 0.9 * RADIUS * math.sqrt(2)],
                  [0.005, 0.0, 0.02]])  # fmt: skip
    sim = Simulation(Spheres.create(x, RADIUS, DENSITY), Trough(LENGTH, WIDTH), _law(), _dt(),
                     mesh=mesh)  # fmt: skip
    sim.compute_forces()
    np.testing.assert_array_equal(sim.contact_counts(), [2, 1, 0])
