"""One velocity-Verlet step on the GPU: one launch, one thread per sphere.

The CPU engine's step (:func:`dem.kernels.integrate.advance`) with its operations in its order,
so that in numba's CUDA simulator the trajectories are the CPU engine's to the bit:

- :func:`kick_drift_kernel`, the first half kick and drift of a call, in place;
- :func:`step_kernel`, the rest of step n and the start of step n + 1 fused, as the CPU fuses
  them: thread i evaluates sphere i's force at x_{n+1}, v_{n+1/2} (reading every sphere's
  state in the buffers ``x, v, omega``), kicks v_{n+1}, adds m_i v_x,i to its running sum for the
  measurement, kicks again and drifts to x_{n+2} (``next_drift``), writing the other buffers
  ``x2, v2, omega2``: nothing a thread writes is read by another within the launch. The host
  swaps the buffers after each launch.

Both flag a rebuild when sphere i has moved more than skin/2 since the last build, the CPU
engine's criterion (any sphere past it rebuilds them all), by writing their launch's number
``seq`` into ``trip[0]`` (:data:`NO_TRIP`: none yet). A launch whose ``seq`` is above
``trip[0]`` does nothing: the host queues several steps without waiting for each one's flag,
and the steps queued after the one that flagged are no-ops, relaunched after the rebuild
(:meth:`dem.engine.gpu.GpuEngine.steps`). The kick-drift launch is ``seq`` 0, step k of a call
``seq`` k + 1.
"""

from numba import cuda, float64, int32

from dem.kernels.cuda.forces import (
    candidate_force,
    candidate_touches,
    mesh_sphere_force,
    sphere_force,
)
from dem.kernels.forces import N_WALLS
from dem.kernels.periodic import minimum_image

#: ``trip[0]`` when no sphere has moved past skin/2 (above every launch's ``seq``).
NO_TRIP = 1 << 62

#: Threads per block of :func:`lanes_step_kernel` (its shared array's rows); a multiple of every
#: lane count, so that a sphere's lanes share a block.
LANE_BLOCK = 128

#: Lane counts :func:`lanes_step_kernel` takes (divisors of :data:`LANE_BLOCK`).
LANE_COUNTS = (1, 2, 4, 8, 16, 32)

#: Threads per block of :func:`compact_step_kernel` (its shared arrays' rows).
COMPACT_BLOCK = 128

#: Touching candidates a sphere lists in one pass of :func:`compact_step_kernel` (its shared
#: list's rows, a column a thread: a warp's writes fall in different banks); a sphere with more
#: takes further passes.
COMPACT_KEEP = 16


@cuda.jit(device=True)
def moved_past(x, x_ref, i, length, limit):
    """Whether sphere i moved more than sqrt(limit) since the last build (minimum image)."""
    dx = minimum_image(x[i, 0] - x_ref[i, 0], length, 0.5 * length)
    dy = x[i, 1] - x_ref[i, 1]
    dz = x[i, 2] - x_ref[i, 2]
    return dx * dx + dy * dy + dz * dz > limit


@cuda.jit
def kick_drift_kernel(
    seq, trip, dt, x, v, omega, force, torque, inv_mass, inv_inertia, rotation, x_ref, length,
    limit,
):  # fmt: skip
    """Half kick of v (and omega if ``rotation``) with the stored force, then drift x; trip."""
    i = cuda.grid(1)
    if i >= x.shape[0] or trip[0] < seq:
        return
    h = 0.5 * dt
    a = h * inv_mass[i]
    for c in range(3):
        v[i, c] += a * force[i, c]
        x[i, c] += dt * v[i, c]
    if rotation:
        b = h * inv_inertia[i]
        for c in range(3):
            omega[i, c] += b * torque[i, c]
    if moved_past(x, x_ref, i, length, limit):
        trip[0] = seq


@cuda.jit(device=True)
def _finish(
    i, f, seq, trip, x, v, omega, x2, v2, omega2, mass, inv_mass, inv_inertia, length, dt,
    rotation, kick, next_drift, x_ref, limit, force, torque, px,
):  # fmt: skip
    """Sphere i's force and torque ``f`` stored, then its kicks and drift (:func:`step_kernel`)."""
    for c in range(3):
        force[i, c] = f[c]
        torque[i, c] = f[3 + c]
    if not kick:
        return
    h = 0.5 * dt
    a = h * inv_mass[i]
    vx = v[i, 0] + a * f[0]
    vy = v[i, 1] + a * f[1]
    vz = v[i, 2] + a * f[2]
    wx = omega[i, 0]
    wy = omega[i, 1]
    wz = omega[i, 2]
    b = h * inv_inertia[i]
    if rotation:
        wx += b * f[3]
        wy += b * f[4]
        wz += b * f[5]
    px[i] += mass[i] * vx
    if next_drift:
        vx += a * f[0]
        vy += a * f[1]
        vz += a * f[2]
        x2[i, 0] = x[i, 0] + dt * vx
        x2[i, 1] = x[i, 1] + dt * vy
        x2[i, 2] = x[i, 2] + dt * vz
        if rotation:
            wx += b * f[3]
            wy += b * f[4]
            wz += b * f[5]
    else:
        x2[i, 0] = x[i, 0]
        x2[i, 1] = x[i, 1]
        x2[i, 2] = x[i, 2]
    v2[i, 0] = vx
    v2[i, 1] = vy
    v2[i, 2] = vz
    omega2[i, 0] = wx
    omega2[i, 1] = wy
    omega2[i, 2] = wz
    if next_drift and moved_past(x2, x_ref, i, length, limit):
        trip[0] = seq


