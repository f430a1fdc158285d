"""Contact laws: forces against a brute-force twin, conservation, two-sphere impacts."""

import math

import numpy as np
import pytest
from naive_dem import all_forces

from dem.engine.simulation import ContactLaw, Simulation
from dem.engine.state import Spheres
from dem.kernels import contact
from dem.scene.trough import Trough

LENGTH, WIDTH = 0.012, 0.010


def _packing(rng, n=40, length=LENGTH, width=WIDTH, zmax=0.006):
    r = rng.uniform(1.0e-3, 1.5e-3, n)
    x = np.column_stack(
        [
            rng.uniform(0, length, n),
            rng.uniform(-width / 2, width / 2, n),
            rng.uniform(0.5e-3, zmax, n),
        ]
    )
    return x, r


def _coefficients(model, e, mu, mu_roll, limit, tangential="liggghts", arm="surface"):
    return {
        "kn": 2.0e3, "kt_ratio": 0.4, "E": 1.0e7, "nu": 0.25, "e": e, "mu": mu,
        "mu_roll": mu_roll, "limit": limit, "tangential": tangential, "zeta_t": 0.7,
        "f_t": 2 / 7, "arm": "radius" if arm == "lammps" else arm,
        "f_w": {"surface": 1.0, "midpoint": 0.5, "lammps": 0.0}[arm],
        "slip": "radius" if arm == "lammps" else "contact",
    }  # fmt: skip


def _law(model, c):
    return ContactLaw(
        model,
        contact.make_params(
            model=model, stiffness=c["kn"], tangential_stiffness_ratio=c["kt_ratio"],
            youngs_modulus=c["E"],
            poisson_ratio=c["nu"], restitution=c["e"], friction=c["mu"],
            rolling_friction=c["mu_roll"], limit_force=c["limit"], tangential=c["tangential"],
            tangential_damping_ratio=c["zeta_t"], tangential_mass_factor=c["f_t"],
            wall_lever_arm=c.get("arm", "surface"), slip_lever_arm=c.get("slip", "contact"),
        ),
    )  # fmt: skip


