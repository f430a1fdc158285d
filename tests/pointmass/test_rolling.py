"""The rolling sphere (dem.pointmass.rolling) against independent oracles.

(a) its limits: a locked spin is the Coulomb-bounded point mass, no rotational inertia a
frictionless grain; (b) closed forms: pure rolling on a level trough, rolling down an incline;
(c) a brute-force time-stepped twin of the sphere's own equations (tests/oracles/naive_rolling).
The DEM's free sphere is in test_rolling_dem.py.
"""

import math

import numpy as np
import pytest
from naive_rolling import brute_rolling

from dem import pointmass
from dem.config import GRAVITY
from dem.errors import InputError
from dem.pointmass import rolling

SLIDING = [(0.5, 25.0, 0.35), (0.8, 45.0, 0.6), (0.95, 15.0, 0.2)]
HOPPING = [(1.3, 30.0, 0.35), (1.8, 25.0, 0.35), (3.0, 15.0, 0.6)]


@pytest.mark.parametrize(("gamma", "phi", "mu"), SLIDING + HOPPING)
@pytest.mark.parametrize("eps_t", [0.8, 0.5])
def test_a_locked_spin_is_the_coulomb_bounded_point_mass(gamma, phi, mu, eps_t):
    """(a) k = I / (m r^2) -> infinity: the spin cannot change, the sphere is a sliding block."""
    bounded = pointmass.velocity(gamma, phi, mu, eps_t=eps_t, impact="coulomb").velocity_norm
    for landing in rolling.LANDINGS:
        locked = rolling.velocity(gamma, phi, mu, eps_t=eps_t, inertia_factor=math.inf,
                                  landing=landing)  # fmt: skip
        assert locked.velocity_norm == bounded
        # the finite-k path converges on it
        heavy = rolling.velocity(gamma, phi, mu, eps_t=eps_t, inertia_factor=1e6, landing=landing)
        assert heavy.velocity_norm == pytest.approx(bounded, abs=1e-4)


@pytest.mark.parametrize(("gamma", "phi", "mu"), [SLIDING[0], HOPPING[1]])
def test_no_rotational_inertia_is_a_frictionless_grain_not_the_point_mass(gamma, phi, mu):
    """k -> 0: the spin follows any friction force at no cost, so friction moves nothing and the
    grain keeps its start's momentum: v_norm = P (1 for a start at rest at phase 0)."""
    light = rolling.velocity(gamma, phi, mu, inertia_factor=1e-9).velocity_norm
    assert light == pytest.approx(1.0, abs=1e-6)
    assert abs(light - pointmass.velocity(gamma, phi, mu, impact="coulomb").velocity_norm) > 0.2


@pytest.mark.parametrize("k", [rolling.SOLID_SPHERE, rolling.THIN_SHELL, 2.5])
@pytest.mark.parametrize("phi", [15.0, 40.0])
def test_pure_rolling_on_a_level_trough(k, phi):
    """(b) Rolling, dv/dt = a / (1 + k): from rest at phase 0, u = (1 - cos theta) / (1 + k),
    whose mean is 1 / (1 + k), while friction can hold it: m_t |a| <= mu N, i.e. below
    Gamma = mu' / (cot(phi) + mu') with mu' = mu (1 + 1/k) (the paper's Eq. 1 at mu')."""
    mu = 0.3
    mu_slip = mu * (1.0 + 1.0 / k)
    onset = mu_slip / (1.0 / math.tan(math.radians(phi)) + mu_slip)
    below = rolling.velocity(0.95 * onset, phi, mu, inertia_factor=k)
    assert below.regime == "rolling" and below.rolling == pytest.approx(1.0)
    assert below.velocity_norm == pytest.approx(1.0 / (1.0 + k), abs=1e-12)
    assert below.slip_norm == 0.0
    above = rolling.velocity(1.05 * onset, phi, mu, inertia_factor=k)
    assert above.regime == "slipping forward" and above.rolling < 1.0
    # a grain at rest in the laboratory as it starts rolls under the trough and conveys nothing
    assert (
        rolling.velocity(0.95 * onset, phi, mu, inertia_factor=k, momentum=0.0).velocity_norm == 0
    )


