"""Neighbour search: cell list -> Verlet pair list with a skin; contact history carried by key.

Geometry: periodic in x with period ``length`` (positions are wrapped into [0, length) at each
build, distances use the minimum image), bounded in y by the side walls at +-width/2 and in z by
the floor (the grid spans the spheres' current z range; nothing is periodic in y or z).

A build:

1. bins the spheres into cubic-ish cells of edge >= 2 r_max + skin (counting sort, serial, O(N));
2. finds, per sphere i, the neighbours j > i with |x_i - x_j| < r_i + r_j + skin in the 27
   surrounding cells and writes them, sorted by j, into i's own fixed block of slots (parallel
   over i, race-free: each i writes only its own block and count);
3. compacts the blocks at the prefix-sum offsets, so the pairs come out sorted by the key
   i N + j (computed, never stored); members of one rigid clump are never paired;
4. carries the tangential history over from the previous list by one merge of the sorted new
   and old keys (pairs not found start from zero);
5. builds the CSR index sphere -> its pair ends, serially: sphere s owns the slots
   ``part_start[s]`` to ``part_start[s + 1]`` in increasing pair index, and ``part_slot[2 k]``,
   ``part_slot[2 k + 1]`` are the slots of pair k's ends i and j (where the parallel pair loop
   writes what each end receives, :mod:`dem.kernels.forces`).

Capacities are fixed; a build that would overflow the pair, slot or cell arrays changes nothing
and reports the size it needs (status :data:`OVERFLOW_PAIRS` / :data:`OVERFLOW_SLOTS` /
:data:`OVERFLOW_CELLS`), and Python regrows and builds again.
"""

import numba

from dem.config import NUMBA_OPTIONS, NUMBA_PARALLEL_OPTIONS
from dem.kernels.periodic import minimum_image, wrap

OK = 0
OVERFLOW_PAIRS = 1
OVERFLOW_CELLS = 2
OVERFLOW_SLOTS = 3
#: Most cells along z; a taller grid gets taller cells (grains thrown far up are rare and few).
MAX_CELLS_Z = 4096


@numba.njit(**NUMBA_OPTIONS)
def _grid(x, n, cell, length, width):
    """Cell grid of the current positions: (ncx, ncy, ncz, sx, sy, sz, zmin)."""
    zmin = x[0, 2]
    zmax = x[0, 2]
    for i in range(1, n):
        zmin = min(zmin, x[i, 2])
        zmax = max(zmax, x[i, 2])
    return grid_of(zmin, zmax, cell, length, width)


@numba.njit(**NUMBA_OPTIONS)
def grid_of(zmin, zmax, cell, length, width):
    """Cell grid for centres between heights zmin and zmax: (ncx, ncy, ncz, sx, sy, sz, zmin).

    ncx < 3 collapses to one column in x (every neighbour then is found through the minimum image
    in that column, without visiting a column twice). The GPU build (:mod:`dem.kernels.cuda`)
    calls it with the extremes it reduced on the device, for the same grid.
    """
    ncx = int(length / cell)
    if ncx < 3:
        ncx = 1
    ncy = max(1, int(width / cell))
    ncz = max(1, int((zmax - zmin) / cell) + 1)
    sz = cell
    if ncz > MAX_CELLS_Z:
        ncz = MAX_CELLS_Z
        sz = (zmax - zmin) / (ncz - 1)
    return ncx, ncy, ncz, length / ncx, width / ncy, sz, zmin


