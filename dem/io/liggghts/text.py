"""How numbers go into LIGGGHTS input files: floats written exactly, and the prime seeds.

Every part of a deck (:mod:`dem.io.liggghts.deck` and the blocks it assembles) and the STL file
of a mesh (:mod:`dem.io.liggghts.geometry`) write floats with :func:`fmt`, the shortest repr,
so a number read back by LIGGGHTS is the same double dem used. LIGGGHTS wants each random seed
a prime above 10000: :func:`prime_at_least`.
"""

from __future__ import annotations

import math


def prime_at_least(n: int) -> int:
    """Smallest prime >= n (LIGGGHTS wants prime seeds above 10000)."""
    candidate = max(n, 10007)
    while any(candidate % d == 0 for d in range(2, math.isqrt(candidate) + 1)):
        candidate += 1
    return candidate


def fmt(x: float) -> str:
    """Format a float exactly (shortest repr) for the deck."""
    return repr(float(x) + 0.0)  # + 0.0 turns -0.0 into 0.0
