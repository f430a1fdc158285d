"""Grain templates: analytic volumes and inertias, lens volumes, a brute-force voxel twin."""

import math

import numpy as np
import pytest

from dem import config
from dem.errors import InputError
from dem.io.liggghts import write_clump
from dem.physics import mass
from dem.scene import shapes

RHO = 7800.0
FAST = 1e-3  # grid tolerance in these tests (the default is tighter and slower)
# The voxel twin's tolerance in its own standard errors (6 shifted grids: Student t with 5
# degrees of freedom, P(|t| > 6) = 0.2 %; the vector and tensor norms are more conservative).
K = 6.0


def _lens(r, d):
    """Volume of the intersection of two spheres of radius r at distance d < 2 r."""
    return math.pi * (4.0 * r + d) * (2.0 * r - d) ** 2 / 12.0


def _rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def _analytic_disjoint(c, r):
    """Volume, centre and inertia per unit density of separate spheres (parallel-axis theorem)."""
    v = 4.0 / 3.0 * math.pi * r**3
    com = v @ c / v.sum()
    inertia = np.zeros((3, 3))
    for ci, ri, vi in zip(c, r, v, strict=True):
        d = ci - com
        inertia += 0.4 * vi * ri**2 * np.eye(3) + vi * (d @ d * np.eye(3) - np.outer(d, d))
    return v.sum(), com, inertia


def _voxels(c, r, h, shifts=6, seed=3):
    """Brute-force twin: voxel counts on randomly shifted grids of spacing h.

    Returns the means of volume, centre and inertia per unit density (about the centre) and
    their standard errors (volume, |com| and Frobenius norm of the inertia).
    """
    lo = (c - r[:, None]).min(axis=0) - h
    hi = (c + r[:, None]).max(axis=0) + h
    n = np.ceil((hi - lo) / h).astype(int)
    rng = np.random.default_rng(seed)
    results = []
    for _ in range(shifts):
        off = rng.random(3)
        axes = [lo[a] + h * (np.arange(n[a]) + off[a]) for a in range(3)]
        y, z = np.meshgrid(axes[1], axes[2], indexing="ij")
        m0, m1, m2 = 0.0, np.zeros(3), np.zeros((3, 3))
        for x in axes[0]:
            p = np.column_stack([np.full(y.size, x), y.ravel(), z.ravel()])
            inside = np.zeros(len(p), bool)
            for ci, ri in zip(c, r, strict=True):
                inside |= np.sum((p - ci) ** 2, axis=1) <= ri * ri
            q = p[inside]
            m0 += len(q)
            m1 += q.sum(axis=0)
            m2 += q.T @ q
        vol = m0 * h**3
        com = m1 * h**3 / vol
        s = m2 * h**3 - vol * np.outer(com, com)
        results.append((vol, com, np.trace(s) * np.eye(3) - s))
    vols = np.array([x[0] for x in results])
    coms = np.array([x[1] for x in results])
    inertias = np.array([x[2] for x in results])
    se = 1.0 / math.sqrt(shifts * (shifts - 1))
    return (
        (vols.mean(), coms.mean(axis=0), inertias.mean(axis=0)),
        (
            se * math.sqrt(np.sum((vols - vols.mean()) ** 2)),
            se * math.sqrt(np.sum((coms - coms.mean(axis=0)) ** 2)),
            se * math.sqrt(np.sum((inertias - inertias.mean(axis=0)) ** 2)),
        ),
    )


# --- analytic values ----------------------------------------------------------------------------


def test_single_sphere_exact():
    r = 2.0e-3
    t = shapes.sphere(r, RHO)
    v = 4.0 / 3.0 * math.pi * r**3
    assert t.method == "disjoint" and t.count == 1
    assert t.volume == pytest.approx(v, rel=1e-14)
    assert t.mass == pytest.approx(RHO * v, rel=1e-14)
    assert np.allclose(t.moments, 0.4 * t.mass * r**2, rtol=1e-14, atol=0)
    assert np.array_equal(t.centres, np.zeros((1, 3)))
    assert t.bounding_radius == pytest.approx(r)


