"""The paper's point-mass model: regime limits, event-driven motion, sweeps and optima.

>>> from dem import pointmass
>>> pointmass.thresholds(angle=25, friction=0.75, inclination=2.5).forward_sliding  # Eq. (1)
0.2742...
>>> pointmass.velocity(throw_number=1.8, angle=25, friction=0.35).regime
'hopping'
"""

from dem.pointmass.limits import Thresholds, thresholds
from dem.pointmass.model import (
    REGIMES,
    VelocityResult,
    amplitude_from_throw_number,
    throw_number_from_amplitude,
    velocities,
    velocity,
    velocity_scale,
)

__all__ = [
    "REGIMES",
    "Thresholds",
    "VelocityResult",
    "amplitude_from_throw_number",
    "velocity_scale",
    "thresholds",
    "throw_number_from_amplitude",
    "velocities",
    "velocity",
]
