"""Mass properties of a rigid clump of spheres: volume, centre, inertia tensor, principal axes.

Used by the grain templates of :mod:`dem.scene.shapes` and, for a single sphere, by every place
that needs a sphere's mass (:func:`sphere_mass`: the state, the scene, the time step, the feeder).

Mass properties are those of the UNION of the spheres (overlaps counted once), uniform density
rho:

    V = int_U dV,   c = (1/V) int_U x dV,   I = rho int_U (|r|^2 Id - r r^T) dV,  r = x - c.

:func:`union_properties` computes them by one of three methods, chosen automatically:

* ``"disjoint"``: no two spheres overlap (touching allowed). Exact: sums of sphere values,
  I_sphere = (2/5) m R^2 Id moved by the parallel-axis theorem.
* ``"axial"``: all centres on one line (a sphere, a screw). The union is a solid of revolution
  whose radius profile is rho(t)^2 = max(0, max_i R_i^2 - (t - t_i)^2) along the axis t. The
  pieces between breakpoints (sphere ends t_i +- R_i and profile crossings) are polynomials of
  degree <= 4 in t, integrated exactly by 3-point Gauss-Legendre:

      V = pi int rho^2 dt,  int t dV = pi int t rho^2 dt,  int t^2 dV = pi int t^2 rho^2 dt,
      int u^2 dV = int v^2 dV = (pi/4) int rho^4 dt  (u, v across the axis).

* ``"grid"``: any other overlapping clump. Lines parallel to x through the nodes of a square
  grid (spacing h) covering the (y, z) silhouette; along each line the union of the sphere chords
  is merged exactly and int 1, x, x^2 dx over it are exact, so only the 2-D rule in (y, z)
  carries error. The grid is shifted by a uniformly random offset in [0, h)^2, which makes each
  estimate unbiased (a randomised lattice rule); the mean of ``GRID_SHIFTS`` independent shifts
  (fixed seed: deterministic) is returned and the error bound is ``GRID_SIGMAS`` standard errors
  of that mean: for V a two-sided confidence of about 99.5 % (Student t, 7 degrees of freedom);
  the bounds on |c| and on the Frobenius norm of I pool 3 and 6 components and are safer still.
  h is halved from ``GRID_START_CELLS`` cells across until the bounds of V (relative), c
  (relative to the largest extent) and I (Frobenius, relative) are below ``rtol``; at
  ``GRID_MAX_CELLS`` it stops and returns the larger bound it reached.
  Measured (tests and checks): errors between 0.01 and 0.65 of the bound; rtol = 1e-4 takes
  0.3 to 5 s for clumps of 2 to 9 spheres, rtol = 1e-3 under 0.3 s.
  An unshifted grid is not used: its error is not monotone in h (silhouettes aligned with grid
  lines), so successive differences can understate it.

The exact methods report rounding-level bounds (``EXACT_RTOL`` times the value).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dem.errors import InputError

#: Relative error bound reported for the exact methods (rounding only).
EXACT_RTOL = 1e-12
#: Default relative tolerance of the grid method (volume, centre of mass / extent, inertia).
GRID_RTOL = 1e-4
#: Grid method: cells across the larger (y, z) extent on the first level, and the most allowed.
GRID_START_CELLS = 64
GRID_MAX_CELLS = 1024
#: Grid method: independent random grid offsets per level, their seed, and the bound in standard
#: errors of their mean (4 standard errors: about 99.5 % two-sided for 8 shifts, Student t).
GRID_SHIFTS = 8
GRID_SEED = 20240521
GRID_SIGMAS = 4.0
#: Grid method: at most this many (line, sphere) entries are held in memory at once.
_GRID_CHUNK = 2_000_000

# 3-point Gauss-Legendre on [-1, 1]: exact for polynomials of degree <= 5.
_GL_X = np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
_GL_W = np.array([5.0, 8.0, 5.0]) / 9.0


@dataclass(frozen=True)
class UnionProperties:
    """Geometric mass properties of a union of spheres (unit density).

    Attributes:
        volume: V, m^3.
        com: Centre of the union, (3,), m.
        inertia: Inertia tensor per unit density about ``com``, int (|r|^2 Id - r r^T) dV, (3, 3),
            m^5.
        volume_error: Bound on |V - V_true|, m^3.
        com_error: Bound on |com - com_true| (Euclidean), m.
        inertia_error: Bound on the Frobenius norm of the inertia error, m^5; by Weyl's
            inequality it bounds the error of each principal moment too.
        method: ``"disjoint"``, ``"axial"`` or ``"grid"``.

    """

    volume: float
    com: np.ndarray
    inertia: np.ndarray
    volume_error: float
    com_error: float
    inertia_error: float
    method: str


def sphere_volume(radius):
    """Volume V = 4/3 pi R^3, m^3, of a sphere of radius R (m; a float or an array of radii)."""
    return 4.0 / 3.0 * math.pi * radius**3


def sphere_mass(density, radius):
    """Mass m = rho 4/3 pi R^3, kg, of a sphere (rho kg/m^3; R m, a float or an array).

    Evaluated left to right as ``rho * 4 / 3 * pi * R^3``, the order every solid sphere in dem
    gets its mass in (the one-sphere template's rho V, :func:`sphere_volume` times rho, equals it
    to rounding only).
    """
    return density * 4.0 / 3.0 * math.pi * radius**3


def principal_axes(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and principal axes (columns, right-handed) of an inertia tensor.

    The largest component of each of the first two axes is made positive and the third is their
    cross product, so the frame is unique where the moments differ and det(axes) = +1.
    """
    eigenvalues, axes = np.linalg.eigh(inertia)
    for col in range(2):  # largest component of each axis positive, then right-handed
        if axes[np.argmax(np.abs(axes[:, col])), col] < 0.0:
            axes[:, col] = -axes[:, col]
    axes[:, 2] = np.cross(axes[:, 0], axes[:, 1])
    return eigenvalues, axes


