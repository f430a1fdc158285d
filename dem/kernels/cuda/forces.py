"""Force and torque on one sphere, summed by one GPU thread without atomics.

The pair list lives in fixed slots (:mod:`dem.kernels.cuda.neighbours`): sphere a's partners
b > a are ``nbr[a S : a S + count[a]]``, sorted by b, and pair (a, b) in slot k = a S + s keeps
its history in row k of ``hist``. The pairs sphere b is the upper end of are listed in its
reverse slots ``rev[b R : b R + rev_count[b]]`` (pair slots k, sorted, hence by a). The key
order of the CPU engine's compact list, i N + j, is the slots' order: sphere i's reverse slots
then its own slots visit its pairs in increasing key, the order in which the CPU engine adds
them (:mod:`dem.kernels.forces`).

Thread i evaluates each of its pairs itself, always oriented as the pair (a < b): the two ends
of a pair compute it from the same inputs by the same code, so they get the same bits, F_b =
-F_a exactly, and nothing is written that another thread reads. The alternative, one thread per
pair writing both ends' shares and a second kernel gathering them (the CPU engine's parallel
path), does half the law's arithmetic but adds a launch and 24 floats of memory traffic per
pair; the contact law is some hundreds of flops on data already in registers, cheap on a GPU.

History is double-buffered: every thread reads ``hist_in``; the pair's lower end alone writes the
new row to ``hist_out`` (a separated pair writes zeros, as :func:`dem.kernels.forces.pair_contact`
does). Thread i owns its wall rows N_WALLS i + w of ``wall_in``/``wall_out``.

Every sphere's sum has the CPU engine's terms in the CPU engine's order (m a_body, the pairs by
key, the floor, the side walls y = -width/2 and +width/2, the back wall), so in numba's CUDA
simulator, where the kernels run as Python and the contact law as the CPU's compiled code, the
forces are the CPU engine's to the bit. On a GPU the compiler fuses multiplies and adds (FMA),
which changes the last bits.
"""

import math

import numpy as np
from numba import cuda

from dem.kernels.contact import N_PARAMS, contact_core, pair_arms, wall_arms
from dem.kernels.cuda.launch import THREADS_PER_BLOCK, blocks
from dem.kernels.cuda.mesh import mesh_walls
from dem.kernels.forces import N_WALLS, flat_wall
from dem.kernels.periodic import minimum_image


@cuda.jit(device=True)
def separation(a, b, x, radius, length):
    """Pair (a, b): x_a - x_b (minimum image in x), its square, r_a + r_b: (dx, dy, dz, d2, rsum).

    The pair touches where d2 < rsum^2: the test every path of this module makes.
    """
    dx = minimum_image(x[a, 0] - x[b, 0], length, 0.5 * length)
    dy = x[a, 1] - x[b, 1]
    dz = x[a, 2] - x[b, 2]
    return dx, dy, dz, dx * dx + dy * dy + dz * dz, radius[a] + radius[b]


@cuda.jit(device=True)
def wall_gap(i, w, x, radius, half_width, back):
    """Sphere i's overlap with wall w and the wall's inward normal: (delta, nx, ny, nz).

    The walls: the floor, the side walls y = -width/2 and +width/2, the back wall x = back
    (inward normal +x). The sphere touches the wall where delta > 0.
    """
    if w < N_WALLS - 1:
        gap, ny, nz = flat_wall(w, x[i, 1], x[i, 2], half_width)
        nx = 0.0
    else:
        gap = x[i, 0] - back
        nx, ny, nz = 1.0, 0.0, 0.0
    return radius[i] - gap, nx, ny, nz


@cuda.jit(device=True)
def _pair(model, p, x, v, omega, radius, mass, a, b, k, hist_in, dx, dy, dz, d2, dt):
    """The contact law of touching pair k = (a, b), a < b, at squared distance d2 (15 floats)."""
    d = math.sqrt(d2)
    ra = radius[a]
    rb = radius[b]
    rsum = ra + rb
    delta = rsum - d
    inv_d = 1.0 / d
    ma = mass[a]
    mb = mass[b]
    ca, cb, aa, ab = pair_arms(p, ra, rb, delta)
    h3 = 0.0
    h4 = 0.0
    if hist_in.shape[1] > 3:
        h3 = hist_in[k, 3]
        h4 = hist_in[k, 4]
    return contact_core(
        model, p, dx * inv_d, dy * inv_d, dz * inv_d, delta,
        v[a, 0] - v[b, 0], v[a, 1] - v[b, 1], v[a, 2] - v[b, 2],
        omega[a, 0], omega[a, 1], omega[a, 2], omega[b, 0], omega[b, 1], omega[b, 2],
        ca, cb, aa, ab, ma * mb / (ma + mb), ra * rb / rsum,
        hist_in[k, 0], hist_in[k, 1], hist_in[k, 2], h3, h4, dt,
    )  # fmt: skip


