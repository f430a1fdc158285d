"""The pair loop and the wall contacts: forces and torques on every sphere.

Race-free by construction, no atomics. On several threads:

1. :func:`pair_forces` runs in parallel over the pair list; pair k writes what each of its two
   ends receives (force and torque, six floats) into that end's slot of ``inbox``:
   ``part_slot[2 k]`` for i, ``part_slot[2 k + 1]`` for j (:mod:`dem.kernels.neighbours`), and
   row k of the contact history ``hist``. No two pairs share a slot.
2. :func:`sphere_force` is called by a parallel loop over spheres
   (:func:`dem.kernels.integrate.forces_kick`); sphere i sums its own slots, which lie together
   in increasing pair index (a sequential read), adds its wall contacts (history rows
   N_WALLS i + w of ``wall_hist``, its own) and the body force m a_body. Each pair is computed
   once.

On one thread, :func:`pair_forces_serial` adds each pair's force and torques to its two spheres
directly (no per-pair rows, no gather: the rows' memory is never touched) and the sphere loop
adds only the walls (:func:`wall_forces`). Every sphere's sum has the same terms in the same
order both ways, so one thread and several give the same bits (tested).

Walls (trough frame, README, Symbols): w = 0 the floor z = 0 with normal +z, w = 1 the side
wall y = -width/2 with normal +y, w = 2 the side wall y = +width/2 with normal -y, w = 3 a finite
feeder's back wall x = ``back`` with normal +x (none where ``back`` = -inf). Each sphere owns
:data:`N_WALLS` = 4 rows of ``wall_hist``, row N_WALLS i + w for wall w, keyed by the sphere's
index (they move with it when grains are dropped or added, :meth:`dem.engine.state.Spheres.take`
and ``concat``); a row holds the contact's history (the tangential spring, m, and, for the
"impact" law, its phase and last normal velocity: :data:`dem.kernels.contact.HISTORY_WIDTH`
floats) and is set to zeros in every step in which the sphere does not touch that wall, so a
contact that re-forms starts at rest. A mesh trough's triangles take the floor and side walls'
place (their history in the mesh slots, :mod:`dem.kernels.mesh`) and rows 0-2 stay at zero.
A wall has infinite mass and radius (m* = m_i, R* = r_i), no spin, lever arm
c_i = r_i - f_w delta (``[contact] wall_lever_arm``: f_w = 1, 1/2 or 0,
:data:`dem.kernels.contact.WALL_LEVER_ARMS`; the slip velocity's arm is r_i with
``slip_lever_arm = "radius"``).

Every contact law goes through :func:`dem.kernels.contact.contact_core` (by
:func:`dem.kernels.contact.contact_force`, its CPU wrapper).
"""

import math

import numba

from dem.config import NUMBA_OPTIONS, NUMBA_PARALLEL_OPTIONS
from dem.kernels.contact import add_wall_contact, contact_force_inlined, pair_arms, wall_row
from dem.kernels.mesh import mesh_touches, mesh_wall_forces
from dem.kernels.periodic import minimum_image

N_WALLS = 4


@numba.njit(inline="always", **NUMBA_OPTIONS)
def clear_row(hist, row):
    """Set row ``row`` of a contact history to zeros: the contact does not touch (now).

    The stores are written out for the two widths there are (3, and 5 for the "impact" law,
    :data:`dem.kernels.contact.HISTORY_WIDTH`). A loop over the row's columns compiled to a
    call of libc's memset per row, for three or five floats, and testing each value first to
    skip the store cost more still: 11.1e9 and 13.1e9 instructions against 9.9e9 for the
    sphere deck's measured cycle (validation/performance/count_instructions.py); the same
    bits all three ways.
    """
    hist[row, 0] = 0.0
    hist[row, 1] = 0.0
    hist[row, 2] = 0.0
    if hist.shape[1] > 3:
        hist[row, 3] = 0.0
        hist[row, 4] = 0.0


@numba.njit(inline="always", **NUMBA_OPTIONS)
def pair_separation(x, i, j, length, half):
    """x_i - x_j with the nearest periodic image along x, and its square: (dx, dy, dz, d2), m, m^2.

    Spheres i and j touch where d2 < (r_i + r_j)^2: the test of :func:`pair_contact` and of
    :func:`contact_counts`.
    """
    dx = minimum_image(x[i, 0] - x[j, 0], length, half)
    dy = x[i, 1] - x[j, 1]
    dz = x[i, 2] - x[j, 2]
    return dx, dy, dz, dx * dx + dy * dy + dz * dz


