"""summary.json records the contact law of both interactions (dem.physics.contact report)."""

import dataclasses
import json
from pathlib import Path

import pytest

from dem.run.runner import run_case
from dem.scene.case import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.mark.integration
def test_a_runs_summary_records_e_nu_eps_n_eps_t_of_both_interactions(tmp_path):
    overrides = {"wall.friction": 0.5, "wall.restitution_normal": 0.3,
                 "wall.restitution_tangential": 0.7}  # fmt: skip
    case = load_case(CASES / "sphere-bed", overrides)
    case = dataclasses.replace(
        case,
        particles=dataclasses.replace(case.particles, count=30),
        trough=dataclasses.replace(case.trough, length=0.03, width=0.02),
        run=dataclasses.replace(case.run, settle_cycles=1, replicas=1),
    )
    run_case(case, tmp_path, cycles=1, progress=False, threads=1)
    law = json.loads((tmp_path / "summary.json").read_text())["contact_law"]
    c = case.contact
    for name, material in (("grain_grain", case.material), ("grain_wall", case.wall_material)):
        row = law[name]
        assert row["model"] == c.model == "hertz_mindlin"
        assert row["youngs_modulus"] == c.youngs_modulus
        assert row["poisson_ratio"] == c.poisson_ratio
        assert row["restitution_normal"] == material.restitution_normal
        assert row["restitution_tangential"] == material.restitution_tangential
        assert row["friction"] == material.friction
        assert row["tangential"] == c.tangential
    assert law["grain_wall"]["restitution_tangential"] == 0.7
