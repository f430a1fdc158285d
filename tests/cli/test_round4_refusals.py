"""Hostile values that broke the last round (hardening round 4, items 4-9): each one line.

Item 4: a case file nested deeper than Python recurses; item 5: a NUL in a path key; item 6: a
failing sweep point's one line; item 7: an error in a value given on the command line names
the option, not case.toml; item 8: degenerate values at the small end of a range; item 9: a
frictionless floor, and a friction too small for the settle to remove the start-up velocity.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import pytest
from small_case import SMALL_CASE, write_case

from dem.cli import main
from dem.errors import InputError
from dem.scene.case import load_case

ROOT = Path(__file__).resolve().parents[2]


def _error(capsys, *argv) -> str:
    code = main(list(argv))
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err and err.startswith("dem: error:"), err
    return err


# --- item 4: nested values ----------------------------------------------------------------------


@pytest.mark.parametrize("nest", ["[" * 3000 + "]" * 3000, "{a = " * 3000 + "1" + "}" * 3000])
def test_a_case_nested_past_the_recursion_limit_is_one_line(tmp_path, capsys, nest):
    case = write_case(tmp_path / "deep", SMALL_CASE + f"\n[feeder]\nrate = {nest}\n")
    err = _error(capsys, "plan", str(case))
    assert "case.toml" in err and "nested" in err


# --- item 5: NUL in a path key ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("key", "extra"),
    [("trough.mesh", ""), ("particles.template", 'shape = "clump"\n')],
)
def test_a_nul_in_a_path_key_is_named(tmp_path, capsys, key, extra):
    table, name = key.split(".")
    text = SMALL_CASE.replace(f"[{table}]\n", f'[{table}]\n{name} = "geo\\u0000x.stl"\n', 1)
    if extra:
        text = text.replace('shape = "sphere"\n', extra).replace("radius = 0.002\n", "")
    case = write_case(tmp_path / "nul", text)
    err = _error(capsys, "plan", str(case))
    assert f"{key} = 'geo\\x00x.stl'" in err and "NUL" in err


# --- item 7: where a value came from ------------------------------------------------------------


def test_set_values_are_named_as_set_and_integers_stay_integers(tmp_path, capsys):
    case = write_case(tmp_path / "case")
    err = _error(capsys, "plan", str(case), "--set", "material.friction=nan")
    assert err.startswith("dem: error: --set: material.friction = nan") and "case.toml" not in err
    err = _error(capsys, "plan", str(case), "--set", "run.replicas=5000")
    assert "run.replicas = 5000:" in err and "5000.0" not in err and "an integer" not in err
    err = _error(capsys, "run", str(case), "--replicas", "5000", "--out", str(tmp_path / "o"))
    assert err.startswith("dem: error: --replicas: run.replicas = 5000:")
    assert not (tmp_path / "o").exists()
    # an error in the file itself is still the file's
    bad = write_case(tmp_path / "bad", SMALL_CASE.replace("friction = 0.35", "friction = -1.0"))
    err = _error(capsys, "plan", str(bad), "--set", "drive.angle=30")
    assert "case.toml: material.friction = -1.0" in err


def test_load_case_names_an_overrides_origin():
    with pytest.raises(InputError) as info:
        load_case(
            ROOT / "cases" / "single-sphere", {"run.replicas": 0}, {"run.replicas": "--replicas"}
        )
    assert info.value.source == "--replicas" and info.value.key == "run.replicas"
    with pytest.raises(InputError) as info:
        load_case(ROOT / "cases" / "single-sphere", {"drive.angle": 95.0})
    assert info.value.source == "--set"


# --- item 8: the small end of every range -------------------------------------------------------


@pytest.mark.parametrize(
    "setting",
    ["drive.throw_number=1e-300", "drive.frequency=1e-300", "contact.youngs_modulus=1e-300",
     "material.density=1e-300", "run.timestep=1e-300", "particles.mass=1e-300",
     "drive.throw_number=0.0009"],
)  # fmt: skip
def test_degenerate_small_values_are_refused_by_their_key(capsys, setting):
    case = ROOT / "cases" / ("sphere-bed" if "youngs" in setting else "single-sphere")
    if "mass" in setting:
        case = ROOT / "cases" / "screw-trough"
    err = _error(capsys, "plan", str(case), "--set", setting)
    assert f"{setting.split('=')[0]} = " in err and " in [" in err, err


def test_a_derived_throw_number_is_in_range_too(tmp_path, capsys):
    case = write_case(tmp_path / "case")  # amplitude 0.5 mm
    err = _error(capsys, "plan", str(case), "--set", "drive.frequency=0.01")
    assert "drive.amplitude = 0.0005" in err and "throw number" in err and "[0.001, 100]" in err


def test_pointmass_refuses_a_vanishing_drive(capsys):
    err = _error(capsys, "pointmass", "velocity", "--throw-number", "1e-300", "--angle", "25",
                 "--friction", "0.35")  # fmt: skip
    assert "--throw-number" in err


def test_plan_at_the_small_ends_prints_plain_numbers_and_no_numpy_warning(capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy overflow or divide warning fails the test
        assert (
            main(["plan", str(ROOT / "cases" / "sphere-bed"), "--set", "run.timestep=1e-15"]) == 0
        )
        out = capsys.readouterr().out
        assert main(["plan", str(ROOT / "cases" / "sphere-bed"), "--set",
                     "contact.youngs_modulus=1e3"]) == 0  # fmt: skip
    steps = next(line for line in out.splitlines() if "steps per cycle" in line)
    assert len(steps.split()[-1]) < 12 and "e+" in steps
    assert "0.00 x" not in out


# --- item 9: friction ---------------------------------------------------------------------------


@pytest.mark.parametrize("key", ["material.friction", "wall.friction"])
def test_a_frictionless_floor_is_refused_by_the_dem_and_both_point_masses(tmp_path, capsys, key):
    case = write_case(tmp_path / "case")
    err = _error(capsys, "plan", str(case), "--set", f"{key}=0")
    assert f"{key} = 0.0: > 0 on the floor" in err and "start-up" in err
    for impact in ("paper", "coulomb"):
        err = _error(capsys, "pointmass", "velocity", "--throw-number", "0.5", "--angle", "25",
                     "--friction", "0", "--impact", impact)  # fmt: skip
        assert "--friction = 0.0: > 0 for a conveying velocity" in err and "start-up" in err
    # the regime limits are defined at mu = 0 (flight at Gamma 1)
    assert main(["pointmass", "thresholds", "--angle", "25", "--friction", "0"]) == 0
    capsys.readouterr()


def test_frictionless_grains_on_a_rough_floor_are_a_case():
    case = load_case(ROOT / "cases" / "single-sphere", {"material.friction": 0.0,
                                                        "wall.friction": 0.35})  # fmt: skip
    assert case.material.friction == 0.0 and case.wall_material.friction == 0.35


def test_the_settle_outlasts_the_start_up_velocity_that_friction_removes():
    from dem import config
    from dem.physics.drive import friction_relaxation_cycles
    from dem.run.plan import plan
    from dem.run.record import settle_floor

    single = ROOT / "cases" / "single-sphere"
    case = load_case(single, {"material.friction": 0.01, "run.settle_cycles": "auto"})
    d = case.drive
    relax = friction_relaxation_cycles(d.velocity_scale, d.frequency, 0.01)
    assert relax == pytest.approx(d.frequency * d.velocity_scale / (0.01 * 9.81))
    assert settle_floor(case) == math.ceil(config.DEM_FRICTION_RELAX_FACTOR * relax) > 6
    assert plan(case).settle_cycles == settle_floor(case)
    for name in ("screw-trough", "sphere-bed", "u-trough", "v-trough"):  # shipped: as before
        assert settle_floor(load_case(ROOT / "cases" / name)) == config.DEM_AUTO_SETTLE_MIN_CYCLES
    explicit = plan(load_case(single, {"material.friction": 0.01, "run.settle_cycles": 5}))
    warned = [a for a in explicit.advice if a.key == "run.settle_cycles" and a.level == "warn"]
    assert warned and warned[0].value == settle_floor(case) and "start-up" in warned[0].text
    tiny = plan(load_case(single, {"material.friction": 1e-4, "run.settle_cycles": "auto"}))
    assert [a for a in tiny.advice if a.key == "material.friction" and a.level == "warn"]
    assert friction_relaxation_cycles(0.1, 60.0, 0.0) == math.inf


@pytest.mark.validation
def test_a_low_friction_grain_settles_onto_the_point_mass_not_its_start_up(tmp_path):
    """mu = 0.05, Gamma 0.6 (sliding): the automatic settle gives the point mass's velocity,
    not the start-up's (v_norm 1 at mu = 0)."""
    from dem.run.runner import run_case

    case = load_case(ROOT / "cases" / "single-sphere", {
        "material.friction": 0.05, "run.settle_cycles": "auto", "run.cycles": 4})  # fmt: skip
    s = run_case(case, tmp_path / "out", overwrite=True, progress=False, frames=False)
    assert s["settle_cycles"] >= 9
    pm = s["pointmass_bounded_velocity_norm"]
    assert s["mean_velocity_norm"] == pytest.approx(pm, rel=0.01)
    assert pm < 0.1  # far from the start-up's 1


# --- item 6: a failing sweep point --------------------------------------------------------------


def test_a_failed_point_is_one_line_naming_the_file(tmp_path):
    from dem.studies.sweep import failure_text

    folder = tmp_path / "000_x"
    full = failure_text(OSError(28, "No space left on device"), folder)
    assert full == f"OSError: cannot write or read a file in {folder}: No space left on device"
    named = failure_text(OSError(28, "No space left on device", "/x/results.h5"), folder)
    assert "/x/results.h5" in named
    many = failure_text(ValueError("first line\nTraceback (most recent call last):\n  ..."), folder)
    assert many == "ValueError: first line"


def test_cli_full_disk_line_is_the_commands_own(tmp_path, capsys, monkeypatch):
    """The run's hint (results.h5 up to its last cycle) is not given for a sweep's table."""
    import dem.studies.sweep as sweep

    def full(*args, **kwargs):
        raise OSError(28, "No space left on device", str(tmp_path / "out" / "sweep.csv"))

    monkeypatch.setattr(sweep, "run_sweep", full)
    code = main(["sweep", str(write_case(tmp_path / "case")), "--set", "drive.angle=20",
                 "--out", str(tmp_path / "out")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 1 and "sweep.csv" in err and "results.h5" not in err and "rerun" in err