@numba.njit(inline="always", **NUMBA_OPTIONS)
def flat_wall(w, y, z, half_width):
    """Gap of a centre at (y, z) from flat wall w and the wall's inward normal: (gap, ny, nz).

    w = 0 the floor z = 0, 1 the side wall y = -width/2, 2 the side wall y = +width/2. The sphere
    touches the wall where r - gap > 0: the test of :func:`wall_forces` and
    :func:`contact_counts`, and of the GPU kernel (:mod:`dem.kernels.cuda`), hence scalars.
    """
    if w == 0:
        return z, 0.0, 1.0
    if w == 1:
        return y + half_width, 1.0, 0.0
    return half_width - y, -1.0, 0.0


@numba.njit(inline="always", **NUMBA_OPTIONS)
def pair_contact(model, p, x, v, omega, radius, mass, i, j, hist, k, length, half, dt):
    """Force on i and torques on i and j of pair k = (i, j); zeros (history reset) if apart.

    Returns:
        (fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz) in N and N m.

    """
    dx, dy, dz, d2 = pair_separation(x, i, j, length, half)
    ri = radius[i]
    rj = radius[j]
    rsum = ri + rj
    if d2 >= rsum * rsum:
        clear_row(hist, k)
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    d = math.sqrt(d2)
    delta = rsum - d
    inv_d = 1.0 / d
    mi = mass[i]
    mj = mass[j]
    ci, cj, ai, aj = pair_arms(p, ri, rj, delta)
    f = contact_force_inlined(
        model, p, dx * inv_d, dy * inv_d, dz * inv_d, delta,
        v[i, 0] - v[j, 0], v[i, 1] - v[j, 1], v[i, 2] - v[j, 2],
        omega[i, 0], omega[i, 1], omega[i, 2], omega[j, 0], omega[j, 1], omega[j, 2],
        ci, cj, ai, aj, mi * mj / (mi + mj), ri * rj / rsum, hist, k, dt,
    )  # fmt: skip
    return f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8]


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def pair_forces(
    model, p, x, v, omega, radius, mass, pair_i, pair_j, n_pairs, hist, length, dt, part_slot,
    inbox,
):  # fmt: skip
    """Contact force and torques of each pair of the list into its ends' slots (parallel).

    Args:
        model, p: Contact law id and parameters (:mod:`dem.kernels.contact`).
        x, v, omega: Positions (m), velocities (m/s), spins (rad/s), shape (n, 3).
        radius, mass: Shape (n,), m and kg.
        pair_i, pair_j: Pairs i < j, shape (cap,); the first ``n_pairs`` are valid.
        hist: Contact history per pair, shape (cap, width) (the tangential spring, m, first;
            :data:`dem.kernels.contact.HISTORY_WIDTH`); updated (reset if apart).
        length: Period in x, m (minimum image).
        dt: Time step, s.
        part_slot: Slot of pair k's end i (2 k) and end j (2 k + 1), shape (2 cap,).
        inbox: Out: force (N) and torque (N m) each end receives, by slot, shape (2 cap, 6);
            end j gets minus the force on i, exactly.

    """
    half = 0.5 * length
    for k in numba.prange(n_pairs):
        f = pair_contact(
            model, p, x, v, omega, radius, mass, pair_i[k], pair_j[k], hist, k, length, half, dt
        )
        a = part_slot[2 * k]
        b = part_slot[2 * k + 1]
        inbox[a, 0] = f[0]
        inbox[a, 1] = f[1]
        inbox[a, 2] = f[2]
        inbox[a, 3] = f[3]
        inbox[a, 4] = f[4]
        inbox[a, 5] = f[5]
        inbox[b, 0] = -f[0]
        inbox[b, 1] = -f[1]
        inbox[b, 2] = -f[2]
        inbox[b, 3] = f[6]
        inbox[b, 4] = f[7]
        inbox[b, 5] = f[8]


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def pair_forces_serial(
    model, p, x, v, omega, radius, mass, pair_i, pair_j, n_pairs, hist, length, dt, n, ax, ay, az,
    force, torque,
):  # fmt: skip
    """One thread: ``force`` = m a + the pairs' forces, ``torque`` = the pairs' torques.

    Pair k adds its force to i and subtracts it from j directly, in pair order. Each sphere's
    pairs come in increasing k either way, so the sums have the same terms in the same order
    as :func:`pair_forces` followed by the gather of :func:`sphere_force` (x - f and x + (-f)
    are the same float): the same bits, without the slots and the gather.

    The loop is the single iteration of a ``prange(1)``: one thread runs it whatever the thread
    count, and numba compiles a parallel loop's body with its arrays marked as not aliasing each
    other, which made this loop twice as fast as the same loop in a plain function (measured in
    validation/performance/README.md, "Where a step's time goes").
    """
    for _ in numba.prange(1):
        for i in range(n):
            m = mass[i]
            force[i, 0] = m * ax
            force[i, 1] = m * ay
            force[i, 2] = m * az
            torque[i, 0] = 0.0
            torque[i, 1] = 0.0
            torque[i, 2] = 0.0
        half = 0.5 * length
        for k in range(n_pairs):
            i = pair_i[k]
            j = pair_j[k]
            f = pair_contact(model, p, x, v, omega, radius, mass, i, j, hist, k, length, half, dt)
            force[i, 0] += f[0]
            force[i, 1] += f[1]
            force[i, 2] += f[2]
            force[j, 0] -= f[0]
            force[j, 1] -= f[1]
            force[j, 2] -= f[2]
            torque[i, 0] += f[3]
            torque[i, 1] += f[4]
            torque[i, 2] += f[5]
            torque[j, 0] += f[6]
            torque[j, 1] += f[7]
            torque[j, 2] += f[8]


