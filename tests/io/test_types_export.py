"""Decks of sphere types and size distributions: LIGGGHTS and LAMMPS carry the distribution.

No engine runs here: the deck text is read. LIGGGHTS gets one ``particletemplate/sphere`` per
type and radius (a continuous distribution in equal-number bins) under a number-based
``particledistribution/discrete`` whose weights are dem's fractions; LAMMPS gets dem's fill with
each sphere's diameter and density, each type its atom type and group. Both measure the
mass-weighted mean x-velocity.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from test_liggghts_export import fix, parse

from dem.errors import InputError
from dem.io.liggghts import write_deck
from dem.scene import sizes
from dem.scene.case import load_case
from dem.scene.fill import fill_types
from dem.scene.resolved import resolve

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.fixture
def mix():
    return load_case(CASES / "sphere-mix")


def test_the_liggghts_deck_inserts_every_type_and_bin_by_number(mix, tmp_path):
    deck = write_deck(mix, tmp_path / "deck", timestep=1.4e-6, steps=100, settle_steps=10)
    commands = parse(deck)
    pdd = fix(commands, "pdd")
    assert pdd[2] == "particledistribution/discrete/numberbased"
    count = int(pdd[4])
    names, weights = pdd[5::2], [float(w) for w in pdd[6::2]]
    assert count == len(names) == sizes.DECK_BINS + 1  # the fine type's bins and one coarse
    assert sum(weights) == pytest.approx(1.0, abs=1e-12)
    fine, coarse = mix.particles.types
    radii, fractions = sizes.bins(fine.size)
    seeds = set()
    for name, weight in zip(names, weights, strict=True):
        args = fix(commands, name)
        assert args[2] == "particletemplate/sphere" and args[4:6] == ["atom_type", "1"]
        seeds.add(int(args[3]))
        density, radius = float(args[args.index("density") + 2]), float(args[-1])
        if name.startswith("pts1_"):
            b = int(name.split("_")[1]) - 1
            assert (density, radius) == (2500.0, radii[b]) and weight == 0.5 * fractions[b]
        else:
            assert (density, radius, weight) == (7800.0, 0.0025, 0.5)
    assert len(seeds) == count  # every template its own seed
    # the bins keep the fine type's mean volume
    assert np.dot(fractions, np.asarray(radii) ** 3) == pytest.approx(
        sizes.mean_power(fine.size, 3), rel=1e-3
    )
    text = deck.read_text()
    assert "# type 1 fine: 0.5 of the grains by number, density 2500 kg/m^3, lognormal" in text
    assert "variable wvx atom mass*vx/v_mmean" in text
    assert "compute vxm all reduce ave v_wvx" in text
    assert f"particles_in_region {mix.particles.count} region fill" in text


def test_the_single_size_liggghts_deck_is_unchanged(tmp_path):
    deck = write_deck(load_case(CASES / "sphere-bed"), tmp_path / "d", timestep=4e-6, steps=10,
                      settle_steps=10)  # fmt: skip
    text = deck.read_text()
    assert "particledistribution/discrete 32452843 1 pts 1.0" in text or (
        "particledistribution/discrete " in text and " 1 pts 1.0" in text
    )
    assert "compute vxm all reduce ave vx" in text and "numberbased" not in text


def test_a_linear_liggghts_deck_of_types_is_refused(mix, tmp_path):
    linear = load_case(mix.directory, {"contact.model": "linear", "contact.stiffness": 2000.0,
                                       "contact.youngs_modulus": None,
                                       "contact.poisson_ratio": None})  # fmt: skip
    with pytest.raises(InputError) as err:
        write_deck(linear, tmp_path / "d", timestep=1e-6, steps=10, settle_steps=10)
    assert err.value.key == "contact.model" and "m*" in err.value.allowed


def test_the_lammps_data_file_carries_each_spheres_size_density_and_type(mix, tmp_path):
    from dem.io.lammps.deck import write_data
    from dem.io.lammps.deck import write_deck as write_lammps

    mix = load_case(mix.directory, {"contact.tangential": "coulomb"})  # LAMMPS's convention
    scene = resolve(mix)
    x, r, rho, kind, _ = fill_types(mix)
    mass = rho * 4.0 / 3.0 * math.pi * r**3
    write_data(tmp_path / "data.fill", scene, x, np.zeros_like(x), np.zeros_like(x), r, mass,
               kind=kind)  # fmt: skip
    write_lammps(scene, tmp_path, timestep=1.4e-6, steps=10, settle_steps=10, r_max=float(r.max()))
    lines = (tmp_path / "data.fill").read_text().splitlines()
    assert "2 atom types" in lines
    start = lines.index("Atoms # sphere") + 2
    rows = np.array([[float(w) for w in line.split()] for line in lines[start : start + len(x)]])
    np.testing.assert_array_equal(rows[:, 1], kind + 1)
    np.testing.assert_allclose(rows[:, 2], 2.0 * r, rtol=1e-15)
    np.testing.assert_allclose(rows[:, 3], rho, rtol=1e-12)
    deck = (tmp_path / "in.lammps").read_text()
    assert "group fine type 1" in deck and "group coarse type 2" in deck
    assert "compute vxm all reduce ave v_wvx" in deck
    assert "variable mmean equal (mass(all)+1e-30)/(count(all)+1e-30)" in deck


def test_a_lammps_pour_of_types_is_refused(mix):
    from dem.io.lammps.pour import refuse_unpourable

    with pytest.raises(InputError) as err:
        refuse_unpourable(resolve(mix))
    assert err.value.key == "particles.types" and "--fill dem" in err.value.allowed
