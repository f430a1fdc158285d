"""Rigid clumps in the engine: the one-sphere clump, rest, no intra-clump contacts, momentum,
the sliding screw against the point mass, and a small screw run through ``run_case``."""

import json
import math

import numpy as np
import pytest
from small_case import write_case

from dem.engine import setup
from dem.engine.simulation import ContactLaw, Simulation
from dem.engine.state import Bodies, Spheres
from dem.io import checkpoint
from dem.kernels import contact
from dem.kernels.rigid import matrix_to_quat, quat_to_matrix
from dem.physics import drive
from dem.run.runner import run_case
from dem.scene import shapes
from dem.scene.case import load_case
from dem.scene.trough import Trough

RADIUS, DENSITY = 2.0e-3, 7800.0
SCREW = dict(length=0.016, shank_radius=0.0014, head_radius=0.0028)
SCREW_MASS = 2.5e-3


def _linear(kn=1.0e5, e=0.3, mu=0.35):
    return ContactLaw(
        "linear", contact.make_params(model="linear", stiffness=kn, restitution=e, friction=mu)
    )


def _screw():
    return shapes.screw(**SCREW, mass=SCREW_MASS)


def _lying_orientation(template):
    """Quaternion that lays the screw along +x with head and tip sphere both on the floor."""
    head = template.centres[np.argmax(template.radii)]
    tip = template.centres[np.argmax(template.centres @ (template.centres[-1] - head))]
    u = (tip - head) / np.linalg.norm(tip - head)
    span = np.linalg.norm(tip - head)
    drop = SCREW["head_radius"] - SCREW["shank_radius"]
    theta = math.asin(drop / span)
    w = np.array([math.cos(theta), 0.0, -math.sin(theta)])
    axis = np.cross(u, w)
    s, c = np.linalg.norm(axis), float(u @ w)
    k = axis / s if s > 1e-15 else np.array([0.0, 0.0, 1.0])
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    rot = np.eye(3) + s * kx + (1 - c) * kx @ kx
    q = matrix_to_quat(rot)
    # centre of mass height: the head sphere's bottom on the floor
    z = SCREW["head_radius"] - (quat_to_matrix(q) @ head)[2]
    return q, z


@pytest.mark.validation
def test_one_sphere_clump_follows_the_sphere_path():
    """A clump of one sphere and the sphere integrator: same trajectory to rounding."""
    law = _linear(e=0.5)
    mass = DENSITY * 4 / 3 * math.pi * RADIUS**3
    dt = contact.linear_collision_time(1.0e5, mass, law.params[contact.P_BETA]) / 50
    x0 = np.array([[0.01, 0.0, 1.3 * RADIUS]])
    v0 = np.array([[0.2, 0.05, -0.1]])
    w0 = np.array([[3.0, -20.0, 1.0]])
    spheres = Spheres.create(x0, RADIUS, DENSITY)
    spheres.v[:] = v0
    spheres.omega[:] = w0
    ref = Simulation(spheres, Trough(0.02, 0.02), law, dt)
    template = shapes.sphere(RADIUS, DENSITY)
    bodies, members = Bodies.create(template, x0, np.array([[1.0, 0.0, 0.0, 0.0]]))
    bodies.v[:] = v0
    bodies.ang_mom[:] = w0 * template.moments[0]
    bodies.place(members)
    clump = Simulation(members, Trough(0.02, 0.02), law, dt, bodies=bodies)
    for _ in range(4):
        ref.run(500)
        clump.run(500)
        np.testing.assert_allclose(members.x, spheres.x, rtol=0, atol=1e-15)
        np.testing.assert_allclose(members.v, spheres.v, rtol=0, atol=1e-13)
        np.testing.assert_allclose(members.omega, spheres.omega, rtol=0, atol=1e-11)
    assert abs(spheres.v[0, 0] - v0[0, 0]) > 1e-3  # the contact did something


