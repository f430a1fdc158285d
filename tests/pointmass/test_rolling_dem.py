"""(d) The DEM's free sphere against the rolling sphere: two drives of validation/rolling-sphere
(its own functions, shorter runs on a softer contact), the incline, and summary.json's reference.

The study itself (20 drives at the shipped k_n = 1.6e7 N/m) is validation/rolling-sphere/run.py.
"""

import importlib.util
import json
from pathlib import Path

import pytest

from dem.run.runner import run_case
from dem.scene.case import load_case

STUDY = Path(__file__).resolve().parents[2] / "validation" / "rolling-sphere" / "run.py"


def _study():
    spec = importlib.util.spec_from_file_location("rolling_sphere_study", STUDY)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.validation
@pytest.mark.parametrize(
    "drive",
    [
        {"throw_number": 0.8, "angle": 25.0, "friction": 0.35, "eps_t": 0.8},
        # hopping, where the two landing laws differ by 6 %: the DEM follows "centre"
        {"throw_number": 1.8, "angle": 15.0, "friction": 0.2, "eps_t": 0.8},
    ],
)
def test_a_free_dem_sphere_conveys_as_the_rolling_sphere(drive):
    row = _study().dem_row(drive, settle=8, cycles=4, stiffness=4.0e6)
    assert abs(row["error_rolling"]) < 0.02, row
    # far from the point mass: the rolling reference is the one that applies
    assert row["dem_velocity_norm"] > 1.5 * row["pointmass_bounded_velocity_norm"]


@pytest.mark.validation
def test_a_free_dem_sphere_rolls_down_an_incline_at_five_sevenths_g_sin_alpha():
    study = _study()
    free = study.incline_row(True, duration=0.02, stiffness=4.0e6)
    assert free["dem_acceleration_m_s2"] == pytest.approx(free["expected_acceleration_m_s2"],
                                                          rel=1e-4)  # fmt: skip
    assert abs(free["slip_m_s"]) < 1e-6  # it rolls, the contact point does not slip
    locked = study.incline_row(False, duration=0.02, stiffness=4.0e6)
    assert abs(locked["dem_acceleration_m_s2"]) < 1e-6  # tan(10 deg) < mu: the block rests


@pytest.mark.integration
def test_a_run_of_a_free_sphere_names_the_rolling_reference_and_meets_it(tmp_path):
    case = load_case(
        "cases/single-sphere",
        {"particles.rotation": True, "contact.stiffness": 4.0e6, "run.settle_cycles": 4,
         "run.cycles": 3, "drive.throw_number": 0.8},
    )  # fmt: skip
    summary = run_case(case, tmp_path, progress=False, frames=False)
    on_disk = json.loads((tmp_path / "summary.json").read_text())
    assert on_disk["reference"] == "pointmass_rolling"
    reference = on_disk[on_disk["reference"] + "_velocity_norm"]
    assert summary["mean_velocity_norm"] == pytest.approx(reference, rel=0.02)
    # every earlier key keeps its meaning: the point mass and its bounded variant are still there
    assert on_disk["pointmass_bounded_velocity_norm"] < 0.5 < on_disk["mean_velocity_norm"]