@cuda.jit(device=True)
def _upper_add(
    i, k, model, p, x, v, omega, radius, mass, slots, hist_in, length, dt, fx, fy, fz, tx, ty, tz,
):  # fmt: skip
    """Pair slot k = (a, i), a < i, from its upper end i: (touching, the sums updated).

    -F and the torque on i are added to the sums, as :func:`sphere_force` adds them.
    """
    a = k // slots
    dx, dy, dz, d2, rsum = separation(a, i, x, radius, length)
    if d2 >= rsum * rsum:
        return False, fx, fy, fz, tx, ty, tz
    f = _pair(model, p, x, v, omega, radius, mass, a, i, k, hist_in, dx, dy, dz, d2, dt)
    return True, fx - f[0], fy - f[1], fz - f[2], tx + f[6], ty + f[7], tz + f[8]


@cuda.jit(device=True)
def _lower_add(
    i, k, model, p, x, v, omega, radius, mass, nbr, hist_in, hist_out, length, dt, fx, fy, fz,
    tx, ty, tz,
):  # fmt: skip
    """Pair slot k = (i, b), b > i, from its lower end i: (touching, the sums updated).

    F and the torque on i are added; i writes the slot's history row (zeros where apart).
    """
    b = nbr[k]
    dx, dy, dz, d2, rsum = separation(i, b, x, radius, length)
    if d2 >= rsum * rsum:
        for c in range(hist_out.shape[1]):
            hist_out[k, c] = 0.0
        return False, fx, fy, fz, tx, ty, tz
    f = _pair(model, p, x, v, omega, radius, mass, i, b, k, hist_in, dx, dy, dz, d2, dt)
    for c in range(hist_out.shape[1]):
        hist_out[k, c] = f[10 + c]
    return True, fx + f[0], fy + f[1], fz + f[2], tx + f[3], ty + f[4], tz + f[5]


@cuda.jit(device=True)
def _wall_add(
    i, w, model, pw, x, v, omega, radius, mass, wall_in, wall_out, half_width, back, dt, fx, fy,
    fz, tx, ty, tz,
):  # fmt: skip
    """Sphere i on wall w (:func:`wall_gap`) by the grain-wall law.

    Returns (touching, the sums with F and torque added); i writes its wall row (zeros where
    apart).
    """
    width = wall_in.shape[1]
    ri = radius[i]
    delta, nx, ny, nz = wall_gap(i, w, x, radius, half_width, back)
    row = N_WALLS * i + w
    if delta <= 0.0:
        for c in range(width):
            wall_out[row, c] = 0.0
        return False, fx, fy, fz, tx, ty, tz
    ci, ai = wall_arms(pw, ri, delta)
    h3 = 0.0
    h4 = 0.0
    if width > 3:
        h3 = wall_in[row, 3]
        h4 = wall_in[row, 4]
    f = contact_core(
        model, pw, nx, ny, nz, delta, v[i, 0], v[i, 1], v[i, 2], omega[i, 0], omega[i, 1],
        omega[i, 2], 0.0, 0.0, 0.0, ci, 0.0, ai, 0.0, mass[i], ri,
        wall_in[row, 0], wall_in[row, 1], wall_in[row, 2], h3, h4, dt,
    )  # fmt: skip
    for c in range(width):
        wall_out[row, c] = f[10 + c]
    return True, fx + f[0], fy + f[1], fz + f[2], tx + f[3], ty + f[4], tz + f[5]


@cuda.jit(device=True)
def sphere_force(
    i, model, p, pw, x, v, omega, radius, mass, nbr, count, rev, rev_count, hist_in, hist_out,
    wall_in, wall_out, length, half_width, back, dt, ax, ay, az,
):  # fmt: skip
    """Force and torque on sphere i (fx, fy, fz, tx, ty, tz); writes i's history rows.

    The terms in the CPU engine's order: m a_body, the pairs (a, i) of i's reverse slots (i the
    upper end receives -F and the torque on j), the pairs (i, b) of its own slots, the walls.

    Args:
        i, model: The sphere, the normal law id (:data:`dem.kernels.contact.MODELS`).
        p, pw: Grain-grain and grain-wall parameter rows, tuples of N_PARAMS floats.
        x, v, omega, radius, mass: The spheres' state (n, 3) and (n,), SI units.
        nbr, count, rev, rev_count: The slots (module docstring); S = len(nbr) // n and
            R = len(rev) // n.
        hist_in, hist_out: Pair history by slot before and after, (n S, width), width 3 or 5.
        wall_in, wall_out: Wall history before and after, rows N_WALLS i + w, same width.
        length: Period in x, m. half_width: Half the trough width, m. back: The back wall's x, m
            (-inf: none). dt: Time step, s. ax, ay, az: Body acceleration a_body, m/s^2.

    """
    fx, fy, fz, tx, ty, tz = _pair_sums(
        i, model, p, x, v, omega, radius, mass, nbr, count, rev, rev_count, hist_in, hist_out,
        length, dt, ax, ay, az,
    )  # fmt: skip
    for w in range(N_WALLS):
        _, fx, fy, fz, tx, ty, tz = _wall_add(
            i, w, model, pw, x, v, omega, radius, mass, wall_in, wall_out, half_width, back, dt,
            fx, fy, fz, tx, ty, tz,
        )  # fmt: skip
    return fx, fy, fz, tx, ty, tz


