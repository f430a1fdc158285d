"""The impact-aware tangential law (``[contact] tangential = "impact"``).

Independent checks: eps_t of virtual impacts against the law's target and the Coulomb bound,
a block on a tilted floor against rigid Coulomb friction, the history's phase switch, a contact
that re-forms, and one grain against the (Coulomb-bounded) point mass.
"""

import dataclasses
import math

import numpy as np
import pytest

from dem import pointmass
from dem.engine import setup
from dem.engine.simulation import ContactLaw, Simulation, measure_cycles
from dem.engine.state import Spheres
from dem.kernels import contact
from dem.physics.measure import conveying_velocity
from dem.pointmass.bounded import coulomb_bounded_velocity
from dem.scene.case import load_case
from dem.scene.trough import Trough
from dem.studies import calibrate

RADIUS, DENSITY = 0.002, 7800.0
MASS = DENSITY * 4.0 / 3.0 * math.pi * RADIUS**3


def _case(model="linear", value=4.0e6, *, e_t=0.8, e_n=0.0, mu=0.35, rotation=False, **kw):
    """cases/single-sphere under the impact law, another normal law, eps_t, mu or rotation."""
    c = load_case("cases/single-sphere")
    contact = dataclasses.replace(
        c.contact, model=model, tangential="impact", tangential_stiffness_ratio=None,
        tangential_damping_ratio=None,
        youngs_modulus=value if model == "hertz_mindlin" else None,
        stiffness=value if model == "linear" else None, **kw,
    )  # fmt: skip
    material = dataclasses.replace(
        c.material, restitution_tangential=e_t, restitution_normal=e_n, friction=mu
    )
    particles = dataclasses.replace(c.particles, rotation=rotation)
    return dataclasses.replace(c, contact=contact, material=material, particles=particles)


def _bound(mu, incidence):
    """eps_t of the Coulomb-bounded rigid landing with eps_n = 0: 1 - mu cot(theta)."""
    return 1.0 - mu / math.tan(math.radians(incidence))


@pytest.mark.parametrize(
    ("model", "value"), [("linear", 4.0e6), ("hertz_mindlin", 5.0e7), ("hertz_mindlin", 5.0e9)]
)
@pytest.mark.validation
@pytest.mark.parametrize("rotation", [False, True])
def test_eps_t_is_a_material_property_at_every_incidence_and_speed(model, value, rotation):
    """Flat at eps_t where Coulomb does not bind, on the rigid bounded value where it does."""
    case = _case(model, value, rotation=rotation)
    for incidence in (5.0, 30.0, 60.0, 75.0, 85.0):
        for speed in (0.05, 1.0):
            eps_t = calibrate.virtual_impact(case, incidence, speed).eps_t
            target = max(0.8, _bound(0.35, incidence))
            assert eps_t == pytest.approx(target, abs=0.005), (incidence, speed)


@pytest.mark.validation
@pytest.mark.parametrize("e_t", [0.2, 0.5])
def test_low_eps_t_of_a_block_is_reached_and_bounded(e_t):
    case = _case(e_t=e_t)
    assert calibrate.virtual_impact(case, 20.0, 0.3).eps_t == pytest.approx(e_t, abs=0.005)
    assert calibrate.virtual_impact(case, 70.0, 0.3).eps_t == pytest.approx(
        max(e_t, _bound(0.35, 70.0)), abs=0.005
    )


@pytest.mark.validation
def test_a_rolling_sphere_stops_slipping_at_rolling():
    """A sphere free to roll cannot give its centre less than 5/7 of v_t without reversing its
    contact point's slip; the law ends the impact when the slip stops (no energy created)."""
    eps_t = calibrate.virtual_impact(_case(e_t=0.2, rotation=True), 20.0, 0.3).eps_t
    assert eps_t == pytest.approx(5.0 / 7.0, abs=0.01)


def _block_on_floor(case, tilt_deg, dt, vx=0.0):
    """A block resting on a floor tilted by ``tilt_deg`` (no drive), its overlap at rest."""
    law = ContactLaw.from_case(case)
    kn = case.contact.stiffness
    g = 9.81
    z = RADIUS - MASS * g * math.cos(math.radians(tilt_deg)) / kn
    spheres = Spheres.create(np.array([[0.01, 0.0, z]]), RADIUS, DENSITY)
    spheres.v[0, 0] = vx
    trough = Trough(0.02, 0.01, inclination=math.radians(tilt_deg))
    return Simulation(spheres, trough, law, dt, rotation=False)