@numba.njit(inline="always", **NUMBA_OPTIONS)
def cell_coords(px, py, pz, ncx, ncy, ncz, sx, sy, sz, zmin, width):
    """Cell (cx, cy, cz) of a centre at (px, py, pz); scalars, so a GPU kernel calls it too."""
    cx = min(max(int(px / sx), 0), ncx - 1)
    cy = min(max(int((py + 0.5 * width) / sy), 0), ncy - 1)
    cz = min(max(int((pz - zmin) / sz), 0), ncz - 1)
    return cx, cy, cz


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def _scan_neighbours(
    x, radius, body, n, skin, length, width, grid, cell_start, cell_particles, out_count,
    out_slots,
):  # fmt: skip
    """Neighbours j > i of each i into its slots ``out_slots[i s : i s + s]``, sorted by j.

    Spheres of the same rigid body (``body[i] == body[j]``) are never neighbours.

    s = len(out_slots) // n slots per sphere; ``out_count[i]`` is the true number of neighbours
    (more than s means the slots overflowed and only the first s found were kept).
    """
    ncx, ncy, ncz, sx, sy, sz, zmin = grid
    slots = out_slots.shape[0] // n
    half = 0.5 * length
    dxs = 3 if ncx >= 3 else 1
    for i in numba.prange(n):
        cx, cy, cz = cell_coords(x[i, 0], x[i, 1], x[i, 2], ncx, ncy, ncz, sx, sy, sz, zmin, width)
        found = 0
        base = i * slots
        xi = x[i, 0]
        yi = x[i, 1]
        zi = x[i, 2]
        ri = radius[i] + skin
        bi = body[i]
        for oz in range(-1, 2):
            iz = cz + oz
            if iz < 0 or iz >= ncz:
                continue
            for oy in range(-1, 2):
                iy = cy + oy
                if iy < 0 or iy >= ncy:
                    continue
                row = (iz * ncy + iy) * ncx
                for ox in range(dxs):
                    ix = cx + ox - 1 if dxs == 3 else 0
                    if ix < 0:
                        ix += ncx
                    elif ix >= ncx:
                        ix -= ncx
                    c = row + ix
                    for m in range(cell_start[c], cell_start[c + 1]):
                        j = cell_particles[m]
                        if j <= i or body[j] == bi:
                            continue
                        dx = minimum_image(xi - x[j, 0], length, half)
                        dy = yi - x[j, 1]
                        dz = zi - x[j, 2]
                        cut = ri + radius[j]
                        if dx * dx + dy * dy + dz * dz < cut * cut:
                            if found < slots:
                                out_slots[base + found] = j
                            found += 1
        out_count[i] = found
        # insertion sort of the slots by j: keys i n + j become globally sorted
        for a in range(base + 1, base + min(found, slots)):
            v = out_slots[a]
            b = a - 1
            while b >= base and out_slots[b] > v:
                out_slots[b + 1] = out_slots[b]
                b -= 1
            out_slots[b + 1] = v


@numba.njit(**NUMBA_OPTIONS)
def _carry_history(n, counts, offsets, scratch_j, slots, pair_i, pair_j, hist, n_old, out_hist):
    """Each new pair's history from the old pair with the same key i n + j, else 0.

    The new pairs (sphere i's ``counts[i]`` partners in ``scratch_j``, sorted) and the old list
    are both in key order, so one merge pass finds all matches: O(n_new + n_old). Keys are
    computed, not stored.
    """
    m = 0
    for i in range(n):
        for s in range(counts[i]):
            k = offsets[i] + s
            key = i * n + scratch_j[i * slots + s]
            while m < n_old and pair_i[m] * n + pair_j[m] < key:
                m += 1
            if m < n_old and pair_i[m] * n + pair_j[m] == key:
                for c in range(hist.shape[1]):
                    out_hist[k, c] = hist[m, c]
            else:
                for c in range(hist.shape[1]):
                    out_hist[k, c] = 0.0


