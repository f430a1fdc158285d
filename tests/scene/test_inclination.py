"""An inclination steeper than the friction angle is refused at load (issue item 15).

On a floor inclined beyond atan(mu) no friction holds a grain: the bed slides downhill faster
and faster, the periodic section has no steady conveying velocity, and the run used to end in
"integration unstable, use a smaller time step". Now the case is refused before anything runs:
exit 2, one line naming trough.inclination, its value and the allowed range.
"""

import math

import pytest
from small_case import SMALL_CASE, write_case

from dem.cli import main
from dem.errors import InputError
from dem.scene.case import load_case

FRICTION_ANGLE = math.degrees(math.atan(0.35))  # SMALL_CASE's material.friction


def _with(text: str, inclination: float, friction: float = 0.35) -> str:
    text = text.replace("width = 0.02", f"width = 0.02\ninclination = {inclination!r}")
    return text.replace("friction = 0.35", f"friction = {friction!r}")


@pytest.mark.parametrize("inclination", [60.0, -60.0, 19.5, -25.0])
def test_inclination_beyond_the_friction_angle_is_refused_at_load(tmp_path, inclination):
    folder = write_case(tmp_path / "case", _with(SMALL_CASE, inclination))
    with pytest.raises(InputError) as info:
        load_case(folder)
    message = str(info.value)
    assert info.value.key == "trough.inclination" and info.value.value == inclination
    assert f"{FRICTION_ANGLE:.4g}" in message  # the allowed range, from the friction angle
    assert "material.friction = 0.35" in message and "case.toml" in message


@pytest.mark.parametrize("inclination", [0.0, 15.0, -15.0, 19.0])
def test_inclination_within_the_friction_angle_loads(tmp_path, inclination):
    case = load_case(write_case(tmp_path / "case", _with(SMALL_CASE, inclination)))
    assert case.trough.inclination == inclination


def test_a_frictionless_floor_is_refused_level_or_not(tmp_path):
    """Until round 4 a frictionless floor loaded on a level trough, and its run reported the
    drive's start-up velocity as transport (v_norm 1.000 +- 5e-16): now refused either way."""
    for i, inclination in enumerate((0.0, 1.0)):
        with pytest.raises(InputError, match=r"material.friction = 0.0 .*> 0 on the floor"):
            load_case(write_case(tmp_path / str(i), _with(SMALL_CASE, inclination, friction=0.0)))


def test_dem_run_refuses_a_steep_trough_with_exit_2_one_line_nothing_written(tmp_path, capsys):
    folder = write_case(tmp_path / "case", _with(SMALL_CASE, 60.0))
    out = tmp_path / "out"
    code = main(["run", str(folder), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "trough.inclination = 60.0" in err and f"{FRICTION_ANGLE:.4g}" in err
    assert not out.exists()


def test_an_override_is_checked_against_the_friction_angle_too(tmp_path):
    folder = write_case(tmp_path / "case", SMALL_CASE)
    with pytest.raises(InputError, match="trough.inclination"):
        load_case(folder, overrides={"trough.inclination": 30.0})
    assert load_case(folder, overrides={"trough.inclination": 30.0, "material.friction": 0.8})
