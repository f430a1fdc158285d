"""The point-mass model against exact oracles and a brute-force time-stepping twin."""

import math

import numpy as np
import pytest
from naive_pointmass import brute

from dem import pointmass as pm
from dem.errors import InputError


def test_thresholds_paper_example():
    t = pm.thresholds(angle=25, friction=0.75, inclination=2.5)
    assert t.forward_sliding == pytest.approx(0.2742, abs=1e-4)
    assert t.backward_sliding == pytest.approx(0.5065, abs=1e-4)
    assert t.flight == 1.0


def test_backward_sliding_impossible_when_cot_phi_below_mu():
    assert pm.thresholds(angle=60, friction=0.75).backward_sliding is None
    assert pm.velocity(0.99, 60, 0.75).regime == "forward sliding"


def test_backward_sliding_when_drive_leans_back_over_steep_incline():
    # phi + alpha > 90 deg, cot phi < mu: backward sliding before flight at
    # Gamma > (mu - tan a) / (mu - cot phi), a case Eq. (2) does not cover
    t = pm.thresholds(angle=89, friction=0.75, inclination=2.5)
    expected = (0.75 - math.tan(math.radians(2.5))) / (0.75 - 1 / math.tan(math.radians(89)))
    assert t.backward_sliding == pytest.approx(expected)
    assert t.forward_sliding > 1.0  # here the mass never slides forward before it flies
    assert pm.velocity(0.99 * expected, 89, 0.75, 2.5).regime == "rest"
    assert pm.velocity(1.01 * expected, 89, 0.75, 2.5).regime == "backward sliding"


@pytest.mark.parametrize(
    "angle,friction,inclination", [(25, 0.35, 0), (40, 0.6, 5), (15, 0.25, -3)]
)
def test_regimes_switch_at_the_thresholds(angle, friction, inclination):
    t = pm.thresholds(angle, friction, inclination)
    below = pm.velocity(0.98 * t.forward_sliding, angle, friction, inclination)
    assert below.regime == "rest" and below.velocity_norm == 0.0
    forward = pm.velocity(1.02 * t.forward_sliding, angle, friction, inclination)
    assert forward.regime == "forward sliding" and forward.velocity_norm > 0
    if t.backward_sliding is not None and t.backward_sliding < 0.97:
        both = pm.velocity(1.03 * t.backward_sliding, angle, friction, inclination)
        assert both.regime == "forward and backward sliding"
        just_below = pm.velocity(0.97 * t.backward_sliding, angle, friction, inclination)
        assert just_below.regime == "forward sliding"
    assert pm.velocity(1.05, angle, friction, inclination).flight > 0


def gamma_of_flight(n):
    """Throw number whose flight (eps_n = 0) lasts n cycles (README, The point-mass model)."""
    a = 2 * math.pi * n
    return math.sqrt(1 + ((2 * math.pi**2 * n**2 + math.cos(a) - 1) / (a - math.sin(a))) ** 2)


@pytest.mark.parametrize("n,expected", [(0.5, 1.36846), (0.8, 2.23411), (1.0, 3.29691)])
def test_flight_duration_oracle(n, expected):
    assert gamma_of_flight(n) == pytest.approx(expected, abs=1e-5)
    if n < 1:
        r = pm.velocity(gamma_of_flight(n), 25, 0.35)
        assert r.flight == pytest.approx(n, abs=1e-9)


@pytest.mark.parametrize("gamma,expected", [(1.1, 0.21932), (1.5, 0.67471), (2.0, 0.86361)])
def test_ideal_adhesion_oracle(gamma, expected):
    # mu -> infinity, eps_t = 0: v = pi n^2 / Gamma
    r = pm.velocity(gamma, 25, 1e9, eps_t=0.0)
    assert r.velocity_norm == pytest.approx(expected, abs=2e-5)


@pytest.mark.parametrize("alpha", [0.0, -4.0, 6.0])
def test_ideal_adhesion_on_incline(alpha):
    phi, gamma = 30.0, 1.7
    n = _flight_fraction(gamma)
    expected = math.pi * n**2 * (1 - math.tan(math.radians(alpha)) * math.tan(math.radians(phi)))
    r = pm.velocity(gamma, phi, 1e9, inclination=alpha, eps_t=0.0)
    assert r.velocity_norm == pytest.approx(expected / gamma, abs=1e-6)


def _flight_fraction(gamma):
    lo, hi = 1e-6, 1.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gamma_of_flight(mid) < gamma else (lo, mid)
    return lo


@pytest.mark.parametrize("gamma", [3.4, 3.6])
@pytest.mark.parametrize("friction,eps_t", [(0.2, 0.8), (0.9, 0.3), (0.35, 0.0)])
def test_one_period_flight_oracle(gamma, friction, eps_t):
    # sqrt(1 + pi^2) < Gamma < sqrt(4 + pi^2): every flight lasts one cycle, v = pi / Gamma
    r = pm.velocity(gamma, 25, friction, eps_t=eps_t)
    assert r.flight == pytest.approx(1.0)
    assert r.velocity_norm == pytest.approx(math.pi / gamma, abs=1e-7)


