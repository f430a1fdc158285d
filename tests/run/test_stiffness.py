"""The bed-compliance rule (dem.run.stiffness): the estimate, its inverse and the warning it
gives."""

import math
from dataclasses import replace
from pathlib import Path

import pytest

from dem.run import stiffness
from dem.run.plan import plan
from dem.scene.case import load_case
from dem.scene.resolved import resolve

CASES = Path(__file__).resolve().parents[2] / "cases"
#: The LIGGGHTS-parity sphere bed: cases/sphere-bed at 5e7 Pa, as shipped until 2026-11-26.
PARITY = Path(__file__).resolve().parents[2] / "validation" / "liggghts-bulk" / "sphere-bed-5e7"


@pytest.mark.integration
def test_one_grain_is_the_resting_contact_of_the_single_grain_study():
    """One grain on the floor: omega_bed is the contact's own sqrt(S / m), with S the Hertz
    tangent stiffness under the grain's weight, as validation/impact-law's compliant floor."""
    case = load_case(CASES / "sphere-bed", {"particles.count": 1})
    scene = resolve(case)
    mode = stiffness.bed_mode(scene)
    r, m = case.particles.radius, scene.grain_mass
    y_star = case.contact.youngs_modulus / (2.0 * (1.0 - case.contact.poisson_ratio**2))
    rest = (m * 9.81 / (4.0 / 3.0 * y_star * math.sqrt(r))) ** (2.0 / 3.0)
    s = 2.0 * y_star * math.sqrt(r * rest)
    assert mode.layers == 1.0
    assert mode.contact_stiffness == pytest.approx(s, rel=1e-12)
    assert mode.omega_bed == pytest.approx(math.sqrt(s / m), rel=1e-12)
    assert mode.compliance == pytest.approx(case.drive.omega**2 * m / s, rel=1e-12)


@pytest.mark.integration
def test_compliance_falls_as_e_to_the_minus_two_thirds_and_inverts():
    scene = resolve(load_case(CASES / "sphere-bed"))
    base = stiffness.bed_mode(scene).compliance
    hertz = scene.law.normal
    stiffer = stiffness.bed_mode(scene, replace(hertz, youngs_modulus=8.0 * hertz.youngs_modulus))
    assert stiffer.compliance == pytest.approx(base / 4.0, rel=1e-9)
    key, value = stiffness.stiffness_for(scene, base / 10.0)
    assert key == "contact.youngs_modulus"
    assert stiffness.bed_mode(
        scene, replace(hertz, youngs_modulus=value)
    ).compliance == pytest.approx(base / 10.0, rel=1e-9)
    linear = resolve(load_case(CASES / "single-sphere"))
    key, value = stiffness.stiffness_for(linear, stiffness.bed_mode(linear).compliance / 2.0)
    assert key == "contact.stiffness"
    assert value == pytest.approx(2.0 * linear.case.contact.stiffness)


@pytest.mark.integration
def test_the_warning_fires_on_the_soft_sphere_bed_and_not_at_the_stiffness_it_names():
    data = stiffness.study()
    assert data is not None, "dem/data/stiffness_convergence.json ships with dem"
    soft = plan(load_case(PARITY))
    warned = [a for a in soft.warnings() if a.key == "contact.youngs_modulus"]
    assert warned and "validation/bulk-convergence" in warned[0].text
    value = float(warned[0].text.rsplit(">= ", 1)[1])
    ok = plan(load_case(CASES / "sphere-bed", {"contact.youngs_modulus": 1.01 * value}))
    assert not [a for a in ok.warnings() if a.key == "contact.youngs_modulus"]
    one = plan(load_case(CASES / "single-sphere"))
    assert not [a for a in one.warnings() if a.key.startswith("contact.")]


