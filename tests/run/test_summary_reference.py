"""The summary's single-grain references: the rolling sphere beside the point mass, and which one
applies and why (dem.run.summary.reference_fields), as summary.json and the terminal give them."""

import functools
import math

import pytest

from dem import pointmass
from dem.config import GRAVITY
from dem.pointmass import rolling
from dem.run.summary import pointmass_bounded, reference_fields
from dem.scene.case import load_case
from dem.studies.answers import run_summary_lines


def _fields(name, overrides=None):
    """The case and its reference fields; each case loaded once (a load takes 0.2-0.4 s)."""
    return _cached(name, tuple(sorted((overrides or {}).items())))


@functools.cache
def _cached(name, overrides):
    case = load_case(f"cases/{name}", dict(overrides))
    return case, reference_fields(case)


def test_spheres_free_to_roll_take_the_rolling_sphere():
    case, f = _fields("single-sphere", {"particles.rotation": True})
    assert f["reference"] == "pointmass_rolling" and "rotation locked" in f["reference_reason"]
    # Gamma 0.6, phi 25, mu 0.35 of the case: the solid sphere, started at rest at phase 0
    expected = rolling.velocity(0.6, 25.0, 0.35, 0.0, 0.8, 0.0, 0.4, 1.0, "centre", "coulomb")
    assert f["pointmass_rolling_velocity_norm"] == expected.velocity_norm
    bounded = pointmass.velocity(0.6, 25.0, 0.35, impact="coulomb").velocity_norm
    assert expected.velocity_norm > bounded + 0.3  # it rolls where the block sticks


@pytest.mark.parametrize(
    ("name", "words"), [("single-sphere", "rotation = false"), ("screw-trough", "screws")]
)
def test_grains_that_cannot_roll_keep_the_coulomb_bounded_point_mass(name, words):
    """Spheres locked (the case as shipped) and screws (rotation free: they are no spheres)."""
    case, f = _fields(name)
    assert f["reference"] == "pointmass_bounded" and words in f["reference_reason"]
    assert f["pointmass_rolling_velocity_norm"] is None
    assert pointmass_bounded(case) is not None  # the value summary.json holds under that name


def test_a_free_sphere_on_an_incline_has_no_reference_and_says_why():
    _, f = _fields("single-sphere", {"particles.rotation": True, "trough.inclination": 3.0})
    assert f["reference"] is None and f["pointmass_rolling_velocity_norm"] is None
    a = GRAVITY * math.sin(math.radians(3.0)) * 5.0 / 7.0
    assert "no steady state" in f["reference_reason"] and f"{a:.3g} m/s^2" in f["reference_reason"]


def test_a_ramped_start_leaves_no_momentum_about_the_contact_line():
    _, f = _fields("single-sphere", {"particles.rotation": True, "drive.ramp_cycles": 2})
    expected = rolling.velocity(0.6, 25.0, 0.35, momentum=0.0).velocity_norm
    assert f["pointmass_rolling_velocity_norm"] == pytest.approx(expected, abs=1e-15)
    assert "ramped" in f["reference_reason"]


@pytest.mark.parametrize("rotation", [True, False])
def test_two_component_drives(rotation):
    two = {"drive.second_amplitude": 1e-4, "drive.second_angle": 90.0, "drive.second_phase": 90.0}
    _, f = _fields("single-sphere", {"particles.rotation": rotation, **two})
    if rotation:
        assert f["reference"] is None and "line drives only" in f["reference_reason"]
    else:  # the stepped point mass
        assert f["reference"] == "pointmass" and "stepped" in f["reference_reason"]


def test_the_rolling_model_says_it_has_no_rolling_friction():
    _, f = _fields("single-sphere", {"particles.rotation": True, "wall.rolling_friction": 0.01})
    assert f["reference"] == "pointmass_rolling" and "rolling friction" in f["reference_reason"]


def _summary(fields):
    return {
        "mean_velocity": 0.03, "mean_velocity_stderr": 1e-4, "mean_velocity_norm": 0.82,
        "mean_velocity_norm_stderr": 1e-3, "mass_flow_rate": 1e-5,
        "mass_flow_rate_per_width": 1e-3, "timestep": 1e-6, "steps": 10, "wall_time_s": 1.0,
        "pointmass_velocity_norm": 0.30, "pointmass_bounded_velocity_norm": 0.34, **fields,
    }  # fmt: skip


def test_the_terminal_shows_the_rolling_reference_for_grains_that_roll():
    _, f = _fields("single-sphere", {"particles.rotation": True})
    text = "\n".join(run_summary_lines(_summary(f)))
    assert f"rolling sphere     {f['pointmass_rolling_velocity_norm']:.3f} in v_norm" in text
    assert "0.340 (Coulomb-bounded) in v_norm" in text
    _, f = _fields("single-sphere")
    text = "\n".join(run_summary_lines(_summary(f)))
    assert "rolling sphere" not in text and "the DEM's reference" in text
    _, f = _fields("single-sphere", {"particles.rotation": True, "trough.inclination": 3.0})
    assert "rolling sphere     no reference: " in "\n".join(run_summary_lines(_summary(f)))