@numba.njit(**NUMBA_OPTIONS)
def rebuild(
    x, radius, body, n, skin, length, width, x_ref, pair_i, pair_j, hist, n_pairs_old,
    scratch_j, scratch_hist, counts, offsets, cell_of, cell_start, cell_particles,
    part_start, part_slot,
):  # fmt: skip
    """Build the Verlet pair list of the current positions, keeping the contact history.

    Args:
        x: Positions, shape (n, 3), m; x is wrapped into [0, length) in place.
        radius: Radii, shape (n,), m.
        body: Rigid body of each sphere, int64 (n,); members of one body are never paired.
        n: Number of spheres.
        skin: Verlet skin, m.
        length, width: Periodic length and wall distance, m.
        x_ref: Out: positions at this build, shape (n, 3).
        pair_i, pair_j: In/out pair list (i < j, sorted by the key i n + j), shape (cap,).
        hist: In/out contact history per pair, shape (cap, width) (the law's history width).
        n_pairs_old: Number of valid pairs on entry.
        scratch_j: Neighbour slots, shape (n slots,), int64.
        scratch_hist: Work array of the pair capacity, shape (cap, width).
        counts, offsets: Work arrays, shapes (n,) and (n + 1,).
        cell_of, cell_particles: Work arrays, shape (n,); cell_start: shape (cell_cap + 1,).
        part_start, part_slot: Out CSR index, shapes (n + 1,) and (2 cap,) (module docstring).

    Returns:
        (status, n_pairs, needed): status OK or an OVERFLOW_* code; on overflow the list is
        unchanged, n_pairs is the old count and ``needed`` the capacity (pairs, slots per sphere
        or cells) required.

    """
    for i in range(n):
        x[i, 0] = wrap(x[i, 0], length)
    r_max = 0.0
    for i in range(n):
        r_max = max(r_max, radius[i])
    grid = _grid(x, n, 2.0 * r_max + skin, length, width)
    ncx, ncy, ncz = grid[0], grid[1], grid[2]
    n_cells = ncx * ncy * ncz
    if n_cells + 1 > cell_start.shape[0]:
        return OVERFLOW_CELLS, n_pairs_old, n_cells + 1
    # counting sort into cells
    cell_start[: n_cells + 1] = 0
    for i in range(n):
        cx, cy, cz = cell_coords(
            x[i, 0], x[i, 1], x[i, 2], ncx, ncy, ncz, grid[3], grid[4], grid[5], grid[6], width
        )
        c = (cz * ncy + cy) * ncx + cx
        cell_of[i] = c
        cell_start[c + 1] += 1
    for c in range(n_cells):
        cell_start[c + 1] += cell_start[c]
    fill_pos = cell_start[:n_cells].copy()
    for i in range(n):
        c = cell_of[i]
        cell_particles[fill_pos[c]] = i
        fill_pos[c] += 1
    # neighbours into per-sphere slots, then check capacities
    _scan_neighbours(
        x, radius, body, n, skin, length, width, grid, cell_start, cell_particles, counts,
        scratch_j,
    )  # fmt: skip
    slots = scratch_j.shape[0] // n
    offsets[0] = 0
    most = 0
    for i in range(n):
        offsets[i + 1] = offsets[i] + counts[i]
        most = max(most, counts[i])
    if most > slots:
        return OVERFLOW_SLOTS, n_pairs_old, most
    n_new = offsets[n]
    if n_new > pair_j.shape[0]:
        return OVERFLOW_PAIRS, n_pairs_old, n_new
    _carry_history(
        n, counts, offsets, scratch_j, slots, pair_i, pair_j, hist, n_pairs_old, scratch_hist
    )
    for i in range(n):
        for m in range(counts[i]):
            k = offsets[i] + m
            pair_i[k] = i
            pair_j[k] = scratch_j[i * slots + m]
    for k in range(n_new):
        for c in range(hist.shape[1]):
            hist[k, c] = scratch_hist[k, c]
    # CSR: sphere -> its pair ends; slot of end i (2 k) and end j (2 k + 1)
    counts[:n] = 0
    for k in range(n_new):
        counts[pair_i[k]] += 1
        counts[pair_j[k]] += 1
    part_start[0] = 0
    for i in range(n):
        part_start[i + 1] = part_start[i] + counts[i]
        counts[i] = part_start[i]
    for k in range(n_new):
        a = pair_i[k]
        part_slot[2 * k] = counts[a]
        counts[a] += 1
        b = pair_j[k]
        part_slot[2 * k + 1] = counts[b]
        counts[b] += 1
    for i in range(n):
        x_ref[i, 0] = x[i, 0]
        x_ref[i, 1] = x[i, 1]
        x_ref[i, 2] = x[i, 2]
    return OK, n_new, n_new


@numba.njit(**NUMBA_OPTIONS)
def max_displacement_sq(x, x_ref, n, length):
    """Largest squared displacement since the last build (minimum image in x), m^2."""
    half = 0.5 * length
    best = 0.0
    for i in range(n):
        dx = minimum_image(x[i, 0] - x_ref[i, 0], length, half)
        dy = x[i, 1] - x_ref[i, 1]
        dz = x[i, 2] - x_ref[i, 2]
        d2 = dx * dx + dy * dy + dz * dz
        if d2 > best:
            best = d2
    return best