def _screw_sim(law, dt, positions, quats, trough, rotation=True):
    bodies, spheres = Bodies.create(_screw(), positions, quats)
    return Simulation(spheres, trough, law, dt, rotation=rotation, bodies=bodies)


def _dt(kn=1.0e5, e=0.3):
    t = _screw()
    beta = _linear(kn, e).params[contact.P_BETA]
    return contact.linear_collision_time(kn, t.mass / 4, beta) / 50


@pytest.mark.validation
def test_screw_at_rest_on_still_trough_stays_put():
    q, z = _lying_orientation(_screw())
    sim = _screw_sim(_linear(), _dt(), [[0.02, 0.0, z]], [q], Trough(0.04, 0.03))
    sim.run(int(0.1 / sim.dt))
    x1, q1 = sim.bodies.x.copy(), sim.bodies.q.copy()
    assert sim.contact_counts().sum() == 2  # head and tip on the floor
    sim.run(int(0.4 / sim.dt))
    assert np.max(np.abs(sim.bodies.x - x1)) < 1e-9
    turn = 2 * math.acos(min(1.0, abs(float(sim.bodies.q[0] @ q1[0]))))
    assert turn < 1e-6
    assert np.max(np.abs(sim.bodies.v)) < 1e-7 and np.max(np.abs(sim.bodies.omega)) < 1e-5


def test_no_contacts_inside_a_clump():
    q, z = _lying_orientation(_screw())
    positions = [[0.02, 0.0, z], [0.02, 0.0, z + 2 * SCREW["head_radius"]]]  # stacked, touching
    sim = _screw_sim(_linear(), _dt(), positions, [q, q], Trough(0.04, 0.03))
    sim.compute_forces()
    k = sim.pairs.n_pairs
    body = sim.spheres.body
    i, j = sim.pairs.pair_i[:k], sim.pairs.pair_j[:k]
    assert k > 0 and np.all(body[i] != body[j])
    single = _screw_sim(_linear(), _dt(), positions[:1], [q], Trough(0.04, 0.03))
    single.compute_forces()
    assert single.pairs.n_pairs == 0  # overlapping members, yet no pairs


def test_clump_collision_conserves_momentum():
    """Two screws collide in free space (no gravity, far from the walls): sum M V is kept."""
    rng = np.random.default_rng(4)
    q = rng.standard_normal((2, 4))
    positions = np.array([[0.04, 0.0, 0.05], [0.058, 0.002, 0.05]])
    sim = _screw_sim(_linear(e=0.5), _dt(e=0.5), positions, q, Trough(0.1, 0.1))
    sim.gravity = np.zeros(3)
    sim.bodies.v[:] = [[0.4, 0.0, 0.0], [-0.4, 0.0, 0.0]]
    sim.bodies.place(sim.spheres)
    p0 = sim.bodies.mass @ sim.bodies.v
    sim.run(int(0.1 / sim.dt))
    assert np.max(np.abs(sim.bodies.v - [[0.4, 0, 0], [-0.4, 0, 0]])) > 0.05  # they met
    assert np.max(np.abs(sim.bodies.ang_mom)) > 0.0
    np.testing.assert_allclose(sim.bodies.mass @ sim.bodies.v, p0, atol=1e-15)


