"""Trough geometry and drive, in the trough's own (accelerating) frame.

Frame (DESIGN.md section 2): x along the trough, y across, z normal to the floor. The floor is
z = 0, the side walls are y = -width/2 and y = +width/2, and the section is periodic in x with
period ``length``. Inclination alpha > 0 means the trough rises in +x, so gravity in this frame is

    g_vec = g (-sin alpha, 0, -cos alpha).

Drive. In the laboratory the trough moves by s(t) = A sin(omega t) e, e = (cos phi, 0, sin phi).
A grain's laboratory position is X = s(t) + x, with x its position relative to the trough, so

    m X'' = F_contact + m g_vec   =>   m x'' = F_contact + m g_vec - m s''(t),

and s''(t) = -A omega^2 sin(omega t) e. The frame force is therefore

    -m s''(t) = +m A omega^2 sin(omega t) e,

the extra acceleration every grain gets while the walls stay still. Contact forces depend on
relative positions and velocities only, which are the same in both frames, so nothing is lost.
Velocities in this frame are the velocities relative to the trough, the ones the conveying
velocity is measured in (DESIGN.md section 3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dem.config import GRAVITY


@dataclass(frozen=True)
class Trough:
    """Straight periodic trough section with a straight-line sinusoidal drive.

    Attributes:
        length: Period along x, m.
        width: Distance between the side walls, m.
        inclination: alpha, rad.
        amplitude: A, m.
        omega: Angular frequency omega = 2 pi f, rad/s.
        angle: Vibration angle phi, rad.

    """

    length: float
    width: float
    inclination: float = 0.0
    amplitude: float = 0.0
    omega: float = 0.0
    angle: float = 0.0

    @classmethod
    def from_case(cls, case) -> Trough:
        """Trough of a :class:`dem.case.Case` (angles converted from degrees)."""
        return cls(
            length=case.trough.length,
            width=case.trough.width,
            inclination=math.radians(case.trough.inclination),
            amplitude=case.drive.amplitude,
            omega=case.drive.omega,
            angle=math.radians(case.drive.angle),
        )

    @property
    def gravity(self) -> np.ndarray:
        """Gravity g (-sin alpha, 0, -cos alpha), shape (3,), m/s^2."""
        a = self.inclination
        return np.array([-GRAVITY * math.sin(a), 0.0, -GRAVITY * math.cos(a)])

    @property
    def direction(self) -> np.ndarray:
        """Drive direction e = (cos phi, 0, sin phi), shape (3,)."""
        return np.array([math.cos(self.angle), 0.0, math.sin(self.angle)])

    @property
    def period(self) -> float:
        """Drive period 2 pi / omega, s (inf without a drive)."""
        return 2.0 * math.pi / self.omega if self.omega > 0 else math.inf

    @property
    def drive_speed(self) -> float:
        """Peak trough speed A omega, m/s."""
        return self.amplitude * self.omega

    @property
    def throw_number(self) -> float:
        """Gamma = A omega^2 sin(phi) / (g cos(alpha))."""
        return (
            self.amplitude
            * self.omega**2
            * math.sin(self.angle)
            / (GRAVITY * math.cos(self.inclination))
        )

    def drive_array(self, on: bool = True) -> np.ndarray:
        """Kernel form (A omega^2, omega, e_x, e_y, e_z), shape (5,); zeros when ``on`` is off."""
        if not on:
            return np.zeros(5)
        e = self.direction
        return np.array([self.amplitude * self.omega**2, self.omega, e[0], e[1], e[2]])

    def frame_acceleration(self, t: float) -> np.ndarray:
        """Frame acceleration +A omega^2 sin(omega t) e at time t, shape (3,), m/s^2."""
        return self.amplitude * self.omega**2 * math.sin(self.omega * t) * self.direction

    def displacement(self, t: float) -> np.ndarray:
        """Laboratory trough displacement s(t) = A sin(omega t) e, shape (3,), m."""
        return self.amplitude * math.sin(self.omega * t) * self.direction

    def velocity(self, t: float) -> np.ndarray:
        """Laboratory trough velocity s'(t) = A omega cos(omega t) e, shape (3,), m/s."""
        return self.amplitude * self.omega * math.cos(self.omega * t) * self.direction
