"""Rigid multi-sphere clumps: sphere -> body reduction, rotation integrator, member update.

A clump (``body``) owns several spheres (its members). Bodies carry their centre of mass X (B, 3),
its velocity V (B, 3), a unit quaternion q = (w, x, y, z) (B, 4), the angular momentum L (B, 3)
in the trough (lab) frame and the body-frame principal moments I (B, 3). R(q) maps body-frame
vectors to the trough frame; member s of body b sits at x_s = X_b + R(q_b) d_s with a fixed
body-frame offset d_s (n, 3). The trough frame accelerates but does not rotate: the uniform
fictitious force acts at the centre of mass and adds no torque.

One velocity-Verlet step of dt for the bodies (:func:`kick_drift_bodies` fuses 1-2 and 6)::

    1. V += dt/2 F/M, L += dt/2 T        (kick_angular; T: torque about X, trough frame)
    2. X += dt V, q <- Phi_free(dt) q    (free_rotation; L is constant in free flight)
    3. omega = R I^-1 R^T L; members x, v, spin (angular_velocity, update_members)
    4. neighbour list, pair forces, per-sphere gather (unchanged sphere kernels)
    5. F, T about X per body (reduce_to_bodies) + M a_body
    6. V += dt/2 F/M, L += dt/2 T; omega; member v, spin (update_members)

Phi_free is the symmetric (Strang) Lie-Poisson splitting of the free rigid body
H = sum_k pi_k^2 / (2 I_k), pi = R^T L the body-frame angular momentum, into a symmetric top
and one axis rotation (Touma & Wisdom, Astron. J. 107, 1189 (1994); the "symmetric" splitting of
Fasso, J. Comput. Phys. 189, 527 (2003); the three-axis variant is Dullweber, Leimkuhler &
McLachlan, J. Chem. Phys. 107, 5840 (1997) and NO_SQUISH, Miller et al., J. Chem. Phys. 116,
8649 (2002)). With the moments sorted I_s <= I_m <= I_l and alpha = 1 / I_m,
beta_k = 1 / I_k - alpha::

    H = alpha |pi|^2 / 2  +  beta_s pi_s^2 / 2  +  beta_l pi_l^2 / 2
        (Casimir: rotation     (rotation about        (rotation about
         about pi)              body axis s)           body axis l)

    Phi_free(dt) = A_l(dt/2) o [C(dt) o A_s(dt)] o A_l(dt/2)

Each flow is an exact rotation of the body: about body axis k by theta = dt beta_k pi_k
(q <- q (cos theta/2, sin theta/2 e_k), pi <- R_k(theta)^T pi), and about pi by
phi = dt alpha |pi| (q <- q (cos phi/2, sin phi/2 pi/|pi|), pi unchanged). C commutes with
everything, so the scheme is exact for a sphere-symmetric body and for a symmetric top (screws:
I_s = I_m or I_m = I_l, equal to the bit), and second order, symplectic and time-reversible in
general; with the kicks the whole step is the second-order symplectic splitting
kick(dt/2) free(dt) kick(dt/2).
L is never touched by the free flight, so torque-free L (and |L|) is conserved exactly; the
energy error is O(dt^2) and bounded (no secular drift). Each sub-rotation multiplies q by a unit
quaternion, so |q| = 1 holds to rounding; q is renormalised once per step to stop the rounding
random walk (this does not change the scheme).

Kernels take arrays and scalars and write into ``out_*`` arrays (``out_*`` may alias the input
of the same shape); parallel loops run over bodies (or over spheres in :func:`update_members`)
and each iteration writes only its own row: race-free by construction. Units SI: m, s, kg, N,
N m, kg m^2/s, rad/s.
"""

import math

import numba
import numpy as np

from dem.config import NUMBA_OPTIONS, NUMBA_PARALLEL_OPTIONS
from dem.kernels.periodic import nearest_image


