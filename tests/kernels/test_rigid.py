"""Rigid clumps: reduction against brute force, free-rotor invariants, Dzhanibekov flip, order."""

import math

import numba
import numpy as np
import pytest
from numba import njit

from dem.kernels import rigid

I_ASYM = np.array([1.0, 2.0, 3.0])


@pytest.fixture
def one_thread():
    """Serial kernels for the long step loops: 1e5 parallel regions of one body each cost far
    more than they save, and much more again when the two cores are shared."""
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(threads)


def _one(q, ang_mom, inertia):
    return (
        np.array(q, dtype=np.float64).reshape(1, 4),
        np.array(ang_mom, dtype=np.float64).reshape(1, 3),
        np.array(inertia, dtype=np.float64).reshape(1, 3),
    )


def _random_quats(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


def _matrices(q):
    return np.array([rigid.quat_to_matrix(qi) for qi in q])


def _body_omega(q, ang_mom, inertia):
    out = np.empty_like(ang_mom)
    rigid.body_frame_angular_velocity(q, ang_mom, inertia, out)
    return out


@njit(cache=True)
def _euler_rk4(omega0, inertia, dt, n_steps, every):
    """Oracle: Euler's equations I dOmega/dt = (I Omega) x Omega, classical RK4, body frame."""
    out = np.empty((n_steps // every + 1, 3))
    w = omega0.copy()
    out[0] = w
    i0, i1, i2 = inertia[0], inertia[1], inertia[2]

    def f(w):
        return np.array(
            [
                (i1 - i2) * w[1] * w[2] / i0,
                (i2 - i0) * w[2] * w[0] / i1,
                (i0 - i1) * w[0] * w[1] / i2,
            ]
        )

    for s in range(1, n_steps + 1):
        k1 = f(w)
        k2 = f(w + 0.5 * dt * k1)
        k3 = f(w + 0.5 * dt * k2)
        k4 = f(w + dt * k3)
        w = w + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        if s % every == 0:
            out[s // every] = w
    return out


def _sign_changes(t, y):
    """Times where y changes sign (linear interpolation)."""
    k = np.flatnonzero(np.sign(y[1:]) != np.sign(y[:-1]))
    return t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])


def _run_free(q, ang_mom, inertia, dt, n_steps, every):
    """Free rotation of B bodies: body-frame Omega (k, B, 3) and energies (k, B), final q."""
    q = q.copy()
    omegas = [_body_omega(q, ang_mom, inertia)]
    for s in range(1, n_steps + 1):
        rigid.free_rotation(q, ang_mom, inertia, dt, q)
        if s % every == 0:
            omegas.append(_body_omega(q, ang_mom, inertia))
    omegas = np.array(omegas)
    return omegas, 0.5 * np.sum(inertia * omegas**2, axis=2), q


# --- helpers ----------------------------------------------------------------------------------
def test_quaternion_matrix_round_trip():
    rng = np.random.default_rng(1)
    q = _random_quats(rng, 50)
    r = _matrices(q)
    np.testing.assert_allclose(r @ np.transpose(r, (0, 2, 1)), np.broadcast_to(np.eye(3), r.shape),
                               atol=1e-14)  # fmt: skip
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-14)
    back = np.array([rigid.matrix_to_quat(ri) for ri in r])
    np.testing.assert_allclose(back, q * np.sign(q[:, :1]), atol=1e-14)
    # omega = R I^-1 R^T L against NumPy
    ang_mom = rng.normal(size=(50, 3))
    inertia = rng.uniform(0.5, 3.0, size=(50, 3))
    omega = np.empty((50, 3))
    rigid.angular_velocity(q, ang_mom, inertia, omega)
    body = np.einsum("bji,bj->bi", r, ang_mom) / inertia
    np.testing.assert_allclose(omega, np.einsum("bij,bj->bi", r, body), atol=1e-13)
    energy = 0.5 * np.sum(body * body * inertia)
    assert rigid.rotational_energy(q, ang_mom, inertia) == pytest.approx(energy, rel=1e-13)


# --- sphere -> body reduction -----------------------------------------------------------------
def test_reduce_to_bodies_equals_brute_force_with_periodic_wrap():
    rng = np.random.default_rng(2)
    length, n_bodies = 0.05, 40
    counts = rng.integers(1, 9, n_bodies)
    n = int(counts.sum())
    body_of = np.repeat(np.arange(n_bodies), counts)
    perm = rng.permutation(n)  # members scattered through the sphere arrays
    body_of_sphere = np.empty(n, dtype=np.int64)
    body_of_sphere[perm] = body_of
    body_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    body_members = perm.astype(np.int64)
    body_x = np.column_stack([rng.uniform(0, length, n_bodies), rng.normal(size=(n_bodies, 2))])
    body_x[:5, 0] = [0.0005, 0.001, 0.049, 0.0499, 0.025]  # clumps across the seam
    rel = rng.uniform(-0.004, 0.004, size=(n, 3))
    x = body_x[body_of_sphere] + rel
    x[:, 0] %= length  # the neighbour build wraps sphere centres into [0, length)
    force = rng.normal(size=(n, 3))
    torque = rng.normal(size=(n, 3))
    out_f = np.empty((n_bodies, 3))
    out_t = np.empty((n_bodies, 3))
    rigid.reduce_to_bodies(force, torque, x, body_x, body_start, body_members, length, out_f, out_t)
    for b in range(n_bodies):
        f = np.zeros(3)
        t = np.zeros(3)
        for s in range(n):
            if body_of_sphere[s] == b:
                r = x[s] - body_x[b]
                r[0] -= length * round(r[0] / length)
                f += force[s]
                t += torque[s] + np.cross(r, force[s])
        np.testing.assert_allclose(out_f[b], f, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(out_t[b], t, rtol=1e-12, atol=1e-13)


def test_equal_and_opposite_member_forces_give_a_pure_couple():
    body_x = np.array([[0.0999, 0.0, 0.01]])
    d1, d2 = np.array([0.0003, 0.001, 0.0]), np.array([-0.0004, -0.002, 0.0005])
    x = body_x + np.array([d1, d2])
    x[:, 0] %= 0.1  # the first member wraps to x = 0.0002
    f = np.array([[0.0, 0.0, 2.0], [0.0, 0.0, -2.0]])
    out_f, out_t = np.empty((1, 3)), np.empty((1, 3))
    rigid.reduce_to_bodies(f, np.zeros((2, 3)), x, body_x, np.array([0, 2]), np.array([0, 1]),
                           0.1, out_f, out_t)  # fmt: skip
    np.testing.assert_allclose(out_f[0], 0.0, atol=1e-15)
    np.testing.assert_allclose(out_t[0], np.cross(d1 - d2, f[0]), rtol=1e-9)


# --- free rotation ----------------------------------------------------------------------------
@pytest.mark.validation
def test_torque_free_asymmetric_body_conserves_energy_and_momentum(one_thread):
    rng = np.random.default_rng(3)
    n_bodies, dt, n_steps, every = 8, 0.01, 100_000, 100
    q = _random_quats(rng, n_bodies)
    inertia = np.tile(I_ASYM, (n_bodies, 1))
    inertia[1:] = rng.uniform(0.5, 3.0, size=(n_bodies - 1, 3))
    # |omega| ~ 1 rad/s: 1000 s is about 160 turns, dt |omega| = 0.01
    ang_mom = np.einsum("bij,bj->bi", _matrices(q), inertia * rng.normal(size=(n_bodies, 3)))
    ang_mom0 = ang_mom.copy()
    _, energies, q_end = _run_free(q, ang_mom, inertia, dt, n_steps, every)
    energies = energies.T
    assert np.abs(np.linalg.norm(q_end, axis=1) - 1.0).max() < 1e-14  # renormalised each step
    rel = energies / energies[:, :1] - 1.0
    quarter = rel.shape[1] // 4
    first, last = np.abs(rel[:, :quarter]).max(axis=1), np.abs(rel[:, -quarter:]).max(axis=1)
    # measured: max |dE/E| 9.5e-7 for I = (1, 2, 3), at most 3.7e-6 over the 8 bodies, the same
    # (to 3 digits) in the first and the last quarter; fitted slope < 1.5e-8 per 1000 s
    assert np.all(np.abs(rel).max(axis=1) < 2e-5)
    assert np.all(last < 1.5 * first + 1e-12)  # bounded oscillation, no secular growth
    np.testing.assert_array_equal(ang_mom, ang_mom0)  # L is not written by the free flight


@pytest.mark.validation
def test_intermediate_axis_flips_and_outer_axes_are_stable(one_thread):
    eps, dt, t_end = 1e-3, 0.005, 200.0
    n_steps, every = int(round(t_end / dt)), 10
    t = np.arange(n_steps // every + 1) * every * dt
    for axis in range(3):
        omega0 = np.full(3, eps)
        omega0[axis] = 1.0
        q = np.array([[1.0, 0.0, 0.0, 0.0]])
        q_, ang_mom, inertia = _one(q, I_ASYM * omega0, I_ASYM)
        omegas, _, _ = _run_free(q_, ang_mom, inertia, dt, n_steps, every)
        w = omegas[:, 0, :]
        flips = _sign_changes(t, w[:, axis])
        if axis == 1:
            ref = _euler_rk4(omega0, I_ASYM, dt / 10, 10 * n_steps, 10 * every)
            ref_flips = _sign_changes(t, ref[:, axis])
            assert len(flips) >= 4  # the Dzhanibekov (tennis-racket) flip, periodically
            assert len(flips) == len(ref_flips)
            # measured: flip times agree with the RK4 oracle to 3e-5 s (half period 27.53 s)
            np.testing.assert_allclose(flips, ref_flips, atol=1e-3)
            np.testing.assert_allclose(np.diff(flips), np.diff(flips).mean(), rtol=0.01)
        else:
            assert len(flips) == 0
            assert np.all(w[:, axis] > 0.999)
            others = [k for k in range(3) if k != axis]
            assert np.abs(w[:, others]).max() < 10 * eps


def test_free_rotation_is_second_order(one_thread):
    q0, ang_mom, inertia = _one([0.9, 0.1, -0.3, 0.2], [0.7, -1.1, 2.3], I_ASYM)
    q0 /= np.linalg.norm(q0)
    t_end = 10.0

    def end(dt):
        q = q0.copy()
        for _ in range(int(round(t_end / dt))):
            rigid.free_rotation(q, ang_mom, inertia, dt, q)
        return rigid.quat_to_matrix(q[0])

    ref = end(1e-4)
    errors = np.array([np.linalg.norm(end(dt) - ref) for dt in (0.04, 0.02, 0.01)])
    ratios = errors[:-1] / errors[1:]
    # measured: errors 2.61e-4, 6.52e-5, 1.63e-5; ratios 4.000, 4.000
    np.testing.assert_allclose(ratios, 4.0, rtol=0.05)


@pytest.mark.validation
def test_kicked_rotation_is_second_order(one_thread):
    """Constant force F on one member at body offset d: torque (R d) x F, through the kernels."""
    d = np.array([[0.3, -0.1, 0.2]])
    force = np.array([[0.0, 0.0, -5.0]])
    inertia = np.array([I_ASYM])
    body_of = np.zeros(1, dtype=np.int64)
    start, members = np.array([0, 1]), np.array([0])
    zeros = np.zeros((1, 3))
    t_end = 2.0

    def torque_of(q, ang_mom, out):
        x, v, w = np.empty((1, 3)), np.empty((1, 3)), np.empty((1, 3))
        omega = np.empty((1, 3))
        rigid.angular_velocity(q, ang_mom, inertia, omega)
        rigid.update_members(zeros, zeros, q, omega, d, body_of, x, v, w)
        rigid.reduce_to_bodies(force, zeros, x, zeros, start, members, 0.0, np.empty((1, 3)), out)

    def end(dt):
        q = np.array([[1.0, 0.0, 0.0, 0.0]])
        ang_mom = np.array([[0.5, 1.0, -0.5]])
        torque = np.empty((1, 3))
        torque_of(q, ang_mom, torque)
        for _ in range(int(round(t_end / dt))):
            rigid.kick_angular(ang_mom, torque, 0.5 * dt)
            rigid.free_rotation(q, ang_mom, inertia, dt, q)
            torque_of(q, ang_mom, torque)
            rigid.kick_angular(ang_mom, torque, 0.5 * dt)
        return rigid.quat_to_matrix(q[0])

    ref = end(2e-4)
    errors = np.array([np.linalg.norm(end(dt) - ref) for dt in (0.04, 0.02, 0.01)])
    ratios = errors[:-1] / errors[1:]
    # measured: errors 2.59e-4, 6.48e-5, 1.62e-5; ratios 4.001, 4.001
    np.testing.assert_allclose(ratios, 4.0, rtol=0.05)


@pytest.mark.parametrize(
    "moments", [(1.0, 1.0, 2.5), (2.5, 1.0, 1.0), (1.0, 2.5, 2.5), (2.5, 1.0, 2.5), (2.0, 2.0, 2.0)]
)
def test_symmetric_top_is_exact(one_thread, moments):
    """Two equal moments: the splitting is exact, so a large and a small dt agree."""
    q0, ang_mom, inertia = _one([0.8, 0.2, 0.4, -0.4], [0.3, -0.8, 1.5], moments)
    q0 /= np.linalg.norm(q0)

    def end(dt, n):
        q = q0.copy()
        for _ in range(n):
            rigid.free_rotation(q, ang_mom, inertia, dt, q)
        return q

    np.testing.assert_allclose(end(0.5, 8), end(0.005, 800), atol=1e-12)


# --- members ----------------------------------------------------------------------------------
def test_members_move_on_circles_and_stay_rigid(one_thread):
    rng = np.random.default_rng(5)
    n, dt, n_steps = 6, 0.01, 500
    offsets = rng.uniform(-0.003, 0.003, size=(n, 3))
    body_of = np.zeros(n, dtype=np.int64)
    inertia = np.full((1, 3), 2e-9)
    omega0 = np.array([3.0, -4.0, 12.0])  # |omega| = 13 rad/s
    ang_mom = inertia * omega0
    q = np.array([[0.6, 0.0, 0.8, 0.0]])
    body_x, body_v = np.array([[0.02, 0.001, 0.005]]), np.array([[0.1, 0.0, -0.05]])
    x, v, w = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    omega = np.empty((1, 3))
    r0 = rigid.quat_to_matrix(q[0]) @ offsets.T
    dist0 = np.linalg.norm(offsets[:, None] - offsets[None], axis=2)
    k = omega0 / np.linalg.norm(omega0)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    for s in range(1, n_steps + 1):
        rigid.free_rotation(q, ang_mom, inertia, dt, q)
        body_x += dt * body_v
        rigid.angular_velocity(q, ang_mom, inertia, omega)
        rigid.update_members(body_x, body_v, q, omega, offsets, body_of, x, v, w)
        phi = np.linalg.norm(omega0) * s * dt
        rot = np.eye(3) + math.sin(phi) * kx + (1 - math.cos(phi)) * kx @ kx  # Rodrigues
        rel = (rot @ r0).T
        np.testing.assert_allclose(x, body_x + rel, rtol=0, atol=1e-15)
        np.testing.assert_allclose(v, body_v + np.cross(omega0, rel), rtol=0, atol=1e-13)
        np.testing.assert_allclose(w, np.broadcast_to(omega0, (n, 3)), rtol=1e-14)
    # circles: distance from the axis through the centre of mass and speed |omega| rho are kept
    rho0 = np.linalg.norm(np.cross(k, r0.T), axis=1)
    rho = np.linalg.norm(np.cross(k, x - body_x), axis=1)
    np.testing.assert_allclose(rho, rho0, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(v - body_v, axis=1), 13.0 * rho0, rtol=1e-12)
    dist = np.linalg.norm(x[:, None] - x[None], axis=2)
    # rigid to the rounding of the absolute positions (|x| ~ 0.5 m: one ulp is 1.1e-16 m)
    np.testing.assert_allclose(dist, dist0, rtol=0, atol=4 * np.spacing(np.abs(x).max()))


@pytest.mark.validation
def test_fused_body_step_equals_the_separate_kernels():
    rng = np.random.default_rng(6)
    nb, dt = 30, 1e-3
    q = _random_quats(rng, nb)
    ang_mom, inertia = rng.normal(size=(nb, 3)), rng.uniform(0.5, 3.0, size=(nb, 3))
    x, v = rng.normal(size=(nb, 3)), rng.normal(size=(nb, 3))
    f, t, inv_m = rng.normal(size=(nb, 3)), rng.normal(size=(nb, 3)), rng.uniform(1, 2, nb)
    # reference: kick, drift, rotate, omega with the separate kernels
    v_ref = v + 0.5 * dt * inv_m[:, None] * f
    x_ref = x + dt * v_ref
    l_ref = ang_mom.copy()
    rigid.kick_angular(l_ref, t, 0.5 * dt)
    q_ref = np.empty_like(q)
    rigid.free_rotation(q, l_ref, inertia, dt, q_ref)
    w_ref = np.empty((nb, 3))
    rigid.angular_velocity(q_ref, l_ref, inertia, w_ref)
    omega = np.empty((nb, 3))
    rigid.kick_drift_bodies(dt, True, True, x, v, q, ang_mom, f, t, inv_m, inertia, omega)
    for got, want in ((x, x_ref), (v, v_ref), (q, q_ref), (ang_mom, l_ref), (omega, w_ref)):
        np.testing.assert_allclose(got, want, rtol=1e-14, atol=1e-15)
    # closing half kick: no drift, q kept; rotation off: L kept
    x0, q0, l0 = x.copy(), q.copy(), ang_mom.copy()
    rigid.kick_drift_bodies(dt, False, False, x, v, q, ang_mom, f, t, inv_m, inertia, omega)
    np.testing.assert_array_equal(x, x0)
    np.testing.assert_array_equal(q, q0)
    np.testing.assert_array_equal(ang_mom, l0)
    np.testing.assert_allclose(v, v_ref + 0.5 * dt * inv_m[:, None] * f, rtol=1e-14)
