"""The point mass on a trough moving on an ellipse (two drive components out of phase).

The paper's model (:mod:`dem.pointmass.model`) has the trough move along one line, so the
accelerations along and normal to the floor are both a + b sin(omega t) and every phase change is
a root of a closed form. With two components out of phase (:class:`dem.physics.drive.Motion`) the
trough's motion along x and along z are sinusoids of different phase,

    s_x = |X| sin(omega t + arg X),   s_z = |Z| sin(omega t + arg Z),

and the point mass is stepped in time instead (Moreau-Jean,
:func:`dem.pointmass.stepped.step_motion`), with the same phases (rest, sliding, flight) and the
same landing law (the paper's Eq. 12: u <- eps_t u, w <- -eps_n w). For a line drive the two
methods agree to the stepping error (tests/physics/test_drive.py). The start-up ramp is a
transient and does not enter the steady state this returns.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from dem.config import GRAVITY
from dem.physics.drive import Motion
from dem.pointmass.stepped import step_motion
from dem.pointmass.validate import check_inclination, check_restitution, check_transport_friction

#: Time steps per drive cycle, cycles discarded and cycles averaged by :func:`velocity`.
STEPS = 8000
TRANSIENT = 60
MEASURED = 60


@dataclass(frozen=True)
class EllipticResult:
    """Mean conveying velocity of the point mass on a two-component drive.

    Attributes:
        velocity: Mean velocity along the trough, m/s.
        velocity_norm: velocity / (|X| omega), the peak trough speed along the trough (A omega
            cos phi for a line drive).
        spread: |difference| of the two halves of the measured cycles over |X| omega (0 for a
            periodic orbit; larger where the motion does not settle).
        method: "stepped".
        steps_per_cycle, transient, measured: The stepping.

    """

    velocity: float
    velocity_norm: float
    spread: float
    method: str
    steps_per_cycle: int
    transient: int
    measured: int

    def as_dict(self) -> dict:
        """Plain dictionary (for JSON)."""
        return asdict(self)


def stepping_args(motion: Motion, inclination: float) -> tuple[tuple, float]:
    """The drive and gravity arguments of :func:`dem.pointmass.stepped.step_motion`, and L (m).

    Lengths in units of L = max(|X|, |Z|), so velocities come out in L omega. ``inclination``
    alpha in degrees.
    """
    x, z = motion.phasors
    scale = max(abs(x), abs(z))
    if not (scale > 0.0 and motion.omega > 0.0):
        raise ValueError("the motion has no amplitude or no frequency")
    g = GRAVITY / (scale * motion.omega**2)
    a = math.radians(inclination)
    args = (abs(x) / scale, math.atan2(x.imag, x.real), abs(z) / scale,
            math.atan2(z.imag, z.real), -g * math.sin(a), -g * math.cos(a))  # fmt: skip
    return args, scale


def velocity(
    motion: Motion,
    friction: float,
    inclination: float = 0.0,
    eps_t: float = 0.8,
    eps_n: float = 0.0,
    *,
    steps: int = STEPS,
    transient: int = TRANSIENT,
    measured: int = MEASURED,
) -> EllipticResult:
    """Steady mean velocity of the point mass on ``motion`` (ramp ignored), alpha in degrees."""
    check_transport_friction(friction)
    check_inclination(inclination)
    check_restitution(eps_t, "eps_t")
    check_restitution(eps_n, "eps_n")
    x, z = motion.phasors
    args, scale = stepping_args(motion, inclination)
    args = (*args, friction, eps_t, eps_n, steps)
    none = np.zeros((0, 2))
    half = max(1, measured // 2)
    _, first = step_motion(*args, transient, half, False, none)
    _, both = step_motion(*args, transient, 2 * half, False, none)
    second = 2.0 * both - first
    v_scale = abs(x) * motion.omega
    v = both * scale * motion.omega
    norm = v / v_scale if v_scale > 0.0 else math.nan
    spread = abs(second - first) * scale * motion.omega / v_scale if v_scale > 0.0 else math.nan
    return EllipticResult(v, norm, spread, "stepped", steps, transient, 2 * half)
