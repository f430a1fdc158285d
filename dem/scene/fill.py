"""Initial placement of grains in the trough: random sequential addition, seeded.

A fill draws each grain's centre (and, for clumps, a uniform random orientation) inside a box
over the trough floor and keeps it if it overlaps nothing placed before (periodic in x); after
``DEM_FILL_TRIES`` failed tries the box is made 25 % taller. The box's starting height is a
function of the case alone (:func:`box_height`), which is what the automatic time step
(:mod:`dem.scene.timestep`) takes its impact speed from: the time step never depends on the draw.

Cost: O(N). Grains placed so far are kept in a grid of cells at least one interaction range
wide (a sphere diameter; a clump's bounding diameter), so a try tests only the grains of the 27
cells around it. The draws and the accept/reject decisions are those of a test against every
grain placed so far, so a seed gives the same fill as it did before the grid (tested). Spheres
run in a compiled loop over pre-drawn uniforms (the same stream as one ``uniform`` call per
coordinate); clumps, whose orientation draws interleave, in Python with the grid.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from dem.config import DEM_FILL_HEIGHT_FACTOR, DEM_FILL_TRIES
from dem.errors import InputError
from dem.kernels.rigid import quat_to_matrix
from dem.scene.trough import Trough


def sphere_box_height(n: int, radius: float, length: float, width: float) -> float:
    """Starting fill-box height for n spheres, m.

    ``DEM_FILL_HEIGHT_FACTOR`` times the height of a dense bed (packing fraction 0.6) plus a
    diameter.
    """
    bed = n * 4.0 / 3.0 * math.pi * radius**3 / (0.6 * length * width)
    return DEM_FILL_HEIGHT_FACTOR * bed + 2.0 * radius


def clump_box_height(n: int, template, length: float, width: float) -> float:
    """Starting fill-box height for n clumps of a :class:`dem.scene.shapes.Template`, m.

    ``DEM_FILL_HEIGHT_FACTOR`` times the height of a loose bed (packing fraction 0.3) plus the
    bounding diameter.
    """
    bed = n * template.volume / (0.3 * length * width)
    return DEM_FILL_HEIGHT_FACTOR * bed + 2.0 * template.bounding_radius


def box_height(case) -> float:
    """Starting fill-box height of a :class:`dem.scene.case.Case`'s grains, m (no fill is drawn).

    Spheres of several types or sizes: the dense bed of their mean volume (from the case, not
    the draw: :func:`dem.scene.sizes.mean_volume`) plus the largest diameter.
    """
    pt, t = case.particles, case.trough
    if pt.types:
        from dem.scene.sizes import mean_volume

        bed = pt.count * mean_volume(pt.types) / (0.6 * t.length * t.width)
        return DEM_FILL_HEIGHT_FACTOR * bed + 2.0 * pt.radius
    if not pt.clumps:
        return sphere_box_height(pt.count, pt.radius, t.length, t.width)
    return clump_box_height(pt.count, pt.grain, t.length, t.width)


def fill(case) -> tuple[np.ndarray, np.ndarray | None, float]:
    """The case's grains placed at random (seed ``run.seed``).

    A finite feeder (``case.feeder``) is filled between its back wall and its discharge edge,
    clear of both by a grain's bounding radius b: centres in b <= x <= length - b (the fill of a
    section of length - 2 b, moved by b).

    Returns:
        (centres or centres of mass (N, 3) in m, quaternions (N, 4) or None for spheres,
        final box height in m).

    """
    pt, t = case.particles, case.trough
    rng = np.random.default_rng(case.run.seed)
    reach = pt.reach
    start, span = 0.0, t.length
    if getattr(case, "feeder", None) is not None:
        start, span = reach, t.length - 2.0 * reach
        if span <= 0.0:
            raise InputError("trough.length", t.length,
                             f"> {2.0 * reach:.4g} m, two grain extents (a finite feeder holds "
                             "its grains between the back wall and the edge)")  # fmt: skip
    if t.mesh is not None:
        return fill_mesh(case, rng, start, span)
    if not pt.clumps:
        positions, height = random_fill(pt.count, pt.radius, span, t.width, rng)
        quats = None
    else:
        positions, quats, height = random_fill_clumps(pt.count, pt.grain, span, t.width, rng)
    positions[:, 0] += start
    order = spatial_order(positions, 2.0 * reach, t.width)
    return positions[order], None if quats is None else quats[order], height


def fill_types(case) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """A case of several sphere types or sizes placed at random (seed ``run.seed``).

    Each type gets its whole share of the grains (:func:`dem.scene.sizes.split`) and each grain
    its radius (:func:`dem.scene.sizes.draw_types`, a stream of its own); the spheres are placed
    largest first by :func:`random_fill_sized` (the small ones fill the gaps the large ones
    leave), then numbered along the trough (:func:`spatial_order`).

    Returns:
        (centres (N, 3) m, radii (N,) m, densities (N,) kg/m^3, type index (N,) int64, final
        box height m).

    """
    from dem.scene.sizes import draw_types

    pt, t = case.particles, case.trough
    radius, density, kind = draw_types(pt.types, pt.count, case.run.seed)
    first = np.argsort(-radius, kind="stable")
    radius, density, kind = radius[first], density[first], kind[first]
    rng = np.random.default_rng(case.run.seed)
    positions, height = random_fill_sized(radius, t.length, t.width, rng, height=box_height(case))
    order = spatial_order(positions, 2.0 * pt.radius, t.width)
    return positions[order], radius[order], density[order], kind[order], height


def random_fill_sized(
    radius: np.ndarray,
    length: float,
    width: float,
    rng: np.random.Generator,
    *,
    height: float,
) -> tuple[np.ndarray, float]:
    """Random sequential placement of spheres of radii ``radius`` (n,), in that order.

    As :func:`random_fill`, sphere i drawn in y in [-width/2 + r_i, width/2 - r_i], z in
    [r_i, height - r_i] and kept if it is farther than r_i + r_j from every earlier sphere j
    (periodic in x); the grid's cells are one largest diameter wide, so a try tests the 27
    cells around it and the cost stays O(N) for radii within a bounded ratio. Returns
    (positions (n, 3) m, final box height m).
    """
    radius = np.ascontiguousarray(radius, dtype=np.float64)
    n = radius.size
    r_max = float(radius.max()) if n else 0.0
    if width <= 2.0 * r_max:
        raise ValueError(f"trough width {width} m leaves no room for spheres of radius {r_max} m")
    pos = np.empty((n, 3))
    nxt = np.full(n, -1, dtype=np.int64)
    placed, fails = 0, 0
    u = np.empty(0)
    k = 0
    batch = 3 * max(1024, min(n, 1 << 20))
    grid = _Grid(length, width, height, 2.0 * r_max)
    while placed < n:
        if k >= u.size:
            u, k = rng.random(batch), 0
        placed, k, fails, stuck = _place_sized(
            u, k, pos, radius, placed, n, r_max, length, width, height, fails, DEM_FILL_TRIES,
            grid.head, nxt, grid.shape, grid.cell,
        )  # fmt: skip
        if stuck:
            height *= 1.25
            fails = 0
            grid = _Grid(length, width, height, 2.0 * r_max)
            nxt[:] = -1
            _insert_all(pos, placed, grid.head, nxt, grid.shape, grid.cell, width)
    return pos, height


@numba.njit(cache=True)
def _free_sized(cx, cy, cz, rc, pos, radius, length, width, head, nxt, shape, cell):
    """True if no sphere in the 27 cells around (cx, cy, cz) overlaps one of radius rc there."""
    ix, iy, iz = _cell_of(cx, cy, cz, shape, cell, width)
    nx = shape[0]
    wide = nx >= 3
    for a in range(3 if wide else nx):
        jx = (ix + a - 1) % nx if wide else a
        for jy in range(max(iy - 1, 0), min(iy + 2, shape[1])):
            for jz in range(max(iz - 1, 0), min(iz + 2, shape[2])):
                j = head[(jx * shape[1] + jy) * shape[2] + jz]
                while j >= 0:
                    dx = pos[j, 0] - cx
                    dx -= length * np.round(dx / length)
                    dy = pos[j, 1] - cy
                    dz = pos[j, 2] - cz
                    reach = rc + radius[j]
                    if dx * dx + dy * dy + dz * dz < reach * reach:
                        return False
                    j = nxt[j]
    return True


@numba.njit(cache=True)
def _place_sized(u, k, pos, radius, placed, n, r_max, length, width, height, fails, tries, head,
                 nxt, shape, cell):  # fmt: skip
    """:func:`_place_spheres` for spheres of radii ``radius``; returns (placed, k, fails, stuck)."""
    while placed < n:
        if k + 3 > u.size:
            return placed, u.size, fails, False
        r = radius[placed]
        y_lo = -0.5 * width + r
        y_range = (0.5 * width - r) - y_lo
        z_range = max(r, height - r) - r
        cx = 0.0 + length * u[k]
        cy = y_lo + y_range * u[k + 1]
        cz = r + z_range * u[k + 2]
        k += 3
        if _free_sized(cx, cy, cz, r, pos, radius, length, width, head, nxt, shape, cell):
            pos[placed, 0] = cx
            pos[placed, 1] = cy
            pos[placed, 2] = cz
            ix, iy, iz = _cell_of(cx, cy, cz, shape, cell, width)
            c = (ix * shape[1] + iy) * shape[2] + iz
            nxt[placed] = head[c]
            head[c] = placed
            placed += 1
            fails = 0
        else:
            fails += 1
            if fails == tries:
                return placed, k, fails, True
    return placed, k, fails, False


def fill_mesh(
    case, rng: np.random.Generator, start: float = 0.0, span: float | None = None
) -> tuple[np.ndarray, np.ndarray | None, float]:
    """The case's grains placed at random inside its mesh trough (returns as :func:`fill`).

    Grains are drawn by the box fill over the mesh's bounding box (x over the section, y across
    the mesh, z from its lowest point), more of them than asked by the share of the box that
    lies inside the trough; a grain is kept if its centre lies on the grains' side of the mesh
    (the closest triangle's normal points to it) and its bounding sphere clears the mesh. The
    first N kept, in the box fill's order, are the fill. The box grows until N fit. Cost
    O(N T) for T triangles (every triangle is within reach of the index for this test).
    Centres are drawn in ``start`` <= x < ``start + span`` (default the whole section).
    """
    from dem.scene.mesh import load_mesh

    pt, t = case.particles, case.trough
    sphere = not pt.clumps
    reach = pt.radius if sphere else pt.grain.bounding_radius
    mesh = load_mesh(t.mesh, length=t.length)
    lo, hi = mesh.tri.min(axis=(0, 1)), mesh.tri.max(axis=(0, 1))
    mesh.index(max(reach, float(np.max(hi[1:] - lo[1:]))))
    width = float(hi[1] - lo[1])
    span = t.length if span is None else span
    shift = np.array([start, 0.5 * (lo[1] + hi[1]), lo[2]])
    n = pt.count
    probe = rng.uniform(size=(4096, 3)) * [span, width, 2.0 * (hi[2] - lo[2])]
    share = max(float(np.mean(_inside(mesh, probe + shift - [0.0, 0.5 * width, 0.0], 0.0))), 0.05)
    for _ in range(8):
        extra = int(np.ceil(1.2 * n / share)) + 8
        if sphere:
            pos, height = random_fill(extra, pt.radius, span, width, rng)
            quats = None
        else:
            pos, quats, height = random_fill_clumps(extra, pt.grain, span, width, rng)
        pos = pos + shift
        keep = np.flatnonzero(_inside(mesh, pos, reach))
        if keep.size >= n:
            keep = keep[:n]
            pos = pos[keep]
            quats = None if quats is None else quats[keep]
            order = spatial_order(pos, 2.0 * reach, width)
            return pos[order], None if quats is None else quats[order], height + lo[2]
        share *= max(keep.size, 1) / (1.2 * n)
    raise InputError(
        "particles.count", n, f"fewer grains than fit inside the mesh trough {t.mesh} (the fill "
        "found no room for them: are the triangle normals pointing to the grains' side?)",
    )  # fmt: skip


def inside_mesh(mesh, points: np.ndarray, clearance: float) -> np.ndarray:
    """Points on the grains' side of the mesh and at least ``clearance`` from it, (n,) bool."""
    return _inside(mesh, points, clearance)


def _inside(mesh, points: np.ndarray, clearance: float) -> np.ndarray:
    """Points on the grains' side of the mesh and at least ``clearance`` from it, (n,) bool."""
    side = mesh.sides(points)
    gap = mesh.gaps(points)
    return (np.isnan(side) | (side > 0.0)) & (gap >= clearance)


def spatial_order(positions: np.ndarray, cell: float, width: float) -> np.ndarray:
    """Grain order by cells of edge ``cell``: x slowest, then y, then z (a permutation).

    Random placement numbers grains in random spatial order. Numbered along the trough instead,
    neighbours have nearby indices: the step reads nearby memory, and the threads, which split
    the grains into contiguous index ranges, each take a slab of the section (the bed moves as
    a whole, so the slabs persist) and seldom touch each other's grains. On two threads the
    sphere bed stepped 1.4 times faster for it (validation/performance/README.md). O(N log N).
    """
    if len(positions) == 0:
        return np.arange(0)
    cx = np.floor(positions[:, 0] / cell).astype(np.int64)
    cy = np.floor((positions[:, 1] + 0.5 * width) / cell).astype(np.int64)
    cz = np.floor((positions[:, 2] - positions[:, 2].min()) / cell).astype(np.int64)
    return np.lexsort((cz, cy, cx))


def random_fill(
    n: int,
    radius: float,
    length: float,
    width: float,
    rng: np.random.Generator,
    *,
    height: float | None = None,
) -> tuple[np.ndarray, float]:
    """Random sequential placement of n non-overlapping spheres in the trough.

    Centres are drawn uniformly in x in [0, length), y in [-width/2 + r, width/2 - r],
    z in [r, height - r] and kept if they overlap no earlier sphere (periodic in x). After
    ``DEM_FILL_TRIES`` failed tries for one sphere the box is made 25 % taller.

    Args:
        n: Number of spheres.
        radius: Sphere radius, m.
        length, width: Trough section, m.
        rng: Random generator (seeded by the caller).
        height: Initial box height, m; default ``DEM_FILL_HEIGHT_FACTOR`` times the height of a
            dense bed (packing fraction 0.6) plus a diameter.

    Returns:
        (positions (n, 3) in m, final box height in m).

    """
    if width <= 2.0 * radius:
        raise ValueError(f"trough width {width} m leaves no room for spheres of radius {radius} m")
    if height is None:
        height = sphere_box_height(n, radius, length, width)
    pos = np.empty((n, 3))
    nxt = np.full(n, -1, dtype=np.int64)
    placed, fails = 0, 0
    u = np.empty(0)
    k = 0
    batch = 3 * max(1024, min(n, 1 << 20))
    grid = _Grid(length, width, height, 2.0 * radius)
    while placed < n:
        if k >= u.size:
            u, k = rng.random(batch), 0
        placed, k, fails, stuck = _place_spheres(
            u, k, pos, placed, n, radius, length, width, height, fails, DEM_FILL_TRIES,
            grid.head, nxt, grid.shape, grid.cell,
        )  # fmt: skip
        if stuck:  # DEM_FILL_TRIES failures for one sphere: a taller box, a grid to match
            height *= 1.25
            fails = 0
            grid = _Grid(length, width, height, 2.0 * radius)
            nxt[:] = -1
            _insert_all(pos, placed, grid.head, nxt, grid.shape, grid.cell, width)
    return pos, height


class _Grid:
    """Cells at least ``size`` wide over the fill box, for the sphere fill.

    x in [0, length), y in [-width/2, width/2], z in [0, height] (a point above height goes in
    the top layer); ``head`` is the first grain of each cell (-1: none), linked through a
    per-grain ``next`` array.
    """

    def __init__(self, length: float, width: float, height: float, size: float):
        n = [max(1, int(extent / size)) for extent in (length, width, height)]
        self.shape = np.array(n, dtype=np.int64)
        self.cell = np.array([length / n[0], width / n[1], height / n[2]])
        self.head = np.full(n[0] * n[1] * n[2], -1, dtype=np.int64)


@numba.njit(cache=True)
def _cell_of(x, y, z, shape, cell, width):
    ix = min(max(int(x / cell[0]), 0), shape[0] - 1)
    iy = min(max(int((y + 0.5 * width) / cell[1]), 0), shape[1] - 1)
    iz = min(max(int(z / cell[2]), 0), shape[2] - 1)
    return ix, iy, iz


@numba.njit(cache=True)
def _insert_all(pos, placed, head, nxt, shape, cell, width):
    for i in range(placed):
        ix, iy, iz = _cell_of(pos[i, 0], pos[i, 1], pos[i, 2], shape, cell, width)
        c = (ix * shape[1] + iy) * shape[2] + iz
        nxt[i] = head[c]
        head[c] = i


@numba.njit(cache=True)
def _free(cx, cy, cz, pos, d2_min, length, width, head, nxt, shape, cell):
    """True if no sphere in the 27 cells around (cx, cy, cz) is closer than sqrt(d2_min)."""
    ix, iy, iz = _cell_of(cx, cy, cz, shape, cell, width)
    nx = shape[0]
    wide = nx >= 3  # else every x column, once (no double visits through the wrap)
    for a in range(3 if wide else nx):
        jx = (ix + a - 1) % nx if wide else a
        for jy in range(max(iy - 1, 0), min(iy + 2, shape[1])):
            for jz in range(max(iz - 1, 0), min(iz + 2, shape[2])):
                j = head[(jx * shape[1] + jy) * shape[2] + jz]
                while j >= 0:
                    dx = pos[j, 0] - cx
                    dx -= length * np.round(dx / length)
                    dy = pos[j, 1] - cy
                    dz = pos[j, 2] - cz
                    if dx * dx + dy * dy + dz * dz < d2_min:
                        return False
                    j = nxt[j]
    return True


@numba.njit(cache=True)
def _place_spheres(u, k, pos, placed, n, radius, length, width, height, fails, tries, head, nxt,
                   shape, cell):  # fmt: skip
    """Place spheres by tries from ``u[k:]``, three uniforms each.

    Runs until all n are placed, the draws run out, or ``tries`` tries in a row fail (stuck: the
    caller raises the box). Returns (placed, k, fails, stuck).
    """
    d2_min = (2.0 * radius) ** 2
    y_lo = -0.5 * width + radius
    y_range = (0.5 * width - radius) - y_lo
    z_range = max(radius, height - radius) - radius
    while placed < n:
        if k + 3 > u.size:
            return placed, u.size, fails, False
        cx = 0.0 + length * u[k]
        cy = y_lo + y_range * u[k + 1]
        cz = radius + z_range * u[k + 2]
        k += 3
        if _free(cx, cy, cz, pos, d2_min, length, width, head, nxt, shape, cell):
            pos[placed, 0] = cx
            pos[placed, 1] = cy
            pos[placed, 2] = cz
            ix, iy, iz = _cell_of(cx, cy, cz, shape, cell, width)
            c = (ix * shape[1] + iy) * shape[2] + iz
            nxt[placed] = head[c]
            head[c] = placed
            placed += 1
            fails = 0
        else:
            fails += 1
            if fails == tries:
                return placed, k, fails, True
    return placed, k, fails, False


def random_orientations(n: int, rng: np.random.Generator) -> np.ndarray:
    """Uniformly distributed unit quaternions (w, x, y, z) with w >= 0, (n, 4)."""
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    q[q[:, 0] < 0] *= -1.0
    return q


def random_fill_clumps(
    n: int,
    template,
    length: float,
    width: float,
    rng: np.random.Generator,
    *,
    height: float | None = None,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Random sequential placement of n clumps at random positions and orientations.

    Each try draws a centre of mass uniformly in x in [0, length), y across the trough and z in
    [r_min, height] and a uniform random orientation, and keeps it if every member sphere lies
    inside the walls (z >= r, |y| <= width/2 - r) and overlaps no member of an earlier clump
    (periodic in x). After ``DEM_FILL_TRIES`` failed tries the box is made 25 % taller.

    Args:
        n: Number of clumps.
        template: A :class:`dem.scene.shapes.Template`.
        length, width: Trough section, m.
        rng: Random generator (seeded by the caller).
        height: Initial box height, m; default ``DEM_FILL_HEIGHT_FACTOR`` times the height of a
            loose bed (packing fraction 0.3) plus the bounding diameter.

    Returns:
        (centres of mass (n, 3) in m, quaternions (n, 4), final box height in m).

    """
    centres = np.asarray(template.centres, dtype=np.float64)
    radii = np.asarray(template.radii, dtype=np.float64)
    r_min, r_max = float(radii.min()), float(radii.max())
    bound = template.bounding_radius
    if width <= 2.0 * r_max:
        raise ValueError(f"trough width {width} m leaves no room for spheres of radius {r_max} m")
    if height is None:
        height = clump_box_height(n, template, length, width)
    section = Trough(length, width)
    k = len(radii)
    pos = np.empty((n, 3))
    quat = np.empty((n, 4))
    members = np.empty((n * k, 3))
    member_r = np.tile(radii, n)
    y_max = 0.5 * width - r_min
    grid = _ClumpGrid(length, width, height, 2.0 * bound)
    placed = 0
    while placed < n:
        for _ in range(DEM_FILL_TRIES):
            c = np.array(
                [
                    rng.uniform(0.0, length),
                    rng.uniform(-y_max, y_max),
                    rng.uniform(r_min, max(r_min, height - r_min)),
                ]
            )
            q = random_orientations(1, rng)[0]
            xs = c + centres @ quat_to_matrix(q).T
            if np.any(xs[:, 2] < radii) or np.any(np.abs(xs[:, 1]) > 0.5 * width - radii):
                continue
            m = placed * k
            if placed:
                cand = grid.near(c)
                near = section.minimum_image(pos[cand] - c)
                close = cand[np.einsum("ij,ij->i", near, near) < (2.0 * bound) ** 2]
                if close.size:
                    idx = (np.sort(close)[:, None] * k + np.arange(k)).ravel()
                    d = section.minimum_image(members[idx][None, :, :] - xs[:, None, :])
                    dist2 = np.einsum("abi,abi->ab", d, d)
                    reach = radii[:, None] + member_r[idx][None, :]
                    if np.any(dist2 < reach**2):
                        continue
            pos[placed] = c
            quat[placed] = q
            members[m : m + k] = xs
            grid.add(placed, c)
            placed += 1
            break
        else:
            height *= 1.25
            grid = _ClumpGrid(length, width, height, 2.0 * bound, pos[:placed])
    return pos, quat, height


class _ClumpGrid:
    """Placed clumps by cell (cells at least one bounding diameter wide), for the fill."""

    def __init__(self, length: float, width: float, height: float, size: float, placed=()):
        self.width = width
        self.length = length
        self.n = [max(1, int(extent / size)) for extent in (length, width, height)]
        self.size = [length / self.n[0], width / self.n[1], height / self.n[2]]
        self.cells: dict[tuple[int, int, int], list[int]] = {}
        for i, c in enumerate(placed):
            self.add(i, c)

    def _index(self, c) -> tuple[int, int, int]:
        shifted = (c[0], c[1] + 0.5 * self.width, c[2])
        i, j, k = (
            min(max(int(v / h), 0), n - 1)
            for v, h, n in zip(shifted, self.size, self.n, strict=True)
        )
        return i, j, k

    def add(self, i: int, c) -> None:
        self.cells.setdefault(self._index(c), []).append(i)

    def near(self, c) -> np.ndarray:
        """Clumps in the 27 cells around c (each x column once when the grid wraps onto itself)."""
        ix, iy, iz = self._index(c)
        nx = self.n[0]
        xs = {(ix + a) % nx for a in (-1, 0, 1)}
        out: list[int] = []
        for jx in xs:
            for jy in range(max(iy - 1, 0), min(iy + 2, self.n[1])):
                for jz in range(max(iz - 1, 0), min(iz + 2, self.n[2])):
                    out.extend(self.cells.get((jx, jy, jz), ()))
        return np.array(out, dtype=np.int64)
