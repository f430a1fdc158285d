"""dem.scene.resolved: a case resolved once (grain, law, step, trough), the same numbers as the
case."""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from small_case import SMALL_CASE, write_case

from dem.engine import setup
from dem.run import plan
from dem.scene.case import load_case
from dem.scene.resolved import Scene, resolve
from dem.scene.timestep import ContactLaw, timestep_for
from dem.scene.trough import Trough

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.fixture
def case(tmp_path):
    return load_case(write_case(tmp_path / "case", SMALL_CASE.replace("count = 120", "count = 40")))


@pytest.fixture
def law_builds(monkeypatch):
    """Count the calls of ContactLaw.from_case from now on."""
    calls = {"n": 0}
    original = ContactLaw.from_case.__func__

    def counting(cls, case):
        calls["n"] += 1
        return original(cls, case)

    monkeypatch.setattr(ContactLaw, "from_case", classmethod(counting))
    return calls


def test_load_and_resolve_build_the_law_once(tmp_path, law_builds):
    """load_case checks the time step against the law and keeps it: resolve takes the same."""
    case = load_case(write_case(tmp_path / "case", SMALL_CASE))
    assert law_builds["n"] == 1
    assert resolve(case).law is case.law
    assert law_builds["n"] == 1


def test_resolve_builds_the_law_once_and_a_scene_passes_through(case, law_builds):
    scene = resolve(case)
    assert law_builds["n"] == 0  # built at load_case's time-step check, kept on the case
    assert resolve(scene) is scene
    plan.plan(scene, threads=1)
    assert law_builds["n"] == 0  # the plan takes the scene's law and step
    finer = resolve(scene, timestep=0.5 * scene.step.dt)
    assert law_builds["n"] == 0 and finer.law is scene.law
    assert finer.step.dt == 0.5 * scene.step.dt and finer.step.limit == scene.step.limit


@pytest.mark.validation
def test_the_scene_holds_what_the_case_gives(case):
    scene = resolve(case)
    assert scene.case is case
    assert scene.step == timestep_for(case)
    assert scene.trough == Trough.from_case(case)
    law = ContactLaw.from_case(case)
    assert scene.law.model == law.model and np.array_equal(scene.law.params, law.params)


def test_the_sphere_grain_is_a_one_sphere_template_of_the_right_mass(case):
    scene = resolve(case)
    r, rho = case.particles.radius, case.material.density
    assert scene.grain.count == 1 and scene.grain.radii.tolist() == [r]
    assert scene.grain.mass == pytest.approx(4.0 / 3.0 * math.pi * r**3 * rho, rel=1e-14)
    assert scene.grain_mass == pytest.approx(scene.grain.mass, rel=1e-14)
    assert scene.max_radius == r and scene.grain.bounding_radius == r
    # the mass the engine gives each sphere, bit for bit (the feeder and the plan use it)
    sim = setup.from_case(scene)
    assert np.all(sim.spheres.mass == scene.grain_mass)


@pytest.mark.validation
def test_a_clump_grain_is_the_case_template():
    case = load_case(CASES / "screw-trough")
    scene = resolve(case)
    assert scene.grain is case.particles.grain
    assert scene.grain_mass == case.particles.grain.mass
    assert scene.max_radius == float(max(case.particles.grain.radii))


@pytest.mark.validation
def test_a_scene_builds_the_same_simulation_as_its_case(case):
    from_case = setup.from_case(case)
    from_scene = setup.from_case(resolve(case))
    for sim in (from_case, from_scene):
        sim.run(300)
    assert from_case.dt == from_scene.dt
    assert np.array_equal(from_case.spheres.x, from_scene.spheres.x)
    assert np.array_equal(from_case.spheres.v, from_scene.spheres.v)


@pytest.mark.validation
def test_a_scene_places_the_same_grains_as_its_case(case):
    x = [[0.01, 0.0, 0.003], [0.02, 0.0, 0.004]]
    v = [[0.1, 0.0, -0.2], [0.0, 0.0, 0.0]]
    a = setup.from_grains(case, x, velocities=v)
    b = setup.from_grains(resolve(case), x, velocities=v)
    assert (a.dt, a.timestep_limit) == (b.dt, b.timestep_limit)
    for sim in (a, b):
        sim.run(200)
    assert np.array_equal(a.spheres.x, b.spheres.x)


@pytest.mark.validation
def test_a_changed_case_is_resolved_anew(case):
    scene = resolve(case)
    few = dataclasses.replace(case, particles=dataclasses.replace(case.particles, count=1))
    other = resolve(few)
    assert isinstance(other, Scene) and other.case is few
    assert other.step == timestep_for(few) != scene.step  # one grain: no sphere-sphere contact


@pytest.mark.validation
def test_from_grains_places_spheres_of_several_sizes_and_materials(case):
    """Two different spheres (a collision benchmark): each its own radius, mass and inertia;
    the step the smallest of each kind's own; the case's own kind gives the case's step."""
    x = [[0.01, 0.0, 0.004], [0.02, 0.0, 0.004]]
    radii, densities = (1.0e-3, 0.5e-3), (2500.0, 7800.0)
    sim = setup.from_grains(case, x, radii=radii, densities=densities)
    np.testing.assert_array_equal(sim.spheres.radius, radii)
    masses = [rho * 4.0 / 3.0 * math.pi * r**3 for r, rho in zip(radii, densities, strict=True)]
    np.testing.assert_allclose(sim.spheres.mass, masses, rtol=1e-15)
    np.testing.assert_allclose(
        sim.spheres.inv_inertia, 1.0 / (0.4 * np.array(masses) * np.array(radii) ** 2), rtol=1e-15
    )
    kinds = [
        setup.from_grains(
            dataclasses.replace(
                case,
                particles=dataclasses.replace(case.particles, radius=r),
                material=dataclasses.replace(case.material, density=rho),
            ),
            x,
        )
        for r, rho in zip(radii, densities, strict=True)
    ]
    assert sim.dt == min(k.dt for k in kinds)
    assert sim.timestep_limit == min(k.timestep_limit for k in kinds)
    own = setup.from_grains(case, x, radii=case.particles.radius)
    default = setup.from_grains(case, x)
    assert own.dt == default.dt
    assert np.array_equal(own.spheres.mass, default.spheres.mass)
    with pytest.raises(ValueError, match="spheres"):
        setup.from_grains(load_case(CASES / "screw-trough"), [[0.01, 0.0, 0.01]], radii=[1e-3])
