"""dem.physics.drive against independent forms of Eq. 3, and the sites that call it."""

import math

import numpy as np
import pytest

from dem import pointmass
from dem.config import GRAVITY
from dem.physics import drive
from dem.scene.spec import resolve_drive
from dem.scene.trough import Trough


def test_throw_number_is_eq3_and_amplitude_inverts_it():
    f, phi, alpha, a = 50.0, 25.0, 3.0, 0.6e-3
    w = 2.0 * math.pi * f
    gamma = a * w**2 * math.sin(math.radians(phi)) / (GRAVITY * math.cos(math.radians(alpha)))
    assert drive.throw_number(a, f, phi, alpha) == pytest.approx(gamma, rel=1e-15)
    assert drive.amplitude(gamma, f, phi, alpha) == pytest.approx(a, rel=1e-15)
    assert isinstance(drive.throw_number(a, f, phi, alpha), float)


def test_resolve_drive_is_dem_drive_bit_for_bit():
    for f, phi, alpha, value in [(60.0, 25.0, 0.0, 1.8), (17.3, 41.0, -2.5, 0.77)]:
        by_gamma = resolve_drive(f, phi, alpha, throw_number=value)
        assert by_gamma.amplitude == drive.amplitude(value, f, phi, alpha)
        by_amp = resolve_drive(f, phi, alpha, amplitude=value * 1e-3)
        assert by_amp.throw_number == drive.throw_number(value * 1e-3, f, phi, alpha)
        assert by_amp.omega == drive.omega(f)
        # the DEM's velocity scale is dem.physics.drive's, to rounding (|X| omega of the motion)
        scale = drive.velocity_scale(by_amp.amplitude, f, phi)
        assert by_amp.velocity_scale == pytest.approx(scale, rel=1e-15)


def test_velocity_scale_of_a_throw_number_is_gamma_g_cos_over_omega_tan():
    gamma = np.linspace(0.2, 5.0, 7)[:, None]
    phi = np.linspace(5.0, 85.0, 9)[None, :]
    f, alpha = 45.0, 4.0
    w = 2.0 * np.pi * f
    direct = gamma * GRAVITY * np.cos(np.radians(alpha)) / (w * np.tan(np.radians(phi)))
    v = pointmass.velocity_scale(gamma, f, phi, alpha)
    assert v.shape == (7, 9)
    np.testing.assert_allclose(v, direct, rtol=1e-14)
    # the point-mass names are dem.physics.drive's relations, with the same argument order
    a = drive.amplitude(1.8, f, 25.0, alpha)
    assert pointmass.velocity_scale(1.8, f, 25.0, alpha) == drive.velocity_scale(a, f, 25.0)
    assert pointmass.amplitude_from_throw_number(1.8, f, 25.0, alpha) == drive.amplitude(
        1.8, f, 25.0, alpha
    )
    assert pointmass.throw_number_from_amplitude(3e-4, f, 25.0, alpha) == drive.throw_number(
        3e-4, f, 25.0, alpha
    )


@pytest.mark.parametrize("alpha", [0.0, 3.0])
def test_frequencies_for_held_amplitude_and_peak_speed_give_gamma_back(alpha):
    gamma, phi = np.array([0.5, 1.8, 4.0]), 30.0
    amp = 0.8e-3
    f = drive.frequency_for_amplitude(gamma, amp, phi, alpha)
    np.testing.assert_allclose(drive.throw_number(amp, f, phi, alpha), gamma, rtol=1e-14)
    speed = 0.2  # A omega, m/s
    f = drive.frequency_for_peak_speed(gamma, speed, phi, alpha)
    amp = speed / drive.omega(f)
    np.testing.assert_allclose(amp * drive.omega(f), speed, rtol=1e-15)
    np.testing.assert_allclose(drive.throw_number(amp, f, phi, alpha), gamma, rtol=1e-14)


def test_trough_throw_number_is_the_case_value():
    d = resolve_drive(60.0, 25.0, 2.0, throw_number=1.8)
    trough = Trough(0.1, 0.05, math.radians(2.0), d.motion)
    assert trough.throw_number == pytest.approx(1.8, rel=1e-14)


# --- two components and the start-up ramp -------------------------------------------------------


def _motion(second=None, ramp_time=0.0, amplitude=0.3e-3, angle=25.0, f=60.0):
    from dem.physics.drive import Component, Motion

    comps = [Component(amplitude, math.radians(angle))]
    if second is not None:
        a2, phi2, psi2 = second
        comps.append(Component(a2, math.radians(phi2), math.radians(psi2)))
    return Motion(drive.omega(f), tuple(comps), ramp_time)


@pytest.mark.parametrize(
    "second, ramp_time",
    [(None, 0.0), ((0.2e-3, 90.0, 90.0), 0.0), ((0.1e-3, 120.0, -40.0), 0.05), (None, 0.05)],
)
def test_motion_velocity_and_frame_acceleration_are_derivatives_of_the_displacement(
    second, ramp_time
):
    m = _motion(second, ramp_time)
    h = 1e-6
    for t in np.linspace(0.0015, 0.08, 23):
        s_m, s_0, s_p = m.displacement(t - h), m.displacement(t), m.displacement(t + h)
        np.testing.assert_allclose(m.velocity(t), (s_p - s_m) / (2 * h), atol=1e-9)
        scale = m.omega**2 * 0.5e-3
        fd = -(s_p - 2.0 * s_0 + s_m) / h**2
        np.testing.assert_allclose(m.frame_acceleration(t), fd, atol=2e-5 * scale)


