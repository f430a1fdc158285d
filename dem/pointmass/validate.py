"""Range checks for the point-mass model's inputs; each raises InputError naming the value."""

import math

from dem.errors import InputError


def _finite(key: str, value: float) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(key, value, "a number") from None
    if not math.isfinite(number):
        raise InputError(key, value, "a finite number")
    return number


def check_throw_number(value: float, key: str = "throw_number") -> float:
    """Gamma > 0."""
    number = _finite(key, value)
    if number <= 0.0:
        raise InputError(key, value, "must be > 0 (Gamma = A omega^2 sin(phi) / (g cos(alpha)))")
    return number


def check_angle(value: float, key: str = "angle") -> float:
    """Vibration angle phi in (0, 90) degrees."""
    number = _finite(key, value)
    if not 0.0 < number < 90.0:
        raise InputError(key, value, "vibration angle must be in (0, 90) degrees")
    return number


def check_friction(value: float, key: str = "friction") -> float:
    """Coulomb friction coefficient mu >= 0."""
    number = _finite(key, value)
    if number < 0.0:
        raise InputError(key, value, "friction coefficient must be >= 0")
    return number


def check_inclination(value: float, key: str = "inclination") -> float:
    """Trough inclination |alpha| < 90 degrees."""
    number = _finite(key, value)
    if not -90.0 < number < 90.0:
        raise InputError(key, value, "inclination must be in (-90, 90) degrees")
    return number


def check_restitution(value: float, key: str) -> float:
    """Coefficient of restitution in [0, 1]."""
    number = _finite(key, value)
    if not 0.0 <= number <= 1.0:
        raise InputError(key, value, "coefficient of restitution must be in [0, 1]")
    return number


def check_positive(value: float, key: str, what: str) -> float:
    """A strictly positive physical quantity (amplitude, frequency, acceleration)."""
    number = _finite(key, value)
    if number <= 0.0:
        raise InputError(key, value, f"{what} must be > 0")
    return number
