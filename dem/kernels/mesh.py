"""Sphere-triangle contacts with a trough mesh: closest points, a cell index, no double counting.

A mesh trough (``trough.mesh``) is a set of triangles fixed in the trough frame. A sphere of
radius r at x touches triangle t where the point q of t closest to x lies within r: the contact
normal is n = (x - q) / |x - q|, the overlap delta = r - |x - q|, and the contact law is that of
the flat walls (:func:`dem.kernels.contact.contact_force` with the wall's infinite mass and
radius: m* = m, R* = r, lever arm r - f_w delta, ``[contact] wall_lever_arm``).

Closest points (:func:`closest_point`) follow the Voronoi regions of the triangle (Ericson,
Real-Time Collision Detection, 2005, section 5.1.5) and say which feature q lies on: the face,
one of the three edges or one of the three vertices.

No double counting. A sphere resting on a flat region that is cut into many triangles touches
the one its centre lies over with a face contact, and its neighbours at their shared edges or
vertices with the same or a smaller overlap; a sphere on a ridge touches both triangles at the
same edge point. So a contact is counted only if

- it is a face contact, or
- it is an edge or vertex contact whose point q lies on no triangle that the sphere touches with
  a face contact (q would be a point of that face: the face contact already holds it), and no
  triangle earlier in the cell's list gives the same point q (one contact per shared edge point
  or vertex).

Two faces that meet at an angle (the bottom of a V, a floor and a wall) each give their own face
contact, as two flat walls would.

History across triangles. Each sphere has ``MESH_SLOTS`` contact slots, each holding the contact's
history (the tangential spring, m, and, for the "impact" law, its phase and last normal velocity:
:data:`dem.kernels.contact.HISTORY_WIDTH` floats) and the normal of its last contact. A contact
takes the slot whose last normal is closest to its own (within ``MATCH_COS``), so a sphere sliding
from one triangle to the next in a flat or gently curved region keeps its spring; slots nothing
claimed are reset.

Index. Triangles are binned once into a uniform grid over the mesh's bounding box padded by the
reach (largest radius plus skin): each cell lists every triangle whose padded bounding box meets
it, so a sphere needs only the list of the cell its centre lies in, and a sphere outside the
padded box touches nothing. The cost per sphere is that of the few triangles near it, whatever
the triangle count.
"""

import math

import numba
import numpy as np

from dem.config import NUMBA_OPTIONS
from dem.kernels.contact import P_SLIP_ARM, P_WALL_ARM, contact_force
from dem.kernels.periodic import wrap

#: Contact slots (tangential springs) per sphere for mesh contacts.
MESH_SLOTS = 4
#: A contact continues a slot whose last normal n_old has n . n_old >= this (45 degrees).
MATCH_COS = math.cos(math.radians(45.0))
#: Points closer than this fraction of the radius are the same contact point.
SAME_POINT = 1e-9

FACE = 0
EDGE = 1
VERTEX = 2


@numba.njit(inline="always", **NUMBA_OPTIONS)
def closest_point(px, py, pz, tri, t):
    """Point of triangle ``tri[t]`` (3 corners x 3) closest to p, and the feature it lies on.

    Returns:
        (qx, qy, qz, feature): feature FACE, EDGE or VERTEX.

    """
    ax, ay, az = tri[t, 0, 0], tri[t, 0, 1], tri[t, 0, 2]
    bx, by, bz = tri[t, 1, 0], tri[t, 1, 1], tri[t, 1, 2]
    cx, cy, cz = tri[t, 2, 0], tri[t, 2, 1], tri[t, 2, 2]
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return ax, ay, az, VERTEX
    bpx, bpy, bpz = px - bx, py - by, pz - bz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return bx, by, bz, VERTEX
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        s = d1 / (d1 - d3)
        return ax + s * abx, ay + s * aby, az + s * abz, EDGE
    cpx, cpy, cpz = px - cx, py - cy, pz - cz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return cx, cy, cz, VERTEX
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        s = d2 / (d2 - d6)
        return ax + s * acx, ay + s * acy, az + s * acz, EDGE
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        s = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return bx + s * (cx - bx), by + s * (cy - by), bz + s * (cz - bz), EDGE
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    return ax + abx * v + acx * w, ay + aby * v + acy * w, az + abz * v + acz * w, FACE


