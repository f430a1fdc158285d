"""Velocity Verlet in the trough's accelerating frame, many steps per call.

One step n -> n + 1 (t_n = n dt), as in LAMMPS ``fix nve/sphere``:

1. half kick and drift (parallel over spheres):
   v += dt/2 F/m, omega += dt/2 T/I (if rotation is on), x += dt v
   (fused into step 4 of the previous step within one call);
2. if some sphere moved more than skin/2 since the last build, rebuild the pair list
   (:func:`dem.kernels.neighbours.rebuild`, history carried over by pair key);
3. pair forces (parallel over pairs, :func:`dem.kernels.forces.pair_forces`) with the positions
   x_{n+1} and the half-step velocities v_{n+1/2} (damping and friction see these);
4. gather, walls, body force m (g - s''(t_{n+1})) (the drive, :func:`body_acceleration`) and
   the second half kick
   v += dt/2 F/m, omega += dt/2 T/I (parallel over spheres), summing the x-momentum
   sum_i m_i v_x,i for the measurement.

Arrays travel as named layouts (:mod:`dem.kernels.layout`): ``sph`` (SphereArrays), ``nb``
(PairArrays), ``bod`` (BodyArrays) and ``geom`` (Geometry: length, width, skin, dt); fields are
read by name, shapes in :mod:`dem.engine.state`.
"""

import math

import numba
import numpy as np

from dem.config import NUMBA_OPTIONS, NUMBA_PARALLEL_OPTIONS
from dem.kernels.forces import pair_forces, pair_forces_serial, total_force
from dem.kernels.neighbours import OK, max_displacement_sq, rebuild
from dem.kernels.periodic import wrap
from dem.kernels.rigid import (
    kick_drift_bodies,
    kick_drift_one,
    member_arm,
    place_members_of,
    reduce_to_bodies,
    update_members,
)

#: status returned by :func:`advance` when all steps were done.
DONE = OK

#: Fixed chunks of the per-step momentum sums (parallel over chunks, summed in order), so the
#: reported per-cycle velocity has the same bits on any number of threads.
MOMENTUM_CHUNKS = 256


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def kick_drift(n, dt, x, v, omega, force, torque, inv_mass, inv_inertia, rotation):
    """Half kick of v (and omega if ``rotation``) with the stored force, then drift x."""
    h = 0.5 * dt
    for i in numba.prange(n):
        a = h * inv_mass[i]
        for c in range(3):
            v[i, c] += a * force[i, c]
            x[i, c] += dt * v[i, c]
        if rotation:
            b = h * inv_inertia[i]
            for c in range(3):
                omega[i, c] += b * torque[i, c]


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def forces_kick(
    n, model, p, sph, nb, half_width, back, dt, ax, ay, az, rotation, kick, next_drift,
    gathered, mesh,
):  # fmt: skip
    """Gather forces per sphere into ``force``/``torque``; then (if ``kick``) the half kick.

    With ``gathered``, ``force``/``torque`` already hold m a_body plus the pairs
    (:func:`dem.kernels.forces.pair_forces_serial`) and only the walls are added.

    With ``next_drift`` the next step's first half kick and drift follow in the same loop (one
    parallel region less per step): v_{n+3/2} = v_{n+1} + dt/2 F_{n+1}/m, x_{n+2} = x_{n+1} +
    dt v_{n+3/2}.

    Returns:
        sum_i m_i v_x,i after the (second) half kick, kg m/s, summed over ``MOMENTUM_CHUNKS``
        fixed chunks in order: the same bits on any number of threads (the trajectory never
        depended on it; the reported per-cycle velocity now does not either).

    """
    x, v, omega, force, torque, radius, mass, inv_mass, inv_inertia, wall_hist = sph
    part_start, inbox = nb.part_start, nb.inbox
    h = 0.5 * dt
    chunks = min(MOMENTUM_CHUNKS, max(n, 1))
    partial = np.zeros(chunks)
    for chunk in numba.prange(chunks):
        px = 0.0
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            f = total_force(
                i, gathered, model, p, x, v, omega, radius, mass, wall_hist, half_width, back, dt,
                part_start, inbox, force, torque, ax, ay, az, mesh,
            )  # fmt: skip
            force[i, 0] = f[0]
            force[i, 1] = f[1]
            force[i, 2] = f[2]
            torque[i, 0] = f[3]
            torque[i, 1] = f[4]
            torque[i, 2] = f[5]
            if kick:
                a = h * inv_mass[i]
                v[i, 0] += a * f[0]
                v[i, 1] += a * f[1]
                v[i, 2] += a * f[2]
                if rotation:
                    b = h * inv_inertia[i]
                    omega[i, 0] += b * f[3]
                    omega[i, 1] += b * f[4]
                    omega[i, 2] += b * f[5]
            px += mass[i] * v[i, 0]
            if next_drift:
                a = h * inv_mass[i]
                for c in range(3):
                    v[i, c] += a * f[c]
                    x[i, c] += dt * v[i, c]
                if rotation:
                    b = h * inv_inertia[i]
                    for c in range(3):
                        omega[i, c] += b * f[3 + c]
        partial[chunk] = px
    return _ordered_sum(partial)