@pytest.mark.parametrize("alpha,eps_t", [(3.0, 0.8), (-5.0, 0.5), (4.0, 0.0)])
def test_one_period_flight_on_incline(alpha, eps_t):
    # With alpha != 0 gravity along the floor is balanced by the landing impulses alone:
    # u0 = -2 pi c eps_t / (1 - eps_t) with c = tan a tan phi / Gamma, so
    # v = pi (1 - tan a tan phi) / Gamma - 2 pi c eps_t / (1 - eps_t).
    # (The form without the eps_t term holds for alpha = 0 or eps_t = 0 only.)
    gamma, phi = 3.5, 25.0
    c = math.tan(math.radians(alpha)) * math.tan(math.radians(phi)) / gamma
    expected = math.pi / gamma - math.pi * c - 2 * math.pi * c * eps_t / (1 - eps_t)
    r = pm.velocity(gamma, phi, 0.35, inclination=alpha, eps_t=eps_t)
    assert r.velocity_norm == pytest.approx(expected, abs=1e-7)


def test_period_doubling_at_sqrt_4_plus_pi_squared():
    critical = math.sqrt(4 + math.pi**2)
    assert pm.velocity(critical - 0.03, 25, 0.35).period == 1
    assert pm.velocity(critical + 0.03, 25, 0.35).period == 2


def test_eps_t_irrelevant_without_flight():
    gammas = np.linspace(0.1, 0.99, 30)
    v = [pm.velocities(gammas, 25, 0.35, eps_t=e)["velocity_norm"] for e in (0.2, 0.5, 0.8)]
    np.testing.assert_array_equal(v[0], v[1])
    np.testing.assert_array_equal(v[0], v[2])
    assert pm.velocity(1.5, 25, 0.35, eps_t=0.2).velocity_norm != pytest.approx(
        pm.velocity(1.5, 25, 0.35, eps_t=0.8).velocity_norm, abs=1e-3
    )


@pytest.mark.parametrize("eps_n", [0.3, 0.7, 0.95])
@pytest.mark.parametrize("gamma", [1.5, 2.5, 5.0])
def test_bouncing_terminates_and_is_finite(eps_n, gamma):
    r = pm.velocity(gamma, 25, 0.35, eps_n=eps_n)
    assert math.isfinite(r.velocity_norm)
    assert r.velocity_min <= r.velocity_norm <= r.velocity_max


def test_small_eps_n_limit_is_the_zeno_limit():
    # With eps_n > 0 a landing ends in a Zeno sequence of ever smaller bounces, each
    # multiplying the tangential relative velocity by eps_t, so it leaves none: as eps_n -> 0+
    # the motion tends to that with eps_t = 0, not to eps_n = 0 with eps_t = 0.8.
    zeno = pm.velocity(1.8, 25, 0.35, eps_t=0.0, eps_n=0.0).velocity_norm
    for eps_n in (1e-6, 1e-4):
        assert pm.velocity(1.8, 25, 0.35, eps_n=eps_n).velocity_norm == pytest.approx(
            zeno, abs=1e-3
        )
    assert pm.velocity(1.8, 25, 0.35, eps_n=0.0).velocity_norm > zeno + 0.1


def test_velocities_broadcast_matches_scalar():
    out = pm.velocities([1.2, 2.5], 25, [[0.25], [0.6]])
    assert out["velocity_norm"].shape == (4,)
    assert out["velocity_norm"][3] == pm.velocity(2.5, 25, 0.6).velocity_norm


def _grid():
    rng = np.random.default_rng(20261121)
    n = 160
    random = np.column_stack(
        [
            rng.uniform(0.1, 7.0, n),
            rng.uniform(5.0, 85.0, n),
            rng.uniform(0.1, 1.0, n),
            rng.uniform(-10.0, 10.0, n),
            rng.uniform(0.0, 0.95, n),
            np.zeros(n),
        ]
    )
    # eps_t = 1 (no loss at landing) where every cycle has a contact phase that dissipates;
    # inside the one-cycle-flight window the motion is neutral and depends on the transient.
    lossless = np.column_stack(
        [rng.uniform(0.1, 3.2, 20), rng.uniform(5, 85, 20), rng.uniform(0.1, 1, 20)]
        + [np.zeros(20), np.ones(20), np.zeros(20)]
    )
    dip = np.array([[g, 25.0, 0.35, 0.0, e, 0.0] for g in (4.3, 4.5, 4.6, 4.7) for e in (0.2, 0.8)])
    return np.vstack([random, lossless, dip])


@pytest.mark.validation
def test_agrees_with_brute_force_time_stepping():
    grid = _grid()
    model = pm.velocities(*grid.T)
    periodic = model["periodic"]
    assert periodic.mean() > 0.97  # a grid point that never settles is compared below
    # skip about as many cycles as the model needed to close the orbit, plus a margin
    transient = (1.5 * model["cycles"][periodic]).astype(int) + 100
    reference = brute(grid[periodic], steps=8000, transient=transient, measured=48)
    error = np.abs(reference - model["velocity_norm"][periodic])
    worst = int(np.argmax(error))
    assert error.max() < 0.005, (grid[periodic][worst], error.max())


@pytest.mark.parametrize(
    "kwargs,key",
    [
        ({"throw_number": 0.0}, "throw_number"),
        ({"throw_number": -1.0}, "throw_number"),
        ({"angle": 90.0}, "angle"),
        ({"angle": 0.0}, "angle"),
        ({"friction": -0.1}, "friction"),
        ({"inclination": 90.0}, "inclination"),
        ({"eps_t": 1.2}, "eps_t"),
        ({"eps_n": -0.5}, "eps_n"),
        ({"throw_number": math.nan}, "throw_number"),
    ],
)
def test_bad_input_names_key(kwargs, key):
    args = {"throw_number": 1.8, "angle": 25.0, "friction": 0.35} | kwargs
    with pytest.raises(InputError) as info:
        pm.velocity(**args)
    assert info.value.key == key
    assert key in str(info.value)