@pytest.mark.parametrize("method", ["auto", "grid"])
def test_separate_spheres_parallel_axis(method):
    """Separate spheres: exact sums (auto picks 'disjoint'), or the grid within its bound."""
    c = np.array([[0.0, 0.0, 0.0], [3.0, 0.5, 0.0], [0.0, 2.5, 1.0], [1.2, -1.0, 2.0]])
    r = np.array([1.0, 1.2, 0.6, 0.5])
    vol, com, inertia = _analytic_disjoint(c, r)
    p = mass.union_properties(c, r, method=method, rtol=FAST)
    assert p.method == ("disjoint" if method == "auto" else "grid")
    if method == "auto":
        assert p.volume == pytest.approx(vol, rel=1e-13)
        assert np.allclose(p.com, com, rtol=0, atol=1e-13)
        assert np.allclose(p.inertia, inertia, rtol=1e-13, atol=1e-13)
    assert abs(p.volume - vol) <= p.volume_error
    assert np.linalg.norm(p.com - com) <= p.com_error
    assert np.linalg.norm(p.inertia - inertia) <= p.inertia_error
    assert p.volume_error <= 2 * FAST * vol  # the bound is also tight enough to be useful


def test_sphere_by_grid_within_bound():
    p = mass.union_properties([[0.3, -0.2, 0.1]], [1.0], method="grid", rtol=FAST)
    v = 4.0 / 3.0 * math.pi
    assert abs(p.volume - v) <= p.volume_error <= FAST * v
    assert np.linalg.norm(p.inertia - 0.4 * v * np.eye(3)) <= p.inertia_error


@pytest.mark.parametrize("d", [0.3, 1.0, 1.5, 1.99])
def test_two_overlapping_spheres_lens_volume(d):
    c = np.array([[0.0, 0.0, 0.0], [d, 0.0, 0.0]]) @ _rotation(1).T  # any direction
    exact = 2.0 * 4.0 / 3.0 * math.pi - _lens(1.0, d)
    axial = mass.union_properties(c, [1.0, 1.0])
    assert axial.method == "axial"
    assert axial.volume == pytest.approx(exact, rel=1e-13)
    assert np.allclose(axial.com, 0.5 * (c[0] + c[1]), atol=1e-14)
    grid = mass.union_properties(c, [1.0, 1.0], method="grid", rtol=FAST)
    assert abs(grid.volume - exact) <= grid.volume_error
    assert np.linalg.norm(grid.inertia - axial.inertia) <= grid.inertia_error


def test_three_sphere_ring_pairwise_lenses():
    """Three spheres on a triangle of side d with no point in all three (circumradius d/sqrt 3 >
    R): V = 3 V_sphere - 3 lens exactly; the grid method must agree within its bound."""
    d = 1.9
    c = np.array([[0, 0, 0], [d, 0, 0], [d / 2, d * math.sqrt(3) / 2, 0]]) @ _rotation(2).T
    p = mass.union_properties(c, np.ones(3), rtol=FAST)
    assert p.method == "grid"
    exact = 4.0 * math.pi - 3.0 * _lens(1.0, d)
    assert abs(p.volume - exact) <= p.volume_error
    assert np.linalg.norm(p.com - c.mean(axis=0)) <= p.com_error


# --- screw --------------------------------------------------------------------------------------

SCREW = {"length": 0.02, "shank_radius": 0.0015, "head_radius": 0.003}


def test_screw_mass_and_geometry():
    t = shapes.screw(**SCREW, mass=2.5e-3)
    assert t.mass == pytest.approx(2.5e-3, rel=1e-14)
    assert t.density * t.volume == pytest.approx(2.5e-3, rel=1e-14)
    assert t.method == "axial"
    x = t.input_centres()
    assert np.allclose(x[:, 1:], 0.0) and x[0, 0] == 0.0
    assert (x[-1, 0] + t.radii[-1]) - (x[0, 0] - t.radii[0]) == pytest.approx(SCREW["length"])
    assert t.radii[0] == SCREW["head_radius"]
    assert np.all(t.radii[1:] == SCREW["shank_radius"])
    assert np.all(x[1:, 0] + t.radii[1:] > SCREW["head_radius"])  # none hidden in the head
    assert np.allclose(np.abs(t.axes[:, 0]), [1.0, 0.0, 0.0])  # long axis = smallest moment
    by_density = shapes.screw(**SCREW, density=RHO)
    assert by_density.mass == pytest.approx(RHO * t.volume, rel=1e-14)


