"""The golden-section search, written once for the point-mass optimum and the calibration fit."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import cast

#: (sqrt(5) - 1) / 2: each step keeps this fraction of the bracket.
RATIO = (math.sqrt(5.0) - 1.0) / 2.0


def golden_evaluations(width: float, tol: float) -> int:
    """Most evaluations :func:`golden_section` makes to narrow ``width`` to ``tol``.

    Two, then one per narrowing by the golden ratio (the other point is kept).
    """
    return 2 + max(0, math.ceil(math.log(tol / width) / math.log(RATIO)))


def golden_section(
    f: Callable[[float], float],
    a: float,
    b: float,
    *,
    tol: float | None = None,
    iterations: int | None = None,
    maximize: bool = False,
) -> tuple[float, float]:
    """Golden-section search of ``f`` on [a, b] for its minimum (or maximum); (x, f(x)).

    Stops when the bracket is ``tol`` wide or after ``iterations`` narrowings (one of the two).
    Each narrowing evaluates ``f`` once. Returns the better of the two inner points. On a tie
    a maximum keeps the left part, a minimum the right part.
    """
    if (tol is None) == (iterations is None):
        raise ValueError("golden_section takes tol or iterations, one of them")
    c, d = b - RATIO * (b - a), a + RATIO * (b - a)
    fc, fd = f(c), f(d)
    done = 0
    # one of the two is None (checked above), so ``iterations`` is an int when ``tol`` is None
    while (b - a > tol) if tol is not None else (done < cast(int, iterations)):
        if (fc >= fd) if maximize else (fc < fd):
            b, d, fd = d, c, fc
            c = b - RATIO * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + RATIO * (b - a)
            fd = f(d)
        done += 1
    if maximize:
        return (c, fc) if fc >= fd else (d, fd)
    return (c, fc) if fc < fd else (d, fd)
