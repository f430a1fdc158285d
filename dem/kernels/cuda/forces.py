"""Forces and torques on every sphere, one GPU thread per sphere, gathered without atomics.

Thread i walks sphere i's slots: the pairs of the pair list that it is an end of, in increasing
pair index k (:func:`sphere_slots`, built on the host from the CPU engine's pair list). For each
it evaluates the pair k = (pair_i[k], pair_j[k]) itself, always oriented as the pair list has
it, and adds the force on i (or minus it, on end j) and the torque on its end. So each pair is
computed twice, once by each end, from the same inputs and by the same code: the two ends get
the same bits, F_j = -F_i exactly, and nothing is written that another thread reads. The
alternative, one thread per pair writing both ends' shares to slots and a second kernel
gathering them (the CPU engine's parallel path), does half the law's arithmetic but adds a
launch and 24 floats of memory traffic per pair (12 written, 12 read back); the contact law is
some hundreds of flops on data already in registers, cheap on a GPU, so this kernel spends flops
to save memory traffic and a launch. Which of the two is faster
on an H100 is for the next step to measure.

History is double-buffered: every thread reads ``hist_in`` and the pair's lower end (``pair_i``)
alone writes the new row to ``hist_out`` (both ends compute it, the same bits), a separated pair
writing zeros as :func:`dem.kernels.forces.pair_contact` does. Thread i owns its wall rows
N_WALLS i + w of ``wall_in``/``wall_out``. The host swaps the buffers after a step.

Every sphere's sum has the terms of the CPU engine in the CPU engine's order (m a_body, the pairs
in increasing k, the floor, the side walls y = -width/2 and +width/2, the back wall; see
:mod:`dem.kernels.forces`), so in numba's CUDA simulator, where the kernel runs as Python and
the contact law as the CPU's compiled code, the forces are the CPU engine's to the bit. On a GPU
the compiler may fuse a multiply and an add (FMA), which changes the last bits.
"""

import math

import numpy as np
from numba import cuda

from dem.kernels.contact import N_PARAMS, contact_core, pair_arms, wall_arms
from dem.kernels.forces import N_WALLS, flat_wall
from dem.kernels.periodic import minimum_image

#: Threads per block of :func:`sphere_forces_kernel`.
THREADS_PER_BLOCK = 128


def sphere_slots(pair_i: np.ndarray, pair_j: np.ndarray, n_pairs: int, n: int):
    """Each sphere's pairs, in increasing pair index: (slot_start, slot_pair), int64.

    Sphere i's pairs are ``slot_pair[slot_start[i]:slot_start[i + 1]]``, each pair k listed
    under both its ends; shapes (n + 1,) and (2 n_pairs,). The order is that in which the CPU
    engine adds them (:mod:`dem.kernels.forces`).
    """
    ends = np.concatenate([pair_i[:n_pairs], pair_j[:n_pairs]]).astype(np.int64)
    pairs = np.concatenate([np.arange(n_pairs), np.arange(n_pairs)]).astype(np.int64)
    order = np.lexsort((pairs, ends))
    slot_start = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(ends, minlength=n), out=slot_start[1:])
    return slot_start, pairs[order]


