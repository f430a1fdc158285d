"""[wall]: grain-wall friction and restitution distinct from grain-grain.

Checked in the case reader, the kernels (a block on a tilted floor slides by the wall's mu, not
the grains'; a grain-grain collision keeps the material's), the time step, the point mass (which
sees the wall's values) and the LIGGGHTS deck.
"""

import math

import numpy as np
import pytest
from small_case import SMALL_CASE, write_case

from dem.config import GRAVITY
from dem.engine import setup
from dem.errors import InputError
from dem.kernels import contact
from dem.physics.contact import ContactLaw
from dem.scene.case import load_case


def _case(tmp_path, wall: str = "", **overrides):
    text = SMALL_CASE + ("\n[wall]\n" + wall if wall else "")
    return load_case(write_case(tmp_path / "case", text), overrides or None)


@pytest.mark.validation
def test_wall_values_default_to_the_materials_and_are_checked_by_key(tmp_path):
    case = _case(tmp_path)
    assert case.wall_material == case.material and case.wall.given == ()
    law = ContactLaw.from_case(case)
    n = contact.N_PARAMS
    assert law.params.shape == (2 * n,)
    assert np.array_equal(law.params[:n], law.params[n:])  # one material: identical rows
    case = _case(tmp_path, "friction = 0.6\nrestitution_tangential = 0.5\n")
    assert case.wall_material.friction == 0.6 and case.material.friction == 0.35
    law = ContactLaw.from_case(case)
    assert law.params[contact.P_MU] == 0.35 and law.wall_params[contact.P_MU] == 0.6
    with pytest.raises(InputError) as info:
        _case(tmp_path, "friction = -0.1\n")
    assert info.value.key == "wall.friction"
    with pytest.raises(InputError) as info:
        _case(tmp_path, "frictoin = 0.3\n")
    assert "wall.frictoin" in info.value.key and "friction" in str(info.value)


def _slide(tmp_path, wall: str, incline: float, grains: float = 0.35) -> float:
    """A locked sphere on a floor tilted ``incline`` deg, drive off: its acceleration along it.

    The case is flat (a case steeper than its friction angle is refused); gravity is tilted on
    the built simulation.
    """
    text = SMALL_CASE.replace("count = 120", "count = 1")
    text = text.replace("friction = 0.35", f"friction = {grains}")
    text = text.replace("[particles]", "[particles]\nrotation = false")
    case = load_case(write_case(tmp_path / "slide", text + "\n[wall]\n" + wall))
    r = case.particles.radius
    sim = setup.from_grains(case, [[0.5 * case.trough.length, 0.0, r]])
    sim.drive_on = False
    a = math.radians(incline)
    sim.gravity[:] = (-GRAVITY * math.sin(a), 0.0, -GRAVITY * math.cos(a))
    n = round(0.02 / sim.dt)
    sim.run(n)
    v0 = sim.mean_velocity_x()
    sim.run(n)
    return (sim.mean_velocity_x() - v0) / (n * sim.dt)


@pytest.mark.validation
def test_a_block_slides_on_the_floor_by_the_walls_friction_not_the_grains(tmp_path):
    """On 14 deg, steeper than atan(0.2) = 11.3 deg: a = -g (sin a - mu_w cos a) with the wall's
    mu_w = 0.2 (the grains' 0.35 would hold it); with the wall at 0.35 and the grains at 0.2 it
    sticks."""
    a = math.radians(14.0)
    acc = _slide(tmp_path / "a", "friction = 0.2\n", 14.0)
    assert acc == pytest.approx(-GRAVITY * (math.sin(a) - 0.2 * math.cos(a)), rel=1e-3)
    assert abs(_slide(tmp_path / "b", "friction = 0.35\n", 14.0, grains=0.2)) < 1e-6


def test_an_incline_steeper_than_the_walls_friction_angle_is_refused_by_that_key(tmp_path):
    text = SMALL_CASE.replace("width = 0.02", "width = 0.02\ninclination = 14.0")
    with pytest.raises(InputError) as info:
        load_case(write_case(tmp_path / "c", text + "\n[wall]\nfriction = 0.2\n"))
    assert info.value.key == "trough.inclination" and "wall.friction" in str(info.value)


@pytest.mark.validation
def test_the_point_mass_and_the_deck_see_the_walls_values(tmp_path):
    from dem.io.liggghts import write_deck
    from dem.run.summary import pointmass_bounded

    case = _case(tmp_path, "friction = 0.6\n")
    plain = _case(tmp_path / "p")
    assert pointmass_bounded(case) != pointmass_bounded(plain)
    deck = write_deck(case, tmp_path / "deck", timestep=1e-6, steps=10).read_text()
    friction = next(line for line in deck.splitlines() if "coefficientFriction" in line)
    assert "0.35" in friction and "0.6" in friction


def test_walls_not_given_follow_a_changed_material(tmp_path):
    """A study that changes the material (dataclasses.replace) changes the walls it did not
    give, and keeps the ones it gave."""
    import dataclasses

    case = _case(tmp_path, "friction = 0.6\n")
    other = dataclasses.replace(
        case, material=dataclasses.replace(case.material, restitution_tangential=0.2, friction=0.3)
    )
    assert other.wall_material.restitution_tangential == 0.2
    assert other.wall_material.friction == 0.6
