"""Smoke test of validation/paper/make_figures.py on coarse grids (a few seconds)."""

import csv
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "validation" / "paper"))
import make_figures as mf  # noqa: E402


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    return out, mf.run(out, quick=True, argv=["make_figures.py", "--quick"])


def test_writes_every_figure_and_table(quick_run):
    out, _ = quick_run
    for stem in ("fig2_regimes", "fig6_throw_number", "fig7_friction", "fig8_throw_number"):
        assert (out / f"{stem}.png").stat().st_size > 10_000
        lines = (out / f"{stem}.csv").read_text().splitlines()
        comments = [line for line in lines if line.startswith("#")]
        assert any("dem_version" in line for line in comments)
        assert any("command" in line for line in comments)
        rows = list(csv.DictReader(line for line in lines if not line.startswith("#")))
        assert rows and all(len(r) == len(rows[0]) for r in rows)
    claims = json.loads((out / "claims.json").read_text())
    assert claims["quick"] is True
    assert "| hold |" in (out / "claims.md").read_text()


def test_quick_claims_are_consistent(quick_run):
    _, claims = quick_run
    assert claims["a"]["max_abs_difference_below_1"] == 0.0
    assert claims["a"]["max_abs_difference_above_1"] > 0.01
    assert claims["fig2"]["agreeing"] == claims["fig2"]["compared_outside_2pct_bands"]
    # at a fixed frequency, holding A and holding A omega^2 are the same constraint
    rows = claims["fig8"]["optima"]
    for gamma in mf.FIG8["throw_number"]:
        amp, acc = (
            r["optimum_angle"]
            for r in rows
            if r["nominal_throw_number"] == gamma and r["hold"] != "throw_number"
        )
        assert amp == pytest.approx(acc, abs=1e-5)


def test_landing_phase_oracles():
    # one-cycle flights: z(t0 + 2 pi) = 2 pi (cos t0 - pi / Gamma) = 0, so take-off and
    # landing at acos(pi / Gamma) (after the first, longer flight from asin(1 / Gamma))
    for gamma in (3.4, 3.6):
        landings = mf.normal_landings(gamma)
        assert np.allclose(landings, math.degrees(math.acos(math.pi / gamma)), atol=1e-6)
    # half-cycle flight at Gamma(0.5) = 1.36846 (DESIGN.md section 4)
    gamma = 1.368457
    landings = mf.normal_landings(gamma)
    assert np.allclose(landings, math.degrees(math.asin(1 / gamma)) + 180.0, atol=1e-2)
    assert len(set(np.round(mf.normal_landings(4.5), 6))) == 2  # period 2


def test_upper_backward_branch_matches_the_integrator():
    from dem import pointmass as pm

    limit = float(mf.backward_upper_branch(89.0, 0.75, 2.5))
    assert 0.9 < limit < 1.0
    assert pm.velocity(0.99 * limit, 89.0, 0.75, 2.5).regime == "rest"
    assert pm.velocity(1.005 * limit, 89.0, 0.75, 2.5).regime == "backward sliding"


def test_gamma_held_curves_depend_on_mu_tan_phi_only():
    # alpha = 0: every phase's tangential law depends on m = mu tan(phi) alone, so the Fig. 7
    # family (Gamma held) is one curve in m; the README's explanation of claim (c) rests on it
    from dem import pointmass as pm

    phi = np.array([10.0, 30.0, 50.0, 70.0])
    m = 0.25 * np.tan(np.radians(phi))
    other = np.degrees(np.arctan(m / 0.6))
    for gamma in (0.5, 1.8, 4.5):
        a = pm.velocities(gamma, phi, 0.25)["velocity_norm"]
        b = pm.velocities(gamma, other, 0.6)["velocity_norm"]
        np.testing.assert_allclose(a, b, atol=1e-9)
