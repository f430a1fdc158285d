"""Neighbour search on the GPU: cells -> fixed pair slots per sphere, history carried by partner.

The CPU engine's build (:mod:`dem.kernels.neighbours`) with the same grid, the same cut-off and
the same pairs, but no global compaction: sphere a keeps its partners b > a in its own S slots,
``nbr[a S : a S + count[a]]``, sorted by b, so the slots in order are the CPU's key order a N + b.
A build is five kernels and two small reads back:

1. :func:`wrap_kernel`: x wrapped into [0, length); the lowest and highest centre (atomics),
   read back for the grid (:func:`dem.kernels.neighbours.grid_of`, the CPU's arithmetic);
2. :func:`bin_kernel`: each sphere into a cell of at most C spheres (an atomic count per cell;
   the order within a cell does not matter, the partners are sorted next);
3. :func:`scan_kernel`: sphere i's partners j > i within r_i + r_j + skin in the 27 cells
   around it, sorted by j (insertion sort, as the CPU), and each new pair's history copied from
   the same partner among i's old slots: the old partners are sorted too, so one merge pass of
   O(S) finds them (history keyed by the partner's index, which does not change: spheres are not
   reordered). Pairs not found start from zero. Positions at the build go to ``x_ref``;
4. :func:`reverse_kernel` and :func:`sort_reverse_kernel`: the reverse slots, the pairs each
   sphere is the upper end of, sorted by slot (an atomic count per sphere, then a sort).

Capacities are fixed per build (C spheres a cell, S slots and R reverse slots a sphere); a build
that overflows writes what it needs to ``status`` and the host regrows and builds again. The old
slots stay untouched until the new ones are complete, so the history survives a regrow.
"""

import math

import numpy as np
from numba import cuda

from dem.kernels.cuda.launch import THREADS_PER_BLOCK, blocks
from dem.kernels.neighbours import cell_coords
from dem.kernels.periodic import minimum_image, wrap

#: ``status`` entries: most partners of a sphere, most reverse partners, most spheres a cell.
NEED_SLOTS = 0
NEED_REVERSE = 1
NEED_CELL = 2


@cuda.jit(device=True)
def _sort(a, lo, hi):
    """Insertion sort of a[lo:hi] (a few dozen entries), as the CPU engine sorts its slots."""
    for k in range(lo + 1, hi):
        v = a[k]
        m = k - 1
        while m >= lo and a[m] > v:
            a[m + 1] = a[m]
            m -= 1
        a[m + 1] = v


@cuda.jit
def fill_int_kernel(a, value):
    """a[:] = value."""
    i = cuda.grid(1)
    if i < a.shape[0]:
        a[i] = value


@cuda.jit
def wrap_kernel(x, length, zrange):
    """Wrap x into [0, length); zrange[0] = min z, zrange[1] = max z (atomics)."""
    i = cuda.grid(1)
    if i >= x.shape[0]:
        return
    x[i, 0] = wrap(x[i, 0], length)
    cuda.atomic.min(zrange, 0, x[i, 2])
    cuda.atomic.max(zrange, 1, x[i, 2])


@cuda.jit(device=True)
def _put(count, items, key, cap, value, status, need):
    """Append ``value`` to bucket ``key`` of capacity ``cap`` (an atomic count).

    A full bucket records the capacity it needs in ``status[need]`` instead.
    """
    pos = cuda.atomic.add(count, key, 1)
    if pos < cap:
        items[key * cap + pos] = value
    else:
        cuda.atomic.max(status, need, pos + 1)


@cuda.jit
def bin_kernel(
    x, scene, ncx, ncy, ncz, sx, sy, sz, zmin, width, cell_count, cell_items, cap, status,
):  # fmt: skip
    """Sphere i into its cell's list ``cell_items[c cap : c cap + cap]``; overflow: ``status``.

    Each scene (``scene[i]``, :mod:`dem.engine.gpu.replicas`) has a grid of its own, the cells
    ncx ncy ncz scene[i] onwards: spheres of two scenes are never neighbours.
    """
    i = cuda.grid(1)
    if i >= x.shape[0]:
        return
    cx, cy, cz = cell_coords(x[i, 0], x[i, 1], x[i, 2], ncx, ncy, ncz, sx, sy, sz, zmin, width)
    c = ((scene[i] * ncz + cz) * ncy + cy) * ncx + cx
    _put(cell_count, cell_items, c, cap, i, status, NEED_CELL)


