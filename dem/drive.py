"""The linear drive, written once: throw number, amplitude and the velocity scale.

A trough inclined by alpha vibrates along a line at the vibration angle phi to the trough with
amplitude A and angular frequency omega = 2 pi f. The paper's throw number (its Eq. 3) is the
normal part of the peak trough acceleration over the normal part of gravity,

    Gamma = A omega^2 sin(phi) / (g cos(alpha)),

and conveying velocities are reported over the drive velocity A omega cos(phi) (DESIGN.md,
section 3). The inverse forms (the frequency at which a held amplitude or a held peak speed
A omega gives Gamma) live here too. Every function takes angles in degrees and broadcasts over
numpy arrays; with scalars it returns a float. :func:`dem.case.resolve_drive`,
:class:`dem.trough.Trough`, :mod:`dem.measure`, the point-mass model and its sweeps, and the
validation scripts all call these.
"""

from __future__ import annotations

import numpy as np

from dem.config import GRAVITY


def _float_or_array(value):
    return float(value) if np.ndim(value) == 0 else value


def omega(frequency):
    """Angular frequency 2 pi f, rad/s."""
    return 2.0 * np.pi * frequency


def throw_scale(frequency, angle, inclination):
    """Gamma per metre of amplitude: omega^2 sin(phi) / (g cos(alpha)), 1/m."""
    w = omega(frequency)
    return _float_or_array(
        w**2 * np.sin(np.radians(angle)) / (GRAVITY * np.cos(np.radians(inclination)))
    )


def throw_number(amplitude, frequency, angle, inclination=0.0):
    """Gamma = A omega^2 sin(phi) / (g cos(alpha)) (the paper's Eq. 3)."""
    return _float_or_array(amplitude * throw_scale(frequency, angle, inclination))


def amplitude(throw_number, frequency, angle, inclination=0.0):
    """A = Gamma g cos(alpha) / (omega^2 sin(phi)), m."""
    return _float_or_array(throw_number / throw_scale(frequency, angle, inclination))


def frequency_for_amplitude(throw_number, amplitude, angle, inclination=0.0):
    """Eq. 3 solved for f at a held amplitude: omega^2 = Gamma g cos(alpha) / (A sin(phi)), Hz."""
    w2 = (
        throw_number
        * GRAVITY
        * np.cos(np.radians(inclination))
        / (amplitude * np.sin(np.radians(angle)))
    )
    return _float_or_array(np.sqrt(w2) / (2.0 * np.pi))


def frequency_for_peak_speed(throw_number, peak_speed, angle, inclination=0.0):
    """Eq. 3 solved for f at a held peak trough speed V = A omega, Hz.

    Gamma = A omega^2 sin(phi) / (g cos(alpha)) = V omega sin(phi) / (g cos(alpha)), so
    omega = Gamma g cos(alpha) / (V sin(phi)); the amplitude is then A = V / omega.
    """
    w = (
        throw_number
        * GRAVITY
        * np.cos(np.radians(inclination))
        / (peak_speed * np.sin(np.radians(angle)))
    )
    return _float_or_array(w / (2.0 * np.pi))


def drive_velocity(amplitude, frequency, angle):
    """The velocity scale A omega cos(phi), m/s (normalised velocities divide by it)."""
    return drive_velocity_from_omega(amplitude, omega(frequency), angle)


def drive_velocity_from_omega(amplitude, angular_frequency, angle):
    """A omega cos(phi), m/s, for omega given in rad/s (``DriveSpec.omega``, ``Trough.omega``)."""
    return _float_or_array(amplitude * angular_frequency * np.cos(np.radians(angle)))


def drive_velocity_from_throw_number(throw_number, frequency, angle, inclination=0.0):
    """A omega cos(phi), m/s, for a drive given by its throw number."""
    return drive_velocity(amplitude(throw_number, frequency, angle, inclination), frequency, angle)
