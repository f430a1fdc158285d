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
(:meth:`dem.engine.gpu.engine.GpuEngine.steps`). The kick-drift launch is ``seq`` 0, step k of
a call ``seq`` k + 1.
"""

from numba import cuda

from dem.kernels.cuda.forces import mesh_sphere_force, sphere_force
from dem.kernels.periodic import minimum_image

#: ``trip[0]`` when no sphere has moved past skin/2 (above every launch's ``seq``).
NO_TRIP = 1 << 62


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
def finish(
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
    finish(
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
    finish(
        i, f, seq, trip, x, v, omega, x2, v2, omega2, mass, inv_mass, inv_inertia, length, dt,
        rotation, kick, next_drift, x_ref, limit, force, torque, px,
    )  # fmt: skip