def union_properties(
    centres, radii, *, method: str = "auto", rtol: float = GRID_RTOL
) -> UnionProperties:
    """Volume, centre and inertia per unit density of the union of spheres.

    Args:
        centres: (k, 3), m.
        radii: (k,), m.
        method: ``"auto"`` (``"disjoint"`` if no two spheres overlap, else ``"axial"`` if the
            centres are collinear, else ``"grid"``) or one of those names to force it.
        rtol: Grid method: stop when successive changes of V (relative), com (relative to the
            largest extent) and I (Frobenius, relative to |I|) are all below rtol.

    Returns:
        :class:`UnionProperties`, with error bounds as described in the module docstring.

    """
    c = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    r = np.asarray(radii, dtype=np.float64).reshape(-1)
    if method == "auto":
        if _disjoint(c, r):
            method = "disjoint"
        elif _collinear(c, r):
            method = "axial"
        else:
            method = "grid"
    if method == "disjoint":
        if not _disjoint(c, r):
            raise InputError("method", method, "'disjoint' only for spheres that do not overlap")
        return _exact(*_moments_disjoint(c, r), "disjoint")
    if method == "axial":
        if not _collinear(c, r):
            raise InputError("method", method, "'axial' only for collinear centres")
        return _exact(*_moments_axial(c, r), "axial")
    if method == "grid":
        return _grid(c, r, rtol)
    raise InputError("method", method, "'auto', 'disjoint', 'axial' or 'grid'")


def _disjoint(c: np.ndarray, r: np.ndarray) -> bool:
    d = np.linalg.norm(c[:, None, :] - c[None, :, :], axis=2)
    overlap = d < (r[:, None] + r[None, :]) * (1.0 - 1e-12)
    np.fill_diagonal(overlap, False)
    return not overlap.any()