@pytest.mark.parametrize("arm", ["surface", "midpoint", "lammps"])
@pytest.mark.parametrize("tangential", ["liggghts", "coulomb"])
@pytest.mark.parametrize(
    ("model", "e", "mu", "mu_roll", "limit", "dt"),
    [
        ("linear", 0.5, 0.3, 0.0, False, 1e-5),
        ("linear", 0.0, 0.3, 0.1, True, 1e-3),
        ("hertz_mindlin", 0.3, 0.5, 0.05, False, 1e-5),
        ("hertz_mindlin", 0.9, 0.2, 0.0, True, 1e-3),
    ],
)
def test_forces_match_brute_force_twin(model, e, mu, mu_roll, limit, dt, tangential, arm):
    """Forces and torques equal an O(N^2) NumPy twin, over periodic images and walls, twice:
    the second evaluation after a move and a rebuild uses the carried-over tangential history.
    The wall lever arms r - delta, LIGGGHTS's r - delta / 2, and LAMMPS's arms (slip velocity at
    the full radii, wall torque at r)."""
    rng = np.random.default_rng(7)
    x, r = _packing(rng)
    c = _coefficients(model, e, mu, mu_roll, limit, tangential, arm)
    spheres = Spheres.create(x, r, 2500.0)
    sim = Simulation(spheres, Trough(LENGTH, WIDTH, inclination=0.1), _law(model, c), dt)
    history = {}
    crossing = 0
    for _ in range(2):
        spheres.v[:] = rng.normal(0, 0.3, (len(r), 3))
        spheres.omega[:] = rng.normal(0, 300.0, (len(r), 3))
        sim.compute_forces()
        f_ref, t_ref = all_forces(
            model, c, spheres.x, spheres.v, spheres.omega, spheres.radius, spheres.mass,
            LENGTH, WIDTH, sim.gravity, dt, history,
        )  # fmt: skip
        scale = np.max(np.abs(f_ref))
        np.testing.assert_allclose(spheres.force, f_ref, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(spheres.torque, t_ref, rtol=0, atol=1e-10 * scale * r.max())
        spheres.x += rng.normal(0, 1e-4, spheres.x.shape)
        crossing += sum(1 for (i, j) in history if j >= 0 and abs(x[i, 0] - x[j, 0]) > 0.5 * LENGTH)
    assert len(history) > 30  # many contacts, walls included
    assert crossing > 0  # some through the periodic boundary


def test_internal_forces_conserve_momentum_and_angular_momentum():
    rng = np.random.default_rng(3)
    n = 50
    length, width = 0.2, 0.2
    x, r = _packing(rng, n=n, length=0.015, width=0.015, zmax=0.012)
    x[:, 0] += 0.09  # away from the periodic boundary: plain coordinates are the positions
    x[:, 2] += 0.02  # away from the floor
    c = _coefficients("hertz_mindlin", 0.4, 0.4, 0.1, False)
    spheres = Spheres.create(x, r, 2500.0)
    sim = Simulation(spheres, Trough(length, width), _law("hertz_mindlin", c), 1e-4)
    sim.gravity[:] = 0.0
    spheres.v[:] = rng.normal(0, 0.5, (n, 3))
    spheres.omega[:] = rng.normal(0, 500.0, (n, 3))
    sim.compute_forces()
    scale = np.max(np.abs(spheres.force))
    assert scale > 0 and sim.pairs.n_pairs > 20
    np.testing.assert_allclose(spheres.force.sum(axis=0), 0.0, atol=1e-12 * scale * n)
    total_torque = np.cross(spheres.x, spheres.force).sum(axis=0) + spheres.torque.sum(axis=0)
    np.testing.assert_allclose(total_torque, 0.0, atol=1e-12 * scale * n * 0.1)


def test_beta_is_critical_at_zero_restitution():
    assert contact.damping_beta(0.0) == -1.0
    assert contact.damping_beta(1.0) == 0.0
    b = contact.damping_beta(0.5)
    assert math.isclose(math.exp(math.pi * b / math.sqrt(1 - b * b)), 0.5)


def _head_on(law, radius, density, speed, dt):
    """Two equal spheres colliding head-on along x; returns (restitution, contact time)."""
    x = np.array([[0.05 - radius - 1e-6, 0.0, 0.05], [0.05 + radius + 1e-6, 0.0, 0.05]])
    spheres = Spheres.create(x, radius, density)
    spheres.v[0, 0] = 0.5 * speed
    spheres.v[1, 0] = -0.5 * speed
    sim = Simulation(spheres, Trough(0.1, 0.1), law, dt, rotation=False)
    sim.gravity[:] = 0.0
    gaps = [spheres.x[1, 0] - spheres.x[0, 0] - 2 * radius]
    for _ in range(200000):
        sim.advance(1)
        gaps.append(spheres.x[1, 0] - spheres.x[0, 0] - 2 * radius)
        if gaps[-1] > 0 and min(gaps) < 0:
            break
    g = np.array(gaps)
    inside = np.flatnonzero(g < 0)
    a, b = inside[0], inside[-1]
    t_in = (a - 1 + g[a - 1] / (g[a - 1] - g[a])) * dt  # linear interpolation of gap = 0
    t_out = (b + g[b] / (g[b] - g[b + 1])) * dt
    e = (spheres.v[1, 0] - spheres.v[0, 0]) / speed
    return e, t_out - t_in


@pytest.mark.parametrize("e", [0.9, 0.5, 0.2])
def test_linear_head_on_restitution_and_contact_time_are_exact(e):
    """Linear law: e and t_c = pi / sqrt(k/m* - (gamma/2m*)^2) hold exactly (to O(dt))."""
    kn, radius, density = 1.0e4, 1.0e-3, 2500.0
    law = ContactLaw("linear", contact.make_params(model="linear", stiffness=kn, restitution=e))
    m_eff = 0.5 * density * 4 / 3 * math.pi * radius**3
    t_c = contact.linear_collision_time(kn, m_eff, contact.damping_beta(e))
    e_sim, t_sim = _head_on(law, radius, density, 0.5, t_c / 2000)
    assert e_sim == pytest.approx(e, rel=1e-3)
    assert t_sim == pytest.approx(t_c, rel=1e-3)


def test_hertz_head_on_contact_time_is_hertzian():
    """Elastic Hertz impact: t_c = 2.9432 delta_max / v (2.87 (m*^2/(R* Y*^2 v))^(1/5))."""
    youngs, nu, radius, density, speed = 1.0e7, 0.3, 1.0e-3, 2500.0, 0.5
    law = ContactLaw(
        "hertz_mindlin",
        contact.make_params(
            model="hertz_mindlin", youngs_modulus=youngs, poisson_ratio=nu, restitution=1.0
        ),
    )
    m_eff = 0.5 * density * 4 / 3 * math.pi * radius**3
    ystar = youngs / (2 * (1 - nu**2))
    delta_max = contact.hertz_max_overlap(ystar, radius / 2, m_eff, speed)
    # t_c = 2 delta_max / v * int_0^1 dx / sqrt(1 - x^(5/2)) = (4/5) B(2/5, 1/2) delta_max / v
    t_exact = 0.8 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9) * delta_max / speed
    assert t_exact == pytest.approx(
        contact.hertz_collision_time(ystar, radius / 2, m_eff, speed), rel=2e-3
    )
    e_sim, t_sim = _head_on(law, radius, density, speed, t_exact / 2000)
    assert e_sim == pytest.approx(1.0, abs=1e-4)
    assert t_sim == pytest.approx(t_exact, rel=2e-3)