@numba.njit(inline="always", **NUMBA_OPTIONS)
def sphere_force(
    i, model, p, x, v, omega, radius, mass, wall_hist, half_width, back, dt, part_start, inbox,
    ax, ay, az, mesh,
):  # fmt: skip
    """Total force and torque on sphere i: its pairs' slots, its walls and m (ax, ay, az).

    Returns:
        (fx, fy, fz, tx, ty, tz) in N and N m.

    """
    m = mass[i]
    fx = m * ax
    fy = m * ay
    fz = m * az
    tx = 0.0
    ty = 0.0
    tz = 0.0
    for e in range(part_start[i], part_start[i + 1]):
        fx += inbox[e, 0]
        fy += inbox[e, 1]
        fz += inbox[e, 2]
        tx += inbox[e, 3]
        ty += inbox[e, 4]
        tz += inbox[e, 5]
    return wall_forces(
        i, model, p, x, v, omega, radius, mass, wall_hist, half_width, back, dt, mesh,
        fx, fy, fz, tx, ty, tz,
    )  # fmt: skip


@numba.njit(inline="always", **NUMBA_OPTIONS)
def total_force(
    i, gathered, model, p, x, v, omega, radius, mass, wall_hist, half_width, back, dt, part_start,
    inbox, force, torque, ax, ay, az, mesh,
):  # fmt: skip
    """Force and torque on sphere i, N and N m, by either path.

    :func:`sphere_force`; or, with ``gathered`` (``force``/``torque`` already hold m a and the
    pairs, :func:`pair_forces_serial`), the walls added to them.
    """
    if gathered:
        return wall_forces(
            i, model, p, x, v, omega, radius, mass, wall_hist, half_width, back, dt, mesh,
            force[i, 0], force[i, 1], force[i, 2], torque[i, 0], torque[i, 1], torque[i, 2],
        )  # fmt: skip
    return sphere_force(
        i, model, p, x, v, omega, radius, mass, wall_hist, half_width, back, dt, part_start, inbox,
        ax, ay, az, mesh,
    )  # fmt: skip