@numba.njit(**NUMBA_OPTIONS)
def _ordered_sum(values):
    """Sum in index order: the same bits whatever the number of threads."""
    total = 0.0
    for k in range(values.shape[0]):
        total += values[k]
    return total


@numba.njit(**NUMBA_OPTIONS)
def body_acceleration(t, gravity, drive):
    """a_body = g - s''(t), the trough's motion s(t) of :class:`dem.physics.drive.Motion`.

    drive = (omega, T_ramp, A_1 omega^2, psi_1, e_1 (3), A_2 omega^2, psi_2, e_2 (3)), all zeros
    with the drive off. Past the ramp (or without one) -s'' = sum_k A_k omega^2 sin(omega t +
    psi_k) e_k; within it the smootherstep r(t) of :func:`dem.physics.drive.ramp` scales it and adds
    its derivatives: sum_k A_k omega^2 e_k [(r - r''/omega^2) sin - (2 r'/omega) cos].
    """
    w = drive[0]
    ramp_time = drive[1]
    c_sin = 1.0
    c_cos = 0.0
    if ramp_time > 0.0 and t < ramp_time:
        c_sin = 0.0
        if t > 0.0:
            u = t / ramp_time
            r = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
            r1 = 30.0 * u * u * (1.0 - u) * (1.0 - u) / ramp_time
            r2 = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / (ramp_time * ramp_time)
            c_sin = r - r2 / (w * w)
            c_cos = -2.0 * r1 / w
    ax, ay, az = gravity[0], gravity[1], gravity[2]
    for k in range(2):
        a_w2 = drive[2 + 5 * k]
        if a_w2 == 0.0:
            continue
        ph = w * t + drive[3 + 5 * k]
        if c_cos == 0.0 and c_sin == 1.0:
            s = a_w2 * math.sin(ph)  # past the ramp
        else:
            s = a_w2 * (c_sin * math.sin(ph) + c_cos * math.cos(ph))
        ax += s * drive[4 + 5 * k]
        ay += s * drive[5 + 5 * k]
        az += s * drive[6 + 5 * k]
    return ax, ay, az


@numba.njit(**NUMBA_OPTIONS)
def _pairs(serial, model, p, sph, nb, n_pairs, geom, n, ax, ay, az):
    """The pair loop of either path (:mod:`dem.kernels.forces`).

    One thread adds into ``force``/``torque`` (from m a); several threads write the inbox.
    """
    x, v, omega, radius, mass = sph.x, sph.v, sph.omega, sph.radius, sph.mass
    if serial:
        pair_forces_serial(
            model, p, x, v, omega, radius, mass, nb.pair_i, nb.pair_j, n_pairs, nb.hist,
            geom.length, geom.dt, n, ax, ay, az, sph.force, sph.torque,
        )  # fmt: skip
    else:
        pair_forces(
            model, p, x, v, omega, radius, mass, nb.pair_i, nb.pair_j, n_pairs, nb.hist,
            geom.length, geom.dt, nb.part_slot, nb.inbox,
        )  # fmt: skip


