"""dem.drive against independent forms of Eq. 3, and the sites that call it."""

import math

import numpy as np
import pytest

from dem import drive, measure, pointmass
from dem.case import resolve_drive
from dem.config import GRAVITY
from dem.trough import Trough


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
        # the DEM's velocity scale is dem.drive's
        scale = measure.drive_velocity_scale(by_amp.amplitude, by_amp.omega, phi)
        assert scale == drive.drive_velocity(by_amp.amplitude, f, phi)


def test_drive_velocity_from_throw_number_matches_gamma_g_cos_over_omega_tan():
    gamma = np.linspace(0.2, 5.0, 7)[:, None]
    phi = np.linspace(5.0, 85.0, 9)[None, :]
    f, alpha = 45.0, 4.0
    w = 2.0 * np.pi * f
    direct = gamma * GRAVITY * np.cos(np.radians(alpha)) / (w * np.tan(np.radians(phi)))
    v = drive.drive_velocity_from_throw_number(gamma, f, phi, alpha)
    assert v.shape == (7, 9)
    np.testing.assert_allclose(v, direct, rtol=1e-14)
    # the point-mass names are the same relations in their argument order
    assert pointmass.drive_velocity(1.8, 25.0, alpha, f) == drive.drive_velocity_from_throw_number(
        1.8, f, 25.0, alpha
    )
    assert pointmass.amplitude_from_throw_number(1.8, 25.0, alpha, f) == drive.amplitude(
        1.8, f, 25.0, alpha
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
    trough = Trough(0.1, 0.05, math.radians(2.0), d.amplitude, d.omega, math.radians(d.angle))
    assert trough.throw_number == pytest.approx(1.8, rel=1e-14)