@pytest.mark.parametrize("b", [0.05, 0.25, 0.6, 1.0])
def test_screw_bumpiness_rule(b):
    rs, rh, length = SCREW["shank_radius"], SCREW["head_radius"], SCREW["length"]
    s, n = shapes.screw_spacing(length, rs, rh, b)
    s_max = 2.0 * rs * math.sqrt(b * (2.0 - b))
    span = length - rh - rs
    assert s * n == pytest.approx(span)
    assert rs - math.sqrt(rs**2 - (s / 2) ** 2) <= b * rs * (1 + 1e-12)
    assert span / (n - 1) > s_max  # one gap fewer would break the rule: n is the fewest
    t = shapes.screw(length, rs, rh, density=RHO, max_bumpiness=b)
    x = t.input_centres()[:, 0]
    gaps = np.diff(x[1:])
    assert np.allclose(gaps, s)
    # the union's radius profile along the shank never dips below (1 - b) r_s
    probe = np.linspace(0.0, span, 4001)
    profile = np.sqrt(np.max(np.maximum(t.radii**2 - (probe[:, None] - x) ** 2, 0.0), axis=1))
    assert profile.min() >= (1.0 - b) * rs * (1 - 1e-12)


@pytest.mark.validation
def test_screw_matches_voxel_twin():
    """Exact axial integration against brute-force voxels (independent 3-D counting)."""
    t = shapes.screw(**SCREW, mass=2.5e-3)
    c = t.input_centres()
    (vol, com, inertia), (e_vol, e_com, e_inertia) = _voxels(c, t.radii, h=1.0e-4)
    assert abs(t.volume - vol) <= t.volume_error + K * e_vol
    assert np.linalg.norm(t.com_input - com) <= t.com_error + K * e_com
    i_input = t.inertia_tensor("input")
    assert (
        np.linalg.norm(i_input - t.density * inertia) <= t.inertia_error + K * t.density * e_inertia
    )
    assert K * e_vol < 2e-3 * vol  # the twin is sharp enough for the check to mean something


@pytest.mark.validation
def test_overlapping_clump_grid_matches_voxel_twin():
    """A bent, overlapping clump (grid method) against brute-force voxels."""
    c = np.array([[0, 0, 0], [1.2, 0, 0], [2.0, 0.8, 0.0], [2.4, 1.6, 0.9], [0, 0, 1.3]])
    r = np.array([1.0, 0.8, 0.7, 0.6, 0.5])
    t = shapes.clump(c @ _rotation(4).T, r, density=1.0, rtol=FAST)
    assert t.method == "grid"
    (vol, com, inertia), (e_vol, e_com, e_inertia) = _voxels(t.input_centres(), r, h=0.04)
    assert abs(t.volume - vol) <= t.volume_error + K * e_vol
    assert np.linalg.norm(t.com_input - com) <= t.com_error + K * e_com
    assert np.linalg.norm(t.inertia_tensor("input") - inertia) <= t.inertia_error + K * e_inertia


# --- principal axes -----------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [5, 6])
def test_principal_axes_orthonormal_and_diagonalise(seed):
    c = np.array([[0.0, 0.0, 0.0], [3.0, 0.5, 0.0], [0.0, 2.5, 1.0]]) @ _rotation(seed).T + 7.0
    r = np.array([1.0, 1.2, 0.6])
    t = shapes.clump(c, r, density=RHO)
    a = t.axes
    assert np.allclose(a.T @ a, np.eye(3), atol=1e-14)
    assert np.linalg.det(a) == pytest.approx(1.0)
    assert np.all(np.diff(t.moments) >= 0.0)
    vol, com, inertia = _analytic_disjoint(c, r)
    body = a.T @ (RHO * inertia) @ a
    scale = np.max(t.moments)
    assert np.allclose(body, np.diag(t.moments), rtol=0, atol=1e-12 * scale)
    assert np.allclose(t.com_input, com, atol=1e-12)
    # the body-frame spheres have their centre at the origin and a diagonal inertia tensor
    again = mass.union_properties(t.centres, t.radii)
    assert np.allclose(again.com, 0.0, atol=1e-12)
    assert np.allclose(RHO * again.inertia, np.diag(t.moments), rtol=0, atol=1e-12 * scale)
    assert np.allclose(t.input_centres(), c, atol=1e-12)


# --- files --------------------------------------------------------------------------------------


def test_clump_file_round_trip(tmp_path):
    t = shapes.screw(**SCREW, mass=2.5e-3)
    path = tmp_path / "screw.multisphere"
    write_clump(path, t)
    back = shapes.clump_from_file(path, mass=2.5e-3)
    assert back.name == "screw" and back.count == t.count
    assert np.array_equal(back.radii, t.radii)
    assert np.allclose(back.centres, t.centres, atol=1e-15)
    assert np.allclose(back.moments, t.moments, rtol=1e-12)
    assert back.density == pytest.approx(t.density, rel=1e-12)
    # input frame, in millimetres with a scale, comments and blank lines
    rows = np.column_stack([t.input_centres(), t.radii]) * 1e3
    lines = [" ".join(repr(float(v)) for v in row) + "  # mm" for row in rows]
    (tmp_path / "mm.txt").write_text("# screw in mm\n\n" + "\n".join(lines) + "\n")
    mm = shapes.clump_from_file(tmp_path / "mm.txt", density=t.density, scale=1e-3)
    assert mm.mass == pytest.approx(t.mass, rel=1e-12)
    assert np.allclose(mm.com_input, t.com_input, atol=1e-15)


