"""Sweeps and optima of the point-mass model."""

import io
import math

import numpy as np
import pytest

from dem import pointmass as pm
from dem.errors import InputError
from dem.pointmass.sweep import optimum, parse_values, sweep, write_csv


def test_sweep_is_the_cartesian_product():
    r = sweep([1.2, 2.0, 3.5], [20.0, 40.0], [0.3, 0.6])
    assert len(r["velocity_norm"]) == 12
    i = 2 * 2 * 2 + 1 * 2 + 0  # Gamma = 3.5, phi = 40, mu = 0.3
    assert (r["throw_number"][i], r["angle"][i], r["friction"][i]) == (3.5, 40.0, 0.3)
    assert r["velocity_norm"][i] == pm.velocity(3.5, 40, 0.3).velocity_norm
    assert r["regime"][i] == pm.velocity(3.5, 40, 0.3).regime


def test_csv_round_trip():
    r = sweep([0.5, 1.5], 25, 0.35)
    buf = io.StringIO()
    write_csv(r, buf)
    lines = buf.getvalue().splitlines()
    header = lines[0].split(",")
    row = dict(zip(header, lines[2].split(","), strict=True))
    assert float(row["velocity_norm"]) == pytest.approx(r["velocity_norm"][1], rel=1e-5)
    assert float(row["angle_deg"]) == 25.0
    assert row["periodic"] == "true"


@pytest.mark.parametrize(
    "text,expected",
    [("1.8", [1.8]), ("0.25,0.35", [0.25, 0.35]), ("10:30:10", [10.0, 20.0, 30.0])],
)
def test_parse_values(text, expected):
    assert parse_values(text, "--x") == pytest.approx(expected)


@pytest.mark.parametrize("text", ["a", "1:2", "3:1:1", "1:2:0"])
def test_parse_values_rejects(text):
    with pytest.raises(InputError):
        parse_values(text, "--x")


def _dense_objective(over, hold, x, **kw):
    """Independent evaluation of the objective from its definition (m/s or v_norm)."""
    g = 9.81
    f = kw.get("frequency", 60.0)
    omega = 2 * math.pi * f
    if over == "angle":
        phi = x
        if hold == "throw_number":
            return pm.velocities(kw["throw_number"], phi, kw["friction"])["velocity_norm"]
        amp = kw["amplitude"]
        gamma = amp * omega**2 * np.sin(np.radians(phi)) / g
    else:
        phi = np.full_like(x, kw["angle"])
        gamma = x
        amp = gamma * g / (omega**2 * math.sin(math.radians(kw["angle"])))
    v = pm.velocities(gamma, phi, kw["friction"])["velocity_norm"]
    return v * amp * omega * np.cos(np.radians(phi))


@pytest.mark.parametrize(
    "over,hold,kw",
    [
        ("angle", "throw_number", {"throw_number": 1.8, "friction": 0.35}),
        ("angle", "amplitude", {"amplitude": 5e-4, "friction": 0.35}),
        ("throw_number", "frequency", {"angle": 25.0, "friction": 0.35}),
    ],
)
def test_optimum_matches_a_dense_scan(over, hold, kw):
    o = optimum(over, hold, points=81, **kw)
    lo, hi = (1.0, 89.0) if over == "angle" else (0.05, 8.0)
    x = np.linspace(lo, hi, 4001)
    dense = _dense_objective(over, hold, x, **kw)
    best = o.velocity_norm if o.objective == "velocity_norm" else o.velocity
    assert best >= dense.max() - 1e-3 * abs(dense.max())
    assert o.value == pytest.approx(x[np.argmax(dense)], abs=0.01 * (hi - lo))
    assert o.plateau[0] <= o.value <= o.plateau[1]


def test_acceleration_hold_equals_amplitude_hold_at_same_frequency():
    amp, f = 5e-4, 60.0
    k = amp * (2 * math.pi * f) ** 2 / 9.81
    a = optimum("angle", "amplitude", amplitude=amp, frequency=f, friction=0.35)
    b = optimum("angle", "acceleration", peak_acceleration=k, frequency=f, friction=0.35)
    assert a.value == pytest.approx(b.value, abs=1e-6)


@pytest.mark.parametrize(
    "kwargs,key",
    [
        ({"over": "speed", "hold": "amplitude"}, "over"),
        ({"over": "angle", "hold": "frequency"}, "hold"),
        ({"over": "angle", "hold": "amplitude"}, "amplitude"),
        ({"over": "throw_number", "hold": "frequency"}, "angle"),
        ({"over": "angle", "hold": "throw_number", "throw_number": -1.0}, "throw_number"),
    ],
)
def test_optimum_rejects(kwargs, key):
    with pytest.raises(InputError) as info:
        optimum(friction=0.35, **kwargs)
    assert info.value.key == key