@numba.njit(inline="always", **NUMBA_OPTIONS)
def wall_forces(
    i, model, p, x, v, omega, radius, mass, wall_hist, half_width, back, dt, mesh,
    fx, fy, fz, tx, ty, tz,
):  # fmt: skip
    """(fx, ..., tz) plus the forces and torques of sphere i's wall contacts, N and N m.

    The walls use the grain-wall law, the second row of ``p`` (:func:`wall_row`).

    A mesh trough (``mesh`` not None) replaces the floor and side walls by its triangles
    (:func:`dem.kernels.mesh.mesh_wall_forces`). Without one, ``mesh`` is None and numba
    compiles the kernels without the mesh code at all (a separate, cached specialisation for
    mesh troughs).

    Most spheres touch no wall: they only reset their wall history (r - gap <= 0 exactly when
    gap >= r, so the early exit is the loop's own test). Without it the loop, with three inlined
    contact laws in it, cost 50 ns a sphere touching nothing (validation/performance/README.md).
    """
    r = radius[i]
    m = mass[i]
    if mesh is not None:
        pw = wall_row(p)
        fx, fy, fz, tx, ty, tz = mesh_wall_forces(
            i, model, pw, x, v, omega, radius, mass, dt, mesh, fx, fy, fz, tx, ty, tz
        )
        return _back_wall(
            i, model, pw, x, v, omega, r, m, wall_hist, back, dt, fx, fy, fz, tx, ty, tz
        )  # fmt: skip
    if (x[i, 2] >= r and x[i, 1] + half_width >= r and half_width - x[i, 1] >= r
            and x[i, 0] - back >= r):  # fmt: skip
        for row in range(N_WALLS * i, N_WALLS * i + N_WALLS):
            clear_row(wall_hist, row)
        return fx, fy, fz, tx, ty, tz
    pw = wall_row(p)  # the grain-wall law ([wall])
    for w in range(N_WALLS - 1):
        gap, ny, nz = flat_wall(w, x[i, 1], x[i, 2], half_width)
        delta = r - gap
        row = N_WALLS * i + w
        if delta <= 0.0:
            clear_row(wall_hist, row)
            continue
        fx, fy, fz, tx, ty, tz = add_wall_contact(
            model, pw, 0.0, ny, nz, delta, v, omega, i, m, r, wall_hist, row, dt,
            fx, fy, fz, tx, ty, tz,
        )  # fmt: skip
    return _back_wall(i, model, pw, x, v, omega, r, m, wall_hist, back, dt, fx, fy, fz, tx, ty, tz)


@numba.njit(inline="always", **NUMBA_OPTIONS)
def _back_wall(i, model, p, x, v, omega, r, m, wall_hist, back, dt, fx, fy, fz, tx, ty, tz):
    """Add the back wall x = ``back`` (inward normal +x) of a finite feeder; -inf: none.

    Its spring is row ``N_WALLS i + 3`` of ``wall_hist``, for flat walls and meshes alike.
    """
    row = N_WALLS * i + N_WALLS - 1
    delta = r - (x[i, 0] - back)
    if delta <= 0.0:
        clear_row(wall_hist, row)
        return fx, fy, fz, tx, ty, tz
    return add_wall_contact(
        model, p, 1.0, 0.0, 0.0, delta, v, omega, i, m, r, wall_hist, row, dt,
        fx, fy, fz, tx, ty, tz,
    )  # fmt: skip
    return fx, fy, fz, tx, ty, tz


@numba.njit(**NUMBA_OPTIONS)
def contact_counts(n, sph, nb, n_pairs, geom, mesh, out):
    """Add each sphere's touching neighbours and walls to ``out``, (n,) int64.

    The tests are the force kernels' own: a pair of the list touches where
    :func:`pair_separation` says so; a flat wall or the back wall where r - gap > 0
    (:func:`flat_wall`); a mesh counts each contact that :func:`dem.kernels.mesh.mesh_forces`
    adds (:func:`dem.kernels.mesh.mesh_touches`: a sphere in the bottom of a V touches both
    faces). The pair list holds every pair within reach (the Verlet skin), so nothing touching is
    missed; a clump's own spheres are no pair. Serial, O(n + pairs): for frames and summaries,
    not every step.
    """
    x, radius = sph.x, sph.radius
    half = 0.5 * geom.length
    for k in range(n_pairs):
        i = nb.pair_i[k]
        j = nb.pair_j[k]
        d2 = pair_separation(x, i, j, geom.length, half)[3]
        rsum = radius[i] + radius[j]
        if d2 < rsum * rsum:
            out[i] += 1
            out[j] += 1
    half_width = 0.5 * geom.width
    for i in range(n):
        r = radius[i]
        if mesh is not None:
            out[i] += mesh_touches(i, x, r, mesh)
        else:
            for w in range(N_WALLS - 1):
                if r - flat_wall(w, x[i, 1], x[i, 2], half_width)[0] > 0.0:
                    out[i] += 1
        if r - (x[i, 0] - geom.back) > 0.0:
            out[i] += 1