@pytest.mark.integration
def test_every_bed_summary_says_whether_its_stiffness_gives_the_rigid_answer(capsys):
    """summary.json's ``stiffness`` and the terminal's line: the 5e7 Pa LIGGGHTS-parity sphere
    bed is too soft and names the value its warning names; at that value it is stiff enough."""
    from dem.studies.answers import run_summary_lines

    soft = resolve(load_case(PARITY))
    found = stiffness.assessment(soft)
    warned = stiffness.advice(soft)
    assert found["converged"] is False and found["compliance"] > found["compliance_limit"]
    assert (found["key"], found["value"]) == (warned.key, warned.value)
    stiff = resolve(load_case(PARITY, {found["key"]: found["value"]}))
    assert stiffness.assessment(stiff)["converged"] is True
    # one grain is judged by the single-grain rule since round 4 (None before): the shipped
    # linear block, 660x the drive, is stiff enough
    one = stiffness.assessment(resolve(load_case(CASES / "single-sphere")))
    assert one["single_grain"] and one["converged"]
    summary = {
        "mean_velocity": 0.1206, "mean_velocity_stderr": 0.0015, "mean_velocity_norm": 0.706,
        "mean_velocity_norm_stderr": 0.009, "mass_flow_rate": 0.47,
        "mass_flow_rate_per_width": 11.8, "timestep": 6.5e-6, "steps": 77250,
        "wall_time_s": 16.0, "stiffness": found,
    }  # fmt: skip
    out = "\n".join(run_summary_lines(summary))
    assert "TOO SOFT" in out and f"{found['key']} >= {found['value']:.3g}" in out
    # the study's own point at this stiffness: the shipped sphere bed, 20 % slow
    own = [m for m in found["measured"] if m["bed"] == "sphere-bed"]
    assert own and own[0]["youngs_modulus_pa"] == 5e7 and own[0]["error_vs_rigid"] < -0.1
    assert "sphere-bed at E = 5e+07 Pa" in out
    stiff_lines = run_summary_lines(summary | {"stiffness": stiffness.assessment(stiff)})
    assert "stiff enough" in "\n".join(stiff_lines)


@pytest.mark.integration
@pytest.mark.parametrize("name", ["sphere-bed", "screw-trough", "u-trough", "v-trough", "feeder"])
def test_every_shipped_bulk_case_is_stiff_enough_for_the_rigid_answer(name):
    """The shipped beds sit where validation/bulk-convergence measured them within 2 % of the
    rigid limit: no stiffness warning before the run, "converged" in the summary."""
    scene = resolve(load_case(CASES / name))
    assert stiffness.advice(scene) is None
    assert stiffness.assessment(scene)["converged"] is True
    assert not [a for a in plan(scene.case).warnings() if a.key == "contact.youngs_modulus"]


# --- one grain (hardening issue 46, item 3) -----------------------------------------------------

STUDY = Path(__file__).resolve().parents[2] / "validation" / "single-grain-stiffness"


def _lone(tmp_path, youngs, **keys):
    """cases/single-sphere as a Hertz grain of ``youngs`` Pa, at the issue's uphill drive."""
    text = (CASES / "single-sphere" / "case.toml").read_text()
    text = text.replace('model = "linear"', f'model = "hertz_mindlin"\nyoungs_modulus = {youngs}')
    text = "\n".join(line for line in text.splitlines() if not line.startswith("stiffness ="))
    folder = tmp_path / f"lone{youngs:g}"
    folder.mkdir(exist_ok=True)
    (folder / "case.toml").write_text(text + "\n")
    drive = {"drive.throw_number": 0.8, "drive.angle": 35.0, "trough.inclination": 4.4}
    return load_case(folder, drive | keys)


def test_a_soft_lone_grain_near_the_threshold_warns_naming_the_modulus(tmp_path):
    soft = plan(_lone(tmp_path, 5e7))
    warned = [a for a in soft.warnings() if a.key == "contact.youngs_modulus"]
    assert len(warned) == 1 and "one grain's contact is soft" in warned[0].text
    value = warned[0].value
    assert 5e7 < value < 2e9
    # the value it names is stiff enough by the same rule, and the shipped stiffness is too
    for youngs in (value, 2e9):
        case = _lone(tmp_path, youngs)
        assert not [a for a in plan(case).warnings() if a.key == "contact.youngs_modulus"]
        assert stiffness.assessment(resolve(case))["converged"]
    # the shipped linear block needs no warning
    assert not plan(load_case(CASES / "single-sphere")).warnings()


def test_the_lone_grain_rule_covers_every_measured_error():
    """The constant is the study's worst |v_DEM - v_rigid| / c, rounded up."""
    import json

    doc = json.loads((STUDY / "results.json").read_text())
    worst = doc["worst_error_per_compliance"]
    assert worst <= stiffness.SINGLE_GRAIN_ERROR_PER_COMPLIANCE < 1.1 * worst + 0.05
    assert len(doc["rows"]) >= 28 and {r["youngs_modulus_pa"] for r in doc["rows"]} >= {5e7, 2e10}