@pytest.mark.validation
@pytest.mark.parametrize("kn", [4.0e5, 4.0e6])
def test_no_creep_below_the_friction_angle_and_coulomb_sliding_above(kn):
    """Below atan(mu) the block stays put (creep below 1e-6 m/s); above it accelerates at
    g (sin a - mu cos a) down the slope, whatever the contact stiffness."""
    mu = 0.35
    case = _case(value=kn, mu=mu)
    dt = contact.linear_collision_time(kn, MASS, 0.0) / 50
    below = math.degrees(math.atan(mu)) - 3.0
    sim = _block_on_floor(case, below, dt)
    sim.run(int(0.05 / dt))
    x0 = sim.spheres.x[0, 0]
    sim.run(int(0.05 / dt))
    assert abs(sim.spheres.x[0, 0] - x0) / 0.05 < 1e-6
    above = math.degrees(math.atan(mu)) + 5.0
    sim = _block_on_floor(case, above, dt)
    sim.run(int(0.02 / dt))
    v1, t1 = sim.spheres.v[0, 0], sim.step_index * dt
    sim.run(int(0.05 / dt))
    v2, t2 = sim.spheres.v[0, 0], sim.step_index * dt
    a = math.radians(above)
    expected = -9.81 * (math.sin(a) - mu * math.cos(a))  # x rises with the slope: slides to -x
    assert (v2 - v1) / (t2 - t1) == pytest.approx(expected, rel=2e-3)


@pytest.mark.validation
def test_force_is_continuous_at_the_switch_and_a_new_contact_starts_an_impact():
    """Step a wall contact through an impact by hand: the force of the switch step is the
    impact's, the stick spring it leaves gives that same force, and zeroed history (a contact
    that broke) is a new impact."""
    case = _case()
    p = ContactLaw.from_case(case).params
    hist = np.zeros((1, contact.HISTORY_WIDTH["impact"]))
    dt = 1.0e-6
    x, vz, vx = 0.0, -0.3, 0.2
    phases, switched = [], None
    for _ in range(20000):
        x += -vz * dt
        if x <= 0.0:
            break
        f = contact.contact_force(
            0, p, 0.0, 0.0, 1.0, x, vx, 0.0, vz, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            RADIUS - x, 0.0, RADIUS - x, 0.0, MASS, RADIUS, hist, 0, dt,
        )  # fmt: skip
        before = phases[-1] if phases else 0.0
        phases.append(hist[0, 3])
        if before > 0.0 and hist[0, 3] < 0.0:
            m_t = p[contact.P_MASS_T] * MASS
            alpha = p[contact.P_STICK_RATE]
            ks = m_t * (alpha / dt) ** 2
            gs = 2.0 * p[contact.P_STICK_ZETA] * alpha * m_t / dt
            spring_force = -ks * hist[0, 0] - gs * vx
            switched = (f[0], spring_force)
        vz += f[2] / MASS * dt
        vx += f[0] / MASS * dt
    assert phases[0] > 0.0, "a first touch while approaching is an impact"
    assert switched is not None, "the impact switched to the enduring stick"
    assert switched[1] == pytest.approx(switched[0], rel=1e-9, abs=1e-12)
    hist[:] = 0.0
    contact.contact_force(
        0, p, 0.0, 0.0, 1.0, 1e-7, vx, 0.0, -0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        RADIUS, 0.0, RADIUS, 0.0, MASS, RADIUS, hist, 0, dt,
    )  # fmt: skip
    assert hist[0, 3] > 0.0


def _wall_impact(e_n, vz=-0.3, vx=0.2, dt=1.0e-6, steps=4000):
    """Step one wall contact of a locked sphere by hand (no gravity): the normal forces and the
    normal velocity after ``steps`` steps or at separation."""
    p = ContactLaw.from_case(_case("hertz_mindlin", 2.0e9, e_n=e_n)).params
    hist = np.zeros((1, contact.HISTORY_WIDTH["impact"]))
    x, forces = 0.0, []
    for _ in range(steps):
        x += -vz * dt
        if x <= 0.0:
            break
        f = contact.contact_force(
            1, p, 0.0, 0.0, 1.0, x, vx, 0.0, vz, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            RADIUS - x, 0.0, RADIUS - x, 0.0, MASS, RADIUS, hist, 0, dt,
        )  # fmt: skip
        forces.append(f[9])
        vz += f[2] / MASS * dt
        vx += f[0] / MASS * dt
    return np.array(forces), vz, x


def test_a_plastic_impact_returns_no_normal_speed_and_never_pulls():
    """eps_n = 0 under the impact law is perfectly plastic (contact.plastic_normal): the material
    law stops the approach, its last step capped at the force that stops it within the step, and
    the sphere rests in its dent, never pulled; the law before left e_n = 0.135."""
    forces, vz, x = _wall_impact(0.0)
    assert abs(vz) < 1e-12 and x > 0.0, "at rest in the dent, no rebound"
    assert forces.min() >= 0.0
    # eps_n > 0: the material law's own rebound, as before (dem.kernels.contact.params)
    forces, vz, _ = _wall_impact(0.5)
    assert vz == pytest.approx(0.5 * 0.3, rel=0.05)