@cuda.jit
def scan_kernel(
    x, radius, body, scene, skin, length, width, ncx, ncy, ncz, sx, sy, sz, zmin, cell_count,
    cell_items, cap, nbr_old, count_old, hist_old, nbr, count, hist, x_ref, status,
):  # fmt: skip
    """Sphere i's partners j > i into its slots, sorted; their history from i's old slots.

    Only the cells of sphere i's own scene are searched (:func:`bin_kernel`).
    """
    i = cuda.grid(1)
    n = x.shape[0]
    if i >= n:
        return
    slots = nbr.shape[0] // n
    old_slots = nbr_old.shape[0] // n
    width_h = hist.shape[1]
    half = 0.5 * length
    dxs = 3 if ncx >= 3 else 1
    cx, cy, cz = cell_coords(x[i, 0], x[i, 1], x[i, 2], ncx, ncy, ncz, sx, sy, sz, zmin, width)
    found = 0
    base = i * slots
    xi = x[i, 0]
    yi = x[i, 1]
    zi = x[i, 2]
    ri = radius[i] + skin
    bi = body[i]
    first_z = scene[i] * ncz
    for oz in range(-1, 2):
        iz = cz + oz
        if iz < 0 or iz >= ncz:
            continue
        for oy in range(-1, 2):
            iy = cy + oy
            if iy < 0 or iy >= ncy:
                continue
            row = ((first_z + iz) * ncy + iy) * ncx
            for ox in range(dxs):
                ix = cx + ox - 1 if dxs == 3 else 0
                if ix < 0:
                    ix += ncx
                elif ix >= ncx:
                    ix -= ncx
                c = row + ix
                for m in range(min(cell_count[c], cap)):
                    j = cell_items[c * cap + m]
                    if j <= i or body[j] == bi:
                        continue
                    dx = minimum_image(xi - x[j, 0], length, half)
                    dy = yi - x[j, 1]
                    dz = zi - x[j, 2]
                    cut = ri + radius[j]
                    if dx * dx + dy * dy + dz * dz < cut * cut:
                        if found < slots:
                            nbr[base + found] = j
                        found += 1
    count[i] = found
    if found > slots:
        cuda.atomic.max(status, NEED_SLOTS, found)
        return
    _sort(nbr, base, base + found)  # by j: the slots in order are the CPU engine's keys i n + j
    # history by partner: one merge of the new and the old sorted partners
    m = 0
    old_base = i * old_slots
    old_n = count_old[i]
    for s in range(found):
        j = nbr[base + s]
        while m < old_n and nbr_old[old_base + m] < j:
            m += 1
        if m < old_n and nbr_old[old_base + m] == j:
            for c in range(width_h):
                hist[base + s, c] = hist_old[old_base + m, c]
        else:
            for c in range(width_h):
                hist[base + s, c] = 0.0
    x_ref[i, 0] = xi
    x_ref[i, 1] = yi
    x_ref[i, 2] = zi


@cuda.jit
def reverse_kernel(nbr, count, rev, rev_count, status):
    """Each pair slot k = a S + s into its upper end's reverse slots (unsorted)."""
    a = cuda.grid(1)
    n = count.shape[0]
    if a >= n:
        return
    slots = nbr.shape[0] // n
    rslots = rev.shape[0] // n
    for s in range(count[a]):
        k = a * slots + s
        b = nbr[k]
        _put(rev_count, rev, b, rslots, k, status, NEED_REVERSE)


@cuda.jit
def sort_reverse_kernel(rev, rev_count):
    """Sort each sphere's reverse slots (pair slots a S + s, hence by the lower end a)."""
    b = cuda.grid(1)
    n = rev_count.shape[0]
    if b >= n:
        return
    rslots = rev.shape[0] // n
    _sort(rev, b * rslots, b * rslots + min(rev_count[b], rslots))


def reverse_slots(d_nbr, d_count, rslots: int = 16):
    """The reverse slots of the device slots ``d_nbr``/``d_count``: (d_rev, d_rev_count).

    Regrows ``rslots`` until every sphere's reverse partners fit.
    """
    n = d_count.shape[0]
    while True:
        d_rev = cuda.device_array(n * rslots, dtype=np.int32)
        d_rev_count = cuda.device_array(n, dtype=np.int32)
        d_status = cuda.to_device(np.zeros(4, dtype=np.int64))
        fill_int_kernel[blocks(n), THREADS_PER_BLOCK](d_rev_count, 0)
        reverse_kernel[blocks(n), THREADS_PER_BLOCK](d_nbr, d_count, d_rev, d_rev_count, d_status)
        need = int(d_status.copy_to_host()[NEED_REVERSE])
        if need <= rslots:
            sort_reverse_kernel[blocks(n), THREADS_PER_BLOCK](d_rev, d_rev_count)
            return d_rev, d_rev_count
        rslots = int(need * 1.5) + 1


@cuda.jit
def deepest_kernel(x, radius, nbr, count, length, frac, partner):
    """Sphere i's deepest pair among its own slots: overlap over the smaller radius, partner.

    ``frac[i]`` = max over i's partners j of (r_i + r_j - |x_i - x_j|) / min(r_i, r_j) (negative
    where none touches; -inf without partners), ``partner[i]`` the first j reaching it: the
    instability check's deepest pair (:meth:`dem.engine.checks.InstabilityChecks.check`) without
    copying the pair list back.
    """
    i = cuda.grid(1)
    n = x.shape[0]
    if i >= n:
        return
    slots = nbr.shape[0] // n
    half = 0.5 * length
    best = -math.inf
    who = -1
    for s in range(count[i]):
        j = nbr[i * slots + s]
        dx = minimum_image(x[i, 0] - x[j, 0], length, half)
        dy = x[i, 1] - x[j, 1]
        dz = x[i, 2] - x[j, 2]
        f = (radius[i] + radius[j] - math.sqrt(dx * dx + dy * dy + dz * dz)) / min(
            radius[i], radius[j]
        )
        if f > best:
            best = f
            who = j
    frac[i] = best
    partner[i] = who