# --- quaternion helpers (scalar, inlined into the kernels) ------------------------------------
@numba.njit(**NUMBA_OPTIONS)
def rotate(w, qx, qy, qz, vx, vy, vz):
    """R(q) v for a unit quaternion q = (w, qx, qy, qz): v + 2 w (u x v) + 2 u x (u x v)."""
    tx = 2.0 * (qy * vz - qz * vy)
    ty = 2.0 * (qz * vx - qx * vz)
    tz = 2.0 * (qx * vy - qy * vx)
    return (
        vx + w * tx + (qy * tz - qz * ty),
        vy + w * ty + (qz * tx - qx * tz),
        vz + w * tz + (qx * ty - qy * tx),
    )


@numba.njit(**NUMBA_OPTIONS)
def _rotate_t(w, qx, qy, qz, vx, vy, vz):
    """R(q)^T v = R(q*) v (trough frame -> body frame)."""
    return rotate(w, -qx, -qy, -qz, vx, vy, vz)


@numba.njit(**NUMBA_OPTIONS)
def _qmul_axis(w, qx, qy, qz, phi, nx, ny, nz):
    """Quaternion product q (cos phi/2, sin phi/2 n): a turn by phi about the body axis n."""
    c = math.cos(0.5 * phi)
    s = math.sin(0.5 * phi)
    return (
        c * w - s * (qx * nx + qy * ny + qz * nz),
        c * qx + s * (w * nx + qy * nz - qz * ny),
        c * qy + s * (w * ny + qz * nx - qx * nz),
        c * qz + s * (w * nz + qx * ny - qy * nx),
    )


@numba.njit(**NUMBA_OPTIONS)
def _axis_flow(k, theta, w, qx, qy, qz, p0, p1, p2):
    """Exact flow of beta_k pi_k^2 / 2: q <- q (cos theta/2, sin theta/2 e_k), pi <- R_k^T pi.

    theta = 0 (beta_k = 0: the symmetric top's flow about its equal axis) is the identity and is
    skipped, bit for bit the same; cos and sin of theta come from the half angle (two
    trigonometric calls per flow, not four).
    """
    if theta == 0.0:
        return w, qx, qy, qz, p0, p1, p2
    ch = math.cos(0.5 * theta)
    sh = math.sin(0.5 * theta)
    c = (ch - sh) * (ch + sh)
    s = 2.0 * sh * ch
    if k == 0:
        w, qx, qy, qz = w * ch - qx * sh, qx * ch + w * sh, qy * ch + qz * sh, qz * ch - qy * sh
        p1, p2 = c * p1 + s * p2, c * p2 - s * p1
    elif k == 1:
        w, qx, qy, qz = w * ch - qy * sh, qx * ch - qz * sh, qy * ch + w * sh, qz * ch + qx * sh
        p2, p0 = c * p2 + s * p0, c * p0 - s * p2
    else:
        w, qx, qy, qz = w * ch - qz * sh, qx * ch + qy * sh, qy * ch - qx * sh, qz * ch + w * sh
        p0, p1 = c * p0 + s * p1, c * p1 - s * p0
    return w, qx, qy, qz, p0, p1, p2


@numba.njit(**NUMBA_OPTIONS)
def _sorted_axes(i0, i1, i2):
    """Distinct axes (s, m, l) of the smallest, middle and largest principal moment."""
    moments = (i0, i1, i2)
    s = 0
    if moments[1] < moments[s]:
        s = 1
    if moments[2] < moments[s]:
        s = 2
    a = (s + 1) % 3
    c = (s + 2) % 3
    if moments[a] >= moments[c]:
        return s, c, a
    return s, a, c


