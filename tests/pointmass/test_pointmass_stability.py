"""The point-mass model tells periodic orbits from motion that never repeats."""

from dem import pointmass


def test_bouncing_grain_is_flagged_non_periodic():
    # eps_n = 0.6 at Gamma 2.14 (phi 25, mu 0.35): inside a window of erratic bouncing
    r = pointmass.velocity(2.14, 25.0, 0.35, eps_t=0.8, eps_n=0.6)
    assert not r.periodic and r.period == 0 and r.regime == "non-periodic"
    assert r.velocity_min < r.velocity_max and r.spread > 0.0


def test_plastic_landings_double_the_period_as_gamma_grows():
    # eps_n = 0: period 1, 2, 4 (validation/stability/pointmass_bifurcation.png)
    periods = [
        pointmass.velocity(g, 25.0, 0.35, eps_t=0.8, eps_n=0.0).period for g in (2.0, 5.0, 7.0)
    ]
    assert periods == [1, 2, 4]
