"""The linear drive, written once: throw number, amplitude and the velocity scale.

A trough inclined by alpha vibrates along a line at the vibration angle phi to the trough with
amplitude A and angular frequency omega = 2 pi f. The paper's throw number (its Eq. 3) is the
normal part of the peak trough acceleration over the normal part of gravity,

    Gamma = A omega^2 sin(phi) / (g cos(alpha)),

and conveying velocities are reported over the drive velocity A omega cos(phi) (README,
A DEM run). The inverse forms (the frequency at which a held amplitude or a held peak speed
A omega gives Gamma) live here too. Every function takes angles in degrees and broadcasts over
numpy arrays; with scalars it returns a float. :func:`dem.scene.spec.resolve_drive`,
:class:`dem.scene.trough.Trough`, :mod:`dem.physics.measure`, the point-mass model and its sweeps,
and the validation scripts all call these.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

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


def velocity_scale(amplitude, frequency, angle):
    """A omega cos(phi), m/s: the paper's velocity scale (normalised velocities divide by it).

    The peak trough speed along the trough; :attr:`Motion.velocity_scale` is the same for any
    motion, an ellipse included (|X| omega). Broadcasts over arrays.
    """
    return _float_or_array(amplitude * omega(frequency) * np.cos(np.radians(angle)))


def friction_relaxation_cycles(velocity_scale: float, frequency: float, friction: float,
                               inclination: float = 0.0) -> float:  # fmt: skip
    """Drive cycles the floor's friction needs to take the start-up velocity out of a grain.

    The drive starts at full speed (s = A sin(omega t)), so a grain at rest on the floor starts
    with a velocity of the drive's scale V = A omega cos(phi) relative to it, which only
    friction removes: at most at the rate mu g cos(alpha) (the mean normal force is the
    weight's), so it takes at least V / (mu g cos(alpha)) seconds, this many cycles:
    f V / (mu g cos(alpha)). Infinite for mu = 0 (then nothing removes it). A run that settles
    for fewer cycles measures the start-up, not transport; ``dem`` settles for
    :data:`dem.config.DEM_FRICTION_RELAX_FACTOR` times this at least.
    """
    if friction <= 0.0:
        return math.inf
    g_normal = GRAVITY * math.cos(math.radians(inclination))
    return frequency * velocity_scale / (friction * g_normal)


def steps_per_cycle(frequency: float, dt: float) -> float:
    """Time steps in one drive cycle, 1 / (f dt); not a whole number in general."""
    return 1.0 / frequency / dt


def cycle_edge(start_step: int, cycles: float, period: float, dt: float) -> int:
    """The step at which ``cycles`` drive periods after step ``start_step`` end.

    start_step + round(cycles period / dt): every cycle and frame edge is counted from the
    drive's start (``cycles`` may be a fraction for a frame), so no edge drifts from the
    drive's phase however many cycles have run. The measurement, the frames, a checkpoint's
    check and the validation studies all take their edges from here.
    """
    return start_step + int(round(cycles * period / dt))


# --- the trough's motion: one or two sinusoidal components and a start-up ramp --------------


def ramp(t: float, ramp_time: float) -> tuple[float, float, float]:
    """Start-up envelope r(t) and its first two derivatives (r, r', r'').

    r = u^3 (10 - 15 u + 6 u^2), u = t / ramp_time, rises from 0 to 1 over ``ramp_time`` with
    r' and r'' zero at both ends (the smootherstep), so the trough's acceleration s''(t) is
    continuous: no jerk of the frame at the start or at the end of the ramp. ``ramp_time`` = 0
    means none (r = 1 from t = 0). The kernel's :func:`dem.kernels.integrate.body_acceleration`
    is the same formula.
    """
    if ramp_time <= 0.0 or t >= ramp_time:
        return 1.0, 0.0, 0.0
    if t <= 0.0:
        return 0.0, 0.0, 0.0
    u = t / ramp_time
    r = u**3 * (10.0 - 15.0 * u + 6.0 * u * u)
    r1 = 30.0 * u * u * (1.0 - u) ** 2 / ramp_time
    r2 = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / ramp_time**2
    return r, r1, r2


@dataclass(frozen=True)
class Component:
    """One sinusoidal component A sin(omega t + psi) (cos phi, 0, sin phi) of the trough motion.

    Attributes:
        amplitude: A, m.
        angle: phi, rad, measured from +x (along the trough) towards +z (the floor's normal).
        phase: psi, rad; the first component of a drive has psi = 0 (the time origin).

    """

    amplitude: float
    angle: float
    phase: float = 0.0

    @property
    def direction(self) -> np.ndarray:
        """(cos phi, 0, sin phi), shape (3,)."""
        return np.array([math.cos(self.angle), 0.0, math.sin(self.angle)])


@dataclass(frozen=True)
class Motion:
    """The trough's laboratory motion s(t) = r(t) sum_k A_k sin(omega t + psi_k) e_k.

    One component is the paper's straight-line drive; two with different phases trace an ellipse
    (a circle for equal amplitudes at right angles a quarter period apart). r(t) is the start-up
    ramp (:func:`ramp`). In the trough's frame every grain feels -s''(t) (README, Symbols):

        -s'' = sum_k A_k e_k [(omega^2 r - r'') sin(theta_k) - 2 r' omega cos(theta_k)]

    with theta_k = omega t + psi_k, which is A omega^2 sin(omega t) e for one component without a
    ramp. Each component's x and z parts add as phasors, X = sum_k A_k cos(phi_k) e^{i psi_k}
    and Z = sum_k A_k sin(phi_k) e^{i psi_k}: the trough moves by |X| along itself and |Z|
    normal to its floor.

    Attributes:
        omega: Angular frequency, rad/s.
        components: One or two :class:`Component`.
        ramp_time: Duration of the start-up ramp, s (0: full amplitude from t = 0).

    """

    omega: float
    components: tuple[Component, ...]
    ramp_time: float = 0.0

    @property
    def phasors(self) -> tuple[complex, complex]:
        """(X, Z): complex amplitudes of the motion along x and along z, m."""
        x = sum(c.amplitude * math.cos(c.angle) * cmath.exp(1j * c.phase) for c in self.components)
        z = sum(c.amplitude * math.sin(c.angle) * cmath.exp(1j * c.phase) for c in self.components)
        return complex(x), complex(z)

    @property
    def is_single(self) -> bool:
        """Whether the drive is the paper's: one straight-line component."""
        return len(self.components) == 1

    @property
    def is_line(self) -> bool:
        """Whether s(t) moves along one line (the components in phase or in anti-phase)."""
        x, z = self.phasors
        return abs((x.conjugate() * z).imag) <= 1e-12 * (abs(x) * abs(z) + 1e-300)

    @property
    def tangential_amplitude(self) -> float:
        """|X|, the amplitude of the motion along the trough, m."""
        return abs(self.phasors[0])

    @property
    def normal_amplitude(self) -> float:
        """|Z|, the amplitude of the motion normal to the floor, m."""
        return abs(self.phasors[1])

    @property
    def velocity_scale(self) -> float:
        """|X| omega, the peak trough speed along itself (A omega cos phi for a line), m/s."""
        return self.tangential_amplitude * self.omega

    @property
    def peak_speed(self) -> float:
        """Largest trough speed |s'(t)| over a cycle (A omega for a line), m/s.

        The semi-major axis of the velocity ellipse: sqrt((|X|^2 + |Z|^2 + |X^2 + Z^2|) / 2) omega.
        """
        x, z = self.phasors
        major = 0.5 * (abs(x) ** 2 + abs(z) ** 2 + abs(x * x + z * z))
        return math.sqrt(major) * self.omega

    def throw_number(self, inclination: float) -> float:
        """|Z| omega^2 / (g cos alpha): peak normal trough acceleration over normal gravity.

        The paper's Gamma for a line drive; ``inclination`` alpha in degrees.
        """
        return (
            self.normal_amplitude * self.omega**2 / (GRAVITY * math.cos(math.radians(inclination)))
        )

    def _sum(self, t: float, sin_factor: float, cos_factor: float) -> np.ndarray:
        out = np.zeros(3)
        for c in self.components:
            ph = self.omega * t + c.phase
            out += (
                c.amplitude * (sin_factor * math.sin(ph) + cos_factor * math.cos(ph)) * c.direction
            )
        return out

    def displacement(self, t: float) -> np.ndarray:
        """s(t), shape (3,), m."""
        r, _, _ = ramp(t, self.ramp_time)
        return self._sum(t, r, 0.0)

    def velocity(self, t: float) -> np.ndarray:
        """s'(t), shape (3,), m/s."""
        r, r1, _ = ramp(t, self.ramp_time)
        return self._sum(t, r1, r * self.omega)

    def frame_acceleration(self, t: float) -> np.ndarray:
        """-s''(t), the acceleration every grain feels in the trough frame, shape (3,), m/s^2."""
        r, r1, r2 = ramp(t, self.ramp_time)
        return self._sum(t, self.omega**2 * r - r2, -2.0 * r1 * self.omega)

    def kernel_array(self) -> np.ndarray:
        """The kernels' form, shape (12,): omega, ramp_time, then per component A omega^2, psi, e.

        A second component of zero amplitude pads a line drive (see
        :func:`dem.kernels.integrate.body_acceleration`).
        """
        if len(self.components) > 2:
            raise ValueError("at most two drive components")
        out = np.zeros(KERNEL_DRIVE_SIZE)
        out[0], out[1] = self.omega, self.ramp_time
        for k, c in enumerate(self.components):
            out[2 + 5 * k : 7 + 5 * k] = (
                c.amplitude * self.omega**2, c.phase, *c.direction
            )  # fmt: skip
        return out


#: Length of :meth:`Motion.kernel_array`.
KERNEL_DRIVE_SIZE = 12
