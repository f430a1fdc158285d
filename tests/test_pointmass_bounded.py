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