@numba.njit(inline="always", **NUMBA_OPTIONS)
def cell_of(px, py, pz, grid, dims):
    """Index of the index cell holding p, or -1 outside the padded bounding box."""
    ix = int(math.floor((px - grid[0]) / grid[3]))
    iy = int(math.floor((py - grid[1]) / grid[3]))
    iz = int(math.floor((pz - grid[2]) / grid[3]))
    if ix < 0 or iy < 0 or iz < 0 or ix >= dims[0] or iy >= dims[1] or iz >= dims[2]:
        return -1
    return (iz * dims[1] + iy) * dims[0] + ix


@numba.njit(inline="always", **NUMBA_OPTIONS)
def counted(px, py, pz, r, tri, cell_tris, lo, hi, m, qx, qy, qz, feature):
    """True if the contact of list entry m (point q, ``feature``) counts (module docstring)."""
    if feature == FACE:
        return True
    tol = SAME_POINT * r
    tol2 = tol * tol
    for e in range(lo, hi):
        if e == m:
            continue
        t = cell_tris[e]
        ox, oy, oz, of = closest_point(px, py, pz, tri, t)
        dx, dy, dz = px - ox, py - oy, pz - oz
        if dx * dx + dy * dy + dz * dz >= r * r:
            continue  # t does not touch the sphere
        if of == FACE:
            # does q lie on face t? its closest point to q is q itself
            sx, sy, sz, _ = closest_point(qx, qy, qz, tri, t)
            ex, ey, ez = sx - qx, sy - qy, sz - qz
            if ex * ex + ey * ey + ez * ez <= tol2:
                return False
        elif e < m:
            ex, ey, ez = ox - qx, oy - qy, oz - qz
            if ex * ex + ey * ey + ez * ez <= tol2:
                return False  # the same point, counted at the earlier triangle
    return True


@numba.njit(inline="always", **NUMBA_OPTIONS)
def mesh_cell(i, x, mesh):
    """Sphere i's centre x in the section and its index cell's list: (px, lo, hi).

    The cell lists ``mesh.cell_tris[lo:hi]``; lo == hi where it lists none or the centre lies
    outside the padded bounding box.
    """
    return cell_list(i, x, mesh.grid, mesh.dims, mesh.cell_start)


@numba.njit(inline="always", **NUMBA_OPTIONS)
def cell_list(i, x, grid, dims, cell_start):
    """:func:`mesh_cell` with the index's arrays as arguments.

    Arrays, not the named tuple: the GPU compiles this source too (:mod:`dem.kernels.cuda.mesh`).
    """
    px = x[i, 0]
    if grid[4] > 0.0:
        px = wrap(px, grid[4])
    c = cell_of(px, x[i, 1], x[i, 2], grid, dims)
    if c < 0:
        return px, 0, 0
    return px, cell_start[c], cell_start[c + 1]


@numba.njit(inline="always", **NUMBA_OPTIONS)
def mesh_contact(e, px, py, pz, r, tri, cell_tris, lo, hi):
    """The sphere (centre p, radius r) and the triangle of list entry e: (dx, dy, dz, d2, touch).

    d = p - q with q the triangle's closest point, d2 = |d|^2; ``touch`` where the sphere overlaps
    it and the contact counts (module docstring: no double counting).
    """
    qx, qy, qz, feature = closest_point(px, py, pz, tri, cell_tris[e])
    dx, dy, dz = px - qx, py - qy, pz - qz
    d2 = dx * dx + dy * dy + dz * dz
    touch = d2 < r * r and d2 != 0.0
    if touch:
        touch = counted(px, py, pz, r, tri, cell_tris, lo, hi, e, qx, qy, qz, feature)
    return dx, dy, dz, d2, touch