@numba.njit(**NUMBA_OPTIONS)
def evaluate_forces(
    n, model, p, rotation, sph, nb, n_pairs, geom, t, gravity, drive, kick, next_drift, serial,
    mesh,
):  # fmt: skip
    """Pair forces then per-sphere gather at time t (see :func:`forces_kick`); sum m v_x.

    ``serial`` (one thread): the pairs add to the spheres directly
    (:func:`dem.kernels.forces.pair_forces_serial`), the same bits as the parallel pair loop and
    gather.
    """
    width, dt = geom.width, geom.dt
    ax, ay, az = body_acceleration(t, gravity, drive)
    _pairs(serial, model, p, sph, nb, n_pairs, geom, n, ax, ay, az)
    return forces_kick(
        n, model, p, sph, nb, 0.5 * width, geom.back, dt, ax, ay, az, rotation, kick,
        next_drift, serial, mesh,
    )  # fmt: skip


@numba.njit(**NUMBA_OPTIONS)
def build(n, sph, body, nb, counters, geom):
    """Rebuild the pair list of ``nb`` (counters[0] = number of pairs); returns (status, need).

    ``body`` (n,) int64 is the rigid body of each sphere: spheres of one body are not paired.
    """
    x, radius = sph.x, sph.radius
    status, n_pairs, need = rebuild(
        x, radius, body, n, geom.skin, geom.length, geom.width, nb.x_ref, nb.pair_i, nb.pair_j,
        nb.hist, counters[0], nb.scratch_j, nb.scratch_hist, nb.counts,
        nb.offsets, nb.cell_of, nb.cell_start, nb.cell_particles, nb.part_start, nb.part_slot,
    )  # fmt: skip
    counters[0] = n_pairs
    if status == OK:
        counters[1] += 1
    return status, need


@numba.njit(**NUMBA_OPTIONS)
def advance(
    n_steps, step0, resume, n, model, p, rotation, sph, body, nb, counters, geom, gravity, drive,
    out_stats, serial, mesh,
):  # fmt: skip
    """Advance ``n_steps`` velocity-Verlet steps from step index ``step0`` (t = step dt).

    Args:
        n_steps, step0: Steps to take, index of the first step's start.
        resume: True when the first step's kick and drift were already done (a retry after a
            neighbour-list overflow).
        n, model, p, rotation: Sphere count, contact law id and parameters, rotation on/off.
        sph, nb: Array layouts (module docstring).
        body: Grain of each sphere, int64 (n,) (``0..n-1`` here: every grain is one sphere).
        counters: int64 (2,): number of pairs, number of builds; updated.
        geom: Geometry (length, width, skin, dt).
        gravity: float64 (3,), m/s^2, trough frame.
        drive: float64 (12,): :meth:`dem.physics.drive.Motion.kernel_array` (zeros: drive off).
        out_stats: float64 (2,): += sum over steps of sum_i m_i v_x,i; += number of steps.
        serial: True on one thread: pair forces added to the spheres directly (same bits).
        mesh: The trough mesh (:class:`dem.kernels.layout.MeshArrays`), or None: flat walls.

    Returns:
        (status, steps_done, need): status DONE, or a neighbour-list overflow code with the
        capacity needed; then the step ``steps_done`` has been kicked and drifted but has no forces
        yet (call again with ``resume`` after regrowing).

    """
    x, v, omega, force, torque = sph.x, sph.v, sph.omega, sph.force, sph.torque
    inv_mass, inv_inertia = sph.inv_mass, sph.inv_inertia
    length, skin, dt = geom.length, geom.skin, geom.dt
    limit = 0.25 * skin * skin
    for s in range(n_steps):
        if s == 0 and not resume:
            kick_drift(n, dt, x, v, omega, force, torque, inv_mass, inv_inertia, rotation)
        if max_displacement_sq(x, nb.x_ref, n, length) > limit:
            status, need = build(n, sph, body, nb, counters, geom)
            if status != OK:
                return status, s, need
        t = (step0 + s + 1) * dt
        px = evaluate_forces(
            n, model, p, rotation, sph, nb, counters[0], geom, t, gravity, drive, True,
            s < n_steps - 1, serial, mesh,
        )  # fmt: skip
        out_stats[0] += px
        out_stats[1] += 1.0
    return DONE, n_steps, 0


