"""No command writes through a link it did not make (hardening round 4, items 2 and 3).

Every command that writes a file (``dem export liggghts|lammps``, ``dem report``, ``dem
calibrate``, ``dem sweep``, ``dem optimum``, ``dem plan --suggest``, ``dem pointmass sweep``
and ``optimum --plot``, ``dem run``'s default folder) is walked: under each name it writes, a
dangling link and a live link to a file outside are planted in turn, and the command runs with
and without ``--overwrite`` where it has one. It must refuse (exit 2, the path and "link" named)
before it computes anything, leave the link's target as it was (a dangling link's target never
appears) and write nothing through it. A clean run of each cheap command shows that the names
walked are all it writes, so the list cannot fall behind the code.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from small_case import SMALL_CASE, write_case
from test_report import _run_folder

from dem.cli import main
from dem.io.lammps.export import DECK_FILES as LAMMPS_FILES
from dem.io.lammps.export import RUN_FILES as LAMMPS_RUN_FILES
from dem.io.liggghts.export import DECK_FILES as LIGGGHTS_FILES
from dem.run.output import RUN_OUTPUTS
from dem.studies.calibrate import EVALUATIONS_FILE
from dem.studies.optimum import OPTIMUM_FILES
from dem.studies.report import COMPARISON_FILES
from dem.studies.report import RUN_FILES as REPORT_FILES
from dem.studies.sweep import RECORD, TABLE_FILES

ROOT = Path(__file__).resolve().parents[2]
SENTINEL = "a file of the user's, outside every output folder\n"
MESH = ROOT / "cases" / "geometry" / "u_trough.stl"


def _cases(base: Path) -> dict[str, Path]:
    """A sphere case, a clump case and a mesh case."""
    spheres = write_case(base / "spheres")
    clump = base / "clump"
    (clump / "geometry").mkdir(parents=True)
    (clump / "geometry" / "grain.spheres").write_text("0 0 0 0.002\n0.003 0 0 0.0015\n")
    write_case(clump, SMALL_CASE.replace('shape = "sphere"\ncount = 120\nradius = 0.002',
                                         'shape = "clump"\ncount = 40\n'
                                         'template = "geometry/grain.spheres"'))  # fmt: skip
    mesh = base / "mesh"
    (mesh / "geometry").mkdir(parents=True)
    shutil.copy(MESH, mesh / "geometry" / "pan.stl")
    pan = 'length = 0.12\nwidth = 0.06\nmesh = "geometry/pan.stl"'
    write_case(mesh, SMALL_CASE.replace("length = 0.03\nwidth = 0.02", pan))
    return {"spheres": spheres, "clump": clump, "mesh": mesh}


#: command -> (the folder its names are under, relative to the test's tmp_path; the names;
#: the arguments, with OUT for that folder; whether --overwrite is an option).
COMMANDS = {
    "export-liggghts": (
        "deck",
        [*LIGGGHTS_FILES],
        ["export", "liggghts", "{mesh}", "{out}"],
        True,
    ),  # fmt: skip
    "export-lammps": (
        "deck",
        [*LAMMPS_FILES, *LAMMPS_RUN_FILES],
        ["export", "lammps", "{spheres}", "{out}", "--run", "--set", "contact.tangential=coulomb"],
        True,
    ),  # fmt: skip
    "report": ("run/report", [*REPORT_FILES], ["report", "{run}"], False),
    "report-many": (
        "many",
        [*COMPARISON_FILES, "a", "b", *(f"a/{n}" for n in REPORT_FILES)],
        ["report", "{runs}/a", "{runs}/b", "--out", "{out}"],
        False,
    ),  # fmt: skip
    "calibrate": (
        "cases/spheres",
        ["output", f"output/{EVALUATIONS_FILE}", "output/calibration.png", "case.toml.orig"],
        ["calibrate", "{spheres}"],
        False,
    ),  # fmt: skip
    "sweep": (
        "sweep",
        [
            *TABLE_FILES,
            "000_drive.angle=20",
            f"000_drive.angle=20/{RECORD}",
            *(f"000_drive.angle=20/{n}" for n in RUN_OUTPUTS),
        ],
        ["sweep", "{spheres}", "--set", "drive.angle=20", "--out", "{out}"],
        False,
    ),  # fmt: skip
    "optimum": (
        "opt",
        [*OPTIMUM_FILES],
        ["optimum", "{spheres}", "--over", "drive.angle", "--out", "{out}"],
        False,
    ),  # fmt: skip
    "suggest": ("suggested", ["case.toml"], ["plan", "{spheres}", "--suggest", "{out}"], False),
    "pointmass-sweep": (
        "table",
        ["v.csv"],
        [
            "pointmass",
            "sweep",
            "--throw-number",
            "1.8",
            "--angle",
            "25",
            "--friction",
            "0.35",
            "--out",
            "{out}/v.csv",
        ],
        False,
    ),  # fmt: skip
    "pointmass-plot": (
        "fig",
        ["o.png"],
        [
            "pointmass",
            "optimum",
            "--over",
            "angle",
            "--hold",
            "throw_number",
            "--throw-number",
            "1.8",
            "--friction",
            "0.35",
            "--plot",
            "{out}/o.png",
        ],
        False,
    ),  # fmt: skip
    "run-default": ("cases/spheres", ["output"], ["run", "{spheres}"], False),
    "report-default": ("run", ["report"], ["report", "{run}"], False),
    "sweep-default": (
        "cases/spheres",
        ["sweep"],
        ["sweep", "{spheres}", "--set", "drive.angle=20"],
        False,
    ),  # fmt: skip
    "optimum-default": (
        "cases/spheres",
        ["optimum"],
        ["optimum", "{spheres}", "--over", "drive.angle"],
        False,
    ),  # fmt: skip
}


def _setup(tmp_path: Path, command: str = "") -> dict[str, str]:
    cases = _cases(tmp_path / "cases")
    if not command or command.startswith("report"):  # results.h5 files: only where needed
        _run_folder(tmp_path / "run")
        _run_folder(tmp_path / "runs" / "a")
        _run_folder(tmp_path / "runs" / "b", angle=35.0)
    return {"spheres": str(cases["spheres"]), "mesh": str(cases["mesh"]),
            "clump": str(cases["clump"]), "run": str(tmp_path / "run"),
            "runs": str(tmp_path / "runs")}  # fmt: skip


def _walk():
    for command, (_, names, _, overwrite) in COMMANDS.items():
        for name in names:
            for kind in ("dangling", "live"):
                for again in (False, True) if overwrite else (False,):
                    tag = f"{command}:{name}:{kind}{':overwrite' if again else ''}"
                    yield pytest.param(command, name, kind, again, id=tag)


@pytest.mark.integration
@pytest.mark.parametrize(("command", "name", "kind", "overwrite"), list(_walk()))
def test_a_link_under_a_name_a_command_writes_is_refused_before_any_work(
    tmp_path, capsys, command, name, kind, overwrite
):
    where = _setup(tmp_path, command)
    folder, _, argv, _ = COMMANDS[command]
    out = tmp_path / folder
    where["out"] = str(out)
    link = out / name
    link.parent.mkdir(parents=True, exist_ok=True)
    target = tmp_path / "elsewhere" / "target"
    target.parent.mkdir()
    if kind == "live":
        target.write_text(SENTINEL)
    os.symlink(target, link)
    args = [a.format(**where) for a in argv] + (["--overwrite"] if overwrite else [])
    code = main(args)
    err = capsys.readouterr().err
    assert code == 2, err
    assert "link" in err and str(link) in err, err
    if kind == "live":
        assert target.read_text() == SENTINEL
    else:
        assert not target.exists()
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert sorted(p.name for p in target.parent.iterdir()) == (["target"] if kind == "live" else [])


def _written(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


@pytest.mark.integration
def test_the_names_walked_are_all_the_cheap_commands_write(tmp_path, capsys):
    """A clean run of each command that computes nothing heavy writes only the walked names
    (the export decks of spheres, clumps and meshes, reports, the point-mass table and figure,
    a suggested case)."""
    where = _setup(tmp_path)
    cases = {k: where[k] for k in ("spheres", "clump", "mesh")}
    for kind, case in cases.items():
        out = tmp_path / f"liggghts-{kind}"
        assert main(["export", "liggghts", case, str(out)]) == 0
        assert _written(out) <= set(LIGGGHTS_FILES), kind
        if kind != "mesh":  # LAMMPS pours no grains into a mesh pan (refused, as it says)
            out = tmp_path / f"lammps-{kind}"
            assert main(["export", "lammps", case, str(out), "--fill", "lammps",
                         "--set", "contact.tangential=coulomb"]) == 0  # fmt: skip
            assert _written(out) <= set(LAMMPS_FILES), kind
    for command in ("report", "report-many", "pointmass-sweep", "pointmass-plot", "suggest"):
        folder, names, argv, _ = COMMANDS[command]
        out = tmp_path / folder
        where["out"] = str(out)
        out.mkdir(parents=True, exist_ok=True)
        before = _written(out)
        assert main([a.format(**where) for a in argv]) == 0, command
        new = _written(out) - before
        if command == "suggest":
            assert new == {"case.toml"}
        else:
            assert new <= set(names) | ({"b"} | {f"b/{n}" for n in REPORT_FILES}), (command, new)
            assert new, command
    capsys.readouterr()


def test_a_dangling_link_counts_as_an_earlier_deck(tmp_path, capsys):
    """Without --overwrite an export is refused by a dangling link as by a file (exists() is
    false for it): the message says which names are there."""
    case = write_case(tmp_path / "case")
    out = tmp_path / "deck"
    out.mkdir()
    os.symlink(tmp_path / "nowhere", out / "in.dem")
    assert main(["export", "liggghts", str(case), str(out)]) == 2
    err = capsys.readouterr().err
    assert "link" in err and not (tmp_path / "nowhere").exists()


def test_suggest_copies_no_link_of_the_case_folder(tmp_path, capsys):
    """A received case folder may hold a link to a file of its receiver's: --suggest copies
    plain files only, never the link's target."""
    case = write_case(tmp_path / "case")
    secret = tmp_path / "secret.txt"
    secret.write_text("the receiver's secret\n")
    os.symlink(secret, case / "notes.txt")
    (case / "grain.spheres").write_text("0 0 0 0.002\n")
    out = tmp_path / "suggested"
    assert main(["plan", str(case), "--suggest", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["case.toml", "grain.spheres"]
    capsys.readouterr()


def test_an_evaluation_trail_is_never_appended_through_a_link(tmp_path):
    from dem.errors import InputError
    from dem.io.files import append_text, replace_text

    path = tmp_path / "trail.csv"
    replace_text(path, "header\n")
    append_text(path, "row\n")
    assert path.read_text() == "header\nrow\n"
    target = tmp_path / "target"
    target.write_text(SENTINEL)
    path.unlink()
    os.symlink(target, path)
    with pytest.raises(InputError, match="link"):
        append_text(path, "row\n")
    assert target.read_text() == SENTINEL


def test_every_summary_of_a_refusal_is_one_line(tmp_path, capsys):
    """The refusal is dem's one line, not a traceback (the writer's own check, when the door's
    list misses a name, says the same)."""
    from dem.errors import InputError
    from dem.io.files import replace_text

    os.symlink(tmp_path / "t", tmp_path / "x.json")
    with pytest.raises(InputError) as info:
        replace_text(tmp_path / "x.json", json.dumps({}))
    assert "link" in str(info.value) and not (tmp_path / "t").exists()


@pytest.mark.parametrize("kind", ["dangling", "live"])
def test_a_link_planted_among_a_runs_frames_is_refused_at_the_door(tmp_path, capsys, kind):
    """``dem run --overwrite`` or ``--resume`` would replace the frames dem names: a link
    planted under such a name in frames/ is refused before anything runs."""
    case = write_case(tmp_path / "case")
    out = tmp_path / "out"
    (out / "frames").mkdir(parents=True)
    (out / "summary.json").write_text("{}")
    target = tmp_path / "target"
    if kind == "live":
        target.write_text(SENTINEL)
    os.symlink(target, out / "frames" / "particles_000001.vtp")
    code = main(["run", str(case), "--out", str(out), "--overwrite"])
    err = capsys.readouterr().err
    assert code == 2 and "particles_000001.vtp" in err and "link" in err
    assert (out / "summary.json").read_text() == "{}"
    assert target.read_text() == SENTINEL if kind == "live" else not target.exists()