@pytest.mark.parametrize("e", [0.8, 0.5, 0.2])
def test_hertz_head_on_restitution_follows_liggghts_beta(e):
    """Hertz with LIGGGHTS damping gives the set e within 0.005 (measured 2e-4, dt = t_H/2000)."""
    youngs, nu, radius, density, speed = 1.0e7, 0.3, 1.0e-3, 2500.0, 0.5
    law = ContactLaw(
        "hertz_mindlin",
        contact.make_params(
            model="hertz_mindlin", youngs_modulus=youngs, poisson_ratio=nu, restitution=e
        ),
    )
    m_eff = 0.5 * density * 4 / 3 * math.pi * radius**3
    t_h = contact.hertz_collision_time(youngs / (2 * (1 - nu**2)), radius / 2, m_eff, speed)
    e_sim, _ = _head_on(law, radius, density, speed, t_h / 2000)
    assert e_sim == pytest.approx(e, abs=5e-3)


@pytest.mark.parametrize("model", ["linear", "hertz_mindlin"])
def test_coulomb_convention_never_exceeds_the_friction_limit(model):
    """'coulomb' caps spring plus dashpot at mu |F_n|; 'liggghts' caps the spring alone, so a
    damped sticking contact can transmit more (the reason the default changed)."""
    rng = np.random.default_rng(3)
    worst = {}
    for tangential in ("coulomb", "liggghts"):
        c = _coefficients(model, 0.0, 0.3, 0.0, False, tangential)
        p = _law(model, c).params
        ratio = 0.0
        for _ in range(2000):
            n = rng.normal(size=3)
            n /= np.linalg.norm(n)
            hist = rng.normal(0, 2e-6, (1, 3))
            v = rng.normal(0, 0.05, 3)
            f = contact.contact_force(
                contact.MODELS[model], p, *n, rng.uniform(1e-6, 1e-4), *v, 0.0, 0.0, 0.0,
                0.0, 0.0, 0.0, 1e-3, 1e-3, 1e-3, 1e-3, 1e-4, 1e-3, hist, 0, 1e-6,
            )  # fmt: skip
            force = np.array(f[:3])
            ft = force - np.dot(force, n) * n
            ratio = max(ratio, np.linalg.norm(ft) / (0.3 * abs(f[9])))
        worst[tangential] = ratio
    assert worst["coulomb"] <= 1.0 + 1e-12
    assert worst["liggghts"] > 1.05


