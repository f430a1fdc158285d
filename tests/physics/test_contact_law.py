"""The contact law as named sub-models (dem.physics.contact): its report and its one search."""

from pathlib import Path

import pytest

from dem.physics import tangential as fit
from dem.physics.contact import ContactLaw, Coulomb, Hertz, Impact, Linear
from dem.physics.contact import tangential as subs
from dem.scene.case import load_case
from dem.scene.resolved import resolve

CASES = Path(__file__).resolve().parents[2] / "cases"
WALL = {"wall.friction": 0.5, "wall.restitution_normal": 0.3, "wall.restitution_tangential": 0.7}


def test_the_report_gives_each_interactions_coefficients_from_the_case():
    case = load_case(CASES / "sphere-bed", WALL)
    report = ContactLaw.from_case(case).report()
    m, w, c = case.material, case.wall_material, case.contact
    for name, mat in (("grain_grain", m), ("grain_wall", w)):
        row = report[name]
        assert row["model"] == "hertz_mindlin"
        assert row["youngs_modulus"] == c.youngs_modulus
        assert row["poisson_ratio"] == c.poisson_ratio
        assert row["restitution_normal"] == mat.restitution_normal
        assert row["restitution_tangential"] == mat.restitution_tangential
        assert row["friction"] == mat.friction
        assert row["rolling_friction"] == mat.rolling_friction
        assert row["tangential"] == c.tangential
    assert report["grain_wall"]["friction"] == 0.5 and report["grain_grain"]["friction"] == 0.35


def test_the_linear_law_reports_its_stiffness():
    case = load_case(CASES / "single-sphere")
    row = ContactLaw.from_case(case).report()["grain_grain"]
    assert row["model"] == "linear" and row["stiffness"] == case.contact.stiffness
    assert "youngs_modulus" not in row


def test_the_sub_models_are_the_cases():
    law = ContactLaw.from_case(load_case(CASES / "sphere-bed", WALL))
    assert law.normal == Hertz(2.0e9, 0.3)
    assert isinstance(law.grain_grain.tangential, Impact)
    assert law.grain_wall.damping.restitution == 0.3
    assert law.critically_damped  # eps_n = 0 between grains
    assert law.stiffer(2.0) == ("contact.youngs_modulus", 2.0e9 * 2.0**2.5)
    assert Linear(1e4, 0.3).stiffer(2.0).stiffness == 4e4


def test_a_kernel_array_decodes_to_the_same_sub_models():
    """ContactLaw(model, params), as the engine's tests build it, decodes E, nu and eps_n."""
    law = ContactLaw.from_case(load_case(CASES / "sphere-bed", WALL))
    raw = ContactLaw(law.model, law.params)
    for name in ("grain_grain", "grain_wall"):
        built, decoded = law.report()[name], raw.report()[name]
        for key in ("youngs_modulus", "poisson_ratio", "restitution_normal", "friction",
                    "restitution_tangential"):  # fmt: skip
            assert decoded[key] == pytest.approx(built[key], rel=1e-9, abs=1e-12), (name, key)


def test_a_coulomb_run_searches_eps_t_once(monkeypatch):
    """load_case checks the spring, resolve builds both rows: one root search for one eps_t."""
    calls = []
    search = fit.tangential_stiffness_ratio

    def counting(*args, **kwargs):
        calls.append(args)
        return search(*args, **kwargs)

    monkeypatch.setattr(fit, "tangential_stiffness_ratio", counting)
    subs.spring_ratio.cache_clear()
    overrides = {"contact.tangential": "coulomb", "material.restitution_tangential": 0.8313}
    scene = resolve(load_case(CASES / "screw-trough", overrides))
    assert isinstance(scene.law.grain_grain.tangential, Coulomb)
    assert scene.law.grain_grain.tangential.derived
    assert len(calls) == 1