# --- rigid clumps ---------------------------------------------------------------------------------
# Bodies travel as ``bod = (X, V, q, L, inv_mass, mass, moments, force, torque, omega, start,
# members, offsets, body_of)`` (shapes in :class:`dem.engine.state.Bodies`). Member spheres carry
# the clump mass M in ``sph.mass`` (the contact law's effective mass, as LIGGGHTS multisphere);
# their own kick and drift is replaced by the rigid-body update of :mod:`dem.kernels.rigid`.


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def _wrap_bodies(body_x, length):
    """Wrap the centres of mass into [0, length) along x (members follow at update_members)."""
    for b in numba.prange(body_x.shape[0]):
        body_x[b, 0] = wrap(body_x[b, 0], length)


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def _add_body_force(body_force, mass, ax, ay, az):
    """F_b += M_b a_body at the centre of mass (no torque: the frame does not rotate)."""
    for b in numba.prange(body_force.shape[0]):
        body_force[b, 0] += mass[b] * ax
        body_force[b, 1] += mass[b] * ay
        body_force[b, 2] += mass[b] * az


@numba.njit(**NUMBA_OPTIONS)
def evaluate_forces_clumps(
    n, model, p, sph, nb, n_pairs, geom, t, gravity, drive, bod, serial, mesh,
):  # fmt: skip
    """Pair forces, per-member gather (walls, no body force), reduction to the bodies + M a_body.

    Leaves ``sph.force``/``torque`` with the members' contact forces and the bodies'
    ``force``/``torque`` (about X) with F_b = sum F_s + M a_body, T_b = sum (T_s + r_s x F_s).
    ``serial`` as :func:`evaluate_forces`.
    """
    x = sph.x
    length, width, dt = geom.length, geom.width, geom.dt
    _pairs(serial, model, p, sph, nb, n_pairs, geom, n, 0.0, 0.0, 0.0)
    forces_kick(
        n, model, p, sph, nb, 0.5 * width, geom.back, dt, 0.0, 0.0, 0.0, False, False, False,
        serial, mesh,
    )  # fmt: skip
    reduce_to_bodies(
        sph.force, sph.torque, x, bod.x, bod.start, bod.members, length, bod.force, bod.torque,
    )  # fmt: skip
    ax, ay, az = body_acceleration(t, gravity, drive)
    _add_body_force(bod.force, bod.mass, ax, ay, az)


