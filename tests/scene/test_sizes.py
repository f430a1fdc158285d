"""Grain types and size distributions of spheres: keys, refusals, draws, fill, step and forces.

The keys (``particles.radius_distribution`` and its parameters, ``[[particles.types]]``) are
read or refused at load; the fill places each type's share without overlap (checked by brute
force over every pair); the step takes the hardest contact of the smallest spheres; and the
pair kernel's force between two different spheres is Hertz's with the pair's own R* and m*
(a NumPy oracle written from the law, :mod:`tests.oracles.naive_dem`).
"""

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from small_case import SMALL_CASE, write_case

from dem.errors import InputError
from dem.scene import sizes
from dem.scene.case import load_case
from dem.scene.spec import SizeSpec

CASES = Path(__file__).resolve().parents[2] / "cases"

#: Two types: glass of a uniform size distribution, steel of one size (half each by number).
TWO_TYPES = SMALL_CASE.replace(
    'shape = "sphere"\ncount = 120\nradius = 0.002',
    """shape = "sphere"
count = 120

[[particles.types]]
name = "glass"
fraction = 0.5
density = 2500.0
radius_distribution = "uniform"
radius_min = 0.0012
radius_max = 0.0018

[[particles.types]]
name = "steel"
fraction = 0.5
radius = 0.002
""",
)


def _load(tmp_path, text, overrides=None):
    return load_case(write_case(tmp_path / "case", text), overrides)


def test_the_shipped_mix_reads_its_types_and_counts_its_depth_by_the_mean_grain():
    case = load_case(CASES / "sphere-mix")
    fine, coarse = case.particles.types
    assert (fine.name, fine.fraction, fine.density, fine.size.distribution) == (
        "fine", 0.5, 2500.0, "lognormal",
    )  # fmt: skip
    assert (coarse.density, coarse.size.radius) == (7800.0, 0.0025)  # material.density's
    assert case.particles.radius == 0.0025  # the reach: the largest radius
    volume = sizes.mean_volume(case.particles.types)
    d_v = (6.0 * volume / math.pi) ** (1.0 / 3.0)
    n = 4.0 * d_v * 0.6 * 0.06 * 0.03 / volume  # layers = 4 over the 0.06 x 0.03 m floor
    assert case.particles.count == round(n)
    assert case.material.density == pytest.approx(sizes.mean_mass(case.particles.types) / volume)


def test_a_size_distribution_in_particles_is_one_type(tmp_path):
    text = SMALL_CASE.replace(
        "radius = 0.002",
        'radius_distribution = "discrete"\nradii = [0.002, 0.0015]\nradius_fractions = [0.3, 0.7]',
    )
    (only,) = _load(tmp_path, text).particles.types
    assert only.size == SizeSpec("discrete", radii=(0.0015, 0.002), radius_fractions=(0.7, 0.3))
    assert only.density == 7800.0


@pytest.mark.parametrize(
    "old, new, key, words",
    [
        ("radius = 0.002", 'radius_distribution = "uniform"\nradius = 0.002\nradius_min = 0.001'
         "\nradius_max = 0.002", "particles.radius", "radius_min and radius_max bound it"),
        ("radius = 0.002", 'radius_distribution = "uniform"\nradius_min = 0.002\nradius_max = '
         "0.001", "particles.radius_max", "> particles.radius_min"),
        ("radius = 0.002", 'radius_distribution = "uniform"\nradius_min = 0.0001\nradius_max = '
         "0.002", "particles.radius_max", "within a ratio of 10"),
        ("radius = 0.002", 'radius_distribution = "normal"\nradius = 0.003\nradius_std = 0.001\n'
         "radius_min = 0.001\nradius_max = 0.002", "particles.radius", "inside"),
        ("radius = 0.002", 'radius_distribution = "normal"\nradius = 0.0015\nradius_min = 0.001'
         "\nradius_max = 0.002", "particles.radius_std", "required"),
        ("radius = 0.002", "radius = 0.002\nradius_min = 0.001", "particles.radius_min",
         "radius_distribution = 'uniform'"),
        ("radius = 0.002", 'radius_distribution = "normal"\nradius = 0.0015\nradius_std = 0.0002'
         "\nradius_log_std = 0.1\nradius_min = 0.001\nradius_max = 0.002",
         "particles.radius_log_std", "radius_distribution = 'lognormal', not of 'normal'"),
        ("radius = 0.002", 'radius_distribution = "discrete"\nradii = [0.002, 0.001]\n'
         "radius_fractions = [0.5]", "particles.radius_fractions", "one fraction per radius"),
        ("radius = 0.002", 'radius_distribution = "discrete"\nradii = [0.002, 0.001]\n'
         "radius_fractions = [0.5, 0.4]", "particles.radius_fractions", "sum to 1"),
        ("radius = 0.002", 'radius_distribution = "discrete"\nradii = [0.002, -1.0]\n'
         "radius_fractions = [0.5, 0.5]", "particles.radii", "radius must be in"),
    ],
)  # fmt: skip
def test_a_bad_distribution_is_refused_naming_its_key(tmp_path, old, new, key, words):
    with pytest.raises(InputError) as err:
        _load(tmp_path, SMALL_CASE.replace(old, new))
    assert err.value.key == key
    assert words in err.value.allowed