@pytest.mark.validation
@pytest.mark.parametrize("seed", [4, 5])
def test_elastic_clump_collision_keeps_angular_momentum_and_energy(seed):
    """Frictionless, undamped collision of two tumbling screws off-centre: the total angular
    momentum sum X x M V + L about the origin is kept to accumulated round-off (shank members
    have equal radii, so the two forces of a pair act at one contact point; measured about
    5e-17 kg m^2/s in 2.7e-6 after 7000 steps) and the kinetic energy to the
    integrator's O(dt^2) (dt = t_c / 50), while both screws leave spinning."""
    rng = np.random.default_rng(seed)
    positions = np.array([[0.04, 0.0, 0.05], [0.058, 0.002, 0.05]])
    sim = _screw_sim(_linear(e=1.0, mu=0.0), _dt(e=1.0), positions, rng.standard_normal((2, 4)),
                     Trough(0.1, 0.1))  # fmt: skip
    sim.gravity = np.zeros(3)
    b = sim.bodies
    b.v[:] = [[0.4, 0.0, 0.0], [-0.4, 0.0, 0.0]]
    b.ang_mom[:] = rng.normal(scale=1e-6, size=(2, 3))
    b.place(sim.spheres)

    def angular_momentum():
        return np.cross(b.x, b.mass[:, None] * b.v).sum(axis=0) + b.ang_mom.sum(axis=0)

    l0, e0, spin0 = angular_momentum(), sim.kinetic_energy(), b.ang_mom.copy()
    sim.run(int(0.1 / sim.dt))
    assert np.max(np.abs(b.ang_mom - spin0)) > 1e-7  # they met and the contact turned them
    np.testing.assert_allclose(angular_momentum(), l0, rtol=0, atol=1e-9 * np.abs(l0).max())
    assert sim.kinetic_energy() == pytest.approx(e0, rel=1e-3)


SCREW_CASE = """
[trough]
length = {length}
width = {width}

[drive]
frequency = 60.0
angle = 25.0
throw_number = {gamma}

[material]
friction = 0.35
restitution_normal = {eps_n}

[contact]
model = "{model}"
{contact}

[particles]
shape = "screw"
count = {count}
length = 0.016
shank_radius = 0.0014
head_radius = 0.0028
mass = 0.0025
rotation = {rotation}

[run]
settle_cycles = {settle}
cycles = {cycles}
seed = 2

[output]
frames_per_cycle = 2
"""


@pytest.mark.validation
@pytest.mark.parametrize("gamma", [0.4, 0.9])
def test_sliding_screw_matches_point_mass(tmp_path, gamma):
    """A single screw, rotation locked, in the sliding regime: within 3 % of the point mass.

    With the tangential spring derived from eps_t = 0.8 (k_t / k_n = 0.0216) the error falls as
    k_n^-1/2: measured -5.8 / -6.3 % at k_n = 1e6 (Gamma 0.4 / 0.9), -2.6 / -2.4 % at 4e6,
    -1.2 / -0.5 % at 1.6e7 (with k_t = 2/7 k_n: -1.3 / -0.6 % at 1e6). A 2.5 g screw on two
    contacts needs a stiffer spring than a 0.26 g sphere on one for the same tangential frequency.
    """
    text = SCREW_CASE.format(
        length=0.04, width=0.03, gamma=gamma, eps_n=0.0, model="linear",
        contact="stiffness = 1.6e7", count=1, rotation="false", settle=4, cycles=4,
    )  # fmt: skip
    case = load_case(write_case(tmp_path / "case", text))
    summary = run_case(case, tmp_path / "out", progress=False, frames=False)
    reference = summary["pointmass_velocity_norm"]
    assert abs(reference) > 0.05
    assert summary["mean_velocity_norm"] == pytest.approx(reference, rel=0.03)


@pytest.mark.validation
def test_run_case_screws_writes_summary(tmp_path):
    text = SCREW_CASE.format(
        length=0.04, width=0.03, gamma=1.8, eps_n=0.3, model="hertz_mindlin",
        contact="youngs_modulus = 5.0e7", count=20, rotation="true", settle=1, cycles=1,
    )  # fmt: skip
    case = load_case(write_case(tmp_path / "case", text))
    assert case.particles.grain.mass == pytest.approx(SCREW_MASS)
    summary = run_case(case, tmp_path / "out", progress=False)
    on_disk = json.loads((tmp_path / "out" / "summary.json").read_text())
    k = case.particles.grain.count
    assert on_disk["grains"] == 20 and on_disk["spheres"] == 20 * k
    assert on_disk["total_mass"] == pytest.approx(20 * SCREW_MASS)
    assert math.isfinite(summary["mean_velocity"]) and summary["steps"] > 0
    frames = sorted((tmp_path / "out" / "frames").glob("particles_*.vtp"))
    assert frames
    import pyvista as pv

    mesh = pv.read(frames[-1])
    assert mesh.n_points == 20 * k
    assert set(np.unique(mesh.point_data["clump_id"])) == set(range(20))
    assert mesh.point_data["orientation"].shape == (20 * k, 4)


