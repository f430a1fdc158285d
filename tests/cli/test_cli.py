"""The ``dem`` command line: JSON contracts and one-line errors with exit status 2."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from small_case import SMALL_CASE, run_cli, write_case

from dem.cli import main


def run(capsys, *argv):
    try:
        code = main(list(argv))
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def test_thresholds_json_matches_paper(capsys):
    code, out, _ = run(
        capsys,
        "pointmass",
        "thresholds",
        "--angle",
        "25",
        "--friction",
        "0.75",
        "--inclination",
        "2.5",
        "--json",
    )
    assert code == 0
    data = json.loads(out)
    assert data["forward_sliding"] == pytest.approx(0.2742, abs=1e-4)
    assert data["backward_sliding"] == pytest.approx(0.5065, abs=1e-4)
    assert data["flight"] == pytest.approx(1.0, abs=1e-4)


def test_backward_sliding_null_when_impossible(capsys):
    code, out, _ = run(
        capsys, "pointmass", "thresholds", "--angle", "70", "--friction", "0.8", "--json"
    )
    assert code == 0 and json.loads(out)["backward_sliding"] is None


def test_velocity_json_keys(capsys):
    code, out, _ = run(
        capsys,
        "pointmass",
        "velocity",
        "--throw-number",
        "3.5",
        "--angle",
        "25",
        "--friction",
        "0.35",
        "--json",
    )
    assert code == 0
    data = json.loads(out)
    assert {"velocity_norm", "regime", "periodic"} <= data.keys()
    assert data["velocity_norm"] == pytest.approx(3.141592653589793 / 3.5, abs=1e-7)
    assert data["regime"] == "hopping" and data["periodic"] is True


def test_sweep_writes_csv(capsys, tmp_path):
    out = tmp_path / "s.csv"
    code, _, _ = run(
        capsys,
        "pointmass",
        "sweep",
        "--throw-number",
        "0.5:1.5:0.5",
        "--angle",
        "20,30",
        "--friction",
        "0.35",
        "--out",
        str(out),
    )
    assert code == 0
    lines = out.read_text().splitlines()
    assert lines[0].startswith("throw_number,angle_deg,friction,inclination_deg")
    assert len(lines) == 1 + 3 * 2


def test_optimum_json_states_what_is_held(capsys):
    code, out, _ = run(
        capsys,
        "pointmass",
        "optimum",
        "--over",
        "angle",
        "--hold",
        "amplitude",
        "--amplitude",
        "0.0005",
        "--frequency",
        "60",
        "--friction",
        "0.35",
        "--json",
    )
    assert code == 0
    data = json.loads(out)
    assert data["hold"] == "amplitude" and data["held"]["amplitude"] == 0.0005
    assert 5 < data["value"] < 60


@pytest.mark.parametrize(
    "argv,needle",
    [
        (["--throw-number", "0", "--angle", "25", "--friction", "0.3"], "--throw-number = 0.0"),
        (["--throw-number", "-2", "--angle", "25", "--friction", "0.3"], "--throw-number = -2.0"),
        (["--throw-number", "1", "--angle", "90", "--friction", "0.3"], "--angle = 90.0"),
        (["--throw-number", "1", "--angle", "0", "--friction", "0.3"], "(0, 90)"),
        (["--throw-number", "1", "--angle", "25", "--friction", "-0.1"], "--friction = -0.1"),
        (
            ["--throw-number", "1", "--angle", "25", "--friction", "0.3", "--eps-t", "1.5"],
            "--eps-t = 1.5",
        ),
        (["--throw-number", "1", "--angle", "25", "--friction", "0.3", "--eps-n", "-1"], "[0, 1]"),
        (
            ["--throw-number", "1", "--angle", "25", "--friction", "0.3", "--inclination", "95"],
            "--inclination = 95.0",
        ),
        (["--angle", "25", "--friction", "0.3"], "missing option --throw-number"),
        (["--throw-number", "x", "--angle", "25", "--friction", "0.3"], "'x' is not a number"),
    ],
)
def test_bad_input_one_line_exit_2(capsys, argv, needle):
    code, out, err = run(capsys, "pointmass", "velocity", *argv)
    assert code == 2
    assert needle in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err and out == ""


@pytest.mark.integration
def test_console_script_exit_status():
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "dem.cli",
            "pointmass",
            "thresholds",
            "--angle",
            "100",
            "--friction",
            "0.3",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert (
        proc.stderr.strip()
        == "dem: error: --angle = 100.0: vibration angle must be in (0, 90) degrees"
    )


GOOD_CASE = SMALL_CASE


@pytest.mark.parametrize(
    "old,new,needles",
    [
        ("count = 120\n", "", ["particles.count", "missing"]),
        ("count = 120", "count = 0", ["particles.count = 0"]),
        ("radius = 0.002", "radius = -0.002", ["particles.radius = -0.002"]),
        ("radius = 0.002", 'radius = "big"', ["particles.radius", "'big'"]),
        ("friction = 0.35", "friction = 0.35\nfricton = 0.3", ["fricton", "did you mean"]),
        ("width = 0.02", "width = 0.003", ["trough.width = 0.003"]),
        ("amplitude = 0.0005", "amplitude = 0.0005\nthrow_number = 2.0", ["throw_number"]),
        ("angle = 25.0", "angle = 25.0 =", ["line"]),
        ("length = 0.03", 'length = 0.03\nmesh = "geometry/none.stl"', ["none.stl"]),
    ],
)
def test_bad_case_file_one_line_exit_2(capsys, tmp_path, old, new, needles):
    assert old in GOOD_CASE
    (tmp_path / "case.toml").write_text(GOOD_CASE.replace(old, new))
    code, out, err = run(capsys, "run", str(tmp_path), "--out", str(tmp_path / "out"))
    assert code == 2, err
    assert str(tmp_path / "case.toml") in err
    for needle in needles:
        assert needle in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "out").exists()  # nothing written before the case is valid


@pytest.mark.integration
def test_export_liggghts_writes_a_deck_with_dems_timestep(capsys, tmp_path):
    case_dir = tmp_path / "case"
    case_dir.mkdir()
    (case_dir / "case.toml").write_text(SMALL_CASE)
    code, out, err = run(capsys, "export", "liggghts", str(case_dir), str(tmp_path / "deck"))
    assert code == 0, err
    from dem.engine import setup
    from dem.scene.case import load_case

    deck = (tmp_path / "deck" / "in.dem").read_text().splitlines()
    (line,) = [x for x in deck if x.startswith("timestep ")]
    assert float(line.split()[1]) == setup.from_case(load_case(case_dir)).dt
    code, _, err = run(
        capsys, "export", "liggghts", str(case_dir), str(tmp_path / "d2"), "--timestep", "-1"
    )
    assert code == 2 and "timestep" in err
    # a step above the stability limit is named as the option given, not as a case key
    code, _, err = run(
        capsys, "export", "liggghts", str(case_dir), str(tmp_path / "d3"), "--timestep", "0.01"
    )
    assert code == 2 and "--timestep = 0.01" in err and "stability limit" in err, err
    assert not (tmp_path / "d3").exists()


@pytest.mark.integration
def test_export_refuses_to_replace_a_deck_without_overwrite(capsys, tmp_path):
    """A user's edited deck is not lost: a second export into the folder exits 2 and leaves it;
    --overwrite replaces it; a file as OUT_DIR is refused by name."""
    case_dir = tmp_path / "case"
    case_dir.mkdir()
    (case_dir / "case.toml").write_text(SMALL_CASE)
    deck_dir = tmp_path / "deck"
    assert run(capsys, "export", "liggghts", str(case_dir), str(deck_dir))[0] == 0
    deck = deck_dir / "in.dem"
    deck.write_text("# my edits\n")
    code, _, err = run(capsys, "export", "liggghts", str(case_dir), str(deck_dir))
    assert code == 2 and "OUT_DIR" in err and "--overwrite" in err and "in.dem" in err
    assert deck.read_text() == "# my edits\n"
    code, _, err = run(capsys, "export", "liggghts", str(case_dir), str(deck_dir), "--overwrite")
    assert code == 0, err
    assert deck.read_text().startswith("# LIGGGHTS deck exported by dem")
    code, _, err = run(capsys, "export", "liggghts", str(case_dir), str(deck))
    assert code == 2 and "OUT_DIR" in err and "this is a file" in err


def _single_sphere_copy(tmp_path, throw_number=None, tangential=None):
    """A copy of cases/single-sphere at another throw number or tangential law: (dir, toml)."""
    import shutil

    case_dir = tmp_path / "one"
    shutil.copytree("cases/single-sphere", case_dir)
    toml = case_dir / "case.toml"
    text = toml.read_text()
    if throw_number is not None:
        text = text.replace("throw_number = 0.6", f"throw_number = {throw_number}")
    if tangential is not None:
        text = text.replace('tangential = "impact"', f'tangential = "{tangential}"')
    toml.write_text(text)
    return case_dir, toml


@pytest.mark.integration
def test_calibrate_writes_the_contact_and_keeps_the_original(tmp_path, capsys):
    from dem.scene.case import load_case

    case_dir, toml = _single_sphere_copy(tmp_path, 1.8, "coulomb")
    before = toml.read_text()
    plot = tmp_path / "cal.png"
    code, out, _ = run_cli(capsys, "calibrate", case_dir, "--dry-run", "--plot", plot, "--json")
    assert code == 0 and toml.read_text() == before and plot.stat().st_size > 0
    fit = json.loads(out)  # stdout holds the object alone
    assert fit["case_written"] is None and fit["plot"] == str(plot)
    assert 0.015 < fit["calibration"]["kappa"] < 0.025 and fit["calibration"]["fitted"]
    assert not (case_dir / "case.toml.orig").exists()
    assert main(["calibrate", str(case_dir), "--plot", str(plot)]) == 0
    assert (case_dir / "case.toml.orig").read_text() == before
    contact = load_case(case_dir).contact
    assert 0.015 < contact.tangential_stiffness_ratio < 0.025  # eps_t 0.8 at the 34 deg landing
    assert contact.tangential_damping_ratio == 0.3
    assert "# N/m" in toml.read_text()  # the rest of the file, comments included, is kept
    # every evaluation was kept as it came; the written keys record the drive they fit
    trail = (case_dir / "output" / "calibration_evaluations.csv").read_text().splitlines()
    assert trail[0].startswith("evaluation,tangential_stiffness_ratio") and len(trail) > 17
    assert "at Gamma 1.8, phi 25 deg, mu 0.35, alpha 0 deg" in toml.read_text()
    from dem.run.plan import plan

    key = "contact.tangential_stiffness_ratio"
    assert not [a for a in plan(load_case(case_dir)).advice if a.key == key]
    other = plan(load_case(case_dir, {"drive.throw_number": 2.0})).advice
    assert [a for a in other if a.key == key and a.level == "warn"]


def test_calibrate_counts_its_evaluations_and_a_stop_keeps_them(tmp_path, capsys, monkeypatch):
    import dem.studies.calibrate

    case_dir, toml = _single_sphere_copy(tmp_path, 1.8, "coulomb")
    before = toml.read_text()
    measure, calls = dem.studies.calibrate._measure, {"n": 0}

    def stopped_at_the_fifth(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 5:
            raise KeyboardInterrupt
        return measure(*args, **kwargs)

    monkeypatch.setattr(dem.studies.calibrate, "_measure", stopped_at_the_fifth)
    code, _, err = run(capsys, "calibrate", str(case_dir), "--plot", str(tmp_path / "c.png"))
    assert code == 130 and toml.read_text() == before
    assert "[ 1/" in err and "to go" in err and "stopped after 3 evaluations" in err
    trail = (case_dir / "output" / "calibration_evaluations.csv").read_text().splitlines()
    assert len(trail) == 4  # the header and the three evaluations made


def test_calibrate_refuses_the_liggghts_convention(tmp_path, capsys):
    case_dir, _ = _single_sphere_copy(tmp_path, tangential="liggghts")
    assert main(["calibrate", str(case_dir)]) == 2
    assert "contact.tangential" in capsys.readouterr().err


@pytest.mark.integration
def test_calibrate_of_the_impact_law_measures_and_changes_nothing(tmp_path, capsys):
    case_dir, toml = _single_sphere_copy(tmp_path, 1.8)
    before = toml.read_text()
    code, out, _ = run(capsys, "calibrate", str(case_dir), "--plot", str(tmp_path / "c.png"))
    assert code == 0 and "nothing to fit" in out and toml.read_text() == before
    assert not (case_dir / "case.toml.orig").exists()


@pytest.mark.integration
def test_calibrate_writes_the_closest_fit_and_fails_only_when_strict(tmp_path, capsys):
    """Gamma 4.2, a period-2 orbit: its landings at 21 and 42 deg take different eps_t from one
    Coulomb spring (0.756 and 0.819 at best), yet calibrate answers (exit 0) unless --strict."""
    case_dir, _ = _single_sphere_copy(tmp_path, 4.2, "coulomb")
    plot = str(tmp_path / "c.png")
    code, out, err = run(capsys, "calibrate", str(case_dir), "--dry-run", "--plot", plot)
    assert code == 0 and "residual" in out and "within 0.02" in err and "--strict" in err
    assert run(capsys, "calibrate", str(case_dir), "--dry-run", "--strict", "--plot", plot)[0] == 1


@pytest.mark.integration
def test_export_of_an_auto_settle_case_takes_an_earlier_runs_count_or_a_stated_default(
    capsys, tmp_path
):
    import json
    import shutil

    case_dir = tmp_path / "screw-trough"
    shutil.copytree("cases/screw-trough", case_dir, ignore=shutil.ignore_patterns("output"))
    code, out, err = run(capsys, "export", "liggghts", str(case_dir), str(tmp_path / "a"))
    assert code == 0, err
    deck = (tmp_path / "a" / "in.dem").read_text()
    assert "20 cycles, dem's default" in deck and "20 cycles, dem's default" in out
    # the run's own detected transient, from CASE_DIR/output (dem run's default folder)
    (case_dir / "output").mkdir()
    summary = {"case": "screw-trough", "settle_cycles_auto": True, "settle_cycles": 8}
    (case_dir / "output" / "summary.json").write_text(json.dumps(summary))
    assert run(capsys, "export", "liggghts", str(case_dir), str(tmp_path / "b"))[0] == 0
    deck_b = (tmp_path / "b" / "in.dem").read_text()
    assert "8 cycles, the transient dem run detected" in deck_b
    dt = float(deck_b.split("\ntimestep ")[1].split()[0])
    assert f"run {round(8 / (60.0 * dt))}\n" in deck_b  # the settle stage
    # a particle dump every output frame (frames_per_cycle = 4)
    dump = next(line for line in deck_b.splitlines() if line.startswith("dump "))
    assert dump.split()[4] == str(round(1 / (60.0 * dt) / 4)) and "radius" in dump
    # --from-run of another case is refused, naming it
    other = tmp_path / "other"
    other.mkdir()
    (other / "summary.json").write_text(json.dumps({**summary, "case": "sphere-bed"}))
    code, _, err = run(capsys, "export", "liggghts", str(case_dir), str(tmp_path / "c"),
                       "--from-run", str(other))  # fmt: skip
    assert code == 2 and "--from-run" in err and not (tmp_path / "c").exists()
    code, out, err = run(
        capsys, "export", "liggghts", str(case_dir), str(tmp_path / "d"),
        "--settle-cycles", "10", "--no-dump",
    )  # fmt: skip
    assert code == 0, err
    deck_d = (tmp_path / "d" / "in.dem").read_text()
    assert "# settle:" not in deck_d and "\ndump " not in deck_d


@pytest.mark.parametrize(
    "argv, key, cause",
    [
        (["pointmass", "sweep", "--throw-number", "1", "--angle", "20", "--friction", "0.3",
          "--out", "{tmp}"], "--out", "this is a folder"),
        (["pointmass", "optimum", "--over", "angle", "--hold", "throw_number",
          "--throw-number", "1.5", "--friction", "0.3", "--plot", "{tmp}/missing/o.png"],
         "--plot", "does not exist"),
        (["report", "{case}/output", "--out", "{file}"], "--out", "this is a file"),
        (["report", "{case}/output", "--dest", "{file}"], "--out", "this is a file"),
        (["run", "{case}", "--out", "{file}"], "--out", "this is a file"),
        (["run", "{case}", "--out", "{tmp}/" + "x" * 300], "--out", "a path the system allows"),
        (["run", "{case}", "--out", "{file}/sub"], "--out", "is a file"),
    ],
)  # fmt: skip
def test_bad_output_paths_are_refused_by_key_before_any_work(capsys, tmp_path, argv, key, cause):
    """Output paths that cannot be written end in exit 2 and one line naming the option and
    the cause, before anything is computed or written (no traceback)."""
    case_dir = tmp_path / "case"
    case_dir.mkdir()
    (case_dir / "case.toml").write_text(SMALL_CASE)
    (case_dir / "output").mkdir()
    (case_dir / "output" / "summary.json").write_text("{}")
    user_file = tmp_path / "notes.txt"
    user_file.write_text("mine\n")
    args = [a.format(tmp=tmp_path, case=case_dir, file=user_file) for a in argv]
    before = sorted(p.name for p in tmp_path.rglob("*"))
    code, out, err = run(capsys, *args)
    assert code == 2, err
    assert err.count("\n") == 1 and key in err and cause in err, err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.rglob("*")) == before
    assert user_file.read_text() == "mine\n"


def test_a_read_only_output_folder_is_refused_by_key(capsys, tmp_path):
    import os

    if os.geteuid() == 0:
        pytest.skip("root writes into read-only folders")
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    code, _, err = run(capsys, "pointmass", "sweep", "--throw-number", "1", "--angle", "20",
                       "--friction", "0.3", "--out", str(locked / "s.csv"))  # fmt: skip
    assert code == 2 and "--out" in err and "not writable" in err


def test_a_sweep_too_large_for_memory_is_refused_before_computing(capsys, tmp_path):
    """7e7 points died with MemoryError; a sweep over 1e6 points (or one axis of that many)
    is refused at once, naming the options and the size."""
    code, _, err = run(capsys, "pointmass", "sweep", "--throw-number", "0.5:3:0.0001",
                       "--angle", "1:89:0.01", "--friction", "0.3")  # fmt: skip
    assert code == 2 and err.count("\n") == 1 and "at most 1000000 points" in err, err
    code, _, err = run(capsys, "pointmass", "sweep", "--throw-number", "0.5:3:1e-9",
                       "--angle", "20", "--friction", "0.3")  # fmt: skip
    assert code == 2 and "--throw-number" in err and "at most 1000000 values" in err, err


@pytest.mark.integration
def test_run_and_report_print_json_when_asked(tmp_path, capsys):
    """dem run --json prints summary.json's object on stdout (the rest on stderr); dem report
    --json the files it wrote; --target-error sets run.target_error and is named in errors."""
    case_dir = write_case(tmp_path / "case", SMALL_CASE.replace("cycles = 6", "cycles = 2"))
    out = tmp_path / "out"
    code, stdout, _ = run_cli(capsys, "run", case_dir, "--out", out, "--no-frames", "--json")
    summary = json.loads(stdout)
    assert code == 0 and summary == json.loads((out / "summary.json").read_text())
    code, stdout, _ = run_cli(capsys, "report", out, "--json")
    written = json.loads(stdout)["written"]
    assert code == 0 and written and all(Path(p).is_file() for p in written)
    code, _, err = run_cli(capsys, "run", case_dir, "--out", tmp_path / "t", "--target-error", "2")
    assert code == 2 and "--target-error" in err and "run.target_error" in err