@pytest.mark.parametrize(
    "change, key, words",
    [
        (("fraction = 0.5\ndensity = 2500.0", "fraction = 0.4\ndensity = 2500.0"),
         "particles.types", "sum to 1"),
        (('name = "steel"', 'name = "glass"'), "particles.types[2].name", "no other"),
        (('name = "steel"', 'name = "st eel"'), "particles.types[2].name", "letters"),
        (('name = "steel"', 'name = "steel"\ncolour = 1'), "particles.types[2].colour",
         "a key of [particles.types[2]]"),
        (("count = 120", "count = 120\nradius = 0.002"), "particles.radius",
         "given per grain type"),
        (('name = "steel"', 'name = "steel"\nradius_std = 0.001'),
         "particles.types[2].radius_std", "radius_distribution = 'normal'"),
    ],
)  # fmt: skip
def test_bad_types_are_refused_naming_their_key(tmp_path, change, key, words):
    with pytest.raises(InputError) as err:
        _load(tmp_path, TWO_TYPES.replace(*change))
    assert err.value.key == key
    assert words in err.value.allowed


def test_a_material_density_no_type_reads_is_refused(tmp_path):
    text = TWO_TYPES.replace('fraction = 0.5\nradius = 0.002', 'fraction = 0.5\nradius = 0.002\n'
                             'density = 7000.0')  # fmt: skip
    with pytest.raises(InputError) as err:
        _load(tmp_path, text)
    assert err.value.key == "material.density" and "ignored" in err.value.allowed
    case = _load(tmp_path, text.replace("density = 7800.0\n", "", 1))
    assert [t.density for t in case.particles.types] == [2500.0, 7000.0]


@pytest.mark.parametrize(
    "overrides, words",
    [
        ({"run.device": "cuda"}, "GPU engine"),
        ({"feeder.feed_rate": 0.0}, "finite feeder"),
    ],
)
def test_types_are_refused_where_the_engine_takes_one_size(tmp_path, overrides, words):
    with pytest.raises(InputError) as err:
        _load(tmp_path, TWO_TYPES, overrides)
    assert err.value.key == "particles.types" and words in err.value.allowed


def test_a_screw_with_a_distribution_or_types_is_refused(tmp_path):
    screw = load_case(CASES / "screw-trough")
    for key, value in (("particles.radius_distribution", "uniform"),
                       ("particles.types", [{"fraction": 1.0, "radius": 0.002}])):  # fmt: skip
        with pytest.raises(InputError) as err:
            load_case(screw.directory, {key: value})
        assert err.value.key == key and "shape = 'sphere'" in err.value.allowed


def test_split_gives_whole_counts_within_one_of_the_fractions():
    for n in (1, 7, 100, 1001):
        f = [0.2, 0.3, 0.5 - 1e-12, 1e-12]
        counts = sizes.split(n, f)
        assert counts.sum() == n
        assert np.all(np.abs(counts - n * np.asarray(f)) < 1.0)


@pytest.mark.parametrize("distribution", ["uniform", "normal", "lognormal", "discrete"])
def test_draws_stay_in_their_bounds_and_bins_keep_the_mean_volume(distribution):
    size = {
        "uniform": SizeSpec("uniform", radius_min=1e-3, radius_max=2e-3),
        "normal": SizeSpec("normal", radius=1.5e-3, radius_std=3e-4, radius_min=1e-3,
                           radius_max=2e-3),
        "lognormal": SizeSpec("lognormal", radius=1.5e-3, radius_log_std=0.2, radius_min=1e-3,
                              radius_max=2e-3),
        "discrete": SizeSpec("discrete", radii=(1e-3, 2e-3), radius_fractions=(0.25, 0.75)),
    }[distribution]  # fmt: skip
    r = sizes.draw(size, 20000, np.random.default_rng(1))
    assert size.smallest <= r.min() and r.max() <= size.largest
    cube = sizes.mean_power(size, 3)
    assert np.mean(r**3) == pytest.approx(cube, rel=0.02)
    radii, fractions = sizes.bins(size)
    assert np.dot(fractions, np.asarray(radii) ** 3) == pytest.approx(cube, rel=1e-3)
    if distribution == "discrete":
        assert np.count_nonzero(r == 1e-3) == 5000