@cuda.jit(device=True)
def mesh_sphere_force(
    i, model, p, pw, x, v, omega, radius, mass, nbr, count, rev, rev_count, hist_in, hist_out,
    wall_in, wall_out, length, half_width, back, dt, ax, ay, az, tri, grid, dims, cell_start,
    cell_tris, slot_hist, slot_normal,
):  # fmt: skip
    """:func:`sphere_force` in a mesh trough: the mesh's contacts instead of the flat walls.

    As the CPU engine (:func:`dem.kernels.forces.wall_forces` with a mesh): after the pairs the
    mesh contacts (:func:`dem.kernels.cuda.mesh.mesh_walls`, sphere i's slot rows of
    ``slot_hist``, ``slot_normal`` updated in place), then the back wall (wall row
    N_WALLS i + 3). The flat walls' rows are carried over unchanged, as the CPU leaves them.
    """
    fx, fy, fz, tx, ty, tz = _pair_sums(
        i, model, p, x, v, omega, radius, mass, nbr, count, rev, rev_count, hist_in, hist_out,
        length, dt, ax, ay, az,
    )  # fmt: skip
    fx, fy, fz, tx, ty, tz = mesh_walls(
        i, model, pw, x, v, omega, radius, mass, dt, tri, grid, dims, cell_start, cell_tris,
        slot_hist, slot_normal, fx, fy, fz, tx, ty, tz,
    )  # fmt: skip
    for w in range(N_WALLS - 1):
        row = N_WALLS * i + w
        for c in range(wall_in.shape[1]):
            wall_out[row, c] = wall_in[row, c]
    _, fx, fy, fz, tx, ty, tz = _wall_add(
        i, N_WALLS - 1, model, pw, x, v, omega, radius, mass, wall_in, wall_out, half_width, back,
        dt, fx, fy, fz, tx, ty, tz,
    )  # fmt: skip
    return fx, fy, fz, tx, ty, tz


@cuda.jit(device=True)
def _pair_sums(
    i, model, p, x, v, omega, radius, mass, nbr, count, rev, rev_count, hist_in, hist_out,
    length, dt, ax, ay, az,
):  # fmt: skip
    """m_i a_body plus sphere i's pairs, reverse slots then own slots: (fx, ..., tz)."""
    n = x.shape[0]
    slots = nbr.shape[0] // n
    rslots = rev.shape[0] // n
    m = mass[i]
    fx = m * ax
    fy = m * ay
    fz = m * az
    tx = 0.0
    ty = 0.0
    tz = 0.0
    for e in range(rev_count[i]):
        _, fx, fy, fz, tx, ty, tz = _upper_add(
            i, rev[i * rslots + e], model, p, x, v, omega, radius, mass, slots, hist_in, length,
            dt, fx, fy, fz, tx, ty, tz,
        )  # fmt: skip
    for s in range(count[i]):
        _, fx, fy, fz, tx, ty, tz = _lower_add(
            i, i * slots + s, model, p, x, v, omega, radius, mass, nbr, hist_in, hist_out,
            length, dt, fx, fy, fz, tx, ty, tz,
        )  # fmt: skip
    return fx, fy, fz, tx, ty, tz


@cuda.jit
def forces_kernel(
    model, p, pw, x, v, omega, radius, mass, nbr, count, rev, rev_count, hist_in, hist_out,
    wall_in, wall_out, length, half_width, back, dt, ax, ay, az, force, torque,
):  # fmt: skip
    """Thread i: force and torque on sphere i into ``force[i]``, ``torque[i]`` (no kick)."""
    i = cuda.grid(1)
    if i >= x.shape[0]:
        return
    f = sphere_force(
        i, model, p, pw, x, v, omega, radius, mass, nbr, count, rev, rev_count, hist_in,
        hist_out, wall_in, wall_out, length, half_width, back, dt, ax, ay, az,
    )  # fmt: skip
    for c in range(3):
        force[i, c] = f[c]
        torque[i, c] = f[3 + c]


