"""Trough geometry and drive, in the trough's own (accelerating) frame.

Frame (README, Symbols): x along the trough, y across, z normal to the floor. The floor is
z = 0, the side walls are y = -width/2 and y = +width/2, and the section is periodic in x with
period ``length``. Inclination alpha > 0 means the trough rises in +x, so gravity in this frame is

    g_vec = g (-sin alpha, 0, -cos alpha).

Drive. In the laboratory the trough moves by s(t) = A sin(omega t) e, e = (cos phi, 0, sin phi)
(the paper's line drive; a second component and a start-up ramp generalise s(t), see
:class:`dem.physics.drive.Motion`; what follows holds for any s(t)).
A grain's laboratory position is X = s(t) + x, with x its position relative to the trough, so

    m X'' = F_contact + m g_vec   =>   m x'' = F_contact + m g_vec - m s''(t),

and s''(t) = -A omega^2 sin(omega t) e. The frame force is therefore

    -m s''(t) = +m A omega^2 sin(omega t) e   (line drive),

the extra acceleration every grain gets while the walls stay still. Contact forces depend on
relative positions and velocities only, which are the same in both frames, so nothing is lost.
Velocities in this frame are the velocities relative to the trough, the ones the conveying
velocity is measured in (README, A DEM run).

Walls. This module is the Python description of the walls the kernel
(:mod:`dem.kernels.forces`) computes contacts with, in the kernel's order w = 0, 1, 2
(:data:`WALLS`): the floor z = 0 (inward normal +z), the side wall y = -width/2 (+y) and the side
wall y = +width/2 (-y). :meth:`Trough.wall_gaps` gives the distance of points from them (for
Python-side overlap and contact checks) and :meth:`Trough.wall_corners` their outline (drawn by
:mod:`dem.io.vtk`). :meth:`Trough.wrap` and :meth:`Trough.minimum_image` are the periodicity in x
(the fill and the writers use them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dem.config import GRAVITY
from dem.errors import InputError
from dem.physics import drive

#: The kernel's walls in its order w = 0, 1, 2: (name, inward unit normal). Wall w lies where
#: the gap of :meth:`Trough.wall_gaps` is zero: z = 0, y = -width/2 and y = +width/2.
WALLS = (
    ("floor", (0.0, 0.0, 1.0)),
    ("side wall y = -width/2", (0.0, 1.0, 0.0)),
    ("side wall y = +width/2", (0.0, -1.0, 0.0)),
    ("back wall x = 0 (finite feeder)", (1.0, 0.0, 0.0)),
)


@dataclass(frozen=True)
class Trough:
    """Straight periodic trough section and its drive.

    The drive is one :class:`dem.physics.drive.Motion`, built once from the case
    (:attr:`dem.scene.case.DriveSpec.motion`): the paper's straight line A sin(omega t)
    (cos phi, 0, sin phi), optionally a second component A_2 sin(omega t + psi_2)
    (cos phi_2, 0, sin phi_2) (an elliptical drive) and a start-up ramp. The trough reads every
    drive quantity from it (SI units: rad/s, rad).

    Attributes:
        length: Period along x, m.
        width: Distance between the side walls, m.
        inclination: alpha, rad.
        motion: The drive, or None for a trough that does not move.
        discharge: x of a finite feeder's discharge edge, m (inf: a periodic section). A finite
            feeder has a back wall at x = 0 and ``length`` is then the period of the domain the
            kernels wrap, longer than the trough by an empty gap (:mod:`dem.engine.feeder`).

    """

    length: float
    width: float
    inclination: float = 0.0
    motion: drive.Motion | None = None
    discharge: float = math.inf

    @property
    def finite(self) -> bool:
        """Whether this is a finite feeder (back wall at x = 0, discharge edge)."""
        return math.isfinite(self.discharge)

    @property
    def back(self) -> float:
        """The back wall's x, m: 0 for a finite feeder, -inf (none) for a periodic section."""
        return 0.0 if self.finite else -math.inf

    @property
    def extent(self) -> float:
        """Length of the trough itself, m: the discharge edge, or the periodic section."""
        return self.discharge if self.finite else self.length

    @classmethod
    def from_case(cls, case) -> Trough:
        """Trough of a :class:`dem.scene.case.Case`: its geometry and the case's drive object."""
        return cls(
            length=case.trough.length,
            width=case.trough.width,
            inclination=math.radians(case.trough.inclination),
            motion=case.drive.motion,
        )

    @property
    def first(self) -> drive.Component:
        """The drive's first component (the paper's line); a still one without a drive."""
        return self.motion.components[0] if self.motion is not None else drive.Component(0.0, 0.0)

    @property
    def amplitude(self) -> float:
        """A of the first drive component, m (0 without a drive)."""
        return self.first.amplitude

    @property
    def angle(self) -> float:
        """Vibration angle phi of the first drive component, rad."""
        return self.first.angle

    @property
    def omega(self) -> float:
        """Angular frequency omega = 2 pi f, rad/s (0 without a drive)."""
        return self.motion.omega if self.motion is not None else 0.0

    @property
    def gravity(self) -> np.ndarray:
        """Gravity g (-sin alpha, 0, -cos alpha), shape (3,), m/s^2."""
        a = self.inclination
        return np.array([-GRAVITY * math.sin(a), 0.0, -GRAVITY * math.cos(a)])

    @property
    def direction(self) -> np.ndarray:
        """Direction e = (cos phi, 0, sin phi) of the first drive component, shape (3,)."""
        return np.array([math.cos(self.angle), 0.0, math.sin(self.angle)])

    @property
    def period(self) -> float:
        """Drive period 2 pi / omega, s (inf without a drive)."""
        return 2.0 * math.pi / self.omega if self.omega > 0 else math.inf

    @property
    def drive_speed(self) -> float:
        """Peak trough speed, m/s: A omega for a line (``Motion.peak_speed``)."""
        if self.motion is None or self.motion.is_single:
            return self.amplitude * self.omega
        return self.motion.peak_speed

    @property
    def throw_number(self) -> float:
        """Peak normal trough acceleration over g cos(alpha): the paper's Gamma for a line drive.

        (:func:`dem.physics.drive.throw_number`; :meth:`dem.physics.drive.Motion.throw_number` with
        two components.)
        """
        if self.motion is not None and not self.motion.is_single:
            return self.motion.throw_number(math.degrees(self.inclination))
        return drive.throw_number(
            self.amplitude,
            self.omega / (2.0 * math.pi),
            math.degrees(self.angle),
            math.degrees(self.inclination),
        )

    def drive_array(self, on: bool = True) -> np.ndarray:
        """Kernel form of the drive (``Motion.kernel_array``); zeros if off."""
        if not on or self.motion is None:
            return np.zeros(drive.KERNEL_DRIVE_SIZE)
        return self.motion.kernel_array()

    def frame_acceleration(self, t: float) -> np.ndarray:
        """Frame acceleration -s''(t) at drive time t, shape (3,), m/s^2."""
        if self.motion is None:
            return np.zeros(3)
        return self.motion.frame_acceleration(t)

    def displacement(self, t: float) -> np.ndarray:
        """Laboratory trough displacement s(t), shape (3,), m."""
        if self.motion is None:
            return np.zeros(3)
        return self.motion.displacement(t)

    def velocity(self, t: float) -> np.ndarray:
        """Laboratory trough velocity s'(t), shape (3,), m/s."""
        if self.motion is None:
            return np.zeros(3)
        return self.motion.velocity(t)

    def wrap(self, x: np.ndarray) -> np.ndarray:
        """Positions (n, 3) with x wrapped into the periodic section [0, length), a new array, m."""
        out = np.array(x, dtype=np.float64)
        out[:, 0] = np.mod(out[:, 0], self.length)
        return out

    def minimum_image(self, d: np.ndarray) -> np.ndarray:
        """Separations (..., 3) with x taken to the nearest periodic image, a new array, m.

        d_x - L round(d_x / L), so |d_x| <= L/2 (the kernels' minimum image).
        """
        out = np.array(d, dtype=np.float64)
        out[..., 0] -= self.length * np.round(out[..., 0] / self.length)
        return out

    def wall_gaps(self, x: np.ndarray) -> np.ndarray:
        """Distance of points (n, 3) from each wall along its inward normal, (4, n), m.

        Rows in the kernel's wall order (:data:`WALLS`): z, y + width/2, width/2 - y, and x - back
        (inf without a back wall). A sphere of radius r touches wall w where gap[w] < r; its
        overlap there is r - gap[w].
        """
        x = np.asarray(x, dtype=np.float64)
        half = 0.5 * self.width
        return np.stack([x[:, 2], x[:, 1] + half, half - x[:, 1], self.back_gaps(x)])

    def back_gaps(self, x: np.ndarray) -> np.ndarray:
        """Distance of points (n, 3) from the back wall, (n,), m (inf without one)."""
        x = np.asarray(x, dtype=np.float64)
        return x[:, 0] - self.back

    def wall_corners(self, height: float) -> np.ndarray:
        """Corners of the walls as drawn, (3 or 4, 4, 3), m, in the kernel's order (:data:`WALLS`).

        The floor z = 0 over 0 <= x <= extent, |y| <= width/2; each side wall y = -+width/2 over
        0 <= x <= extent, 0 <= z <= ``height``; a finite feeder's back wall x = 0 as well.
        Corners go round each quad.
        """
        lo, hi, length = -0.5 * self.width, 0.5 * self.width, self.extent
        quads = [
            [[0.0, lo, 0.0], [length, lo, 0.0], [length, hi, 0.0], [0.0, hi, 0.0]],
            [[0.0, lo, 0.0], [length, lo, 0.0], [length, lo, height], [0.0, lo, height]],
            [[0.0, hi, 0.0], [length, hi, 0.0], [length, hi, height], [0.0, hi, height]],
        ]
        if self.finite:
            quads.append([[0.0, lo, 0.0], [0.0, hi, 0.0], [0.0, hi, height], [0.0, lo, height]])
        return np.array(quads)


def check_section_length(
    length: float, r_max: float, skin: float, reach: float = 0.0, source: str | None = None
) -> None:
    """Refuse a periodic section too short for its grains (InputError naming trough.length).

    A sphere of radius ``r_max`` with its neighbour ``skin`` must not reach its own periodic
    image, length >= 2 (2 r_max + skin); a clump's members must lie within half a period of
    its centre of mass, length > 2 ``reach`` (the largest member offset).
    """
    need = 2.0 * (2.0 * r_max + skin)
    if length < need:
        raise InputError(
            "trough.length",
            length,
            f">= 2 (2 r + skin) = {need:.6g} m, twice a grain diameter plus the neighbour skin "
            "(a grain must not reach its own periodic image)",
            source=source,
        )
    if length <= 2.0 * reach:
        raise InputError(
            "trough.length",
            length,
            f"> {2.0 * reach:.6g} m, twice the largest member offset (a clump's members must lie "
            "within half a period of its centre of mass)",
            source=source,
        )