@numba.njit(**NUMBA_OPTIONS)
def _bodies_half_step(dt, drift, rotation, bod, sph, length):
    """Body kick (+ drift, free rotation, wrap), then place the members (x, v, spin)."""
    kick_drift_bodies(
        dt, drift, rotation, bod.x, bod.v, bod.q, bod.ang_mom, bod.force, bod.torque, bod.inv_mass,
        bod.moments, bod.omega,
    )  # fmt: skip
    if drift:
        _wrap_bodies(bod.x, length)
    update_members(
        bod.x, bod.v, bod.q, bod.omega, bod.offsets, bod.body_of, sph.x, sph.v, sph.omega
    )


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def bodies_forces_kick(
    model, p, sph, nb, half_width, back, dt, ax, ay, az, rotation, next_drift, bod, length,
    gathered, mesh,
):  # fmt: skip
    """Per body, in one parallel loop: gather, reduce, M a_body, closing kick, next drift, place.

    Body b gathers the forces of its members (:func:`dem.kernels.forces.sphere_force`, walls, no
    body force), reduces them to F_b, T_b about X_b as :func:`dem.kernels.rigid.reduce_to_bodies`
    does (same order of sums), adds M a_body, takes the closing half kick and, with
    ``next_drift``, the next step's half kick, drift, free rotation and wrap; then places its
    members. Each body writes only its own rows and its members' rows: race-free. With
    ``gathered``, the members' ``force``/``torque`` already hold their pairs
    (:func:`dem.kernels.forces.pair_forces_serial` with a = 0) and only the walls are added.

    Returns:
        sum_b M_b V_x,b after the closing half kick, kg m/s, summed over ``MOMENTUM_CHUNKS``
        fixed chunks in order: the same bits on any number of threads.

    """
    x, v, omega, force, torque, radius, mass, wall_hist = (
        sph.x, sph.v, sph.omega, sph.force, sph.torque, sph.radius, sph.mass, sph.wall_hist
    )  # fmt: skip
    part_start, inbox = nb.part_start, nb.inbox
    body_x, body_v, q, ang_mom, inv_mass, body_mass, moments = (
        bod.x, bod.v, bod.q, bod.ang_mom, bod.inv_mass, bod.mass, bod.moments
    )  # fmt: skip
    body_force, body_torque, body_omega, start, members, offsets = (
        bod.force, bod.torque, bod.omega, bod.start, bod.members, bod.offsets
    )  # fmt: skip
    n_bodies = body_x.shape[0]
    chunks = min(MOMENTUM_CHUNKS, max(n_bodies, 1))
    partial = np.zeros(chunks)
    for chunk in numba.prange(chunks):
        px = 0.0
        for b in range(chunk * n_bodies // chunks, (chunk + 1) * n_bodies // chunks):
            fx = fy = fz = 0.0
            tx = ty = tz = 0.0
            for e in range(start[b], start[b + 1]):
                s = members[e]
                f = total_force(
                    s, gathered, model, p, x, v, omega, radius, mass, wall_hist, half_width,
                    back, dt, part_start, inbox, force, torque, 0.0, 0.0, 0.0, mesh,
                )  # fmt: skip
                for c in range(3):
                    force[s, c] = f[c]
                    torque[s, c] = f[3 + c]
                rx, ry, rz = member_arm(x, s, body_x, b, length)
                fx += f[0]
                fy += f[1]
                fz += f[2]
                tx += f[3] + ry * f[2] - rz * f[1]
                ty += f[4] + rz * f[0] - rx * f[2]
                tz += f[5] + rx * f[1] - ry * f[0]
            m = body_mass[b]
            body_force[b, 0] = fx + m * ax
            body_force[b, 1] = fy + m * ay
            body_force[b, 2] = fz + m * az
            body_torque[b, 0] = tx
            body_torque[b, 1] = ty
            body_torque[b, 2] = tz
            kick_drift_one(
                b, dt, False, rotation, body_x, body_v, q, ang_mom, body_force, body_torque,
                inv_mass, moments, body_omega,
            )  # fmt: skip
            px += m * body_v[b, 0]
            if next_drift:
                kick_drift_one(
                    b, dt, True, rotation, body_x, body_v, q, ang_mom, body_force, body_torque,
                    inv_mass, moments, body_omega,
                )  # fmt: skip
                body_x[b, 0] = wrap(body_x[b, 0], length)
            place_members_of(
                b, body_x, body_v, q, body_omega, offsets, start, members, x, v, omega
            )  # fmt: skip
        partial[chunk] = px
    return _ordered_sum(partial)


@numba.njit(**NUMBA_OPTIONS)
def advance_clumps(
    n_steps, step0, resume, n, model, p, rotation, sph, bod, nb, counters, geom, gravity, drive,
    out_stats, serial, mesh,
):  # fmt: skip
    """Advance ``n_steps`` steps of rigid clumps (arguments and return as :func:`advance`).

    One step n -> n + 1 (:mod:`dem.kernels.rigid`):

    1. bodies: V += dt/2 F/M, L += dt/2 T (rotation on), X += dt V, q <- Phi_free(dt) q, X_x
       wrapped into [0, length); members x, v, spin from the bodies;
    2. neighbour list rebuilt if a member moved more than skin/2 (same-body pairs excluded);
    3. pair forces (parallel over pairs; one thread: added to the members directly);
    4. per body (:func:`bodies_forces_kick`, parallel over bodies): gather of the members with
       the walls (no body force per member), reduction to F_b, T_b about X_b, plus M a_body at
       the centre of mass; V += dt/2 F/M, L += dt/2 T; out_stats += sum M V_x; members placed
       (within one call, step n+1's item 1 runs in this same loop).

    Two parallel regions per step, as the sphere integrator.
    """
    length, width, skin, dt = geom.length, geom.width, geom.skin, geom.dt
    limit = 0.25 * skin * skin
    body_of = bod.body_of
    x = sph.x
    for s in range(n_steps):
        if s == 0 and not resume:
            _bodies_half_step(dt, True, rotation, bod, sph, length)
        if max_displacement_sq(x, nb.x_ref, n, length) > limit:
            status, need = build(n, sph, body_of, nb, counters, geom)
            if status != OK:
                return status, s, need
        t = (step0 + s + 1) * dt
        _pairs(serial, model, p, sph, nb, counters[0], geom, n, 0.0, 0.0, 0.0)
        ax, ay, az = body_acceleration(t, gravity, drive)
        out_stats[0] += bodies_forces_kick(
            model, p, sph, nb, 0.5 * width, geom.back, dt, ax, ay, az, rotation,
            s < n_steps - 1, bod, length, serial, mesh,
        )  # fmt: skip
        out_stats[1] += 1.0
    return DONE, n_steps, 0
