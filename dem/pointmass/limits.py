"""Regime limits of the point-mass model: the paper's Eqs. (1), (2) and (4).

A point mass rests on a trough inclined at alpha and driven along a line at the vibration angle
phi. With the throw number ``Gamma = A omega^2 sin(phi) / (g cos(alpha))`` (Eq. 3) the mass

- slides forward at some phase of the cycle when ``Gamma > (mu + tan a) / (cot phi + mu)`` (1),
- slides backward when ``Gamma > (mu - tan a) / (cot phi - mu)`` (2),
- leaves the floor (flight) when ``Gamma >= 1`` (4).

Eq. (2) assumes ``cot phi > mu``. Otherwise the backward pull grows as the floor rises, and
backward sliding starts while the mass is still in contact (sin(omega t) <= 1/Gamma) when
``Gamma > (mu - tan a) / (mu - cot phi)`` and that limit is below 1, i.e. only for
``phi + alpha > 90 deg`` (a drive leaning back over a steep incline); else never before flight.

A negative limit means the motion happens without any vibration (a trough steeper than the
friction angle); it is reported as 0.
"""

import math
from dataclasses import dataclass

from dem.pointmass.validate import check_angle, check_friction, check_inclination


@dataclass(frozen=True)
class Thresholds:
    """Throw numbers at which forward sliding, backward sliding and flight begin."""

    forward_sliding: float
    backward_sliding: float | None  # None: backward sliding never occurs (cot phi <= mu)
    flight: float


def thresholds(angle: float, friction: float, inclination: float = 0.0) -> Thresholds:
    """Regime limits for vibration angle ``angle`` and inclination (degrees), friction ``mu``.

    Example (the paper's): mu = 0.75, alpha = 2.5 deg, phi = 25 deg gives 0.274 and 0.507.
    """
    check_angle(angle)
    check_friction(friction)
    check_inclination(inclination)
    phi = math.radians(angle)
    tan_a = math.tan(math.radians(inclination))
    cot_phi = 1.0 / math.tan(phi)
    forward = max((friction + tan_a) / (cot_phi + friction), 0.0)
    backward: float | None = None
    if tan_a > friction:
        backward = 0.0  # slides down without vibration
    elif cot_phi > friction:
        backward = max((friction - tan_a) / (cot_phi - friction), 0.0)
    elif cot_phi < friction:
        limit = (friction - tan_a) / (friction - cot_phi)
        backward = limit if limit < 1.0 else None
    return Thresholds(forward_sliding=forward, backward_sliding=backward, flight=1.0)
