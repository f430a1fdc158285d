"""dem: granular material on vibratory conveyors.

Two models of one question -- how fast does a material move on a linear vibratory conveyor:

- :mod:`dem.pointmass`: the point-mass model of the paper "Optimum Vibration Angle for
  Transporting Granular Materials on Linear Conveyors" (resting, sliding and flight phases,
  impacts with normal and tangential restitution), integrated event by event.
- the discrete element model (``dem run``): many grains on a sinusoidally driven trough.
"""

__version__ = "0.1.0"