@cuda.jit
def sphere_forces_kernel(
    n, model, p, pw, x, v, omega, radius, mass, pair_i, pair_j, slot_start, slot_pair,
    hist_in, hist_out, wall_in, wall_out, length, half_width, back, dt, ax, ay, az, force, torque,
):  # fmt: skip
    """Thread i: force and torque on sphere i into ``force[i]``, ``torque[i]``; i's history rows.

    Args:
        n, model: Sphere count, normal law id (:data:`dem.kernels.contact.MODELS`).
        p, pw: Grain-grain and grain-wall parameter rows, tuples of N_PARAMS floats.
        x, v, omega: Positions (m), velocities (m/s), spins (rad/s), shape (n, 3).
        radius, mass: Shape (n,), m and kg.
        pair_i, pair_j: Pair list, i < j, shape (n_pairs,) or more.
        slot_start, slot_pair: Each sphere's pairs (:func:`sphere_slots`).
        hist_in, hist_out: Pair history before and after, shape (n_pairs, width), width 3 or 5.
        wall_in, wall_out: Wall history before and after, rows N_WALLS i + w, same width.
        length: Period in x, m. half_width: Half the trough width, m. back: The back wall's x,
            m (-inf: none). dt: Time step, s.
        ax, ay, az: Body acceleration a_body, m/s^2 (gravity and the drive).
        force, torque: Out, shape (n, 3), N and N m.

    """
    i = cuda.grid(1)
    if i >= n:
        return
    width = hist_in.shape[1]
    ri = radius[i]
    m = mass[i]
    fx = m * ax
    fy = m * ay
    fz = m * az
    tx = 0.0
    ty = 0.0
    tz = 0.0
    half = 0.5 * length
    for e in range(slot_start[i], slot_start[i + 1]):
        k = slot_pair[e]
        a = pair_i[k]
        b = pair_j[k]
        dx = minimum_image(x[a, 0] - x[b, 0], length, half)
        dy = x[a, 1] - x[b, 1]
        dz = x[a, 2] - x[b, 2]
        d2 = dx * dx + dy * dy + dz * dz
        ra = radius[a]
        rb = radius[b]
        rsum = ra + rb
        if d2 >= rsum * rsum:
            if a == i:
                for c in range(width):
                    hist_out[k, c] = 0.0
            continue
        d = math.sqrt(d2)
        delta = rsum - d
        inv_d = 1.0 / d
        ma = mass[a]
        mb = mass[b]
        ca, cb, aa, ab = pair_arms(p, ra, rb, delta)
        h3 = hist_in[k, 3] if width > 3 else 0.0
        h4 = hist_in[k, 4] if width > 3 else 0.0
        f = contact_core(
            model, p, dx * inv_d, dy * inv_d, dz * inv_d, delta,
            v[a, 0] - v[b, 0], v[a, 1] - v[b, 1], v[a, 2] - v[b, 2],
            omega[a, 0], omega[a, 1], omega[a, 2], omega[b, 0], omega[b, 1], omega[b, 2],
            ca, cb, aa, ab, ma * mb / (ma + mb), ra * rb / rsum,
            hist_in[k, 0], hist_in[k, 1], hist_in[k, 2], h3, h4, dt,
        )  # fmt: skip
        if a == i:
            fx += f[0]
            fy += f[1]
            fz += f[2]
            tx += f[3]
            ty += f[4]
            tz += f[5]
            for c in range(width):
                hist_out[k, c] = f[10 + c]
        else:
            fx -= f[0]
            fy -= f[1]
            fz -= f[2]
            tx += f[6]
            ty += f[7]
            tz += f[8]
    # the flat walls and the back wall x = back (inward normal +x), the grain-wall law
    for w in range(N_WALLS):
        if w < N_WALLS - 1:
            gap, ny, nz = flat_wall(w, x[i, 1], x[i, 2], half_width)
            nx = 0.0
        else:
            gap = x[i, 0] - back
            nx, ny, nz = 1.0, 0.0, 0.0
        delta = ri - gap
        row = N_WALLS * i + w
        if delta <= 0.0:
            for c in range(width):
                wall_out[row, c] = 0.0
            continue
        ci, ai = wall_arms(pw, ri, delta)
        h3 = wall_in[row, 3] if width > 3 else 0.0
        h4 = wall_in[row, 4] if width > 3 else 0.0
        f = contact_core(
            model, pw, nx, ny, nz, delta, v[i, 0], v[i, 1], v[i, 2], omega[i, 0], omega[i, 1],
            omega[i, 2], 0.0, 0.0, 0.0, ci, 0.0, ai, 0.0, m, ri,
            wall_in[row, 0], wall_in[row, 1], wall_in[row, 2], h3, h4, dt,
        )  # fmt: skip
        fx += f[0]
        fy += f[1]
        fz += f[2]
        tx += f[3]
        ty += f[4]
        tz += f[5]
        for c in range(width):
            wall_out[row, c] = f[10 + c]
    force[i, 0] = fx
    force[i, 1] = fy
    force[i, 2] = fz
    torque[i, 0] = tx
    torque[i, 1] = ty
    torque[i, 2] = tz


def sphere_forces(
    model, p, x, v, omega, radius, mass, pair_i, pair_j, n_pairs, hist, wall_hist, length, width,
    back, dt, a_body,
):  # fmt: skip
    """Forces and torques on every sphere and the new contact history, computed on the GPU.

    The host's side of :func:`sphere_forces_kernel`, for tests and for the engine to come: it
    builds the slots, copies the arrays to the device, launches one thread per sphere and copies
    the results back. Arguments as the CPU engine's (:func:`dem.kernels.forces.pair_forces`,
    :func:`dem.kernels.forces.wall_forces`): ``p`` the law's float64 parameters (the grain-wall
    row second, :func:`dem.kernels.contact.wall_row`), ``hist`` (n_pairs or more, width) and
    ``wall_hist`` (N_WALLS n, width) the history before the step, ``a_body`` (3,) m/s^2.

    Returns:
        (force, torque, hist, wall_hist): (n, 3) N and N m, and the new history, shaped as the
        inputs (rows of ``hist`` past n_pairs copied unchanged).

    """
    n = x.shape[0]
    p = np.asarray(p, dtype=np.float64)
    row = tuple(p[:N_PARAMS].tolist())  # a tuple reaches the kernel as numbers, no array
    wall = tuple(p[N_PARAMS : 2 * N_PARAMS].tolist()) if p.shape[0] >= 2 * N_PARAMS else row
    slot_start, slot_pair = sphere_slots(pair_i, pair_j, n_pairs, n)
    hist_out = np.array(hist)
    to = cuda.to_device
    d_hist_out = to(hist_out)
    d_wall_out = to(np.array(wall_hist))
    d_force = cuda.device_array((n, 3))
    d_torque = cuda.device_array((n, 3))
    blocks = (n + THREADS_PER_BLOCK - 1) // THREADS_PER_BLOCK
    sphere_forces_kernel[blocks, THREADS_PER_BLOCK](
        n, model, row, wall, to(x), to(v), to(omega), to(radius), to(mass), to(pair_i), to(pair_j),
        to(slot_start), to(slot_pair), to(hist), d_hist_out, to(wall_hist), d_wall_out,
        float(length), 0.5 * float(width), float(back), float(dt), float(a_body[0]),
        float(a_body[1]), float(a_body[2]), d_force, d_torque,
    )  # fmt: skip
    return (d_force.copy_to_host(), d_torque.copy_to_host(), d_hist_out.copy_to_host(),
            d_wall_out.copy_to_host())  # fmt: skip
