"""Every numeric option of the point-mass commands against its range at the door, and the
``--plot`` paths of ``dem pointmass optimum`` and ``dem calibrate``: exit 2 and one line naming
the option, the value and the range, before anything is computed or written."""

import shutil

import pytest
from small_case import run_cli as run

PNG = b"\x89PNG\r\n\x1a\n"

VELOCITY = ["pointmass", "velocity", "--throw-number", "1.5", "--angle", "25", "--friction", "0.3"]
OPTIMUM = ["pointmass", "optimum", "--over", "angle", "--hold", "throw_number",
           "--throw-number", "1.5", "--friction", "0.3"]  # fmt: skip
THRESHOLDS = ["pointmass", "thresholds", "--angle", "25", "--friction", "0.3"]
SWEEP = ["pointmass", "sweep", "--throw-number", "1.5", "--angle", "25", "--friction", "0.3"]


@pytest.mark.parametrize(
    "argv, needle",
    [
        # the velocity's --frequency was taken as given: -60 Hz gave a negative velocity
        (VELOCITY + ["--frequency", "-60"], "--frequency = -60.0: frequency must be in [0.01, 1e5"),
        (VELOCITY + ["--frequency", "0"], "--frequency = 0.0"),
        (VELOCITY + ["--frequency", "1e9"], "--frequency = 1000000000.0"),
        (VELOCITY + ["--frequency", "nan"], "not a finite number"),
        # options the chosen hold does not use were ignored whatever their value
        (OPTIMUM + ["--amplitude", "-1"], "--amplitude = -1.0: amplitude must be in [1e-9, 1] m"),
        (OPTIMUM + ["--drive-velocity", "0"], "--drive-velocity = 0.0"),
        (OPTIMUM + ["--peak-acceleration", "1e9"], "--peak-acceleration = 1000000000.0"),
        (OPTIMUM + ["--angle", "95"], "--angle = 95.0"),
        (OPTIMUM + ["--frequency", "-60"], "--frequency = -60.0"),
        (OPTIMUM + ["--inclination", "-95"], "--inclination = -95.0"),
        (OPTIMUM + ["--eps-n", "2"], "--eps-n = 2.0"),
        (OPTIMUM + ["--bounds", "10:95"], "--bounds = 95.0"),
        (OPTIMUM + ["--bounds", "10:x"], "--bounds"),
        (OPTIMUM + ["--bounds", "10:20:30"], "--bounds"),
        (OPTIMUM + ["--bounds", "10,20:30"], "--bounds = '10,20:30': LOW:HIGH, two numbers"),
        (OPTIMUM + ["--bounds", "10:inf"], "--bounds = inf"),
        (THRESHOLDS + ["--inclination", "90"], "--inclination = 90.0"),
        (SWEEP + ["--eps-t", "0.5,1.5"], "--eps-t = 1.5"),
        (SWEEP + ["--inclination", "nan"], "--inclination = nan"),
    ],
)
def test_numeric_options_out_of_range_are_refused_at_the_door(capsys, argv, needle):
    code, out, err = run(capsys, *argv)
    assert code == 2, err
    assert needle in err and err.count("\n") == 1 and "Traceback" not in err, err
    assert out == ""


def test_the_velocity_in_m_per_s_still_comes_with_a_frequency(capsys):
    code, out, err = run(capsys, *VELOCITY, "--frequency", "60")
    assert code == 0 and "m/s at 60 Hz" in out, err


@pytest.mark.parametrize("command", ["optimum", "calibrate"])
def test_a_plot_path_without_png_is_refused_before_the_work(capsys, tmp_path, command):
    """``--plot DIR.../name`` without .png was written as name.png while dem said it wrote
    name; now a name that is neither a folder nor a .png file is refused by option."""
    target = tmp_path / "figure"
    argv = OPTIMUM if command == "optimum" else ["calibrate", "cases/single-sphere", "--dry-run"]
    code, out, err = run(capsys, *argv, "--plot", target)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert f"--plot = '{target}'" in err and ".png" in err, err
    assert list(tmp_path.iterdir()) == []