@pytest.mark.integration
def test_a_soft_lone_grain_is_as_far_off_as_its_summary_says(tmp_path, capsys):
    """5e7 Pa at the uphill drive: the summary and terminal say TOO SOFT, naming the modulus,
    and the run's error lies within K c. (Under the plastic contact of eps_n = 0 this drive's
    error, +0.0004, is also within the 0.0035 allowed: K is the worst drive's, Gamma 0.9 at
    25 deg, whose +0.0017 at 5e7 Pa is not.)"""
    from dem.run.runner import run_case
    from dem.studies.answers import run_summary_lines

    case = _lone(tmp_path, 5e7, **{"run.settle_cycles": "auto", "run.cycles": 6})
    s = run_case(case, tmp_path / "out", overwrite=True, progress=False, frames=False, threads=1)
    stiff = s["stiffness"]
    assert stiff["single_grain"] and not stiff["converged"]
    assert stiff["key"] == "contact.youngs_modulus"
    error = abs(s["mean_velocity_norm"] - s["pointmass_bounded_velocity_norm"])
    assert error <= stiff["expected_error"]
    assert stiff["allowed_error"] < stiff["expected_error"]
    assert any("TOO SOFT for the rigid grain's answer" in line for line in run_summary_lines(s))


# --- a flying lone grain (issue 46, item 2: the drives the finite contact misses) ---------------

HOPPING = Path(__file__).resolve().parents[2] / "validation" / "hopping-bias"


def test_the_hopping_rule_covers_every_measured_lone_grain():
    """K_h is the worst binding ratio of validation/hopping-bias's rule.csv, rounded up, and
    with the sliding rule it covers every lone grain run there (2e9-2e11 Pa)."""
    import csv

    rows = list(csv.DictReader((HOPPING / "rule.csv").open()))
    assert len(rows) >= 74
    ratios = [float(r["ratio"]) for r in rows if r["ratio"] not in ("", "None")]
    worst = max(ratios)
    assert worst <= stiffness.HOPPING_ERROR_PER_SENSITIVITY < 1.1 * worst + 0.5
    assert all(r["covered"] == "True" for r in rows)


def _locked(tmp_path, gamma, youngs=2e9):
    """The hopping study's grain: cases/single-sphere as a locked Hertz sphere, phi 25 deg."""
    return _lone(
        tmp_path,
        youngs,
        **{
            "drive.throw_number": gamma,
            "drive.angle": 25.0,
            "trough.inclination": 0.0,
            "particles.rotation": False,
        },
    )


def test_a_lone_grain_beside_the_fall_warns_and_names_a_modulus_that_does(tmp_path):
    """At Gamma 4.4 (the lone grain +7.7 % off at 2e9 Pa, -0.3 % at 2e10) the summary's rule
    expects more than the 2 % allowed and names a modulus; at Gamma 2.9 (0.00 %) it does not."""
    beside = stiffness.single_grain(resolve(_locked(tmp_path, 4.4)))
    assert not beside["converged"] and beside["key"] == "contact.youngs_modulus"
    # it expects at least the measured miss (0.0476 in v_norm), more than the 0.012 allowed
    assert beside["expected_error_hopping"] >= 0.0476 > beside["allowed_error"]
    assert 2e9 < beside["value"] <= 5e10
    warned = [a for a in plan(_locked(tmp_path, 4.4)).warnings()
              if a.key == "contact.youngs_modulus"]  # fmt: skip
    assert len(warned) == 1 and "bifurcation" in warned[0].text
    # the modulus it names is stiff enough by the same rule
    stiff = stiffness.single_grain(resolve(_locked(tmp_path, 4.4, beside["value"])))
    assert stiff["converged"]
    calm = stiffness.single_grain(resolve(_locked(tmp_path, 2.9)))
    assert calm["converged"] and calm["expected_error"] < 0.002


def test_a_grain_that_does_not_fly_has_no_hopping_term(tmp_path):
    one = stiffness.single_grain(resolve(_lone(tmp_path, 2e9)))  # Gamma 0.8
    assert one["expected_error_hopping"] is None
    assert one["expected_error"] == one["expected_error_sliding"]