def test_coulomb_reset_never_adds_spring_force_along_the_slip():
    """The 'coulomb' law's reset (contact.coulomb_tangential): where the plain reset, the spring
    set to the capped force less the dashpot's, stores no more force along the slip than the
    spring held (none if it held none), the result is the plain one bit for bit; elsewhere the
    force is the same and only the stored spring differs, holding at most what it held along
    the slip. The plain arithmetic is the impact law's stick's (passive False)."""
    rng = np.random.default_rng(11)
    kept = changed = 0
    for _ in range(4000):
        kt, gt = rng.uniform(0.5, 2.0), rng.uniform(0.0, 2.0) * (rng.random() < 0.9)
        s, v = rng.normal(0.0, 1.0, 3), rng.normal(0.0, 1.0, 3)
        f_max = rng.uniform(0.0, 1.5) * np.linalg.norm(-kt * s - gt * v)
        new = np.array(contact.coulomb_tangential(kt, gt, f_max, *s, *v, True))
        plain = np.array(contact.coulomb_tangential(kt, gt, f_max, *s, *v, False))
        f_old = -kt * s  # the spring's force before the reset
        held = max(float(np.dot(f_old, v)), 0.0)
        stored = float(np.dot(-kt * plain[3:], v))
        if stored <= held:
            assert np.array_equal(new, plain)
            kept += 1
        else:
            assert np.array_equal(new[:3], plain[:3])
            tol = 1e-12 * np.linalg.norm(f_old) * np.linalg.norm(v)
            assert np.dot(-kt * new[3:], v) <= held + tol
            assert gt > 0.0  # without a dashpot the capped force is the spring's own: no change
            changed += 1
    assert kept > 1000 and changed > 100


def test_wall_lever_arm_moves_the_contact_point_into_the_overlap():
    """A spinning sphere pressed into the floor: the wall torque is -c n x F_t with c = r - delta
    ("surface") or r - delta / 2 ("midpoint"), and the slip velocity is the spin times the same
    c: the two settings differ exactly by the lever arm."""
    r, delta, spin = 1.0e-3, 2.0e-5, 50.0
    out = {}
    for arm in ("surface", "midpoint"):
        c = _coefficients("linear", 0.5, 0.3, 0.0, False, "liggghts", arm)
        spheres = Spheres.create(np.array([[0.006, 0.0, r - delta]]), np.array([r]), 2500.0)
        spheres.omega[0] = (0.0, spin, 0.0)
        sim = Simulation(spheres, Trough(LENGTH, WIDTH), _law("linear", c), 1e-6)
        sim.compute_forces()
        out[arm] = (spheres.force[0].copy(), spheres.torque[0].copy())
    for arm, f_w in (("surface", 1.0), ("midpoint", 0.5)):
        force, torque = out[arm]
        ft = np.array([force[0], force[1], 0.0])
        lever = r - f_w * delta
        np.testing.assert_allclose(torque, -lever * np.cross([0.0, 0.0, 1.0], ft), rtol=1e-12)
        # the slip at the contact is -(c omega) x n and F_t is linear in it (first step)
        assert ft[0] == pytest.approx(out["surface"][0][0] * lever / (r - delta), rel=1e-12)
        assert ft[0] != 0.0
    assert out["surface"][1][1] != out["midpoint"][1][1]


@pytest.mark.parametrize("wall_arm", ["surface", "radius"])
def test_slip_lever_arm_radius_takes_the_slip_at_the_full_radius(wall_arm):
    """Two spheres spinning alike, pressed together, and one pressed into the floor: with
    slip_lever_arm = "radius" the slip is the spin times the full radius r, with "contact" times
    the torque's arm (r - delta/2 between grains, r - f_w delta at the floor); F_t is linear in
    the slip on the first step, and the torques keep their arms either way."""
    r, delta, spin = 1.0e-3, 2.0e-5, 50.0
    f_w = {"surface": 1.0, "radius": 0.0}[wall_arm]
    out = {}
    for slip in ("contact", "radius"):
        c = dict(_coefficients("linear", 0.5, 0.3, 0.0, False, "coulomb"), arm=wall_arm,
                 slip=slip)  # fmt: skip
        x = np.array([[0.003, 0.0, 0.004], [0.003, 0.0, 0.004 + 2 * r - delta],
                      [0.009, 0.0, r - delta]])  # fmt: skip
        spheres = Spheres.create(x, np.full(3, r), 2500.0)
        spheres.omega[:] = (0.0, spin, 0.0)
        sim = Simulation(spheres, Trough(LENGTH, WIDTH), _law("linear", c), 1e-6)
        sim.compute_forces()
        out[slip] = (spheres.force.copy(), spheres.torque.copy())
    pair_arm, wall_torque_arm = r - 0.5 * delta, r - f_w * delta
    f_pair = out["radius"][0][0, 0]
    assert f_pair == pytest.approx(out["contact"][0][0, 0] * r / pair_arm, rel=1e-12)
    f_wall = out["radius"][0][2, 0]
    assert f_wall == pytest.approx(out["contact"][0][2, 0] * r / wall_torque_arm, rel=1e-12)
    for slip in ("contact", "radius"):
        force, torque = out[slip]
        ft = np.array([force[2, 0], force[2, 1], 0.0])
        np.testing.assert_allclose(torque[2], -wall_torque_arm * np.cross([0, 0, 1.0], ft),
                                   rtol=1e-12)  # fmt: skip
        n = np.array([0.0, 0.0, -1.0])  # from the upper sphere (j) to the lower (i)
        ft = force[0] - np.dot(force[0], n) * n
        np.testing.assert_allclose(torque[0], -pair_arm * np.cross(n, ft), rtol=1e-9,
                                   atol=1e-18)  # fmt: skip
    assert f_pair != 0.0 and f_wall != 0.0