def law_rows(p) -> tuple[tuple, tuple]:
    """The grain-grain and grain-wall rows of a law's parameters, as tuples of floats.

    A tuple reaches a kernel as numbers, with no array (:func:`dem.kernels.contact.wall_row`
    lays the grain-wall row second; a law without one uses the grain-grain row for walls).
    """
    p = np.asarray(p, dtype=np.float64)
    row = tuple(p[:N_PARAMS].tolist())
    wall = tuple(p[N_PARAMS : 2 * N_PARAMS].tolist()) if p.shape[0] >= 2 * N_PARAMS else row
    return row, wall


def compact_to_slots(pair_i, pair_j, hist, n_pairs: int, n: int, slots: int | None = None):
    """The CPU engine's compact pair list in fixed slots: (nbr, count, slot_hist, slots).

    ``pair_i``, ``pair_j`` sorted by the key i n + j (:class:`dem.engine.state.PairList`); sphere
    i's partners go to ``nbr[i S : i S + count[i]]`` in the same order, their history rows to the
    same rows of ``slot_hist``. S is ``slots``, or the most pairs any sphere is the lower end of
    (at least 16).
    """
    pi = np.asarray(pair_i[:n_pairs], dtype=np.int64)
    count = np.bincount(pi, minlength=n).astype(np.int32)
    most = int(count.max()) if n else 0
    slots = max(16, most) if slots is None else int(slots)
    if most > slots:
        raise ValueError(f"a sphere has {most} pairs, more than the {slots} slots")
    start = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(count, out=start[1:])
    rows = pi * slots + (np.arange(n_pairs) - start[pi])
    nbr = np.zeros(n * slots, dtype=np.int32)
    nbr[rows] = pair_j[:n_pairs]
    slot_hist = np.zeros((n * slots, hist.shape[1]))
    slot_hist[rows] = hist[:n_pairs]
    return nbr, count, slot_hist, slots


def slots_to_compact(nbr, count, slot_hist, slots: int):
    """The slots back in the CPU engine's compact order: (pair_i, pair_j, hist), int64 keys."""
    valid = np.arange(slots)[None, :] < count[:, None]
    rows = np.flatnonzero(valid.ravel())
    return rows // slots, nbr[rows].astype(np.int64), slot_hist[rows]


def sphere_forces(
    model, p, x, v, omega, radius, mass, pair_i, pair_j, n_pairs, hist, wall_hist, length, width,
    back, dt, a_body,
):  # fmt: skip
    """Forces and torques on every sphere and the new contact history, computed on the GPU.

    For tests: the CPU engine's compact pair list (sorted by key) goes to the slots, the reverse
    slots are built on the device (:func:`dem.kernels.cuda.neighbours.reverse_slots`), one
    thread per sphere evaluates, and the results come back in the CPU engine's layout. Arguments
    as :func:`dem.kernels.forces.pair_forces` and :func:`dem.kernels.forces.wall_forces`: ``p``
    the law's float64 parameters, ``hist`` (n_pairs or more, width) and ``wall_hist`` (N_WALLS n,
    width) the history before, ``a_body`` (3,) m/s^2.

    Returns:
        (force, torque, hist, wall_hist): (n, 3) N and N m, and the new history, shaped as the
        inputs (rows of ``hist`` past n_pairs copied unchanged).

    """
    from dem.kernels.cuda.neighbours import reverse_slots

    n = x.shape[0]
    row, wall = law_rows(p)
    nbr, count, slot_hist, slots = compact_to_slots(pair_i, pair_j, hist, n_pairs, n)
    to = cuda.to_device
    d_nbr, d_count = to(nbr), to(count)
    d_rev, d_rev_count = reverse_slots(d_nbr, d_count)
    d_hist_out = to(slot_hist)
    d_wall_out = to(np.array(wall_hist))
    d_force = cuda.device_array((n, 3))
    d_torque = cuda.device_array((n, 3))
    forces_kernel[blocks(n), THREADS_PER_BLOCK](
        model, row, wall, to(x), to(v), to(omega), to(radius), to(mass), d_nbr, d_count, d_rev,
        d_rev_count, to(slot_hist), d_hist_out, to(wall_hist), d_wall_out, float(length),
        0.5 * float(width), float(back), float(dt), float(a_body[0]), float(a_body[1]),
        float(a_body[2]), d_force, d_torque,
    )  # fmt: skip
    _, _, new_hist = slots_to_compact(nbr, count, d_hist_out.copy_to_host(), slots)
    out_hist = np.array(hist)
    out_hist[:n_pairs] = new_hist
    return d_force.copy_to_host(), d_torque.copy_to_host(), out_hist, d_wall_out.copy_to_host()
