"""Range checks for the point-mass model's inputs, from :mod:`dem.quantities`.

Each raises :class:`dem.errors.InputError` naming the key (the caller's spelling), the value and
the allowed range, in the same words the case reader and the command line use.
"""

from collections.abc import Callable

import numpy as np

from dem.errors import InputError
from dem.quantities import FRICTIONLESS_WHY, QUANTITIES


def check_throw_number(value: float, key: str = "throw_number") -> float:
    """Gamma > 0."""
    return QUANTITIES["throw_number"].check(value, key)


def check_angle(value: float, key: str = "angle") -> float:
    """Vibration angle phi in (0, 90) degrees."""
    return QUANTITIES["angle"].check(value, key)


def check_friction(value: float, key: str = "friction") -> float:
    """Coulomb friction coefficient mu >= 0."""
    return QUANTITIES["friction"].check(value, key)


def check_transport_friction(value: float, key: str = "friction") -> float:
    """Mu > 0, for a conveying velocity (the regime limits take mu = 0)."""
    QUANTITIES["friction"].check(value, key)
    if value == 0.0:
        raise InputError(key, value, f"> 0 for a conveying velocity: {FRICTIONLESS_WHY}")
    return value


def check_inclination(value: float, key: str = "inclination") -> float:
    """Trough inclination |alpha| < 90 degrees."""
    return QUANTITIES["inclination"].check(value, key)


def check_restitution(value: float, key: str) -> float:
    """Coefficient of restitution in [0, 1]."""
    return QUANTITIES["restitution"].check(value, key)


def check_positive(value: float, key: str) -> float:
    """A strictly positive quantity of the table named ``key`` (frequency, amplitude...)."""
    return QUANTITIES[key].check(value, key)


def checked_arrays(inputs: dict[str, tuple[object, Callable[[float, str], float]]]) -> list:
    """The inputs broadcast together and flattened, each distinct value checked by its key.

    ``inputs`` maps a key (as errors name it) to (value or array, its check): the vectorised
    point-mass functions take scalars and arrays alike and refuse any bad element by name.
    """
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v, _ in inputs.values()))
    flat = [a.ravel() for a in arrays]
    for (key, (_, check)), values in zip(inputs.items(), flat, strict=True):
        for value in np.unique(values):
            check(float(value), key)
    return flat


def drive_inputs(throw_number, angle, friction, inclination, eps_t, eps_n) -> dict:
    """The six inputs of a point-mass drive with their checks, for :func:`checked_arrays`.

    The order is the one the point masses unpack: Gamma, phi, mu, alpha, eps_t, eps_n.
    """
    return {
        "throw_number": (throw_number, check_throw_number),
        "angle": (angle, check_angle),
        "friction": (friction, check_transport_friction),
        "inclination": (inclination, check_inclination),
        "eps_t": (eps_t, check_restitution),
        "eps_n": (eps_n, check_restitution),
    }
