"""The compact step on the GPU: a block gathers its touching contacts before the contact law.

An experiment beside the main path (:mod:`dem.kernels.cuda.step`), opt-in
(:attr:`dem.engine.gpu.engine.GpuEngine.compact`) until a GPU has timed it: the warp model
(validation/performance/warp_model.py) counts 3.4 law runs a warp's worth of spheres with 31 of
32 threads useful, against the plain step's 15.9 with 6.5, but a count is not a timing.

Sphere i's candidates are numbered as :func:`dem.kernels.cuda.forces.sphere_force` visits them:
its reverse slots, its own slots, then the N_WALLS walls (:func:`candidate_force`). The sums are
the plain step's floats, the CPU engine's bits in numba's CUDA simulator
(tests/engine/test_gpu_engine.py).
"""

import math

from numba import cuda, float64, int32

from dem.kernels.contact import contact_core, pair_arms, wall_arms
from dem.kernels.cuda.forces import separation, wall_gap
from dem.kernels.cuda.launch import COMPACT_BLOCK, COMPACT_KEEP
from dem.kernels.cuda.step import finish
from dem.kernels.forces import N_WALLS


@cuda.jit(device=True)
def _candidate(i, e, n_rev, n_pairs, x, radius, nbr, rev, length, half_width, back):
    """Sphere i's candidate e located and measured (:func:`candidate_force`'s numbering).

    Returns:
        (kind, a, b, row, touching, dx, dy, dz, d2, rsum): kind 0 a reverse slot (pair (a, i),
        i = b), 1 an own slot (pair (i, b)), 2 a wall (dx, dy, dz its normal, d2 the overlap
        delta); ``row`` the history row: the pair slot, or the wall row N_WALLS i + w.

    """
    n = x.shape[0]
    slots = nbr.shape[0] // n
    if e >= n_pairs:
        w = e - n_pairs
        delta, nx, ny, nz = wall_gap(i, w, x, radius, half_width, back)
        return 2, i, i, N_WALLS * i + w, delta > 0.0, nx, ny, nz, delta, 0.0
    if e < n_rev:
        kind = 0
        k = rev[i * (rev.shape[0] // n) + e]
        a = k // slots
        b = i
    else:
        kind = 1
        k = i * slots + (e - n_rev)
        a = i
        b = nbr[k]
    dx, dy, dz, d2, rsum = separation(a, b, x, radius, length)
    return kind, a, b, k, d2 < rsum * rsum, dx, dy, dz, d2, rsum


@cuda.jit(device=True)
def candidate_touches(
    i, e, n_rev, n_pairs, x, radius, nbr, rev, hist_out, wall_out, length, half_width, back,
):  # fmt: skip
    """Whether sphere i's candidate e touches, by the test of :func:`candidate_force`.

    Where it does not, the history row i owns (own slot, wall) is written with zeros, as
    :func:`candidate_force` writes it.
    """
    kind, _, _, row, touching, _, _, _, _, _ = _candidate(
        i, e, n_rev, n_pairs, x, radius, nbr, rev, length, half_width, back
    )
    if not touching:
        _clear(kind, row, hist_out, wall_out)
    return touching


@cuda.jit(device=True)
def _clear(kind, row, hist_out, wall_out):
    """Zeros in the history row of a candidate that does not touch (none for a reverse slot)."""
    if kind == 1:
        for c in range(hist_out.shape[1]):
            hist_out[row, c] = 0.0
    elif kind == 2:
        for c in range(wall_out.shape[1]):
            wall_out[row, c] = 0.0


@cuda.jit(device=True)
def _history(hist, row):
    """Row ``row`` of a history array as five floats, the last two zero where it has three."""
    h3 = 0.0
    h4 = 0.0
    if hist.shape[1] > 3:
        h3 = hist[row, 3]
        h4 = hist[row, 4]
    return hist[row, 0], hist[row, 1], hist[row, 2], h3, h4


@cuda.jit(device=True)
def candidate_force(
    i, e, n_rev, n_pairs, model, p, pw, x, v, omega, radius, mass, nbr, rev, hist_in, hist_out,
    wall_in, wall_out, length, half_width, back, dt,
):  # fmt: skip
    """Sphere i's candidate e, in the plain step's order, and what it adds to i's sums.

    e < ``n_rev``: the reverse slots; up to ``n_pairs``: the own slots; then the N_WALLS walls.
    Writes the history row i owns (own pairs, walls), as
    :func:`dem.kernels.cuda.forces.sphere_force` does. The three kinds meet the contact law at
    one call site: the threads of a warp that hold candidates of different kinds run it together
    (the plain step's loops call it once per kind). The law's inputs are the plain step's.

    Returns:
        (touching, dfx, dfy, dfz, dtx, dty, dtz): whether it touches, and its terms added to
        zeros (the same floats as the terms, but for the sign of a zero).

    """
    kind, a, b, row, touching, dx, dy, dz, d2, rsum = _candidate(
        i, e, n_rev, n_pairs, x, radius, nbr, rev, length, half_width, back
    )
    if not touching:
        _clear(kind, row, hist_out, wall_out)
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if kind == 2:
        q = pw
        nx, ny, nz, delta = dx, dy, dz, d2
        ri = radius[i]
        ci, ai = wall_arms(pw, ri, delta)
        cj = 0.0
        aj = 0.0
        vx, vy, vz = v[i, 0], v[i, 1], v[i, 2]
        wjx, wjy, wjz = 0.0, 0.0, 0.0
        m_eff = mass[i]
        r_eff = ri
        h0, h1, h2, h3, h4 = _history(wall_in, row)
    else:
        q = p
        d = math.sqrt(d2)
        ra = radius[a]
        rb = radius[b]
        delta = rsum - d
        inv_d = 1.0 / d
        nx, ny, nz = dx * inv_d, dy * inv_d, dz * inv_d
        ma = mass[a]
        mb = mass[b]
        ci, cj, ai, aj = pair_arms(p, ra, rb, delta)
        vx, vy, vz = v[a, 0] - v[b, 0], v[a, 1] - v[b, 1], v[a, 2] - v[b, 2]
        wjx, wjy, wjz = omega[b, 0], omega[b, 1], omega[b, 2]
        m_eff = ma * mb / (ma + mb)
        r_eff = ra * rb / rsum
        h0, h1, h2, h3, h4 = _history(hist_in, row)
    f = contact_core(
        model, q, nx, ny, nz, delta, vx, vy, vz, omega[a, 0], omega[a, 1], omega[a, 2], wjx, wjy,
        wjz, ci, cj, ai, aj, m_eff, r_eff, h0, h1, h2, h3, h4, dt,
    )  # fmt: skip
    if kind == 0:
        return True, 0.0 - f[0], 0.0 - f[1], 0.0 - f[2], 0.0 + f[6], 0.0 + f[7], 0.0 + f[8]
    if kind == 1:
        for c in range(hist_out.shape[1]):
            hist_out[row, c] = f[10 + c]
    else:
        for c in range(wall_out.shape[1]):
            wall_out[row, c] = f[10 + c]
    return True, 0.0 + f[0], 0.0 + f[1], 0.0 + f[2], 0.0 + f[3], 0.0 + f[4], 0.0 + f[5]


@cuda.jit(device=True)
def _put(share, t, c):
    """Row t of a block's shared terms: the terms of candidate ``c``, and 1 in column 6.

    ``c`` is :func:`candidate_force`'s result; where it does not touch
    the row is left as it is (its flag, column 6, is set to 0 before).
    """
    if c[0]:
        share[t, 0] = c[1]
        share[t, 1] = c[2]
        share[t, 2] = c[3]
        share[t, 3] = c[4]
        share[t, 4] = c[5]
        share[t, 5] = c[6]
        share[t, 6] = 1.0


@cuda.jit(device=True)
def _add_terms(share, first, last, fx, fy, fz, tx, ty, tz):
    """The sums plus the shared terms of rows ``first`` to ``last - 1`` that touch, in order."""
    for j in range(first, last):
        if share[j, 6] != 0.0:
            fx += share[j, 0]
            fy += share[j, 1]
            fz += share[j, 2]
            tx += share[j, 3]
            ty += share[j, 4]
            tz += share[j, 5]
    return fx, fy, fz, tx, ty, tz


@cuda.jit
def compact_step_kernel(
    keep, seq, trip, model, p, pw, x, v, omega, x2, v2, omega2, radius, mass, inv_mass,
    inv_inertia, nbr, count, rev, rev_count, hist_in, hist_out, wall_in, wall_out, length,
    half_width, back, dt, acc, row, scene, rotation, kick, next_drift, x_ref, limit, force, torque,
    px,
):  # fmt: skip
    """The plain step with each block's touching contacts gathered before the contact law.

    One thread a sphere, in blocks of :data:`COMPACT_BLOCK`. In the plain step a warp meets
    the law at each candidate slot of its spheres, whether few or many of them touch (Nsight
    Compute on the bed: 9 of 32 threads active). Here a pass has every thread test its
    sphere's candidates (:func:`candidate_touches`) and list the first
    ``keep`` (at most :data:`COMPACT_KEEP`) that touch in the block's shared memory; a prefix
    sum numbers the block's listed contacts, and in rounds of one contact a thread the block
    evaluates them (:func:`candidate_force`, one call site of the law
    for every kind), each thread's terms going to shared memory, from which after a barrier each
    sphere's thread adds its own in candidate order. A sphere with more than ``keep`` touching
    candidates lists the rest in the next pass. Only the candidates that do not touch are
    skipped, and they add nothing in the plain step either: the sums are the same floats,
    the CPU engine's bits in numba's CUDA simulator.
    """
    codes = cuda.shared.array((COMPACT_KEEP, COMPACT_BLOCK), int32)  # a thread a column
    ends = cuda.shared.array(COMPACT_BLOCK, int32)
    share = cuda.shared.array((COMPACT_BLOCK, 7), float64)
    more = cuda.shared.array(1, int32)
    if trip[0] < seq:  # the same for every thread of the launch
        return
    t = cuda.threadIdx.x
    i = cuda.grid(1)
    base = i - t
    n = x.shape[0]
    n_rev = 0
    n_pairs = 0
    total = 0
    fx = 0.0
    fy = 0.0
    fz = 0.0
    tx = 0.0
    ty = 0.0
    tz = 0.0
    if i < n:
        n_rev = rev_count[i]
        n_pairs = n_rev + count[i]
        total = n_pairs + N_WALLS
        m = mass[i]
        fx = m * acc[row, scene[i], 0]
        fy = m * acc[row, scene[i], 1]
        fz = m * acc[row, scene[i], 2]
    e = 0  # the sphere's next candidate to test
    while True:
        listed = 0
        while e < total and listed < keep:
            if candidate_touches(
                i, e, n_rev, n_pairs, x, radius, nbr, rev, hist_out, wall_out, length,
                half_width, back,
            ):  # fmt: skip
                codes[listed, t] = e
                listed += 1
            e += 1
        if t == 0:
            more[0] = 0
        ends[t] = listed
        cuda.syncthreads()
        if e < total:
            more[0] = 1
        d = 1  # inclusive prefix sum of the listed counts
        while d < COMPACT_BLOCK:
            add = 0
            if t >= d:
                add = ends[t - d]
            cuda.syncthreads()
            ends[t] += add
            cuda.syncthreads()
            d *= 2
        items = ends[COMPACT_BLOCK - 1]
        mine = ends[t] - listed  # this sphere's first contact's number
        for start in range(0, items, COMPACT_BLOCK):
            q = start + t
            share[t, 6] = 0.0
            if q < items:
                lo = 0  # the sphere of contact q: the first thread whose end is past q
                hi = COMPACT_BLOCK - 1
                while lo < hi:
                    mid = (lo + hi) // 2
                    if ends[mid] > q:
                        hi = mid
                    else:
                        lo = mid + 1
                k = q
                if lo > 0:
                    k = q - ends[lo - 1]
                o = base + lo
                o_rev = rev_count[o]
                _put(share, t, candidate_force(
                    o, codes[k, lo], o_rev, o_rev + count[o], model, p, pw, x, v, omega, radius,
                    mass, nbr, rev, hist_in, hist_out, wall_in, wall_out, length, half_width,
                    back, dt,
                ))  # fmt: skip
            cuda.syncthreads()
            fx, fy, fz, tx, ty, tz = _add_terms(
                share, max(mine, start) - start, min(mine + listed, start + COMPACT_BLOCK) - start,
                fx, fy, fz, tx, ty, tz,
            )  # fmt: skip
            cuda.syncthreads()
        again = more[0]
        cuda.syncthreads()  # every thread has read ``more`` before thread 0 clears it
        if again == 0:
            break
    if i >= n:
        return
    finish(
        i, (fx, fy, fz, tx, ty, tz), seq, trip, x, v, omega, x2, v2, omega2, mass, inv_mass,
        inv_inertia, length, dt, rotation, kick, next_drift, x_ref, limit, force, torque, px,
    )  # fmt: skip