@pytest.mark.validation
def test_the_kernels_reset_the_whole_history_row_when_a_contact_breaks():
    case = _case()
    law = ContactLaw.from_case(case)
    spheres = Spheres.create(np.array([[0.01, 0.0, 2.0 * RADIUS]]), RADIUS, DENSITY)
    sim = Simulation(spheres, Trough(0.02, 0.01), law, 1e-6, rotation=False)
    assert sim.spheres.wall_hist.shape[1] == law.history_width == 5
    sim.spheres.wall_hist[:] = 7.0
    sim.run(1)
    assert not sim.spheres.wall_hist.any()


def _block_velocity(case, settle=20, cycles=20):
    sim = setup.from_grains(case, [[0.5 * case.trough.length, 0.0, case.particles.radius]])
    per_cycle = measure_cycles(sim, cycles, settle_cycles=settle)
    d = case.drive
    return conveying_velocity(per_cycle, scale=d.velocity_scale).norm


@pytest.mark.validation
def test_sliding_block_converges_to_rigid_coulomb_as_the_contact_stiffens():
    """Gamma 0.5, phi 20 deg: the error against the point mass falls as E grows (Hertz)."""
    errors = []
    for youngs in (5.0e7, 5.0e8, 5.0e9):
        case = _case("hertz_mindlin", youngs).with_drive(angle=20.0, throw_number=0.5)
        pm = pointmass.velocity(0.5, 20.0, 0.35, 0.0, 0.8, 0.0).velocity_norm
        errors.append(abs(_block_velocity(case) / pm - 1.0))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.01


@pytest.mark.validation
@pytest.mark.parametrize(("gamma", "e_t"), [(1.2, 0.8), (2.0, 0.8), (2.5, 0.2)])
def test_hopping_block_follows_the_coulomb_bounded_point_mass(gamma, e_t):
    """No calibration: at Gamma 1.2 the paper's Eq. 12 asks for more than Coulomb allows (paper
    0.124, bounded 0.354); the block follows the bounded model there too."""
    case = _case(value=1.6e7, e_t=e_t).with_drive(angle=25.0, throw_number=gamma)
    v = _block_velocity(case)
    assert v == pytest.approx(coulomb_bounded_velocity(gamma, 25.0, 0.35, e_t), abs=0.02)


@pytest.mark.validation
@pytest.mark.parametrize("gamma", [1.2, 1.8, 5.5])
def test_a_lone_hertz_grain_at_the_shipped_stiffness_follows_the_bounded_point_mass(gamma):
    """Issue 46 item 2 (validation/hopping-bias): one sphere on Hertz's law at the beds' 2e9 Pa,
    rotation locked, eps_n = 0, nothing calibrated, is within 1 % of the Coulomb-bounded point
    mass, where the dashpot's eps_n = 0 left it 2-5 % fast."""
    case = _case("hertz_mindlin", 2.0e9).with_drive(angle=25.0, throw_number=gamma)
    pm = pointmass.velocity(gamma, 25.0, 0.35, 0.0, 0.8, 0.0, impact="coulomb").velocity_norm
    assert _block_velocity(case, settle=30) == pytest.approx(pm, rel=0.01)


def _tilted_screw_bed_speed(monkeypatch, **sticks) -> float:
    """rms speed of 40 screws at rest on a floor tilted to 0.9 of the friction angle, drive
    off, 0.1 s after their fill came to rest (validation/impact-law stick_creep.csv is the
    200-screw version); ``sticks``: ``stick_rate`` or ``normal_stick_rate`` other than the
    defaults."""
    if sticks:
        defaults = dict(contact.make_params.__kwdefaults__, **sticks)
        monkeypatch.setattr(contact.make_params, "__kwdefaults__", defaults)
    incline = math.degrees(math.atan(0.9 * 0.35))
    case = load_case("cases/screw-trough", {
        "particles.count": 40, "trough.length": 0.05, "trough.width": 0.04,
        "trough.inclination": incline,
    })  # fmt: skip
    sim = setup.from_case(case)
    sim.settle()
    sim.run(round(0.1 / sim.dt))
    return sim.rms_speed()


@pytest.mark.validation
def test_a_screw_bed_at_rest_below_the_friction_angle_stays_at_rest_under_the_default_stick(
    monkeypatch,
):
    """The default sticks (0.5 rad a step tangential, 0.25 normal: eps_n = 0's plastic contact)
    hold a bed whose screws share several sticking contacts; a tangential stick past the
    explicit limit (1.2 rad a step) chatters against its Coulomb cap and never rests (no
    instability guard sees it: the cap bounds it), and so does a normal stick of 0.5 beside the
    tangential one (validation/hopping-bias, run.py stick)."""
    assert _tilted_screw_bed_speed(monkeypatch) < 1e-9
    assert _tilted_screw_bed_speed(monkeypatch, stick_rate=1.2) > 1e-6
    assert _tilted_screw_bed_speed(monkeypatch, normal_stick_rate=0.5) > 1e-6