@pytest.mark.parametrize("alpha", [5.0, -3.0])
@pytest.mark.parametrize("k", [rolling.SOLID_SPHERE, rolling.THIN_SHELL])
def test_a_round_grain_on_an_incline_rolls_downhill_without_a_steady_state(alpha, k):
    """(b) On an incline the mean acceleration is g sin(alpha) / (1 + k) down the slope (5/7 g
    sin(alpha) for a solid sphere), whatever the drive: no mean velocity exists."""
    frequency = 60.0
    for gamma, phi, mu in (SLIDING[0], HOPPING[1]):
        r = rolling.velocity(gamma, phi, mu, alpha, inertia_factor=k)
        assert r.regime == rolling.DOWNHILL and not r.periodic and math.isnan(r.velocity_norm)
        assert r.as_dict()["velocity_norm"] is None
        per_second = r.drift_per_cycle * r.velocity_scale(frequency) * frequency
        assert per_second == pytest.approx(
            -GRAVITY * math.sin(math.radians(alpha)) / (1.0 + k), rel=1e-12
        )
    # the locked spin (the point mass) has a steady state there
    assert rolling.velocity(1.8, 25.0, 0.35, alpha, inertia_factor=math.inf).periodic


def test_regimes_phases_and_units():
    r = rolling.velocity(0.8, 25.0, 0.35)
    assert r.regime == "slipping forward" and r.periodic and r.period == 1
    assert r.rolling + r.slip_forward + r.slip_backward + r.flight == pytest.approx(1.0)
    # v = (P + k <sigma>) / (1 + k)
    assert r.velocity_norm == pytest.approx((1.0 + 0.4 * r.slip_norm) / 1.4, rel=1e-14)
    scale = pointmass.velocity_scale(0.8, 60.0, 25.0)
    assert r.velocity(60.0) == pytest.approx(r.velocity_norm * scale)
    hop = rolling.velocity(1.8, 25.0, 0.35)
    assert hop.flight > 0.0 and hop.regime.startswith("hopping")


def test_non_periodic_motion_is_reported_with_its_spread():
    r = rolling.velocity(1.9, 25.0, 0.35, eps_n=0.6)
    assert r.regime == "non-periodic" and not r.periodic and r.period == 0
    assert r.spread > 0.0
    assert r.velocity_min <= r.velocity_norm <= r.velocity_max


def test_landing_laws():
    """The two laws meet below flight and at eps_t = 1; in flight they differ (Gamma 1.8, phi 15
    deg, mu 0.2: the "centre" law takes (1 - eps_t) of the slip off the centre, 3.5 times what
    the "contact" law takes off it)."""
    assert rolling.slip_restitution(0.8, 0.4, "contact") == 0.8
    assert rolling.slip_restitution(0.8, 0.4, "centre") == pytest.approx(0.3)
    assert rolling.slip_restitution(0.2, 0.4, "centre") == 0.0  # stopped at rolling
    assert rolling.slip_restitution(0.8, math.inf, "centre") == 0.8
    assert rolling.slip_friction(0.35, 0.4) == pytest.approx(1.225)
    centre, contact = (rolling.velocity(gamma, 15.0, 0.2, landing=law).velocity_norm
                       for law in ("centre", "contact") for gamma in [1.8])  # fmt: skip
    assert contact - centre > 0.03
    assert rolling.velocity(0.8, 15.0, 0.2, landing="contact").velocity_norm == (
        rolling.velocity(0.8, 15.0, 0.2, landing="centre").velocity_norm
    )


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"inertia_factor": 0.0}, "inertia_factor"),
        ({"inertia_factor": -0.4}, "inertia_factor"),
        ({"inertia_factor": math.nan}, "inertia_factor"),
        ({"inertia_factor": True}, "inertia_factor"),
        ({"momentum": math.inf}, "momentum"),
        ({"landing": "walton"}, "landing"),
        ({"friction": -1.0}, "friction"),
        ({"eps_t": 1.5}, "eps_t"),
    ],
)
def test_bad_input_is_named_with_its_value_and_range(kwargs, key):
    args = {"throw_number": 0.8, "angle": 25.0, "friction": 0.35} | kwargs
    with pytest.raises(InputError) as info:
        rolling.velocity(**args)
    assert info.value.key == key and repr(kwargs.get(key, args.get(key)))[:3] in str(info.value)
    if not isinstance(args.get(key), bool):  # arrays of numbers hold no booleans
        with pytest.raises(InputError):
            rolling.velocities(**args)


# --- (c) the brute-force twin ------------------------------------------------------------------