@numba.njit(inline="always", **NUMBA_OPTIONS)
def mesh_touches(i, x, r, mesh):
    """The number of mesh contacts of sphere i (radius r): those :func:`mesh_forces` adds."""
    px, lo, hi = mesh_cell(i, x, mesh)
    count = 0
    for e in range(lo, hi):
        if mesh_contact(e, px, x[i, 1], x[i, 2], r, mesh.tri, mesh.cell_tris, lo, hi)[4]:
            count += 1
    return count


@numba.njit(inline="always", **NUMBA_OPTIONS)
def mesh_wall_forces(i, model, p, x, v, omega, radius, mass, dt, mesh, fx, fy, fz, tx, ty, tz):
    """(fx, ..., tz) plus the forces and torques of sphere i's mesh contacts, N and N m.

    ``mesh`` is a :class:`dem.kernels.layout.MeshArrays`; its slot rows ``MESH_SLOTS i + s``
    are sphere i's (module docstring), updated. The centre is taken in the section [0, length)
    along x (``mesh.grid[4]``; the mesh is periodic there, :mod:`dem.scene.mesh`). A sphere whose
    cell lists no triangle only resets its slots here; the others call :func:`mesh_forces` (a call,
    not inlined: inlined into every step kernel it took two minutes to compile).
    """
    return mesh_walls(
        i, model, p, x, v, omega, radius, mass, dt, mesh.tri, mesh.grid, mesh.dims,
        mesh.cell_start, mesh.cell_tris, mesh.slot_hist, mesh.slot_normal, fx, fy, fz, tx, ty, tz,
    )  # fmt: skip


@numba.njit(inline="always", **NUMBA_OPTIONS)
def mesh_walls(
    i, model, p, x, v, omega, radius, mass, dt, tri, grid, dims, cell_start, cell_tris,
    slot_hist, slot_normal, fx, fy, fz, tx, ty, tz,
):  # fmt: skip
    """:func:`mesh_wall_forces` with the mesh's arrays as arguments.

    Arrays, not the named tuple: the GPU compiles this source too (:mod:`dem.kernels.cuda.mesh`).
    """
    px, lo, hi = cell_list(i, x, grid, dims, cell_start)
    if lo == hi:
        for row in range(MESH_SLOTS * i, MESH_SLOTS * i + MESH_SLOTS):
            for k in range(slot_hist.shape[1]):
                slot_hist[row, k] = 0.0
            for k in range(3):
                slot_normal[row, k] = 0.0
        return fx, fy, fz, tx, ty, tz
    f = mesh_forces(
        model, p, dt, tri, lo, hi, cell_tris, slot_hist, slot_normal, MESH_SLOTS * i, px, x[i, 1],
        x[i, 2], v[i, 0], v[i, 1], v[i, 2], omega[i, 0], omega[i, 1], omega[i, 2], radius[i],
        mass[i], fx, fy, fz, tx, ty, tz,
    )  # fmt: skip
    return f[0], f[1], f[2], f[3], f[4], f[5]


