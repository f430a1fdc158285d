"""The fill's rest (Simulation.settle): at rest, or steadily rolling where nothing stops it."""

import warnings

import numpy as np
import pytest

import dem.config as config
from dem.engine import setup
from dem.errors import SimulationError
from dem.scene.case import load_case
from dem.scene.resolved import resolve


@pytest.fixture
def quick_rule(monkeypatch):
    """The steady rule from 0.2 s over 0.1 s (shipped: 2 s over 0.5 s), so that a stiff lone
    sphere (a million steps a simulated second) is tested in seconds; the rule is the same."""
    monkeypatch.setattr(config, "DEM_SETTLE_STEADY_AFTER", 0.2)
    monkeypatch.setattr(config, "DEM_SETTLE_STEADY_WINDOW", 0.1)


def _rolling_sphere(speed: float):
    """One sphere of cases/single-sphere, free to rotate, rolling on the level floor along x."""
    case = load_case("cases/single-sphere", {"particles.rotation": True})
    scene = resolve(case)
    r = case.particles.radius
    sim = setup.from_grains(
        scene, np.array([[0.005, 0.0, r]]), velocities=np.array([[speed, 0.0, 0.0]]),
        spins=np.array([[0.0, speed / r, 0.0]]),
    )  # fmt: skip
    return sim


@pytest.mark.integration
def test_a_sphere_rolling_on_the_floor_settles_as_steady_with_a_warning(quick_rule):
    """Rolling without slip on a level periodic floor it keeps its speed (no rolling friction):
    it never comes to rest (before: SimulationError after 5 s). Once its speed has stayed within
    2 % over the window, below 10 times the rest threshold, the fill is taken as settled, with a
    warning; the sphere still rolls at its speed."""
    sim = _rolling_sphere(0.005)  # the rest threshold is 0.01 sqrt(g r) = 0.0014 m/s
    with pytest.warns(UserWarning, match="steady state, not to rest.*rolling"):
        t = sim.settle()
    assert 0.2 <= t < 0.32
    assert sim.spheres.v[0, 0] == pytest.approx(0.005, rel=0.02)


@pytest.mark.integration
def test_a_fast_roller_or_a_bed_that_rests_is_untouched(quick_rule, monkeypatch):
    """Ten times the threshold is no steady state (a grain that rolls fast is still a fill in
    motion): it still stops with the error; a bed that comes to rest gives no warning."""
    monkeypatch.setattr(config, "DEM_SETTLE_MAX_TIME", 0.5)
    with pytest.raises(SimulationError, match="did not come to rest within 0.5 s"):
        _rolling_sphere(0.05).settle()
    resting = _rolling_sphere(0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert resting.settle() < 0.1
