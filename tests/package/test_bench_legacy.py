"""The legacy deck of the speed bar (validation/performance/lammps_legacy.py), without LAMMPS.

A granular deck's lines are rewritten for ``pair_style gran/hertz/history``: the constants come
from dem's law (Kn = 4/3 Y*, Kt = C_kt, xmu = mu, gamma_n matched at one grain's resting
overlap), every other line stays as it was, and a deck that is not a granular one is refused.
"""

import importlib.util
import math
import sys
from pathlib import Path

import pytest

from dem import config
from dem.io.lammps.contact import granular_model
from dem.scene.case import load_case
from dem.scene.resolved import resolve

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "validation" / "performance" / "lammps_legacy.py"
CASE = ROOT / "validation" / "liggghts-bulk" / "sphere-bed-5e7"


def _module():
    spec = importlib.util.spec_from_file_location("lammps_legacy", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclass looks its module up there
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def legacy():
    return _module()


@pytest.fixture(scope="module")
def scene():
    return resolve(load_case(CASE).with_tangential("coulomb"), timestep=5e-6)


def _deck(scene) -> str:
    """A small granular deck of dem's form (dem.io.lammps.deck), with the scene's own words."""
    pair = granular_model(scene.law).words
    wall = granular_model(scene.law, wall=True).words
    return "\n".join([
        "# LAMMPS deck written by dem",
        "units si",
        "atom_style sphere",
        "read_data data.fill",
        "",
        "pair_style granular",
        f"pair_coeff * * {pair}",
        "neighbor 0.0008 bin",
        f"fix floor all wall/gran granular {wall} zplane 0.0 NULL",
        f"fix sides all wall/gran granular {wall} yplane -0.02 0.02",
        "timestep 5e-06",
        "run 2000",
    ]) + "\n"  # fmt: skip


def test_the_constants_are_the_laws(legacy, scene):
    pair, wall = legacy.constants_for(scene)
    law = scene.law
    y_star = law.grain_grain.normal.y_star
    assert pair.kn == 4.0 / 3.0 * y_star and wall.kn == 4.0 / 3.0 * y_star  # exactly
    assert pair.xmu == law.grain_grain.friction == 0.35
    assert wall.xmu == law.grain_wall.friction
    assert pair.kt == law.kernel_coefficients().tangential_stiffness
    mass, radius = legacy.grain_mass_radius(scene)
    sides = ((pair, radius / 2, mass / 2, False), (wall, radius, mass, True))
    for c, r_eff, m_eff, wall_side in sides:
        # delta0 carries one grain's weight; there the two dashpots are equal
        assert pair.kn * math.sqrt(r_eff) * c.delta0**1.5 == pytest.approx(mass * config.GRAVITY)
        a0 = math.sqrt(r_eff * c.delta0)
        dem_dashpot = law.kernel_coefficients(wall_side).normal_damping * math.sqrt(a0 * m_eff)
        assert a0 * m_eff * c.gamma_n == pytest.approx(dem_dashpot, rel=1e-12)
        assert c.gamma_t == pytest.approx(c.ratio * c.gamma_n, rel=1e-15)


def test_the_lines_are_replaced_and_the_rest_kept(legacy, scene):
    text = _deck(scene)
    out = legacy.convert_text(text, *legacy.constants_for(scene))
    pair, wall = legacy.constants_for(scene)
    lines = out.splitlines()
    header = [line for line in lines if line.startswith("# LEGACY") or line.startswith("#   ")]
    assert "cost-equivalent" in header[0] and "NOT the same physics" in header[0]
    body = lines[len(header) :]
    ps = f"pair_style gran/hertz/history {pair.words()}"
    written = [float(w) for w in ps.split()[2:]]  # %.17g: the floats round-trip exactly
    assert written == [pair.kn, pair.kt, pair.gamma_n, pair.gamma_t, 0.35, 1.0]
    words = wall.words()
    assert body == [
        "# LAMMPS deck written by dem",
        "units si",
        "atom_style sphere",
        "read_data data.fill",
        "",
        ps,
        "pair_coeff * *",
        "neighbor 0.0008 bin",
        f"fix floor all wall/gran hertz/history {words} zplane 0.0 NULL",
        f"fix sides all wall/gran hertz/history {words} yplane -0.02 0.02",
        "timestep 5e-06",
        "run 2000",
    ]
    assert "granular" not in " ".join(body)


def test_a_deck_without_pair_granular_is_refused(legacy, scene):
    text = _deck(scene).replace("pair_style granular", "pair_style gran/hooke/history 1 1 1 1 1 1")
    with pytest.raises(legacy.LegacyDeckError, match="no 'pair_style granular' line"):
        legacy.convert_text(text, *legacy.constants_for(scene))


def test_a_deck_of_another_law_is_refused(legacy, scene):
    text = _deck(scene).replace(" 0.34999999999999998", " 0.5")  # another mu
    with pytest.raises(legacy.LegacyDeckError, match="mindlin mu = 0.5 in the deck"):
        legacy.convert_text(text, *legacy.constants_for(scene))


def test_a_law_that_is_not_coulomb_is_refused(legacy):
    scene = resolve(load_case(CASE).with_tangential("liggghts"), timestep=5e-6)
    with pytest.raises(legacy.LegacyDeckError, match='"liggghts"'):
        legacy.constants_for(scene)