@numba.njit(**NUMBA_OPTIONS)
def mesh_forces(
    model, p, dt, tri, lo, hi, cell_tris, slot_hist, slot_normal, base, px, py, pz,
    vx, vy, vz, wx, wy, wz, r, m, fx, fy, fz, tx, ty, tz,
):  # fmt: skip
    """(fx, ..., tz) plus the force and torque of one sphere's mesh contacts, N and N m.

    The sphere: centre (px, py, pz) in the section, velocity, spin, radius r and mass m; its
    index cell lists ``cell_tris[lo:hi]``; its slots are rows ``base`` to ``base + MESH_SLOTS``
    (module docstring). Scalars, not the sphere arrays: a numba call passes each array as about
    seven arguments. Each contact is added in turn (the order of the flat walls' sums).
    """
    claimed = 0  # bit s: slot s continued or started this step
    for e in range(lo, hi):
        dx, dy, dz, d2, touch = mesh_contact(e, px, py, pz, r, tri, cell_tris, lo, hi)
        if not touch:
            continue
        d = math.sqrt(d2)
        nx, ny, nz = dx / d, dy / d, dz / d
        # the slot whose last normal is closest, else a free one
        best = -1
        best_dot = MATCH_COS
        free = -1
        for s in range(MESH_SLOTS):
            if claimed & (1 << s):
                continue
            row = base + s
            ox, oy, oz = slot_normal[row, 0], slot_normal[row, 1], slot_normal[row, 2]
            if ox == 0.0 and oy == 0.0 and oz == 0.0:
                if free < 0:
                    free = s
                continue
            dot = nx * ox + ny * oy + nz * oz
            if dot >= best_dot:
                best_dot = dot
                best = s
        if best < 0:
            best = free
            if best < 0:  # more contacts than slots: take the last one's spring
                best = MESH_SLOTS - 1
            row = base + best
            for k in range(slot_hist.shape[1]):
                slot_hist[row, k] = 0.0
        claimed |= 1 << best
        row = base + best
        slot_normal[row, 0] = nx
        slot_normal[row, 1] = ny
        slot_normal[row, 2] = nz
        delta = r - d  # a fixed wall: m* = m, R* = r, lever arm r - f_w delta
        f = contact_force(
            model, p, nx, ny, nz, delta, vx, vy, vz, wx, wy, wz, 0.0, 0.0, 0.0,
            r - p[P_WALL_ARM] * delta, 0.0, r - (1.0 - p[P_SLIP_ARM]) * p[P_WALL_ARM] * delta, 0.0,
            m, r, slot_hist, row, dt,
        )  # fmt: skip
        fx, fy, fz = fx + f[0], fy + f[1], fz + f[2]
        tx, ty, tz = tx + f[3], ty + f[4], tz + f[5]
    for s in range(MESH_SLOTS):
        if not claimed & (1 << s):
            row = base + s
            for k in range(slot_hist.shape[1]):
                slot_hist[row, k] = 0.0
            for k in range(3):
                slot_normal[row, k] = 0.0
    return fx, fy, fz, tx, ty, tz


@numba.njit(**NUMBA_OPTIONS)
def mesh_gaps(x, tri, grid, dims, cell_start, cell_tris):
    """Distance of each point (n, 3) to the mesh, (n,), m; inf beyond the index's reach."""
    n = x.shape[0]
    out = np.full(n, np.inf)
    for i in range(n):
        px = wrap(x[i, 0], grid[4]) if grid[4] > 0.0 else x[i, 0]
        c = cell_of(px, x[i, 1], x[i, 2], grid, dims)
        if c < 0:
            continue
        best = np.inf
        for e in range(cell_start[c], cell_start[c + 1]):
            qx, qy, qz, _ = closest_point(px, x[i, 1], x[i, 2], tri, cell_tris[e])
            dx, dy, dz = px - qx, x[i, 1] - qy, x[i, 2] - qz
            best = min(best, dx * dx + dy * dy + dz * dz)
        out[i] = math.sqrt(best)
    return out


@numba.njit(**NUMBA_OPTIONS)
def mesh_sides(x, tri, normals, grid, dims, cell_start, cell_tris):
    """Per point: (x - q) . n_t of the closest triangle t (q its closest point), (n,), m.

    Positive on the side the triangles' normals point to (the grains' side), negative behind
    the mesh, nan beyond the index's reach.
    """
    n = x.shape[0]
    out = np.full(n, np.nan)
    for i in range(n):
        px = wrap(x[i, 0], grid[4]) if grid[4] > 0.0 else x[i, 0]
        c = cell_of(px, x[i, 1], x[i, 2], grid, dims)
        if c < 0:
            continue
        best = np.inf
        for e in range(cell_start[c], cell_start[c + 1]):
            t = cell_tris[e]
            qx, qy, qz, _ = closest_point(px, x[i, 1], x[i, 2], tri, t)
            dx, dy, dz = px - qx, x[i, 1] - qy, x[i, 2] - qz
            d2 = dx * dx + dy * dy + dz * dz
            if d2 < best:
                best = d2
                out[i] = dx * normals[t, 0] + dy * normals[t, 1] + dz * normals[t, 2]
    return out