@numba.njit(**NUMBA_OPTIONS)
def free_rotation_one(w, qx, qy, qz, lx, ly, lz, i0, i1, i2, dt):
    """One step dt of the free rotation of one body (module docstring); returns the unit q."""
    p0, p1, p2 = _rotate_t(w, qx, qy, qz, lx, ly, lz)
    moments = (i0, i1, i2)
    s, m, big = _sorted_axes(i0, i1, i2)
    alpha = 1.0 / moments[m]
    beta_s = 1.0 / moments[s] - alpha
    beta_l = 1.0 / moments[big] - alpha
    h = 0.5 * dt
    pl = (p0, p1, p2)[big]
    w, qx, qy, qz, p0, p1, p2 = _axis_flow(big, h * beta_l * pl, w, qx, qy, qz, p0, p1, p2)
    ps = (p0, p1, p2)[s]
    w, qx, qy, qz, p0, p1, p2 = _axis_flow(s, dt * beta_s * ps, w, qx, qy, qz, p0, p1, p2)
    norm = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    if norm > 0.0:
        w, qx, qy, qz = _qmul_axis(
            w, qx, qy, qz, dt * alpha * norm, p0 / norm, p1 / norm, p2 / norm
        )
    pl = (p0, p1, p2)[big]
    w, qx, qy, qz, p0, p1, p2 = _axis_flow(big, h * beta_l * pl, w, qx, qy, qz, p0, p1, p2)
    inv = 1.0 / math.sqrt(w * w + qx * qx + qy * qy + qz * qz)
    return w * inv, qx * inv, qy * inv, qz * inv


