"""The one table of input quantities: name, unit, allowed range and its text.

Every place that accepts a physical number checks it against this table: the case reader
(:mod:`dem.scene.case`, keys such as ``drive.angle``), the point-mass functions
(:mod:`dem.pointmass.validate`) and the command line (its help and its errors, :mod:`dem.cli`).
A range is stated once, so a value refused in a case file is refused with the same words on the
command line and in the library.

Ranges are physical where physics sets them (an angle, a restitution) and plausibility bounds
elsewhere, wide enough for any vibratory conveyor or lab experiment (a frequency up to 100 kHz,
a Young's modulus up to 10 TPa, diamond's is 1.2 TPa): a value of 1e300 is a typing error, and
it would otherwise overflow deep inside a run instead of being named here. The same holds at the
other end: a positive quantity has a smallest plausible value (a throw number of 0.001, a
drive of 1 nm, a gel's 1 kPa, a density of 1 kg/m^3), below which the numbers a run reports
(v / (A omega cos phi) over a vanishing drive, steps per cycle, a stiffness ratio) are
noise divided by almost nothing.

Each :class:`Quantity` checks a finite float; :meth:`Quantity.check` raises
:class:`dem.errors.InputError` naming the key (the caller's spelling: ``drive.angle``,
``--angle`` or ``angle``), the value and the allowed range.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from dem.errors import InputError

#: Most member spheres one grain may have (a screw's head and shank spheres, a clump template's
#: lines). It bounds the template's own work (pairwise checks and mass properties, quadratic in
#: the count) and sets the smallest ``particles.max_bumpiness`` a screw may ask for; the
#: resolution study (validation/speed_accuracy) uses 6 to 15.
MAX_GRAIN_SPHERES = 1000


@dataclass(frozen=True)
class Quantity:
    """One input quantity.

    Attributes:
        name: Key name without table or dashes (``angle``).
        unit: SI unit or "" for a dimensionless number (``deg`` for angles).
        accepts: True for a value in range (the value is a finite float).
        allowed: The range in words, as errors and help texts show it.
        meaning: What it is, with the paper's symbol.

    """

    name: str
    unit: str
    accepts: Callable[[float], bool]
    allowed: str
    meaning: str

    def check(self, value: object, key: str | None = None, source: str | None = None) -> float:
        """``value`` as a float if finite and in range; InputError naming ``key`` otherwise."""
        key = key or self.name
        if isinstance(value, bool):
            raise InputError(key, value, f"a number: {self.allowed}", source=source)
        try:
            number = float(value)  # type: ignore[arg-type]  # any object: a TypeError refuses it
        except (TypeError, ValueError):
            raise InputError(key, value, f"a number: {self.allowed}", source=source) from None
        if not math.isfinite(number):
            raise InputError(key, value, f"a finite number: {self.allowed}", source=source)
        if not self.accepts(number):
            raise InputError(key, value, self.allowed, source=source)
        return number

    @property
    def help(self) -> str:
        """Command-line help: meaning and range."""
        return f"{self.meaning}; {self.allowed}"


def _q(name, unit, accepts, allowed, meaning) -> tuple[str, Quantity]:
    return name, Quantity(name, unit, accepts, allowed, meaning)


def _positive(x: float) -> bool:
    return x > 0.0


def _non_negative(x: float) -> bool:
    return x >= 0.0


#: Why a conveying velocity needs friction > 0 (the case reader and the point masses say it).
FRICTIONLESS_WHY = (
    "without friction nothing sets a grain's mean velocity along the trough: it keeps the one "
    "it starts with (the drive starts at full speed), so the answer would be the start-up, not "
    "transport"
)


def _unit_interval(x: float) -> bool:
    return 0.0 <= x <= 1.0


QUANTITIES: dict[str, Quantity] = dict(
    [
        # drive and trough
        _q("throw_number", "", lambda x: 1.0e-3 <= x <= 100.0,
           "must be in [0.001, 100] (Gamma = A omega^2 sin(phi) / (g cos(alpha)))",
           "throw number Gamma"),
        _q("angle", "deg", lambda x: 0.0 < x < 90.0,
           "vibration angle must be in (0, 90) degrees", "vibration angle phi, deg"),
        _q("inclination", "deg", lambda x: -90.0 < x < 90.0,
           "inclination must be in (-90, 90) degrees: -90 < alpha < 90",
           "trough inclination alpha, deg"),
        _q("second_amplitude", "m", lambda x: 0.0 <= x <= 1.0,
           "amplitude of the second drive component must be in [0, 1] m (0: a line drive)",
           "amplitude A_2 of the drive's second component, m"),
        _q("second_angle", "deg", lambda x: 0.0 <= x < 180.0,
           "direction of the second drive component must be in [0, 180) degrees from the "
           "trough axis towards the floor normal", "direction phi_2 of the second component, deg"),
        _q("second_phase", "deg", lambda x: -360.0 <= x <= 360.0,
           "phase of the second drive component must be in [-360, 360] degrees",
           "phase psi_2 of the second component ahead of the first, deg"),
        _q("ramp_cycles", "", lambda x: 0.0 <= x <= 1000.0,
           "start-up ramp must be in [0, 1000] drive cycles (0: full amplitude at once)",
           "drive cycles over which the amplitude rises from 0 to full"),
        _q("feed_rate", "kg/s", lambda x: 0.0 <= x <= 1.0e3,
           "feed rate must be in [0, 1000] kg/s (0: the initial charge is emptied)",
           "mass fed at the back of a finite feeder per second, kg/s"),
        _q("frequency", "Hz", lambda x: 0.01 <= x <= 1.0e5, "frequency must be in [0.01, 1e5] Hz",
           "drive frequency f, Hz"),
        _q("amplitude", "m", lambda x: 1.0e-9 <= x <= 1.0, "amplitude must be in [1e-9, 1] m",
           "drive amplitude A, m"),
        _q("peak_acceleration", "g", lambda x: 1.0e-3 <= x <= 1.0e4,
           "peak acceleration must be in [0.001, 1e4] (in g)",
           "peak trough acceleration A omega^2, in units of g"),
        _q("drive_velocity", "m/s", lambda x: 1.0e-6 <= x <= 100.0,
           "drive velocity must be in [1e-6, 100] m/s", "drive velocity amplitude A omega, m/s"),
        _q("length", "m", lambda x: 0.0 < x <= 1.0e3, "must be in (0, 1000] m", "length, m"),
        _q("width", "m", lambda x: 0.0 < x <= 1.0e3, "must be in (0, 1000] m", "width, m"),
        # material
        _q("density", "kg/m^3", lambda x: 1.0 <= x <= 1.0e5,
           "density must be in [1, 1e5] kg/m^3", "grain density"),
        _q("friction", "", lambda x: 0.0 <= x <= 1.0e12,
           "friction coefficient must be in [0, 1e12] (1e9 and up: ideal adhesion)",
           "Coulomb friction coefficient mu"),
        _q("restitution", "", _unit_interval,
           "coefficient of restitution must be in [0, 1]: 0 <= value <= 1",
           "coefficient of restitution"),
        _q("rolling_friction", "", lambda x: 0.0 <= x <= 100.0,
           "rolling friction must be in [0, 100]",
           "rolling friction coefficient"),
        _q("inertia_factor", "", lambda x: 0.0 < x <= 1.0e6,
           "moment of inertia factor must be in (0, 1e6]: I = factor m r^2 (0.4 a solid "
           "sphere, 2/3 a thin shell)",
           "moment of inertia factor k = I / (m r^2) of a round grain about its rolling axis"),
        # contact
        _q("youngs_modulus", "Pa", lambda x: 1.0e3 <= x <= 1.0e13,
           "Young's modulus must be in [1e3, 1e13] Pa",
           "Young's modulus E, Pa"),
        _q("poisson_ratio", "", lambda x: -1.0 < x < 0.5,
           "Poisson ratio must satisfy -1 < nu < 0.5", "Poisson ratio nu"),
        _q("stiffness", "N/m", lambda x: 1.0e-3 <= x <= 1.0e12,
           "stiffness must be in [1e-3, 1e12] N/m",
           "linear normal stiffness k_n, N/m"),
        _q("tangential_stiffness_ratio", "", lambda x: 0.0 < x <= 100.0,
           "k_t / k_n must be in (0, 100]",
           "tangential stiffness ratio kappa = k_t / k_n"),
        _q("tangential_damping_ratio", "", lambda x: 0.0 <= x <= 10.0,
           "tangential damping ratio must satisfy 0 <= value <= 10",
           "tangential damping ratio zeta_t"),
        # grains and run
        _q("radius", "m", lambda x: 1.0e-7 <= x <= 10.0, "radius must be in [1e-7, 10] m",
           "radius, m"),
        _q("radius_log_std", "", lambda x: 0.0 < x <= 3.0,
           "must be in (0, 3]: the standard deviation of ln(r)",
           "standard deviation of ln(radius) of a lognormal size distribution"),
        _q("fraction", "", lambda x: 0.0 < x <= 1.0, "a fraction in (0, 1]",
           "share of the grains by number"),
        _q("mass", "kg", lambda x: 1.0e-18 <= x <= 1.0e3, "mass must be in [1e-18, 1000] kg",
           "grain mass, kg"),
        _q("max_bumpiness", "", lambda x: 0.0 < x <= 1.0,
           "must satisfy 0 < b <= 1 (1: touching shank spheres; smaller: more spheres, at most "
           f"{MAX_GRAIN_SPHERES} per grain)",
           "screw resolution: deepest valley between shank spheres over the shank radius"),
        _q("layers", "", lambda x: 0.01 <= x <= 1.0e4, "must be in [0.01, 1e4] grain layers",
           "bed depth in grain layers of the volume-equivalent diameter"),
        _q("bed_height", "m", lambda x: 1.0e-6 <= x <= 100.0, "must be in [1e-6, 100] m",
           "bed height at the assumed solid fraction, m"),
        _q("mass_per_area", "kg/m^2", lambda x: 1.0e-6 <= x <= 1.0e6,
           "must be in [1e-6, 1e6] kg/m^2", "grain mass per floor area, kg/m^2"),
        _q("target_error", "", lambda x: 1.0e-4 <= x <= 0.5,
           "must be in [1e-4, 0.5] (a fraction of the velocity)",
           "standard error the run pools fills until it reaches, as a fraction of |v|"),
        _q("timestep", "s", lambda x: 1.0e-15 <= x <= 1.0,
           '"auto" or a time step in [1e-15, 1] s',
           "time step dt, s"),
        # whole numbers (read as integers; accepts() sees the int)
        _q("count", "", lambda n: 1 <= n <= 10**9, "a whole number in [1, 1e9]",
           "number of grains"),
        _q("max_replicas", "", lambda n: 2 <= n <= 1000, "a whole number of fills in [2, 1000]",
           "most fills a run with a target error pools"),
        _q("cycles", "", lambda n: 1 <= n <= 10**7, "a whole number of cycles in [1, 1e7]",
           "measured drive cycles"),
        _q("settle_cycles", "", lambda n: 0 <= n <= 10**7,
           "\"auto\" or a whole number of cycles in [0, 1e7]",
           "driven cycles before measuring"),
        _q("seed", "", lambda n: 0 <= n < 2**63, "a whole number in [0, 2^63)",
           "random seed of the fill"),
        _q("replicas", "", lambda n: 1 <= n <= 1000, "a whole number of fills in [1, 1000]",
           "independent fills pooled (seeds seed, seed + 1, ...)"),
        _q("flight_phases", "", lambda n: 0 <= n <= 360, "a whole number in [0, 360]",
           "phase bins per cycle at which the grains in flight are counted (0: none)"),
        _q("frames_per_cycle", "", lambda n: 1 <= n <= 10**6, "a whole number in [1, 1e6]",
           "VTK frames per drive cycle"),
        _q("threads", "", lambda n: 1 <= n <= 4096, "a whole number of threads in [1, 4096]",
           "numba threads"),
        # sweeps and searches of DEM runs (dem sweep, dem optimum)
        _q("workers", "", lambda n: 1 <= n <= 4096,
           "a whole number of worker processes in [1, 4096]", "local Dask workers"),
        _q("max_runs", "", lambda n: 5 <= n <= 10**4,
           "a whole number of DEM runs in [5, 10000] (the search starts with 5)",
           "most DEM runs of a search"),
        _q("tolerance", "", lambda x: 0.0 < x <= 100.0,
           "must be in (0, 100], in the scanned variable's unit (deg or Gamma)",
           "bracket half-width at which a search stops"),
    ]
)  # fmt: skip


def check(name: str, value: object, key: str | None = None, source: str | None = None) -> float:
    """Check ``value`` against the quantity ``name`` (:data:`QUANTITIES`); see Quantity.check."""
    return QUANTITIES[name].check(value, key, source)