#: (Gamma, phi, mu, eps_t, eps_n, k, landing): sliding and hopping, both landing laws, a shell,
#: a locked spin, a bouncing landing
BRUTE = [
    (0.5, 25.0, 0.35, 0.8, 0.0, 0.4, "centre"),
    (0.95, 15.0, 0.2, 0.8, 0.0, 0.4, "centre"),
    (0.8, 45.0, 0.6, 0.8, 0.0, 2.0 / 3.0, "contact"),
    (1.2, 25.0, 0.35, 0.8, 0.0, 0.4, "centre"),
    (1.8, 15.0, 0.2, 0.8, 0.0, 0.4, "centre"),
    (1.8, 15.0, 0.2, 0.8, 0.0, 0.4, "contact"),
    (1.8, 25.0, 0.35, 0.5, 0.0, 2.0 / 3.0, "centre"),
    (2.5, 30.0, 0.4, 0.8, 0.0, math.inf, "centre"),
    (1.4, 25.0, 0.35, 0.8, 0.3, 0.4, "contact"),
]


@pytest.mark.validation
def test_agrees_with_a_brute_force_twin_of_the_spheres_own_equations():
    """(c) Fixed steps of the centre's velocity and the spin (no slip variable, no events),
    first order in the step: within 1e-3 of the event-driven model at every drive."""
    g, phi, mu, et, en, k = np.array([r[:6] for r in BRUTE]).T
    landing = [r[6] for r in BRUTE]
    brute, _ = brute_rolling(g, phi, mu, 0.0, et, en, k, landing=landing, steps=3000,
                             transient=30, measured=6)  # fmt: skip
    for i, row in enumerate(BRUTE):
        exact = rolling.velocity(*row[:3], 0.0, *row[3:6], landing=row[6])
        assert exact.periodic
        assert brute[i] == pytest.approx(exact.velocity_norm, abs=1e-3), row


@pytest.mark.validation
def test_the_brute_force_twin_rolls_down_an_incline_as_the_model_says():
    """(b) with (c): on a 4 deg incline the twin's velocity falls by the model's drift each
    cycle, g sin(alpha) / (1 + k) in physical units, at a sliding and a hopping drive."""
    for gamma, phi, mu in (SLIDING[0], HOPPING[1]):
        _, ends = brute_rolling(gamma, phi, mu, 4.0, steps=2000, transient=10, measured=4)
        drift = rolling.velocity(gamma, phi, mu, 4.0).drift_per_cycle
        assert ends[1, 0] - ends[0, 0] == pytest.approx(drift, rel=2e-3)


def test_the_command_gives_the_rolling_sphere(capsys):
    import json

    from dem.cli import main

    argv = ["pointmass", "velocity", "--throw-number", "1.8", "--angle", "15", "--friction",
            "0.2", "--json"]  # fmt: skip
    assert main([*argv, "--grain", "rolling-sphere"]) == 0
    out = json.loads(capsys.readouterr().out)
    expected = rolling.velocity(1.8, 15.0, 0.2)  # Coulomb-bounded, "centre", solid sphere
    assert out["velocity_norm"] == expected.velocity_norm and out["grain"] == "rolling-sphere"
    assert (out["impact"], out["landing"], out["inertia_factor"]) == ("coulomb", "centre", 0.4)
    assert (
        out["pointmass_velocity_norm"]
        == pointmass.velocity(1.8, 15.0, 0.2, impact="coulomb").velocity_norm
    )
    argv_k = [*argv, "--grain", "rolling-sphere", "--inertia-factor", "0.6667"]
    assert main([*argv_k, "--landing", "contact", "--impact", "paper"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert (
        out["velocity_norm"]
        == rolling.velocity(
            1.8, 15.0, 0.2, 0.0, 0.8, 0.0, 0.6667, landing="contact", impact="paper"
        ).velocity_norm
    )
    # the point mass keeps its default landing law (the paper's)
    assert main(argv) == 0
    assert json.loads(capsys.readouterr().out)["impact"] == "paper"
    assert main(argv[:-1] + ["--grain", "rolling-sphere", "--frequency", "60"]) == 0
    text = capsys.readouterr().out
    assert "rolling sphere, I = 0.4 m r^2" in text and "m/s at 60 Hz" in text
    # options of the rolling sphere only, and its range, are refused with their names
    assert main([*argv, "--landing", "contact"]) == 2
    assert "--landing = 'contact': only with --grain rolling-sphere" in capsys.readouterr().err
    assert main([*argv, "--grain", "rolling-sphere", "--inertia-factor", "0"]) == 2
    assert "--inertia-factor = 0.0: moment of inertia factor" in capsys.readouterr().err