# --- public kernels ----------------------------------------------------------------------------
@numba.njit(**NUMBA_OPTIONS)
def quat_to_matrix(q):
    """Rotation matrix R(q) (3, 3) of a unit quaternion q = (w, x, y, z) (4,); x_lab = R d_body.

    R = [[1 - 2(y^2 + z^2), 2(xy - wz), 2(xz + wy)],
         [2(xy + wz), 1 - 2(x^2 + z^2), 2(yz - wx)],
         [2(xz - wy), 2(yz + wx), 1 - 2(x^2 + y^2)]].
    """
    w, x, y, z = q[0], q[1], q[2], q[3]
    r = np.empty((3, 3))
    r[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    r[0, 1] = 2.0 * (x * y - w * z)
    r[0, 2] = 2.0 * (x * z + w * y)
    r[1, 0] = 2.0 * (x * y + w * z)
    r[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    r[1, 2] = 2.0 * (y * z - w * x)
    r[2, 0] = 2.0 * (x * z - w * y)
    r[2, 1] = 2.0 * (y * z + w * x)
    r[2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return r


@numba.njit(**NUMBA_OPTIONS)
def matrix_to_quat(r):
    """Unit quaternion (4,) with w >= 0 of a proper rotation matrix r (3, 3) (Shepperd's method).

    Use it to start a clump from its principal axes: the columns of r are the body axes in the
    trough frame (e.g. the eigenvectors of the inertia tensor, made right-handed).
    """
    q = np.empty(4)
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    if tr >= r[0, 0] and tr >= r[1, 1] and tr >= r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + tr)
        q[0] = 0.25 * s
        q[1] = (r[2, 1] - r[1, 2]) / s
        q[2] = (r[0, 2] - r[2, 0]) / s
        q[3] = (r[1, 0] - r[0, 1]) / s
    elif r[0, 0] >= r[1, 1] and r[0, 0] >= r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q[0] = (r[2, 1] - r[1, 2]) / s
        q[1] = 0.25 * s
        q[2] = (r[0, 1] + r[1, 0]) / s
        q[3] = (r[0, 2] + r[2, 0]) / s
    elif r[1, 1] >= r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q[0] = (r[0, 2] - r[2, 0]) / s
        q[1] = (r[0, 1] + r[1, 0]) / s
        q[2] = 0.25 * s
        q[3] = (r[1, 2] + r[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q[0] = (r[1, 0] - r[0, 1]) / s
        q[1] = (r[0, 2] + r[2, 0]) / s
        q[2] = (r[1, 2] + r[2, 1]) / s
        q[3] = 0.25 * s
    if q[0] < 0.0:
        for c in range(4):
            q[c] = -q[c]
    inv = 1.0 / math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    for c in range(4):
        q[c] *= inv
    return q


@numba.njit(inline="always", **NUMBA_OPTIONS)
def member_arm(sphere_x, s, body_x, b, length):
    """r_s = x_s - X_b of member s of body b, x in the nearest periodic image (length > 0)."""
    rx = sphere_x[s, 0] - body_x[b, 0]
    if length > 0.0:
        rx = nearest_image(rx, length)
    return rx, sphere_x[s, 1] - body_x[b, 1], sphere_x[s, 2] - body_x[b, 2]


@numba.njit(inline="always", **NUMBA_OPTIONS)
def place_member(s, b, body_x, body_v, q, body_omega, offsets, out_x, out_v, out_omega):
    """Member s of body b: x_s = X_b + R d_s, v_s = V_b + omega_b x R d_s, omega_s = omega_b."""
    rx, ry, rz = rotate(
        q[b, 0], q[b, 1], q[b, 2], q[b, 3], offsets[s, 0], offsets[s, 1], offsets[s, 2]
    )
    ox, oy, oz = body_omega[b, 0], body_omega[b, 1], body_omega[b, 2]
    out_x[s, 0] = body_x[b, 0] + rx
    out_x[s, 1] = body_x[b, 1] + ry
    out_x[s, 2] = body_x[b, 2] + rz
    out_v[s, 0] = body_v[b, 0] + oy * rz - oz * ry
    out_v[s, 1] = body_v[b, 1] + oz * rx - ox * rz
    out_v[s, 2] = body_v[b, 2] + ox * ry - oy * rx
    out_omega[s, 0] = ox
    out_omega[s, 1] = oy
    out_omega[s, 2] = oz


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def reduce_to_bodies(
    force, torque, sphere_x, body_x, body_start, body_members, length, out_force, out_torque,
):  # fmt: skip
    """Total force and torque about the centre of mass of each body from its member spheres.

    F_b = sum_{s in b} F_s,   T_b = sum_{s in b} (T_s + r_s x F_s),   r_s = x_s - X_b

    with r_s in the minimum image along x (period ``length``; no wrap if length <= 0). T_s is the
    sphere's own torque about its centre (tangential contacts, rolling resistance). One thread per
    body, each writes only its own row: race-free.

    Args:
        force: Sphere forces F_s, (n, 3), N.
        torque: Sphere torques T_s about the sphere centres, (n, 3), N m.
        sphere_x: Sphere centres x_s, (n, 3), m.
        body_x: Body centres of mass X_b, (B, 3), m.
        body_start: CSR start of each body's members in ``body_members``, int64 (B + 1,).
        body_members: Sphere indices grouped by body, int64 (n,) (or more: only the CSR ranges
            are read).
        length: Period of the trough section in x, m.
        out_force: Body forces F_b, (B, 3), N.
        out_torque: Body torques T_b about X_b, trough frame, (B, 3), N m.

    """
    n_bodies = body_x.shape[0]
    for b in numba.prange(n_bodies):
        fx = fy = fz = 0.0
        tx = ty = tz = 0.0
        for e in range(body_start[b], body_start[b + 1]):
            s = body_members[e]
            rx, ry, rz = member_arm(sphere_x, s, body_x, b, length)
            f0, f1, f2 = force[s, 0], force[s, 1], force[s, 2]
            fx += f0
            fy += f1
            fz += f2
            tx += torque[s, 0] + ry * f2 - rz * f1
            ty += torque[s, 1] + rz * f0 - rx * f2
            tz += torque[s, 2] + rx * f1 - ry * f0
        out_force[b, 0] = fx
        out_force[b, 1] = fy
        out_force[b, 2] = fz
        out_torque[b, 0] = tx
        out_torque[b, 1] = ty
        out_torque[b, 2] = tz


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def kick_angular(ang_mom, torque, dt_half):
    """Half kick of the angular momentum in place: L += dt_half T.

    Args:
        ang_mom: L, trough frame, (B, 3), kg m^2/s; updated.
        torque: T about the centres of mass, trough frame, (B, 3), N m.
        dt_half: dt / 2, s.

    """
    for b in numba.prange(ang_mom.shape[0]):
        for c in range(3):
            ang_mom[b, c] += dt_half * torque[b, c]


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def free_rotation(q, ang_mom, inertia, dt, out_q):
    """Free (torque-free) rotation over dt by the symmetric splitting of the module docstring.

    Second order, symplectic, time-reversible; exact for sphere-symmetric bodies and symmetric
    tops. L is constant in free flight and is not written. out_q is renormalised.

    Args:
        q: Orientations, unit quaternions (w, x, y, z), (B, 4).
        ang_mom: L, trough frame, (B, 3), kg m^2/s.
        inertia: Body-frame principal moments (I_1, I_2, I_3) > 0, (B, 3), kg m^2.
        dt: Time step, s.
        out_q: New orientations, (B, 4) (may be ``q``).

    """
    for b in numba.prange(q.shape[0]):
        w, qx, qy, qz = free_rotation_one(
            q[b, 0], q[b, 1], q[b, 2], q[b, 3], ang_mom[b, 0], ang_mom[b, 1], ang_mom[b, 2],
            inertia[b, 0], inertia[b, 1], inertia[b, 2], dt,
        )  # fmt: skip
        out_q[b, 0] = w
        out_q[b, 1] = qx
        out_q[b, 2] = qy
        out_q[b, 3] = qz


@numba.njit(**NUMBA_OPTIONS)
def omega_one(w, qx, qy, qz, lx, ly, lz, i0, i1, i2):
    """Angular velocity R I^-1 R^T L of one body (trough frame)."""
    p0, p1, p2 = _rotate_t(w, qx, qy, qz, lx, ly, lz)
    return rotate(w, qx, qy, qz, p0 / i0, p1 / i1, p2 / i2)


@numba.njit(inline="always", **NUMBA_OPTIONS)
def store_omega(b, q, ang_mom, inertia, out_omega):
    """out_omega[b] = R I^-1 R^T L of body b."""
    o0, o1, o2 = omega_one(
        q[b, 0], q[b, 1], q[b, 2], q[b, 3], ang_mom[b, 0], ang_mom[b, 1], ang_mom[b, 2],
        inertia[b, 0], inertia[b, 1], inertia[b, 2],
    )  # fmt: skip
    out_omega[b, 0] = o0
    out_omega[b, 1] = o1
    out_omega[b, 2] = o2


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def angular_velocity(q, ang_mom, inertia, out_omega):
    """Angular velocity omega = R I^-1 R^T L in the trough frame, (B, 3), rad/s.

    Args:
        q: Orientations (B, 4); ang_mom: L (B, 3), kg m^2/s; inertia: principal moments
            (B, 3), kg m^2; out_omega: (B, 3), rad/s.

    """
    for b in numba.prange(q.shape[0]):
        store_omega(b, q, ang_mom, inertia, out_omega)


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def body_frame_angular_velocity(q, ang_mom, inertia, out_omega):
    """Body-frame angular velocity Omega = I^-1 R^T L, (B, 3), rad/s (arguments as above)."""
    for b in numba.prange(q.shape[0]):
        p0, p1, p2 = _rotate_t(
            q[b, 0], q[b, 1], q[b, 2], q[b, 3], ang_mom[b, 0], ang_mom[b, 1], ang_mom[b, 2]
        )
        out_omega[b, 0] = p0 / inertia[b, 0]
        out_omega[b, 1] = p1 / inertia[b, 1]
        out_omega[b, 2] = p2 / inertia[b, 2]


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def rotational_energy(q, ang_mom, inertia):
    """Total rotational kinetic energy E = sum_b sum_k pi_bk^2 / (2 I_bk), pi = R^T L, in J.

    Args:
        q: Orientations (B, 4); ang_mom: L (B, 3), kg m^2/s; inertia: (B, 3), kg m^2.

    """
    energy = 0.0
    for b in numba.prange(q.shape[0]):
        p0, p1, p2 = _rotate_t(
            q[b, 0], q[b, 1], q[b, 2], q[b, 3], ang_mom[b, 0], ang_mom[b, 1], ang_mom[b, 2]
        )
        energy += 0.5 * (
            p0 * p0 / inertia[b, 0] + p1 * p1 / inertia[b, 1] + p2 * p2 / inertia[b, 2]
        )
    return energy


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def kick_drift_bodies(
    dt, drift, rotation, body_x, body_v, q, ang_mom, body_force, body_torque, inv_mass, inertia,
    out_omega,
):  # fmt: skip
    """Fused per-body half step (one parallel region): the body twin of the sphere kick/drift.

    V += dt/2 F/M and (if ``rotation``) L += dt/2 T; then, if ``drift``, X += dt V and
    q <- Phi_free(dt) q (:func:`free_rotation`); last omega = R I^-1 R^T L. ``drift`` True is the
    first half of a step (kick, drift, rotate), False the closing half kick. With ``rotation``
    False L is left alone (keep it zero: then q and omega = 0 stay fixed).

    Args:
        dt: Time step, s.
        drift, rotation: Flags (above).
        body_x, body_v: X (m) and V (m/s), (B, 3); updated.
        q: Orientations (B, 4); updated if ``drift``.
        ang_mom: L, trough frame, (B, 3), kg m^2/s; updated.
        body_force, body_torque: F_b (N) and T_b about X_b (N m), (B, 3)
            (:func:`reduce_to_bodies` plus the body force M a_body).
        inv_mass: 1 / M, (B,), 1/kg.
        inertia: Principal moments, (B, 3), kg m^2.
        out_omega: omega, trough frame, (B, 3), rad/s.

    """
    for b in numba.prange(q.shape[0]):
        kick_drift_one(
            b, dt, drift, rotation, body_x, body_v, q, ang_mom, body_force, body_torque,
            inv_mass, inertia, out_omega,
        )  # fmt: skip


@numba.njit(**NUMBA_PARALLEL_OPTIONS)
def update_members(
    body_x, body_v, q, body_omega, offsets, body_of, out_x, out_v, out_omega,
):  # fmt: skip
    """Place the member spheres of rigid bodies and give them the rigid-body velocity field.

    x_s = X_b + R(q_b) d_s,   v_s = V_b + omega_b x (R(q_b) d_s),   omega_s = omega_b

    with b = body_of[s]. One thread per sphere, each writes only its own rows. Positions are not
    wrapped into the periodic section (the neighbour-list build does that).

    Args:
        body_x: Centres of mass X_b, (B, 3), m.
        body_v: Centre-of-mass velocities V_b, (B, 3), m/s.
        q: Orientations, unit quaternions, (B, 4).
        body_omega: Angular velocities omega_b, trough frame, (B, 3), rad/s
            (:func:`angular_velocity`).
        offsets: Member offsets d_s from the centre of mass in the body frame, (n, 3), m.
        body_of: Body of each sphere, int64 (n,).
        out_x, out_v, out_omega: Sphere positions (m), velocities (m/s), spins (rad/s), (n, 3).

    """
    for s in numba.prange(offsets.shape[0]):
        place_member(s, body_of[s], body_x, body_v, q, body_omega, offsets, out_x, out_v, out_omega)


# --- one body at a time (for fused loops over bodies, e.g. dem.kernels.integrate) -------------
@numba.njit(inline="always", **NUMBA_OPTIONS)
def kick_drift_one(
    b, dt, drift, rotation, body_x, body_v, q, ang_mom, body_force, body_torque, inv_mass, inertia,
    out_omega,
):  # fmt: skip
    """:func:`kick_drift_bodies` for body b only (the same operations, bit for bit)."""
    h = 0.5 * dt
    a = h * inv_mass[b]
    for c in range(3):
        body_v[b, c] += a * body_force[b, c]
        if rotation:
            ang_mom[b, c] += h * body_torque[b, c]
    if drift:
        for c in range(3):
            body_x[b, c] += dt * body_v[b, c]
        w, qx, qy, qz = free_rotation_one(
            q[b, 0], q[b, 1], q[b, 2], q[b, 3], ang_mom[b, 0], ang_mom[b, 1], ang_mom[b, 2],
            inertia[b, 0], inertia[b, 1], inertia[b, 2], dt,
        )  # fmt: skip
        q[b, 0] = w
        q[b, 1] = qx
        q[b, 2] = qy
        q[b, 3] = qz
    store_omega(b, q, ang_mom, inertia, out_omega)


@numba.njit(inline="always", **NUMBA_OPTIONS)
def place_members_of(
    b, body_x, body_v, q, body_omega, offsets, body_start, body_members, out_x, out_v, out_omega,
):  # fmt: skip
    """:func:`update_members` for the members of body b only (CSR ``body_start/members``)."""
    for e in range(body_start[b], body_start[b + 1]):
        place_member(
            body_members[e], b, body_x, body_v, q, body_omega, offsets, out_x, out_v, out_omega
        )
