"""Rigid clumps on the GPU: one thread per body reduces, kicks, rotates and places its members.

The CPU engine's clump step (:func:`dem.kernels.integrate.advance_clumps`) in two launches:

1. :func:`dem.kernels.cuda.step.step_kernel` without its kick, one thread per member sphere:
   the contact forces on the member (pairs and walls, no body force: ``a_body`` = 0), its
   torque about its own centre, the history;
2. :func:`bodies_kernel`, one thread per body, as
   :func:`dem.kernels.integrate.bodies_forces_kick` does it for body b: the members' forces
   and torques reduced to F_b and T_b about the centre of mass X_b (members in their CSR order,
   the same sums in the same order), plus M a_body; the closing half kick V += dt/2 F/M,
   L += dt/2 T, omega = R I^-1 R^T L; M V_x added to the body's momentum sum; with
   ``next_drift`` the next step's half kick, drift, free rotation and wrap of X_x; then the
   members placed (x = X + R d, v = V + omega x R d, spin omega) and the rebuild trip written
   where a member moved past skin/2 (:mod:`dem.kernels.cuda.step`).

Each body writes only its own rows and its members' rows. The rigid body's physics is written
once: a body's kick, drift and free rotation (the symmetric Lie-Poisson splitting), its members'
placement and their arms are the CPU engine's functions (:func:`dem.kernels.rigid.
kick_drift_one`, :func:`~dem.kernels.rigid.place_member`, :func:`~dem.kernels.rigid.
member_arm`) compiled from their source as device functions (:mod:`dem.kernels.cuda.source`).
A body's members are placed in one loop that checks each for a rebuild as it goes, as
:func:`dem.kernels.rigid.place_members_of` places them: ptxas then gives the kernels the
registers and the double-precision operations of the hand-written glue they replace.
The simulator tests (tests/engine/test_gpu_engine.py) hold the two engines to the bit.
"""

from numba import cuda

from dem.kernels import rigid as _rigid
from dem.kernels.cuda.source import device
from dem.kernels.cuda.step import moved_past
from dem.kernels.periodic import wrap

#: :func:`dem.kernels.rigid.kick_drift_one` compiled from its source: body b's half kick (and,
#: with ``drift``, its drift and free rotation), then its angular velocity.
kick_drift = device(_rigid.kick_drift_one, store_omega=device(_rigid.store_omega))
#: :func:`dem.kernels.rigid.place_member` compiled from its source: member s of body b placed.
place_member = device(_rigid.place_member)
#: :func:`dem.kernels.rigid.member_arm` compiled from its source: member s's arm from X_b.
member_arm = device(_rigid.member_arm)


@cuda.jit(device=True)
def _place_members(
    b, body_x, body_v, q, body_omega, offsets, start, members, x, v, omega, seq, trip, x_ref,
    length, limit, check,
):  # fmt: skip
    """Members of body b placed (:func:`dem.kernels.rigid.place_members_of`).

    With ``check``, a member past skin/2 trips a rebuild.
    """
    for e in range(start[b], start[b + 1]):
        s = members[e]
        place_member(s, b, body_x, body_v, q, body_omega, offsets, x, v, omega)
        if check and moved_past(x, x_ref, s, length, limit):
            trip[0] = seq


@cuda.jit(device=True)
def _drift_place(
    b, drift, dt, rotation, body_x, body_v, q, ang_mom, body_force, body_torque, inv_mass,
    inertia, body_omega, offsets, start, members, x, v, omega, seq, trip, x_ref, length, limit,
):  # fmt: skip
    """The next step's half kick, drift, free rotation and wrap (with ``drift``); members placed.

    With ``drift`` a member past skin/2 trips a rebuild.
    """
    if drift:
        kick_drift(
            b, dt, True, rotation, body_x, body_v, q, ang_mom, body_force, body_torque, inv_mass,
            inertia, body_omega,
        )  # fmt: skip
        body_x[b, 0] = wrap(body_x[b, 0], length)
    _place_members(
        b, body_x, body_v, q, body_omega, offsets, start, members, x, v, omega, seq, trip, x_ref,
        length, limit, drift,
    )  # fmt: skip