@pytest.mark.parametrize(
    ("text", "where", "value"),
    [
        ("0 0 0 1\n0 0 1\n", "line 2", "0 0 1"),
        ("# head\n0 0 0 1\n\n0 0 x 1\n", "line 4", "0 0 x 1"),
        ("0 0 0 1\n0 0 0 1 5\n", "line 2", "0 0 0 1 5"),
        ("0 0 0 1\n1 0 0 nan\n", "line 2", "1 0 0 nan"),
        ("0 0 0 1\n\n1 0 0 -0.5 # bad\n", "line 3: r", "-0.5"),
        ("1 0 0 0\n", "line 1: r", "0.0"),
        ("# nothing here\n\n", "spheres", "0"),
        ("", "spheres", "0"),
    ],
)
def test_clump_file_errors_name_the_line(tmp_path, text, where, value):
    path = tmp_path / "bad.spheres"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        shapes.clump_from_file(path, density=RHO)
    message = str(info.value)
    assert message.startswith(f"{path}: {where} = ")
    assert value in message and "allowed" in message


@pytest.mark.parametrize(
    ("call", "key"),
    [
        (lambda: shapes.screw(0.02, 0.001, 0.003), "mass, density"),
        (lambda: shapes.screw(0.02, 0.001, 0.003, mass=1e-3, density=RHO), "mass, density"),
        (lambda: shapes.screw(0.02, 0.004, 0.003, density=RHO), "shank_radius"),
        (lambda: shapes.screw(0.005, 0.002, 0.004, density=RHO), "length"),
        (lambda: shapes.screw(0.02, 0.001, 0.003, density=RHO, max_bumpiness=0), "max_bumpiness"),
        (lambda: shapes.sphere(-1.0, RHO), "radius"),
        (lambda: shapes.sphere(1.0, 0.0), "density"),
        (lambda: shapes.clump(np.zeros((2, 3)), [1.0], density=RHO), "radii"),
        (lambda: mass.union_properties([[0, 0, 0], [1, 0, 0]], [1, 1], method="disjoint"),
         "method"),
    ],
)  # fmt: skip
def test_bad_arguments_refused(call, key):
    with pytest.raises(InputError) as info:
        call()
    assert info.value.key == key


def test_template_arrays_read_only():
    t = shapes.sphere(1.0, 1.0)
    with pytest.raises(ValueError):
        t.centres[0, 0] = 1.0


def test_contact_mass_of_a_sphere_is_the_rolling_mass():
    """A sphere's smallest effective surface mass is 2/7 M (tangential push at the rim)."""
    t = shapes.sphere(0.002, 7800.0)
    assert t.contact_mass() == pytest.approx((1 - config.DEM_CONTACT_MASS_MARGIN) * 2 / 7 * t.mass)


def test_contact_mass_bounds_every_push_on_a_screw():
    """Brute force: random surface points and directions of a screw never see a smaller mass
    than contact_mass(), and the margin is not what makes that so (the sampled minimum comes
    within 1 % of the bound's unmargined value)."""
    t = shapes.screw(length=0.022, shank_radius=0.0018, head_radius=0.0036, mass=0.0025)
    rng = np.random.default_rng(3)
    u = rng.standard_normal((20000, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    member = rng.integers(0, t.count, 20000)
    r = t.centres[member] + t.radii[member, None] * u
    d = rng.standard_normal((20000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    # velocity change of the point per unit impulse along d: d/M + (I^-1 (r x d)) x r
    w = np.cross(r, d) / t.moments
    inverse = 1.0 / t.mass + np.einsum("ij,ij->i", d, np.cross(w, r))
    masses = 1.0 / inverse
    bound = t.contact_mass()
    assert masses.min() >= bound
    assert masses.min() < 1.01 * bound / (1 - config.DEM_CONTACT_MASS_MARGIN)
    # and it is far above the crude bound that pairs the longest lever with the smallest moment
    lever2 = float(np.max(np.sum(t.centres**2, axis=1)))
    assert bound > 5 * 1.0 / (1.0 / t.mass + lever2 / t.moments.min())