@cuda.jit(device=True)
def _put(share, t, c):
    """Row t of a block's shared terms: the terms of candidate ``c``, and 1 in column 6.

    ``c`` is :func:`dem.kernels.cuda.forces.candidate_force`'s result; where it does not touch
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
def step_kernel(
    seq, trip, model, p, pw, x, v, omega, x2, v2, omega2, radius, mass, inv_mass, inv_inertia,
    nbr, count, rev, rev_count, hist_in, hist_out, wall_in, wall_out, length, half_width, back,
    dt, acc, row, scene, rotation, kick, next_drift, x_ref, limit, force, torque, px,
):  # fmt: skip
    """Thread i: the force on sphere i, then its kicks and drift into the other buffers.

    With ``kick`` the second half kick goes into ``v2``, ``omega2`` (and ``px[i] += m_i v_x,i``),
    with ``next_drift`` the next step's half kick and drift into ``x2``, ``v2``, ``omega2`` and
    the rebuild trip. The body acceleration a_body of sphere i is ``acc[row, scene[i]]``: one row
    of the launch's step, one column a scene (replicas of other drives, one for a single scene).
    Without ``kick`` only the force, torque and history are written (an
    evaluation at rest, :meth:`dem.engine.simulation.Simulation.compute_forces`).
    """
    i = cuda.grid(1)
    if i >= x.shape[0] or trip[0] < seq:
        return
    f = sphere_force(
        i, model, p, pw, x, v, omega, radius, mass, nbr, count, rev, rev_count, hist_in,
        hist_out, wall_in, wall_out, length, half_width, back, dt, acc[row, scene[i], 0],
        acc[row, scene[i], 1], acc[row, scene[i], 2],
    )  # fmt: skip
    _finish(
        i, f, seq, trip, x, v, omega, x2, v2, omega2, mass, inv_mass, inv_inertia, length, dt,
        rotation, kick, next_drift, x_ref, limit, force, torque, px,
    )  # fmt: skip


@cuda.jit
def mesh_step_kernel(
    seq, trip, model, p, pw, x, v, omega, x2, v2, omega2, radius, mass, inv_mass, inv_inertia,
    nbr, count, rev, rev_count, hist_in, hist_out, wall_in, wall_out, length, half_width, back,
    dt, acc, row, scene, rotation, kick, next_drift, x_ref, limit, force, torque, px, tri, grid,
    dims, cell_start, cell_tris, slot_hist, slot_normal,
):  # fmt: skip
    """:func:`step_kernel` in a trough mesh (:func:`dem.kernels.cuda.forces.mesh_sphere_force`).

    The mesh's triangles and cell index (``tri`` to ``cell_tris``, :class:`dem.kernels.layout.
    MeshArrays`) and the spheres' mesh contact slots (``slot_hist``, ``slot_normal``, rows
    MESH_SLOTS i + s, updated in place by thread i) follow the step kernel's arguments.
    """
    i = cuda.grid(1)
    if i >= x.shape[0] or trip[0] < seq:
        return
    f = mesh_sphere_force(
        i, model, p, pw, x, v, omega, radius, mass, nbr, count, rev, rev_count, hist_in,
        hist_out, wall_in, wall_out, length, half_width, back, dt, acc[row, scene[i], 0],
        acc[row, scene[i], 1], acc[row, scene[i], 2], tri, grid, dims, cell_start, cell_tris,
        slot_hist, slot_normal,
    )  # fmt: skip
    _finish(
        i, f, seq, trip, x, v, omega, x2, v2, omega2, mass, inv_mass, inv_inertia, length, dt,
        rotation, kick, next_drift, x_ref, limit, force, torque, px,
    )  # fmt: skip


@cuda.jit
def lanes_step_kernel(
    lanes, seq, trip, model, p, pw, x, v, omega, x2, v2, omega2, radius, mass, inv_mass,
    inv_inertia, nbr, count, rev, rev_count, hist_in, hist_out, wall_in, wall_out, length,
    half_width, back, dt, acc, row, scene, rotation, kick, next_drift, x_ref, limit, force, torque,
    px,
):  # fmt: skip
    """:func:`step_kernel` with ``lanes`` threads a sphere, in blocks of :data:`LANE_BLOCK`.

    Launch n lanes threads. Sphere i's candidates (reverse pairs, own pairs, walls:
    :func:`candidate_force`) are dealt round by round, candidate r lanes + l to lane l in round r;
    each lane puts its terms in the block's shared memory and, after a barrier, the sphere's first
    lane adds them in candidate order, the order of :func:`step_kernel`'s loops, so the sum is the
    same float. The first lane then kicks and drifts as :func:`step_kernel`. Each thread's chain of
    dependent reads is a lane count shorter, and the threads that meet the contact law in a round
    are the candidates that touch, not the slots of spheres that happen to share a warp. The block's
    rounds are its most loaded sphere's (a barrier needs every thread of the block).
    """
    share = cuda.shared.array((LANE_BLOCK, 7), float64)
    most = cuda.shared.array(1, int32)
    t = cuda.threadIdx.x
    if trip[0] < seq:  # the same for every thread of the launch
        return
    g = cuda.grid(1)
    i = g // lanes
    lane = g - i * lanes
    first = t - lane
    n = x.shape[0]
    n_rev = 0
    n_pairs = 0
    total = 0
    if i < n:
        n_rev = rev_count[i]
        n_pairs = n_rev + count[i]
        total = n_pairs + N_WALLS
    if t == 0:
        most[0] = 0
    cuda.syncthreads()
    cuda.atomic.max(most, 0, (total + lanes - 1) // lanes)
    cuda.syncthreads()
    rounds = most[0]
    fx = 0.0
    fy = 0.0
    fz = 0.0
    tx = 0.0
    ty = 0.0
    tz = 0.0
    if lane == 0 and i < n:
        m = mass[i]
        fx = m * acc[row, scene[i], 0]
        fy = m * acc[row, scene[i], 1]
        fz = m * acc[row, scene[i], 2]
    for r in range(rounds):
        e = r * lanes + lane
        share[t, 6] = 0.0
        if e < total:
            _put(share, t, candidate_force(
                i, e, n_rev, n_pairs, model, p, pw, x, v, omega, radius, mass, nbr, rev, hist_in,
                hist_out, wall_in, wall_out, length, half_width, back, dt,
            ))  # fmt: skip
        cuda.syncthreads()
        if lane == 0:
            fx, fy, fz, tx, ty, tz = _add_terms(share, first, first + lanes, fx, fy, fz, tx, ty, tz)
        cuda.syncthreads()
    if lane != 0 or i >= n:
        return
    _finish(
        i, (fx, fy, fz, tx, ty, tz), seq, trip, x, v, omega, x2, v2, omega2, mass, inv_mass,
        inv_inertia, length, dt, rotation, kick, next_drift, x_ref, limit, force, torque, px,
    )  # fmt: skip


@cuda.jit
def compact_step_kernel(
    keep, seq, trip, model, p, pw, x, v, omega, x2, v2, omega2, radius, mass, inv_mass,
    inv_inertia, nbr, count, rev, rev_count, hist_in, hist_out, wall_in, wall_out, length,
    half_width, back, dt, acc, row, scene, rotation, kick, next_drift, x_ref, limit, force, torque,
    px,
):  # fmt: skip
    """:func:`step_kernel` with each block's touching contacts gathered before the contact law.

    One thread a sphere, in blocks of :data:`COMPACT_BLOCK`. In :func:`step_kernel` a warp meets
    the law at each candidate slot of its spheres, whether few or many of them touch (Nsight
    Compute on the bed: 9 of 32 threads active). Here a pass has every thread test its
    sphere's candidates (:func:`dem.kernels.cuda.forces.candidate_touches`) and list the first
    ``keep`` (at most :data:`COMPACT_KEEP`) that touch in the block's shared memory; a prefix
    sum numbers the block's listed contacts, and in rounds of one contact a thread the block
    evaluates them (:func:`dem.kernels.cuda.forces.candidate_force`, one call site of the law
    for every kind), each thread's terms going to shared memory, from which after a barrier each
    sphere's thread adds its own in candidate order. A sphere with more than ``keep`` touching
    candidates lists the rest in the next pass. Only the candidates that do not touch are
    skipped, and they add nothing in :func:`step_kernel` either: the sums are the same floats,
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
    _finish(
        i, (fx, fy, fz, tx, ty, tz), seq, trip, x, v, omega, x2, v2, omega2, mass, inv_mass,
        inv_inertia, length, dt, rotation, kick, next_drift, x_ref, limit, force, torque, px,
    )  # fmt: skip
