"""Tangential restitution of the ``"coulomb"`` spring law: the mapping of dem.physics.tangential,
virtual impacts, calibration. The impact-aware default law is tested in test_impact_law.py."""

import dataclasses
import math

import numpy as np
import pytest

from dem.engine.simulation import ContactLaw, Simulation
from dem.engine.state import Spheres
from dem.kernels import contact
from dem.physics import tangential
from dem.scene.case import load_case
from dem.scene.trough import Trough
from dem.studies import calibrate


def _sphere_case(
    e_n=0.0, e_t=0.8, mu=0.35, rotation=False, limit_force=False, timestep=None, **contact
):
    case = load_case("cases/single-sphere")
    return dataclasses.replace(
        case,
        run=dataclasses.replace(case.run, timestep=timestep),
        material=dataclasses.replace(
            case.material, restitution_normal=e_n, restitution_tangential=e_t, friction=mu
        ),
        contact=dataclasses.replace(
            case.contact, limit_force=limit_force, **{"tangential": "coulomb", **contact}
        ),
        particles=dataclasses.replace(case.particles, rotation=rotation),
    )


KN, MASS = 1.6e7, 7800.0 * 4 / 3 * math.pi * 0.002**3
T_UNDAMPED = contact.linear_collision_time(KN, MASS, 0.0)


@pytest.mark.validation
@pytest.mark.parametrize("e", [0.1, 0.3, 0.6, 0.9])
def test_virtual_impact_restitution_matches_linear_formula(e):
    """Head-on impact of the linear spring-dashpot: the rebound is e, to an error that falls
    with dt (first order: the dashpot sees half-step velocities)."""
    errors = []
    for fraction in (50, 400):
        case = _sphere_case(e_n=e, mu=0.0, timestep=T_UNDAMPED / fraction)
        impact = calibrate.virtual_impact(case, 0.0, 0.5)
        errors.append(abs(impact.eps_n - e))
    assert errors[1] < 1.5e-3 and errors[1] < errors[0] / 4
    t_c = contact.linear_collision_time(KN, MASS, contact.damping_beta(e))
    assert impact.duration == pytest.approx(t_c, rel=0.01)


@pytest.mark.parametrize("beta", [-1.0, -1.5, -3.0])
def test_no_rebound_at_and_beyond_critical_damping(beta):
    """eps_n = 0 maps to critical damping; over-critical damping does not rebound either."""
    radius, density, kn = 0.002, 7800.0, 4.0e6
    params = contact.make_params(model="linear", stiffness=kn, friction=0.35, beta=beta)
    spheres = Spheres.create(np.array([[0.01, 0.0, radius + 1e-9]]), radius, density)
    spheres.v[0] = [0.1, 0.0, -0.4]
    mass = spheres.mass[0]
    dt = contact.linear_collision_time(kn, mass, -1.0) / 100
    sim = Simulation(spheres, Trough(0.02, 0.01), ContactLaw("linear", params), dt, rotation=False)
    impact = calibrate.measure_impact(sim)
    assert abs(impact.eps_n) < 3e-3
    assert impact.incidence == pytest.approx(math.degrees(math.atan2(0.1, 0.4)))


def test_hertz_mapping_converges_and_inverts():
    """The self-similar Hertz impact: eps_t converged in the Runge-Kutta step (halving it moves
    eps_t by < 1e-5), the root inverted for a block and a rolling sphere, and a softer spring than
    the linear closed form (which, applied with S_n for k_n, took 11.7 % more impulse)."""
    zeta_n = math.sqrt(5.0 / 6.0)  # eps_n = 0
    kappas = np.array([0.005, 0.02, 0.1])
    coarse = tangential.hertz_slip_velocity(kappas, zeta_n, 0.3, 1.0)
    old = tangential._HERTZ_STEP
    try:
        tangential._HERTZ_STEP = old / 2
        fine = tangential.hertz_slip_velocity(kappas, zeta_n, 0.3, 1.0)
    finally:
        tangential._HERTZ_STEP = old
    assert np.abs(coarse - fine).max() < 1e-5
    for f in (1.0, 2 / 7):
        for e in (0.65, 0.8, 0.95):
            kappa = tangential.tangential_stiffness_ratio(e, zeta_n, 0.3, f, "hertz_mindlin")
            assert tangential.sticking_restitution(
                kappa, zeta_n, 0.3, f, "hertz_mindlin"
            ) == pytest.approx(e, abs=1e-7)
            assert kappa < tangential.tangential_stiffness_ratio(e, 1.0, 0.3, f)
    linear_kappa = tangential.tangential_stiffness_ratio(0.8, 1.0, 0.3, 1.0)
    assert tangential.sticking_restitution(
        linear_kappa, zeta_n, 0.3, 1.0, "hertz_mindlin"
    ) == pytest.approx(0.777, abs=0.002)
    with pytest.raises(ValueError, match="< eps_t < 1 for a Hertz contact"):
        tangential.tangential_stiffness_ratio(0.5, zeta_n, 0.3, 2 / 7, "hertz_mindlin")