def _axis(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean of the centres and the unit direction of their best-fit line (x if none)."""
    p0 = c.mean(axis=0)
    if len(c) == 1:
        return p0, np.array([1.0, 0.0, 0.0])
    _, s, vt = np.linalg.svd(c - p0)
    return p0, (vt[0] if s[0] > 0.0 else np.array([1.0, 0.0, 0.0]))


def _collinear(c: np.ndarray, r: np.ndarray) -> bool:
    p0, d = _axis(c)
    rel = c - p0
    off = rel - np.outer(rel @ d, d)
    return bool(np.max(np.linalg.norm(off, axis=1)) <= 1e-12 * (np.max(np.abs(rel)) + r.max()))


def _moments_disjoint(c: np.ndarray, r: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Raw moments of separate spheres.

    V_i = 4/3 pi R_i^3, int x dV = V_i c_i, int x x^T dV = V_i (c_i c_i^T + R_i^2/5 Id).
    """
    v = sphere_volume(r)
    second = np.einsum("i,ia,ib->ab", v, c, c) + np.sum(v * r**2 / 5.0) * np.eye(3)
    return v.sum(), v @ c, second


def _moments_axial(c: np.ndarray, r: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Raw moments of a union of spheres with collinear centres (solid of revolution)."""
    p0, d = _axis(c)
    t = (c - p0) @ d
    lo, hi = t - r, t + r
    breaks = [lo, hi]
    i, j = np.triu_indices(len(r), 1)
    apart = t[i] != t[j]
    i, j = i[apart], j[apart]
    # R_i^2 - (x - t_i)^2 = R_j^2 - (x - t_j)^2
    #   =>  x = (R_i^2 - R_j^2 + t_j^2 - t_i^2) / (2 (t_j - t_i))
    cross = (r[i] ** 2 - r[j] ** 2 + t[j] ** 2 - t[i] ** 2) / (2.0 * (t[j] - t[i]))
    breaks.append(cross[(cross > lo.min()) & (cross < hi.max())])
    b = np.unique(np.concatenate(breaks))
    a, e = b[:-1], b[1:]
    mid = 0.5 * (a + e)
    q_mid = r[None, :] ** 2 - (mid[:, None] - t[None, :]) ** 2
    owner = np.argmax(q_mid, axis=1)
    keep = q_mid[np.arange(len(mid)), owner] > 0.0
    a, e, owner = a[keep], e[keep], owner[keep]
    x = 0.5 * (a + e)[:, None] + 0.5 * (e - a)[:, None] * _GL_X[None, :]
    w = 0.5 * (e - a)[:, None] * _GL_W[None, :]
    rho2 = r[owner][:, None] ** 2 - (x - t[owner][:, None]) ** 2
    vol = math.pi * np.sum(w * rho2)
    m1 = math.pi * np.sum(w * x * rho2)  # int t dV
    m2 = math.pi * np.sum(w * x * x * rho2)  # int t^2 dV
    m_perp = 0.25 * math.pi * np.sum(w * rho2 * rho2)  # int u^2 dV = int v^2 dV
    first = vol * p0 + m1 * d
    dd = np.outer(d, d)
    second = (
        vol * np.outer(p0, p0)
        + m1 * (np.outer(p0, d) + np.outer(d, p0))
        + m2 * dd
        + m_perp * (np.eye(3) - dd)
    )
    return vol, first, second


def _central(vol: float, first: np.ndarray, second: np.ndarray):
    """Centre and inertia per unit density from raw moments about the origin."""
    com = first / vol
    s = second - vol * np.outer(com, com)  # int r r^T dV about the centre
    return com, np.trace(s) * np.eye(3) - s


def _exact(vol: float, first: np.ndarray, second: np.ndarray, method: str) -> UnionProperties:
    com, inertia = _central(vol, first, second)
    size = math.sqrt(np.trace(inertia) / vol)  # a length of the order of the grain's radius
    return UnionProperties(
        volume=float(vol),
        com=com,
        inertia=0.5 * (inertia + inertia.T),
        volume_error=EXACT_RTOL * vol,
        com_error=EXACT_RTOL * (size + float(np.max(np.abs(com)))),
        inertia_error=EXACT_RTOL * float(np.linalg.norm(inertia)),
        method=method,
    )


def _grid_level(c: np.ndarray, r: np.ndarray, cells: int, offset: np.ndarray):
    """Raw moments (about the origin) by exact chords along x on a shifted (y, z) grid.

    Lines pass through (y, z) = lo - h + (i + offset) h, i = 0 .. n + 1, with h the larger
    (y, z) extent over ``cells`` and offset in [0, 1)^2: the grid covers the silhouette for every
    offset, so with a uniformly random offset the estimate is unbiased.
    """
    lo, hi = (c[:, 1:] - r[:, None]).min(axis=0), (c[:, 1:] + r[:, None]).max(axis=0)
    h = float(np.max(hi - lo)) / cells
    ny, nz = (np.ceil((hi - lo) / h).astype(int) + 2).tolist()
    y = lo[0] + h * (np.arange(ny) - 1.0 + offset[0])
    z = lo[1] + h * (np.arange(nz) - 1.0 + offset[1])
    floor = (c[:, 0] - r).min() - 1.0  # empty chords sit here with zero length
    k = len(r)
    sums = np.zeros(10)  # V, Sx, Sy, Sz, Sxx, Syy, Szz, Sxy, Sxz, Syz
    rows = max(1, _GRID_CHUNK // (k * nz))
    for start in range(0, ny, rows):
        yy, zz = np.meshgrid(y[start : start + rows], z, indexing="ij")
        yy, zz = yy.ravel(), zz.ravel()
        d2 = (yy[:, None] - c[None, :, 1]) ** 2 + (zz[:, None] - c[None, :, 2]) ** 2
        half = np.sqrt(np.maximum(r[None, :] ** 2 - d2, 0.0))
        hit = d2 < r[None, :] ** 2
        a = np.where(hit, c[None, :, 0] - half, floor)
        b = np.where(hit, c[None, :, 0] + half, floor)
        order = np.argsort(a, axis=1)
        a, b = np.take_along_axis(a, order, 1), np.take_along_axis(b, order, 1)
        reach = np.maximum.accumulate(b, axis=1)  # right end of the union of chords so far
        before = np.concatenate([np.full((len(a), 1), floor), reach[:, :-1]], axis=1)
        lo, hi = np.maximum(a, before), np.maximum(b, before)  # new part of each chord
        l0 = np.sum(hi - lo, axis=1)
        l1 = np.sum(hi**2 - lo**2, axis=1) / 2.0
        l2 = np.sum(hi**3 - lo**3, axis=1) / 3.0
        sums += [
            l0.sum(), l1.sum(), yy @ l0, zz @ l0, l2.sum(), (yy * yy) @ l0, (zz * zz) @ l0,
            yy @ l1, zz @ l1, (yy * zz) @ l0,
        ]  # fmt: skip
    sums *= h * h
    v, sx, sy, sz, sxx, syy, szz, sxy, sxz, syz = sums
    second = np.array([[sxx, sxy, sxz], [sxy, syy, syz], [sxz, syz, szz]])
    return v, np.array([sx, sy, sz]), second


def _grid(c: np.ndarray, r: np.ndarray, rtol: float) -> UnionProperties:
    shift = 0.5 * ((c - r[:, None]).min(axis=0) + (c + r[:, None]).max(axis=0))
    extent = float(np.max((c + r[:, None]).max(axis=0) - (c - r[:, None]).min(axis=0)))
    offsets = np.random.default_rng(GRID_SEED).random((GRID_SHIFTS, 2))
    cells = GRID_START_CELLS
    while True:
        levels = []
        for offset in offsets:
            vol, first, second = _grid_level(c - shift, r, cells, offset)
            levels.append((vol, *_central(vol, first, second)))
        # the shifted estimates are independent and unbiased: bound = GRID_SIGMAS standard errors
        vols, coms, inertias = (np.array(column) for column in zip(*levels, strict=True))
        vol, com, inertia = vols.mean(), coms.mean(axis=0), inertias.mean(axis=0)
        scale = GRID_SIGMAS / math.sqrt(GRID_SHIFTS * (GRID_SHIFTS - 1))
        errors = (
            scale * math.sqrt(np.sum((vols - vol) ** 2)),
            scale * math.sqrt(np.sum((coms - com) ** 2)),
            scale * math.sqrt(np.sum((inertias - inertia) ** 2)),
        )
        rel = (errors[0] / vol, errors[1] / extent, errors[2] / np.linalg.norm(inertia))
        if max(rel) <= rtol or 2 * cells > GRID_MAX_CELLS:
            break
        cells *= 2
    return UnionProperties(
        volume=float(vol),
        com=com + shift,
        inertia=0.5 * (inertia + inertia.T),
        volume_error=errors[0],
        com_error=errors[1],
        inertia_error=errors[2],
        method="grid",
    )