def test_settle_failure_names_the_incline_and_only_advises_eps_n_where_it_helps():
    """A fill that cannot rest on an incline (spheres roll) says so; with eps_n = 0 already
    (critical damping) it does not advise lowering eps_n."""
    from dem.errors import SimulationError

    rng = np.random.default_rng(3)
    x, r = _packing(rng, n=10)
    spheres = Spheres.create(x, r, 2500.0)
    law = _law("linear", _coefficients("linear", 0.0, 0.3, 0.0, False, "coulomb"))
    sim = Simulation(spheres, Trough(LENGTH, WIDTH, inclination=math.radians(20.0)), law, 1e-5)
    with pytest.raises(SimulationError) as info:
        sim.settle(max_time=0.01)
    message = str(info.value)
    assert "inclined 20 deg" in message
    assert "restitution_normal" not in message


def test_equivalent_material_is_the_contact_of_two_materials():
    """An Al2O3 sphere on an Al-alloy wall (Chung and Ooi's tests 4-6): the one material whose
    contact with itself has the pair's Hertz modulus Y* and Mindlin modulus G*, so dem's
    one-material law is that contact; between the two Poisson ratios (kappa = 4 G*/Y* is a
    weighted mean of each material's own), symmetric, itself for one material."""
    e1, nu1, e2, nu2 = 3.8e11, 0.23, 7.0e10, 0.33
    y_star, g_star = contact.contact_moduli(e1, nu1, e2, nu2)
    assert y_star == pytest.approx(1.0 / ((1 - nu1**2) / e1 + (1 - nu2**2) / e2), rel=1e-15)
    g1, g2 = e1 / (2 * (1 + nu1)), e2 / (2 * (1 + nu2))
    assert g_star == pytest.approx(1.0 / ((2 - nu1) / g1 + (2 - nu2) / g2), rel=1e-14)
    youngs, nu = contact.equivalent_material(e1, nu1, e2, nu2)
    assert nu1 < nu < nu2
    p = contact.make_params(model="hertz_mindlin", youngs_modulus=youngs, poisson_ratio=nu)
    assert p[contact.P_YSTAR] == pytest.approx(y_star, rel=1e-14)
    assert p[contact.P_GSTAR] == pytest.approx(g_star, rel=1e-14)
    assert contact.equivalent_material(e2, nu2, e1, nu1) == pytest.approx((youngs, nu), rel=1e-14)
    assert contact.equivalent_material(e2, nu2, e2, nu2) == pytest.approx((e2, nu2), rel=1e-14)
    # a rigid partner leaves the sphere's own compliance
    assert contact.contact_moduli(e2, nu2, math.inf, 0.3)[0] == pytest.approx(e2 / (1 - nu2**2))


@pytest.mark.parametrize("width", sorted(set(contact.HISTORY_WIDTH.values())))
def test_clear_row_zeroes_its_row_only(width):
    """clear_row writes its stores out for the widths the laws have: every column, no other row."""
    import numba

    from dem.kernels.forces import clear_row

    @numba.njit
    def clear(hist, row):
        clear_row(hist, row)

    assert set(contact.HISTORY_WIDTH.values()) <= {3, 5}, "clear_row writes 3 or 5 columns"
    hist = np.full((3, width), -1.5)
    hist[1, 0] = -0.0
    clear(hist, 1)
    assert np.all(hist[[0, 2]] == -1.5)
    assert np.all(hist[1] == 0.0) and not np.any(np.signbit(hist[1]))
