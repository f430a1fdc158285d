"""Bed depth (dem.scene.depth): layers, bed height or mass per area instead of a grain count."""

import math
from pathlib import Path

import pytest

from dem.config import BED_PACKING
from dem.errors import InputError
from dem.physics.mass import sphere_volume
from dem.scene import depth
from dem.scene.case import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"


def test_the_three_depths_give_the_count_by_their_definitions():
    base = load_case(CASES / "sphere-bed")  # r = 2 mm, 0.10 x 0.04 m, rho 7800
    area, v = 0.10 * 0.04, sphere_volume(0.002)
    layers = load_case(CASES / "sphere-bed", {"particles.layers": 3.0})
    assert layers.particles.count == round(3 * 0.004 * BED_PACKING * area / v)
    assert layers.particles.layers == 3.0
    height = load_case(CASES / "sphere-bed", {"particles.bed_height": 0.012})
    assert height.particles.count == layers.particles.count  # 3 layers of d = 4 mm
    per_area = load_case(CASES / "sphere-bed", {"particles.mass_per_area": 50.0})
    assert per_area.particles.count == round(50.0 * area / (7800 * v))
    # and back: the summary's bed of a case that gives a count
    bed = depth.bed(base.particles, base.material.density, 0.10, 0.04)
    assert bed["given"] == "count" and bed["count"] == 1500
    assert bed["mass_per_area_kg_m2"] == pytest.approx(1500 * 7800 * v / area)
    assert bed["layers"] == pytest.approx(1500 * v / (BED_PACKING * area) / 0.004)


def test_a_screws_layer_is_its_volume_equivalent_diameter():
    case = load_case(CASES / "screw-trough", {"particles.layers": 2.0})
    d_v = (6 * case.particles.grain.volume / math.pi) ** (1 / 3)
    assert depth.layer_thickness(case.particles) == pytest.approx(d_v)
    assert 0.0084 < d_v < 0.0086  # the 2.5 g screw: 8.5 mm, its head 7.2 mm across
    bed = depth.bed(case.particles, case.material.density, 0.12, 0.06)
    assert bed["given"] == "layers" and bed["layers"] == pytest.approx(2.0, rel=0.01)


def test_a_depth_override_replaces_the_files_count_and_the_reverse():
    case = load_case(CASES / "sphere-bed", {"particles.layers": 1.0})
    assert case.particles.count < 1500
    back = load_case(CASES / "sphere-bed", {"particles.layers": 1.0, "particles.count": None})
    assert back.particles.count == case.particles.count
    with pytest.raises(InputError, match=r"exactly one of particles\.count.*given: count, layers"):
        load_case(CASES / "sphere-bed", {"particles.layers": 1.0, "particles.count": 10})


def test_depths_are_refused_where_there_is_no_flat_section():
    with pytest.raises(InputError, match=r"particles\.layers.*a mesh trough"):
        load_case(CASES / "u-trough", {"particles.layers": 2.0})
    with pytest.raises(InputError, match=r"particles\.layers.*a finite feeder"):
        load_case(CASES / "feeder", {"particles.layers": 2.0})


def test_a_depth_of_less_than_one_grain_names_the_key_and_the_count():
    with pytest.raises(InputError, match=r"particles\.mass_per_area.*this gives 0\.0\d+ grains"):
        load_case(CASES / "sphere-bed", {"particles.mass_per_area": 1e-3})
    with pytest.raises(InputError, match=r"particles\.layers.*\[0\.01, 1e4\]"):
        load_case(CASES / "sphere-bed", {"particles.layers": -1.0})