def test_the_fill_places_every_type_its_share_without_overlap(tmp_path):
    from dem.scene.fill import fill_types

    case = _load(tmp_path, TWO_TYPES, {"particles.count": 300, "trough.length": 0.05})
    x, r, rho, kind, height = fill_types(case)
    assert np.bincount(kind).tolist() == [150, 150]
    assert np.all(rho == np.where(kind == 0, 2500.0, 7800.0))
    glass = r[kind == 0]
    assert 0.0012 <= glass.min() and glass.max() <= 0.0018 and np.all(r[kind == 1] == 0.002)
    d = x[:, None, :] - x[None, :, :]
    d[..., 0] -= 0.05 * np.round(d[..., 0] / 0.05)
    gap = np.sqrt(np.einsum("ijk,ijk->ij", d, d)) - (r[:, None] + r[None, :])
    np.fill_diagonal(gap, np.inf)
    assert gap.min() >= 0.0  # no two spheres overlap
    assert np.all(x[:, 2] >= r) and np.all(np.abs(x[:, 1]) <= 0.01 - r)  # floor and walls
    again = fill_types(case)
    assert np.array_equal(again[0], x) and np.array_equal(again[1], r)  # seeded


def test_the_step_is_the_hardest_contact_of_the_smallest_spheres(tmp_path):
    from dem.scene.timestep import timestep_for

    case = _load(tmp_path, TWO_TYPES)
    step = timestep_for(case)
    glass = replace(
        case,
        particles=replace(case.particles, types=(), radius=0.0012),
        material=replace(case.material, density=2500.0),
    )
    alone = timestep_for(glass, impact_speed=step.impact_speed)
    assert step.limit <= alone.limit * (1 + 1e-12)  # the glass-steel pairs are no harder
    assert step.limit == pytest.approx(alone.limit, rel=0.05)
    one = _load(tmp_path, SMALL_CASE.replace(
        'count = 120\nradius = 0.002', 'count = 120\n[[particles.types]]\nfraction = 1.0\n'
        'radius = 0.002'))  # fmt: skip
    plain = _load(tmp_path, SMALL_CASE)
    assert timestep_for(one).limit == pytest.approx(timestep_for(plain).limit, rel=1e-12)


def test_the_pair_force_of_two_different_spheres_is_hertz_with_their_r_and_m(tmp_path):
    """Head-on, approaching: F = 4/3 Y* sqrt(R*) delta^1.5 + gamma_n(m*, S_n) v_n, with R* and m*
    of the pair, by a NumPy oracle; the same spheres with equal radii or masses would not."""
    from naive_dem import coefficients

    from dem.engine import setup

    text = SMALL_CASE.replace("[contact]", "[contact]\ntangential = 'coulomb'").replace(
        "friction = 0.35", "friction = 0.35\nrestitution_normal = 0.5"
    )
    case = _load(tmp_path, text)
    radii = np.array([1.0e-3, 2.5e-3])
    densities = np.array([2500.0, 7800.0])
    delta, u = 2.0e-5, 0.05
    x = [[0.01, 0.0, 0.005], [0.01 + radii.sum() - delta, 0.0, 0.005]]
    sim = setup.from_grains(case, x, radii=radii, densities=densities,
                            velocities=[[u, 0.0, 0.0], [-u, 0.0, 0.0]])  # fmt: skip
    sim.compute_forces()
    s = sim.spheres
    contact = s.force - s.mass[:, None] * np.asarray(sim.gravity)
    m = densities * 4.0 / 3.0 * math.pi * radii**3
    m_eff, r_eff = m[0] * m[1] / m.sum(), radii[0] * radii[1] / radii.sum()
    c = {"e": 0.5, "nu": 0.3, "E": 5.0e7, "tangential": "coulomb", "kt_ratio": 1.0,
         "zeta_t": 0.0, "f_t": 1.0}  # fmt: skip
    kn, gn, _, _ = coefficients("hertz_mindlin", delta, m_eff, r_eff, c)
    expected = kn * delta + gn * 2.0 * u  # repulsive plus the dashpot against the approach
    np.testing.assert_allclose(contact[0], [-expected, 0.0, 0.0], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(contact[1], -contact[0], rtol=0, atol=0)
    for wrong_m, wrong_r in ((0.5 * m[0], r_eff), (m_eff, 0.5 * radii.mean())):
        kn_w, gn_w, _, _ = coefficients("hertz_mindlin", delta, wrong_m, wrong_r, c)
        assert abs(kn_w * delta + gn_w * 2.0 * u - expected) > 1e-3 * expected