def test_ramp_rises_smoothly_from_rest_to_full_amplitude():
    from dem.physics.drive import ramp

    ramp_time = 0.1
    assert ramp(0.0, ramp_time) == (0.0, 0.0, 0.0)
    assert ramp(ramp_time, ramp_time) == (1.0, 0.0, 0.0)
    assert ramp(0.3, 0.0) == (1.0, 0.0, 0.0)
    r = np.array([ramp(t, ramp_time) for t in np.linspace(0.0, ramp_time, 201)])
    assert np.all(np.diff(r[:, 0]) >= 0.0)
    assert r[100, 0] == pytest.approx(0.5)
    # r' and r'' vanish at both ends: the frame acceleration has no jump
    for t in (1e-7, ramp_time - 1e-7):
        _, r1, r2 = ramp(t, ramp_time)
        assert abs(r1) * ramp_time < 1e-9 and abs(r2) * ramp_time**2 < 1e-4
    m = _motion((0.1e-3, 90.0, 90.0), ramp_time)
    before, after = m.frame_acceleration(ramp_time - 1e-9), m.frame_acceleration(ramp_time + 1e-9)
    np.testing.assert_allclose(before, after, atol=1e-4)
    np.testing.assert_allclose(m.frame_acceleration(1e-9), 0.0, atol=1e-4)


@pytest.mark.parametrize(
    "second, ramp_time", [(None, 0.0), ((0.2e-3, 90.0, 90.0), 0.0), ((0.1e-3, 150.0, 33.0), 0.04)]
)
def test_kernel_body_acceleration_is_gravity_plus_the_frame_acceleration(second, ramp_time):
    from dem.kernels.integrate import body_acceleration

    m = _motion(second, ramp_time)
    g = np.array([-0.5, 0.0, -9.8])
    k = m.kernel_array()
    for t in np.linspace(0.0, 0.1, 37):
        np.testing.assert_allclose(
            body_acceleration(t, g, k), g + m.frame_acceleration(t), rtol=1e-12, atol=1e-12
        )
    assert body_acceleration(0.01, g, np.zeros(drive.KERNEL_DRIVE_SIZE)) == tuple(g)


def test_line_drive_kernel_is_bit_for_bit_the_single_sinusoid():
    """One component, no ramp: g + A omega^2 sin(omega t) e, as the kernel computed it before."""
    from dem.kernels.integrate import body_acceleration

    m = _motion()
    c = m.components[0]
    g = np.array([0.0, 0.0, -9.81])
    for t in np.linspace(0.0, 0.05, 11):
        s = c.amplitude * m.omega**2 * math.sin(m.omega * t)
        assert body_acceleration(t, g, m.kernel_array()) == tuple(g + s * c.direction)


def test_phasors_of_a_circle_a_line_and_the_paper_drive():
    a = 0.2e-3
    circle = _motion((a, 90.0, 90.0), amplitude=a, angle=0.0)
    assert circle.tangential_amplitude == pytest.approx(a)
    assert circle.normal_amplitude == pytest.approx(a)
    assert circle.peak_speed == pytest.approx(a * circle.omega)
    assert not circle.is_line
    # |s'(t)| is constant on a circle
    speeds = [np.linalg.norm(circle.velocity(t)) for t in np.linspace(0, 0.03, 13)]
    np.testing.assert_allclose(speeds, a * circle.omega, rtol=1e-12)
    in_phase = _motion((0.1e-3, 90.0, 0.0))
    assert in_phase.is_line
    assert _motion((0.1e-3, 90.0, 180.0)).is_line
    line = _motion()
    phi = math.radians(25.0)
    assert line.velocity_scale == pytest.approx(0.3e-3 * line.omega * math.cos(phi), rel=1e-14)
    assert line.throw_number(0.0) == pytest.approx(drive.throw_number(0.3e-3, 60.0, 25.0))
    # the peak speed of an ellipse is the largest |s'(t)| over the cycle
    ell = _motion((0.1e-3, 120.0, -40.0))
    sampled = max(np.linalg.norm(ell.velocity(t)) for t in np.linspace(0, 1 / 60, 4001))
    assert ell.peak_speed == pytest.approx(sampled, rel=1e-6)


@pytest.mark.parametrize(
    "gamma, phi, alpha", [(0.5, 25.0, 0.0), (1.8, 25.0, 0.0), (2.5, 40.0, 3.0)]
)
def test_stepped_point_mass_on_a_line_is_the_event_driven_model(gamma, phi, alpha):
    from dem.pointmass import elliptic

    a = drive.amplitude(gamma, 60.0, phi, alpha)
    r = elliptic.velocity(_motion(amplitude=a, angle=phi), 0.35, alpha, 0.8, 0.0)
    ref = pointmass.velocity(throw_number=gamma, angle=phi, friction=0.35, inclination=alpha)
    assert r.velocity_norm == pytest.approx(ref.velocity_norm, abs=1e-3)
    assert r.spread < 1e-6


def test_two_components_in_phase_are_the_line_they_add_up_to():
    from dem.pointmass import elliptic

    m = _motion((0.2e-3, 90.0, 0.0), amplitude=0.1e-3)
    x, z = m.phasors
    amp, phi = abs(complex(x.real, z.real)), math.degrees(math.atan2(z.real, x.real))
    gamma = drive.throw_number(amp, 60.0, phi)
    assert gamma == pytest.approx(m.throw_number(0.0), rel=1e-12)
    ref = pointmass.velocity(throw_number=gamma, angle=phi, friction=0.35)
    got = elliptic.velocity(m, 0.35)
    # normalised by A omega cos(phi) of the equivalent line = |X| omega
    assert got.velocity_norm == pytest.approx(ref.velocity_norm, abs=1e-3)
