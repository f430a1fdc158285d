"""Grain types and size distributions of spheres: radii drawn, moments, and bins for decks.

A sphere case may give a size distribution (``particles.radius_distribution``) or several grain
types (``[[particles.types]]``), each a :class:`dem.scene.spec.GrainType` with its share of the
grains by number, its density and a :class:`dem.scene.spec.SizeSpec`. This module turns them
into numbers:

- :func:`split` gives each type (or each radius of a discrete distribution) its whole number
  of grains, round(N f) by the largest remainder, so the counts sum to N and each is within one
  grain of N f;
- :func:`draw_types` draws every grain's radius, seeded by ``run.seed`` on a stream of its own
  (the positions' stream is the single-size fill's): a discrete distribution by its exact
  counts in random order, a continuous one by inverting its cumulative distribution (a normal or
  lognormal truncated to [radius_min, radius_max], tabulated on :data:`TABLE_POINTS` radii);
- :func:`mean_power` gives E[r^k] over a distribution, and :func:`mean_volume` and
  :func:`mean_mass` the mean grain over the types, from the case alone: a depth
  (:mod:`dem.scene.depth`) and the fill box take them, so neither depends on the draw;
- :func:`bins` discretises a distribution for a LIGGGHTS deck, whose ``particletemplate/sphere``
  takes one radius each: equal-number quantile bins, each at the radius of its mean volume.

All fractions are by number of grains. Units: m, kg, kg/m^3.
"""

from __future__ import annotations

import math

import numpy as np

#: Radii on which a truncated normal or lognormal is tabulated (pdf, cumulative distribution).
TABLE_POINTS = 4097
#: Bins a continuous distribution is cut into for a deck (:func:`bins`).
DECK_BINS = 8
#: The random stream of the radii (beside ``run.seed``), apart from the positions' stream.
SIZE_STREAM = 0x5125


def split(n: int, fractions) -> np.ndarray:
    """Whole counts summing to ``n`` for number ``fractions`` (sum 1): the largest remainder.

    Each count is floor(n f) or that plus one; the grains left over go to the largest
    remainders (the earlier of equal ones first). (len(fractions),) int64.
    """
    f = np.asarray(fractions, dtype=np.float64)
    exact = n * f / f.sum()
    counts = np.floor(exact).astype(np.int64)
    left = n - int(counts.sum())
    if left > 0:
        order = np.argsort(-(exact - counts), kind="stable")
        counts[order[:left]] += 1
    return counts


def _table(size) -> tuple[np.ndarray, np.ndarray]:
    """Radii and the cumulative distribution (0 to 1) of a truncated normal or lognormal."""
    r = np.linspace(size.radius_min, size.radius_max, TABLE_POINTS)
    pdf = _pdf(size, r)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]) * np.diff(r))])
    return r, cdf / cdf[-1]


def _pdf(size, r: np.ndarray) -> np.ndarray:
    """Unnormalised density of a normal or lognormal radius at ``r``."""
    if size.distribution == "normal":
        return np.exp(-0.5 * ((r - size.radius) / size.radius_std) ** 2)
    return np.exp(-0.5 * (np.log(r / size.radius) / size.radius_log_std) ** 2) / r


def mean_power(size, k: int) -> float:
    """E[r^k] over the distribution, m^k (by number of grains)."""
    d = size.distribution
    if d == "none":
        return size.radius**k
    if d == "discrete":
        return float(np.dot(size.radius_fractions, np.asarray(size.radii) ** k))
    a, b = size.radius_min, size.radius_max
    if d == "uniform":
        return (b ** (k + 1) - a ** (k + 1)) / ((k + 1) * (b - a))
    r = np.linspace(a, b, TABLE_POINTS)
    pdf = _pdf(size, r)
    return float(np.trapezoid(pdf * r**k, r) / np.trapezoid(pdf, r))


def draw(size, n: int, rng: np.random.Generator) -> np.ndarray:
    """N radii of the distribution, m (a discrete one by its exact counts, shuffled)."""
    d = size.distribution
    if d == "none":
        return np.full(n, size.radius)
    if d == "discrete":
        radii = np.repeat(np.asarray(size.radii), split(n, size.radius_fractions))
        return rng.permutation(radii)
    u = rng.random(n)
    if d == "uniform":
        return size.radius_min + (size.radius_max - size.radius_min) * u
    r, cdf = _table(size)
    return np.interp(u, cdf, r)


def draw_types(types, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every grain's radius, density and type for ``n`` grains of ``types`` (seeded).

    Returns (radius (n,) m, density (n,) kg/m^3, type index (n,) int64), type by type.
    """
    rng = np.random.default_rng([seed, SIZE_STREAM])
    counts = split(n, [t.fraction for t in types])
    radii = np.concatenate([draw(t.size, int(c), rng) for t, c in zip(types, counts, strict=True)])
    kind = np.repeat(np.arange(len(types), dtype=np.int64), counts)
    density = np.asarray([t.density for t in types])[kind]
    return radii, density, kind


def mean_volume(types) -> float:
    """Mean grain volume over the types, by number, m^3."""
    return sum(t.fraction * 4.0 / 3.0 * math.pi * mean_power(t.size, 3) for t in types)


def mean_mass(types) -> float:
    """Mean grain mass over the types, by number, kg."""
    return sum(t.fraction * t.density * 4.0 / 3.0 * math.pi * mean_power(t.size, 3) for t in types)


def mean_density(types) -> float:
    """The types' density by volume (mean mass over mean volume), kg/m^3."""
    return mean_mass(types) / mean_volume(types)


def bins(size, count: int = DECK_BINS) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The distribution as discrete radii with number fractions, for a deck.

    One radius, and a discrete distribution, as they are; a continuous one as ``count``
    quantile bins of equal number, each at the radius of its mean volume (E[r^3 | bin])^(1/3),
    so that the bins keep the distribution's mean volume and mass.
    """
    d = size.distribution
    if d == "none":
        return (size.radius,), (1.0,)
    if d == "discrete":
        return tuple(size.radii), tuple(size.radius_fractions)
    if d == "uniform":
        r = np.linspace(size.radius_min, size.radius_max, TABLE_POINTS)
        cdf = (r - r[0]) / (r[-1] - r[0])
    else:
        r, cdf = _table(size)
    edges = np.interp(np.linspace(0.0, 1.0, count + 1), cdf, r)
    out = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        inner = np.linspace(lo, hi, 257)
        w = np.ones_like(inner) if d == "uniform" else _pdf(size, inner)
        out.append(float((np.trapezoid(w * inner**3, inner) / np.trapezoid(w, inner)) ** (1 / 3)))
    return tuple(out), tuple([1.0 / count] * count)


def placed(radius: np.ndarray, kind: np.ndarray, types) -> list[dict]:
    """What a fill placed, per type: count, mean, smallest and largest radius (summary.json)."""
    out = []
    for k, t in enumerate(types):
        r = radius[kind == k]
        out.append({
            "name": t.name, "fraction": t.fraction, "density": t.density,
            "distribution": t.size.distribution, "count": int(r.size),
            "radius_mean": float(r.mean()) if r.size else math.nan,
            "radius_min": float(r.min()) if r.size else math.nan,
            "radius_max": float(r.max()) if r.size else math.nan,
        })  # fmt: skip
    return out
