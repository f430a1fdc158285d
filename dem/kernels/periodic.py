"""The periodic section along x, written once for every kernel.

The trough section repeats with period ``length`` along x. Positions are kept in [0, length)
(:func:`wrap`); separations take the nearest periodic image: :func:`minimum_image` for two
points that both lie in the section (|dx| < length, one shift at most, as pair and neighbour
kernels need), :func:`nearest_image` for any separation (a clump member from its centre of mass,
which may lie a period away before the wrap).
"""

import math

import numba

from dem.config import NUMBA_OPTIONS


@numba.njit(inline="always", **NUMBA_OPTIONS)
def wrap(x, length):
    """X wrapped into [0, length); -1e-17 would round to ``length`` and is set to 0."""
    x -= math.floor(x / length) * length
    if x >= length:
        x = 0.0
    return x


@numba.njit(inline="always", **NUMBA_OPTIONS)
def minimum_image(dx, length, half):
    """Dx shifted by one period at most into [-half, half] (half = length / 2)."""
    if dx > half:
        dx -= length
    elif dx < -half:
        dx += length
    return dx


@numba.njit(inline="always", **NUMBA_OPTIONS)
def nearest_image(dx, length):
    """Dx - length round(dx / length): the nearest image at any distance."""
    return dx - length * math.floor(dx / length + 0.5)