def test_pointmass_optimum_plot_into_a_folder_writes_the_file_it_names(capsys, tmp_path):
    code, out, err = run(capsys, *OPTIMUM, "--plot", tmp_path)
    assert code == 0, err
    figure = tmp_path / "optimum.png"
    assert figure.read_bytes()[:8] == PNG
    assert list(tmp_path.iterdir()) == [figure]
    assert f"wrote {figure}" in err


@pytest.mark.integration
def test_calibrate_plot_into_a_folder_writes_the_file_it_names(capsys, tmp_path):
    """``dem calibrate --plot DIR`` wrote DIR.png beside the folder and said it wrote DIR."""
    case = tmp_path / "one"
    shutil.copytree("cases/single-sphere", case)
    toml = case / "case.toml"
    toml.write_text(toml.read_text().replace("throw_number = 0.6", "throw_number = 1.8"))
    folder = tmp_path / "plots"
    folder.mkdir()
    code, out, err = run(capsys, "calibrate", case, "--dry-run", "--plot", folder)
    assert code == 0, err
    figure = folder / "calibration.png"
    assert figure.read_bytes()[:8] == PNG and f"wrote {figure}\n" in out, out
    assert not (tmp_path / "plots.png").exists()
    named = tmp_path / "cal.PNG"  # a .png name, any case, is taken as it is
    code, out, err = run(capsys, "calibrate", case, "--dry-run", "--plot", named)
    assert code == 0 and named.read_bytes()[:8] == PNG and f"wrote {named}\n" in out, out


def test_set_reaches_an_exported_liggghts_deck(capsys, tmp_path):
    """Issue 48, item 4: `dem export liggghts` took no --set."""
    code, out, err = run(capsys, "export", "liggghts", "cases/sphere-bed", tmp_path / "deck",
                         "--set", "drive.angle=30", "--settle-cycles", "2")  # fmt: skip
    assert code == 0, err
    assert "phi = 30.0 deg" in (tmp_path / "deck" / "in.dem").read_text()
    code, _, err = run(capsys, "export", "liggghts", "cases/sphere-bed", tmp_path / "d2",
                       "--set", "material.friction=-1")  # fmt: skip
    assert code == 2 and "material.friction" in err and not (tmp_path / "d2").exists()


def test_set_on_optimum_is_checked_and_never_the_searched_key(capsys, tmp_path):
    """Issue 48, item 4: `dem optimum` took no --set; refused before any run starts."""
    code, _, err = run(capsys, "optimum", "cases/sphere-bed", "--over", "drive.angle",
                       "--set", "drive.angle=30", "--out", tmp_path / "o")  # fmt: skip
    assert code == 2 and "--set" in err and "drive.angle" in err
    code, _, err = run(capsys, "optimum", "cases/sphere-bed", "--over", "drive.angle",
                       "--set", "material.friction=-1", "--out", tmp_path / "o")  # fmt: skip
    assert code == 2 and "material.friction" in err
    assert not (tmp_path / "o").exists()


def test_set_switches_a_throw_number_case_to_an_amplitude_and_back(tmp_path):
    """Issue 48, item 4: `--set drive.amplitude=...` on a throw-number case was refused as
    'both are given'; an override of one replaces the file's other."""
    from dem.scene.case import load_case

    screws = load_case("cases/screw-trough", {"drive.amplitude": 3.0e-4})
    assert screws.drive.amplitude == 3.0e-4 and screws.drive.given == "amplitude"
    spheres = load_case("cases/sphere-bed", {"drive.throw_number": 2.0})
    assert spheres.drive.throw_number == pytest.approx(2.0)
    assert spheres.drive.given == "throw_number"
    from dem.errors import InputError

    with pytest.raises(InputError, match="exactly one of"):
        load_case("cases/sphere-bed", {"drive.throw_number": 2.0, "drive.amplitude": 3e-4})