@cuda.jit(device=True)
def _reduce(b, force, torque, x, body_x, start, members, length):
    """F_b and T_b about X_b from the members (:func:`dem.kernels.rigid.reduce_to_bodies`)."""
    fx = fy = fz = 0.0
    tx = ty = tz = 0.0
    for e in range(start[b], start[b + 1]):
        s = members[e]
        rx, ry, rz = member_arm(x, s, body_x, b, length)
        f0 = force[s, 0]
        f1 = force[s, 1]
        f2 = force[s, 2]
        fx += f0
        fy += f1
        fz += f2
        tx += torque[s, 0] + ry * f2 - rz * f1
        ty += torque[s, 1] + rz * f0 - rx * f2
        tz += torque[s, 2] + rx * f1 - ry * f0
    return fx, fy, fz, tx, ty, tz


@cuda.jit(device=True)
def _body_force(
    b, force, torque, x, body_x, start, members, length, body_mass, ax, ay, az, body_force,
    body_torque,
):  # fmt: skip
    """F_b = sum F_s + M a_body and T_b about X_b into body b's rows."""
    fx, fy, fz, tx, ty, tz = _reduce(b, force, torque, x, body_x, start, members, length)
    m = body_mass[b]
    body_force[b, 0] = fx + m * ax
    body_force[b, 1] = fy + m * ay
    body_force[b, 2] = fz + m * az
    body_torque[b, 0] = tx
    body_torque[b, 1] = ty
    body_torque[b, 2] = tz


@cuda.jit
def reduce_kernel(
    force, torque, x, body_x, start, members, length, body_mass, acc, row, bscene, body_force,
    body_torque,
):  # fmt: skip
    """Thread b: F_b = sum F_s + M a_body and T_b about X_b, no kick; a_body = acc[row, bscene[b]].

    A force evaluation at rest (:func:`dem.kernels.integrate.evaluate_forces_clumps`).
    """
    b = cuda.grid(1)
    if b >= body_x.shape[0]:
        return
    _body_force(b, force, torque, x, body_x, start, members, length, body_mass,
                acc[row, bscene[b], 0], acc[row, bscene[b], 1], acc[row, bscene[b], 2],
                body_force, body_torque)  # fmt: skip


@cuda.jit
def half_step_kernel(
    seq, trip, dt, rotation, body_x, body_v, q, ang_mom, body_force, body_torque, inv_mass,
    inertia, body_omega, offsets, start, members, x, v, omega, x_ref, length, limit,
):  # fmt: skip
    """Thread b: a call's first half kick, drift, free rotation and wrap; members placed.

    As :func:`dem.kernels.integrate._bodies_half_step`; a member past skin/2 trips a rebuild.
    """
    b = cuda.grid(1)
    if b >= body_x.shape[0] or trip[0] < seq:
        return
    _drift_place(
        b, True, dt, rotation, body_x, body_v, q, ang_mom, body_force, body_torque, inv_mass,
        inertia, body_omega, offsets, start, members, x, v, omega, seq, trip, x_ref, length,
        limit,
    )  # fmt: skip


@cuda.jit
def bodies_kernel(
    seq, trip, dt, acc, row, bscene, rotation, next_drift, force, torque, x, v, omega, body_x,
    body_v, q, ang_mom, body_force, body_torque, body_omega, inv_mass, body_mass, inertia, offsets,
    start, members, x_ref, length, limit, px,
):  # fmt: skip
    """Thread b: reduce, M a_body, closing kick, momentum, next drift, members placed.

    As the module docstring says. ``px[b] += M V_x``; ``force``/``torque``: the members'
    contact forces of :func:`dem.kernels.cuda.step.step_kernel` in the same step; a_body =
    ``acc[row, bscene[b]]`` (:func:`dem.kernels.cuda.step.step_kernel`).
    """
    b = cuda.grid(1)
    if b >= body_x.shape[0] or trip[0] < seq:
        return
    _body_force(b, force, torque, x, body_x, start, members, length, body_mass,
                acc[row, bscene[b], 0], acc[row, bscene[b], 1], acc[row, bscene[b], 2],
                body_force, body_torque)  # fmt: skip
    m = body_mass[b]
    kick_drift(
        b, dt, False, rotation, body_x, body_v, q, ang_mom, body_force, body_torque, inv_mass,
        inertia, body_omega,
    )  # fmt: skip
    px[b] += m * body_v[b, 0]
    _drift_place(
        b, next_drift, dt, rotation, body_x, body_v, q, ang_mom, body_force, body_torque,
        inv_mass, inertia, body_omega, offsets, start, members, x, v, omega, seq, trip, x_ref,
        length, limit,
    )  # fmt: skip
