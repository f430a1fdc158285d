"""The fill's rest (Simulation.settle): at rest, or steadily rolling where nothing stops it."""

import warnings

import numpy as np
import pytest

from dem.engine import setup
from dem.errors import SimulationError
from dem.scene.case import load_case
from dem.scene.resolved import resolve


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
def test_a_sphere_rolling_on_the_floor_settles_as_steady_with_a_warning():
    """Rolling without slip on a level periodic floor it keeps its speed (no rolling friction):
    it never comes to rest (before: SimulationError after 5 s). After 2 s with its speed steady
    within 2 % over 0.5 s, below 10 times the rest threshold, the fill is taken as settled,
    with a warning; the sphere still rolls at its speed."""
    sim = _rolling_sphere(0.005)  # the rest threshold is 0.01 sqrt(g r) = 0.0014 m/s
    with pytest.warns(UserWarning, match="steady state, not to rest.*rolling"):
        t = sim.settle()
    assert 2.0 <= t < 2.6
    assert sim.spheres.v[0, 0] == pytest.approx(0.005, rel=0.02)


@pytest.mark.integration
def test_a_fast_roller_or_a_bed_that_rests_is_untouched():
    """Ten times the threshold is no steady state (a grain that rolls fast is still a fill in
    motion): it still stops with the error; a bed that comes to rest gives no warning."""
    import dem.config as config

    sim = _rolling_sphere(0.05)
    old = config.DEM_SETTLE_MAX_TIME
    config.DEM_SETTLE_MAX_TIME = 3.0
    try:
        with pytest.raises(SimulationError, match="did not come to rest within 3.0 s"):
            sim.settle()
    finally:
        config.DEM_SETTLE_MAX_TIME = old
    resting = _rolling_sphere(0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert resting.settle() < 0.1
