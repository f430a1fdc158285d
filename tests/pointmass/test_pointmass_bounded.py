"""The Coulomb-bounded point mass (time-stepped) against the paper's event-driven model."""

import pytest

from dem import pointmass
from dem.pointmass.bounded import coulomb_bounded_velocity


@pytest.mark.parametrize("gamma", [1.85, 2.3, 3.8])
def test_agrees_with_the_event_driven_model_below_the_coulomb_bound(gamma):
    # landings at these drives lose (1 - eps_t) u < mu |dw| tan(phi): the cap never acts
    exact = pointmass.velocity(gamma, 25.0, 0.35, eps_t=0.8).velocity_norm
    assert coulomb_bounded_velocity(gamma, 25.0, 0.35, 0.8) == pytest.approx(exact, abs=2e-3)


def test_grazing_landings_lose_no_more_than_coulomb_allows():
    # Gamma 1.1: the landing is mostly tangential; Eq. 12 would take more than mu |dw|
    paper = pointmass.velocity(1.1, 25.0, 0.35, eps_t=0.2).velocity_norm
    bounded = coulomb_bounded_velocity(1.1, 25.0, 0.35, 0.2)
    assert bounded > paper + 0.3
    # a frictionless floor takes nothing: the bound is zero, eps_t cannot act
    assert coulomb_bounded_velocity(1.5, 25.0, 0.0, 0.2) == pytest.approx(
        coulomb_bounded_velocity(1.5, 25.0, 0.0, 1.0), abs=1e-12
    )


@pytest.mark.parametrize("eps_t", [0.2, 0.5, 0.8])
@pytest.mark.parametrize("gamma", [1.1, 1.3, 1.5, 2.0, 3.0, 4.2, 4.6])
def test_event_driven_bounded_model_agrees_with_the_stepped_one(gamma, eps_t):
    """Two independent integrations of the Coulomb-bounded landing law: the event-driven
    model with ``impact="coulomb"`` (exact phase changes) and the time-stepped one."""
    exact = pointmass.velocity(gamma, 25.0, 0.35, eps_t=eps_t, impact="coulomb").velocity_norm
    assert coulomb_bounded_velocity(gamma, 25.0, 0.35, eps_t) == pytest.approx(exact, abs=2e-3)


def test_bounded_model_is_the_papers_where_coulomb_allows_eq_12():
    for gamma in (2.0, 3.0):
        paper = pointmass.velocity(gamma, 25.0, 0.35).velocity_norm
        assert pointmass.velocity(gamma, 25.0, 0.35, impact="coulomb").velocity_norm == paper
    # the example: Gamma 1.3, phi 30, mu 0.35
    assert pointmass.velocity(1.3, 30.0, 0.35).velocity_norm == pytest.approx(0.327, abs=1e-3)
    bounded = pointmass.velocity(1.3, 30.0, 0.35, impact="coulomb").velocity_norm
    assert bounded == pytest.approx(0.435, abs=1e-3)
    with pytest.raises(ValueError, match="impact must be one of"):
        pointmass.velocity(1.3, 30.0, 0.35, impact="walton")


def test_pointmass_commands_take_the_impact_law(capsys):
    import json

    from dem.cli import main

    argv = ["pointmass", "velocity", "--throw-number", "1.3", "--angle", "30", "--friction",
            "0.35", "--json"]  # fmt: skip
    assert main(argv) == 0
    paper = json.loads(capsys.readouterr().out)
    assert main([*argv, "--impact", "coulomb"]) == 0
    bounded = json.loads(capsys.readouterr().out)
    assert (paper["impact"], bounded["impact"]) == ("paper", "coulomb")
    assert bounded["velocity_norm"] - paper["velocity_norm"] == pytest.approx(0.108, abs=2e-3)
    sweep = ["pointmass", "sweep", "--throw-number", "1.3", "--angle", "30", "--friction", "0.35"]
    assert main([*sweep, "--impact", "coulomb"]) == 0
    header, row = capsys.readouterr().out.splitlines()[:2]
    assert dict(zip(header.split(","), row.split(","), strict=True))["impact"] == "coulomb"
    with pytest.raises(SystemExit) as info:
        main(["pointmass", "velocity", "--throw-number", "1.3", "--angle", "30",
              "--friction", "0.35", "--impact", "walton"])  # fmt: skip
    assert info.value.code == 2 and "--impact" in capsys.readouterr().err