def _small_screw_case(tmp_path, count, rotation):
    text = SCREW_CASE.format(
        length=0.04, width=0.03, gamma=1.8, eps_n=0.3, model="hertz_mindlin",
        contact="youngs_modulus = 5.0e7", count=count, rotation=rotation, settle=1, cycles=1,
    )  # fmt: skip
    return load_case(write_case(tmp_path / "case", text))


@pytest.mark.validation
def test_clump_checkpoint_continues_bit_for_bit(tmp_path):
    case = _small_screw_case(tmp_path, 10, "true")
    straight = setup.from_case(case)
    straight.settle()
    straight.start_drive()
    straight.run(1500)
    first = setup.from_case(case)
    first.settle()
    first.start_drive()
    first.run(700)
    state = {k: v.copy() for k, v in checkpoint.state_dict(first).items()}
    second = setup.from_case(case)
    checkpoint.load_state(second, state)
    second.run(800)
    for name in ("x", "v", "q", "ang_mom"):
        np.testing.assert_array_equal(getattr(second.bodies, name), getattr(straight.bodies, name))
    np.testing.assert_array_equal(second.spheres.x, straight.spheres.x)
    assert np.max(np.abs(straight.bodies.ang_mom)) > 0.0


@pytest.mark.validation
def test_rotation_false_locks_the_orientation(tmp_path):
    case = _small_screw_case(tmp_path, 6, "false")
    sim = setup.from_case(case)
    q0 = sim.bodies.q.copy()
    sim.run(3000)
    assert np.all(sim.bodies.ang_mom == 0.0) and np.all(sim.spheres.omega == 0.0)
    np.testing.assert_array_equal(sim.bodies.q, q0)
    assert np.max(np.abs(sim.bodies.v)) > 0.01  # they fell, without turning
    assert np.all((sim.bodies.x[:, 0] >= 0.0) & (sim.bodies.x[:, 0] < 0.04))  # X_x wrapped


def test_trough_shorter_than_a_clump_is_refused():
    from dem.errors import InputError

    with pytest.raises(InputError, match="trough.length"):
        _screw_sim(_linear(), _dt(), [[0.005, 0.0, 0.01]], [[1.0, 0, 0, 0]], Trough(0.015, 0.03))


def test_body_force_acts_at_the_centre_of_mass():
    """Free fall in the shaken frame: g + A w^2 sin(w t) e moves the screw but never turns it."""
    omega = 2 * math.pi * 60.0
    line = drive.Motion(omega, (drive.Component(3e-4, math.radians(25.0)),))
    trough = Trough(0.04, 0.03, motion=line)
    q = np.random.default_rng(1).standard_normal((1, 4))
    sim = _screw_sim(_linear(), _dt(), [[0.02, 0.0, 0.05]], q, trough)
    sim.start_drive()
    steps = 2000
    sim.run(steps)
    assert np.all(sim.bodies.ang_mom == 0.0) and np.all(sim.spheres.omega == 0.0)
    t = steps * sim.dt
    a = trough.amplitude * omega**2
    shaken = a * (1 - math.cos(omega * t)) / omega  # integral of A w^2 sin(w t) dt
    expected = trough.gravity * t + shaken * trough.direction
    np.testing.assert_allclose(sim.bodies.v[0], expected, rtol=1e-5)  # trapezoid rule
