"""Brute-force NumPy count of each sphere's contacts: every pair (no pair list), every wall.

Written from the geometry (README, Symbols: the floor z = 0, the side walls y = -+width/2,
the back wall x = 0 of a finite feeder, the periodic section along x), not from the kernels, so
that :func:`dem.kernels.forces.contact_counts` is checked against an independent count.
"""

import numpy as np


def contact_counts(x, radius, body, length, width, back=-np.inf, periodic=True):
    """Touching neighbours (spheres of other bodies) plus touching flat walls, (n,) int64."""
    x = np.asarray(x, dtype=float)
    n = len(x)
    count = np.zeros(n, dtype=np.int64)
    for i in range(n):
        for j in range(i + 1, n):
            if body[i] == body[j]:
                continue
            d = x[i] - x[j]
            if periodic:
                d[0] -= length * np.round(d[0] / length)
            if d @ d < (radius[i] + radius[j]) ** 2:
                count[i] += 1
                count[j] += 1
    gaps = [x[:, 2], x[:, 1] + width / 2, width / 2 - x[:, 1], x[:, 0] - back]
    for gap in gaps:
        count += gap < radius
    return count
