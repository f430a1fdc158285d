"""Smoke test of validation/paper/make_figures.py on coarse grids (a few seconds)."""

import csv
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "validation" / "paper"))
import make_figures as mf  # noqa: E402


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    return out, mf.run(out, quick=True, argv=["make_figures.py", "--quick"])


@pytest.mark.validation
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
    assert "| reading |" in (out / "claims.md").read_text()


@pytest.mark.validation
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


@pytest.mark.validation
def test_landing_phase_oracles():
    # one-cycle flights: z(t0 + 2 pi) = 2 pi (cos t0 - pi / Gamma) = 0, so take-off and
    # landing at acos(pi / Gamma) (after the first, longer flight from asin(1 / Gamma))
    for gamma in (3.4, 3.6):
        landings = mf.normal_landings(gamma)
        assert np.allclose(landings, math.degrees(math.acos(math.pi / gamma)), atol=1e-6)
    # half-cycle flight at Gamma(0.5) = 1.36846 (README, The point-mass model)
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


@pytest.mark.validation
def test_v_over_a_omega_reading_reproduces_claim_c(quick_run):
    # Gamma held, velocity in units of the drive velocity amplitude: v / (A omega) =
    # v_norm cos(phi). Check each optimum against the model directly, then the trends.
    from dem import pointmass as pm

    _, claims = quick_run
    rows = [r for r in claims["fig7"]["optima"] if r["reading"] == "v_over_A_omega"]
    rows += [r for r in claims["fig8"]["optima"] if r["reading"] == "v_over_A_omega"]
    assert len(rows) == 6
    for r in rows:
        mu, gamma, phi = r["friction"], r["held_value"], r["optimum_angle"]

        def objective(angle, mu=mu, gamma=gamma):
            v = pm.velocities(gamma, np.atleast_1d(angle), mu)["velocity_norm"]
            return v * np.cos(np.radians(angle))

        top = r["v_over_A_omega_at_optimum"]
        assert objective(phi)[0] == pytest.approx(top, rel=1e-9)
        assert top == pytest.approx(r["velocity_norm_at_optimum"] * math.cos(math.radians(phi)))
        grid = np.linspace(1.0, 89.0, 177)  # independent of the quick grid
        assert objective(grid).max() <= top * (1 + 1e-6)
        lo, hi = r["plateau_90"]
        assert objective(np.array([lo, hi])).min() >= 0.9 * top
        outside = np.array([x for x in (lo - 2.0, hi + 2.0) if 1.0 <= x <= 89.0])
        assert np.all(objective(outside) < 0.9 * top)
    # claim (c): the optimum falls with mu and its 90% plateau narrows (full run: 37.3, 37.0,
    # 29.6 deg; 34, 29, 22 deg wide); with v_norm (Gamma held) the plateau widens instead
    fig7 = rows[:3]
    assert [r["friction"] for r in fig7] == list(mf.FIG7["friction"])
    angles = [r["optimum_angle"] for r in fig7]
    widths = [r["plateau_width"] for r in fig7]
    assert angles[0] > angles[1] > angles[2] + 5.0
    assert widths[0] > widths[1] > widths[2]
    verdict = claims["verdicts"]["c"]
    assert verdict["v_over_A_omega"]["falls"] and verdict["v_over_A_omega"]["sharpens"]
    assert not verdict["throw_number"]["sharpens"]