@pytest.mark.validation
@pytest.mark.parametrize(("rotation", "e_t"), [(False, 0.5), (False, 0.8), (True, 0.8)])
@pytest.mark.parametrize("speed", [0.05, 0.5])
def test_hertz_sticking_impact_gives_eps_t(rotation, e_t, speed):
    """A Hertz sphere at the shipped 2e9 Pa that sticks throughout (mu = 1e4, limit_force, 10
    deg) keeps the eps_t it was given, at two impact speeds a decade apart (the mapping is
    speed-free), rolling or not: within 1e-3 at dt = 5e-8 s, the error falling at first order
    as the step shrinks (the dashpots see half-step velocities; at the automatic step of this
    lone grain, 0.004-0.02)."""
    errors = []
    for timestep in (2.0e-7, 5.0e-8):
        case = _sphere_case(
            e_t=e_t, mu=1.0e4, rotation=rotation, limit_force=True, model="hertz_mindlin",
            youngs_modulus=2.0e9, stiffness=None, timestep=timestep,
        )  # fmt: skip
        errors.append(abs(calibrate.virtual_impact(case, 10.0, speed).eps_t - e_t))
    assert errors[1] < 1e-3 and errors[1] < errors[0] / 2.5, errors


@pytest.mark.parametrize(
    ("rotation", "e_t"), [(False, 0.2), (False, 0.5), (False, 0.8), (True, 0.8)]
)
@pytest.mark.parametrize("incidence", [10.0, 30.0])
def test_sticking_impact_gives_the_eps_t_of_the_formula(rotation, e_t, incidence):
    """With limit_force the grain leaves at the zero of the normal force, where
    dem.physics.tangential
    defines the end of the impact: an impact that sticks throughout (mu = 1e4; with a finite mu
    the shrinking normal force lets it slip at the very end) has the centre-of-mass eps_t of the
    mapping, for a block (f_t = 1) and a rolling sphere (f_t = 2/7)."""
    case = _sphere_case(
        e_t=e_t, mu=1.0e4, rotation=rotation, limit_force=True, timestep=T_UNDAMPED / 200
    )
    impact = calibrate.virtual_impact(case, incidence, 0.3)
    assert impact.eps_t == pytest.approx(e_t, abs=0.005)
    assert impact.eps_n == pytest.approx(math.exp(-2.0), abs=0.01)  # critical: x' at omega t = 2


def test_mapping_inverts_and_refuses_what_sticking_cannot_reach():
    for f in (1.0, 2 / 7):
        for e in (0.65, 0.8, 0.95):
            kappa = tangential.tangential_stiffness_ratio(e, 1.0, 0.3, f)
            assert tangential.sticking_restitution(kappa, 1.0, 0.3, f) == pytest.approx(e)
    # kappa grows as eps_t falls (a stiffer spring takes more from the impact)
    k = [tangential.tangential_stiffness_ratio(e, 1.0, 0.3, 1.0) for e in (0.2, 0.5, 0.8)]
    assert k[0] > k[1] > k[2]
    assert tangential.impact_end_time(1.0) == pytest.approx(2.0)
    with pytest.raises(ValueError, match="< eps_t < 1"):
        tangential.tangential_stiffness_ratio(0.5, 1.0, 0.3, 2 / 7)


@pytest.mark.validation
def test_eps_t_moves_the_dem_impact_as_asked():
    """The spring law (limit_force off, mu = 0.35) at a landing of conveying (34 deg): eps_t = 0.2,
    0.5, 0.8 give ordered, distinct outcomes."""
    out = [calibrate.virtual_impact(_sphere_case(e_t=e), 34.0, 0.1).eps_t for e in (0.2, 0.5, 0.8)]
    assert out[0] < out[1] < out[2]
    assert out[2] == pytest.approx(0.8, abs=0.03)


@pytest.mark.validation
def test_grazing_impact_is_bounded_by_coulomb():
    """A sliding impact takes at most mu J_n / m from v_t. With limit_force the normal impulse
    is m v_n (1 + eps_n): eps_t >= 1 - mu (1 + eps_n) cot(theta), approached as the tangential
    spring stiffens (a soft one spends part of the impact loading below the cap)."""
    theta = 75.0
    out = []
    for kappa in (0.02, 0.3, 3.0):
        case = _sphere_case(mu=0.35, limit_force=True, tangential_stiffness_ratio=kappa)
        impact = calibrate.virtual_impact(case, theta, 0.2)
        bound = 1.0 - 0.35 * (1.0 + impact.eps_n) / math.tan(math.radians(theta))
        out.append(impact.eps_t - bound)
    assert min(out) > -1e-3
    assert out[0] > out[1] >= out[2] and abs(out[2]) < 1e-3, out


def test_landings_follow_the_point_mass():
    """At Gamma = 1.8 (phi 25 deg, eps_n = 0) every landing has the same relative velocity; the
    normal part equals the closed-form gap derivative at the flight's end."""
    case = _sphere_case().with_drive(throw_number=1.8)
    rows = calibrate.landings(case)
    assert rows.shape[0] >= 30
    assert np.ptp(rows[:, 0]) < 0.5 and np.ptp(rows[:, 1]) < 0.01 * rows[0, 1]
    assert 20.0 < rows[0, 0] < 50.0
    assert calibrate.landings(case.with_drive(throw_number=0.8)).shape[0] == 0


@pytest.mark.validation
def test_calibration_reaches_the_same_kappa_from_different_starts():
    case = _sphere_case().with_drive(throw_number=1.8)
    a = calibrate.calibrate(case, start=0.003, max_impacts=2)
    b = calibrate.calibrate(case, start=0.5, max_impacts=2)
    assert a.kappa == pytest.approx(b.kappa, rel=0.01)
    assert a.reachable and abs(a.residual) < 0.005
