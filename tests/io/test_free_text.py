"""A name cannot add a command to a file another program reads (hardening round 4, item 1).

Every control character, the line and paragraph separators, a last ``&`` and a triple quote are
planted in each name a deck writer puts into its files: the case folder's name, the deck folder
(``OUT_DIR``), a mesh file's name, a clump template's name and the run a settle count came
from. Each deck is read as LAMMPS and LIGGGHTS read their input (``&`` and triple quotes join
lines first, then ``#`` starts a comment outside quotes) and must give the same commands as the
deck of plain names; the data, molecule, template and STL files must keep their lines. Where
LAMMPS or LIGGGHTS is installed, they run a deck of a hostile name and nothing is executed.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from needs_lammps import NEEDS_LAMMPS
from small_case import SMALL_CASE, write_case

from dem.io.freetext import free_text, input_line, input_text
from dem.io.lammps.deck import write_data
from dem.io.lammps.deck import write_deck as write_lammps_deck
from dem.io.lammps.pour import write_molecule
from dem.io.liggghts import write_stl
from dem.io.liggghts.export import export_deck, plan_export
from dem.scene.case import load_case
from dem.scene.resolved import resolve

ROOT = Path(__file__).resolve().parents[2]
MESH = ROOT / "cases" / "geometry" / "u_trough.stl"

#: Every character that could end a line or hide text (C0 but NUL, which no file name holds; DEL;
#: the C1 NEL; the line and paragraph separators; a bidi override), one test each.
HOSTILE = [chr(c) for c in range(1, 0x20)] + ["\x7f", "\x85", "\u2028", "\u2029", "\u202e"]
#: How LAMMPS's reader joins lines: both go in every hostile name too.
JOINERS = ['"""', "&"]


def lammps_commands(text: str) -> list[str]:
    """The commands LAMMPS (and LIGGGHTS, its 2013 reader) reads from an input file's text.

    As ``Input::file`` and ``Input::parse``: a line whose last printable character is ``&`` is
    joined to the next, as is a line with an odd count of triple quotes; then everything from a
    ``#`` outside quotes on is a comment. Lines are split on ``\\n`` only (C's fgets).
    """
    lines = text.split("\n")
    commands, held = [], ""
    for line in lines:
        held = held + line
        body = held.rstrip()
        if body.endswith("&"):
            held = body[:-1] + " "
            continue
        if held.count('"""') % 2 == 1:
            held += "\n"
            continue
        commands.append(_strip_comment(held).strip())
        held = ""
    if held:
        commands.append(_strip_comment(held).strip())
    return [c for c in commands if c]


def _strip_comment(line: str) -> str:
    quote = None
    i = 0
    while i < len(line):
        if quote is None and line.startswith('"""', i):
            quote, i = '"""', i + 3
            continue
        if quote == '"""' and line.startswith('"""', i):
            quote, i = None, i + 3
            continue
        ch = line[i]
        if quote is None and ch == "#":
            return line[:i]
        if quote is None and ch in "'\"":
            quote = ch
        elif quote == ch:
            quote = None
        i += 1
    return line


def test_the_reader_model_finds_the_injection_it_must_catch():
    """The model of LAMMPS's reader is not blind: a raw newline or '&' changes the commands."""
    plain = "# case x\nrun 5\n"
    assert lammps_commands(plain) == ["run 5"]
    assert lammps_commands("# case x\nshell touch PWNED #\nrun 5\n") == [
        "shell touch PWNED",
        "run 5",
    ]
    assert lammps_commands("# case x&\nrun 5\n") == []  # the comment swallows the run
    assert lammps_commands('# case x"""\nrun 5\n') == []
    for line in ("# case x\nshell touch PWNED #", "# case x&", '# case x"""', "# c\u2028x"):
        assert lammps_commands(input_text([line, "run 5"])) == ["run 5"]


@pytest.mark.parametrize("ch", HOSTILE + JOINERS, ids=lambda c: f"U+{ord(c[0]):04X}{len(c)}")
def test_input_line_is_one_inert_line(ch):
    line = input_line(f"# case a{ch}shell touch PWNED #{ch}")
    assert "\n" not in line and "\r" not in line and len(line.splitlines()) == 1
    assert line.isprintable() or ch in JOINERS
    assert not line.rstrip().endswith("&") and '"""' not in line
    assert lammps_commands(line + "\nrun 1\n") == ["run 1"]


def test_free_text_keeps_plain_names_and_escapes_the_rest():
    assert free_text("screw-trough_2 (copy) é") == "screw-trough_2 (copy) é"
    assert free_text("a\nb\tc\x7fd\u2028e") == "a\\x0ab\\x09c\\x7fd\\u2028e"
    assert free_text(Path("x/y")) == "x/y"


def _hostile_cases(tmp_path: Path, name: str) -> dict[str, Path]:
    """A sphere, a clump and a mesh case whose folder, template and mesh carry ``name``."""
    spheres = write_case(tmp_path / f"spheres{name}", SMALL_CASE)
    clump_dir = tmp_path / f"clump{name}"
    (clump_dir / "geometry").mkdir(parents=True)
    (clump_dir / "geometry" / f"grain{name}.spheres").write_text("0 0 0 0.002\n0.003 0 0 0.0015\n")
    clump = SMALL_CASE.replace('shape = "sphere"\ncount = 120\nradius = 0.002',
                               'shape = "clump"\ncount = 40\n'
                               f'template = "geometry/grain{_toml(name)}.spheres"')  # fmt: skip
    write_case(clump_dir, clump)
    mesh_dir = tmp_path / f"mesh{name}"
    (mesh_dir / "geometry").mkdir(parents=True)
    shutil.copy(MESH, mesh_dir / "geometry" / f"pan{name}.stl")
    meshed = SMALL_CASE.replace("length = 0.03\nwidth = 0.02",
                                'length = 0.12\nwidth = 0.06\n'
                                f'mesh = "geometry/pan{_toml(name)}.stl"')  # fmt: skip
    write_case(mesh_dir, meshed)
    return {"spheres": spheres, "clump": clump_dir, "mesh": mesh_dir}


def _toml(text: str) -> str:
    """``text`` inside a TOML basic string."""
    from dem.scene.tomledit import toml_string

    return toml_string(text)[1:-1]


def _liggghts_files(case_dir: Path, out: Path, from_run: Path | None = None) -> dict[str, str]:
    case = load_case(case_dir)
    plan = plan_export(case, settle_cycles=None if from_run else 2, from_run=from_run)
    export_deck(plan, out)
    return {p.name: p.read_text() for p in sorted(out.iterdir())}


@pytest.mark.parametrize("ch", HOSTILE, ids=lambda c: f"U+{ord(c):04X}")
def test_liggghts_decks_of_hostile_names_run_the_same_commands(tmp_path, ch):
    name = f"x{ch}shell touch PWNED #{ch}&"
    plain = _hostile_cases(tmp_path / "plain", "x")
    hostile = _hostile_cases(tmp_path / "hostile", name)
    for kind in plain:
        ref = _liggghts_files(plain[kind], tmp_path / "plain" / f"deck-{kind}")
        got = _liggghts_files(hostile[kind], tmp_path / "hostile" / f"deck{name}{kind}")
        assert sorted(got) == sorted(ref), kind
        for file, text in got.items():
            assert "\r" not in text and "\x85" not in text and "\u2028" not in text, (kind, file)
            if file == "in.dem":
                assert lammps_commands(text) == lammps_commands(ref[file]), kind
                assert not any("PWNED" in c for c in lammps_commands(text))
            else:  # the template and STL: the same lines, the name's comment aside
                assert _uncommented(text) == _uncommented(ref[file]), (kind, file)


def _uncommented(text: str) -> list[str]:
    return [line for line in text.split("\n") if not line.startswith("#")]


def test_a_settle_note_from_a_hostile_run_folder_stays_a_comment(tmp_path):
    import json

    auto = SMALL_CASE.replace("settle_cycles = 2", 'settle_cycles = "auto"')
    case_dir = write_case(tmp_path / "case", auto)
    run = tmp_path / "run\nshell touch PWNED #"
    run.mkdir()
    summary = {"case": "case", "settle_cycles_auto": True, "settle_cycles": 7}
    (run / "summary.json").write_text(json.dumps(summary))
    files = _liggghts_files(case_dir, tmp_path / "deck", from_run=run)
    assert "run\\x0ashell touch PWNED #" in files["in.dem"]
    assert not any("PWNED" in c for c in lammps_commands(files["in.dem"]))


@pytest.mark.parametrize("ch", ["\n", "\r", "\x0b", "\x85", "\u2028", "&", '"""'],
                         ids=lambda c: f"U+{ord(c[0]):04X}{len(c)}")  # fmt: skip
def test_lammps_files_of_hostile_names_keep_their_commands_and_lines(tmp_path, ch):
    name = f"x{ch}shell touch PWNED #{ch}"
    texts = {}
    for label, cases in (("plain", _hostile_cases(tmp_path / "p", "x")),
                         ("hostile", _hostile_cases(tmp_path / "h", name))):  # fmt: skip
        for kind in ("spheres", "clump"):
            scene = resolve(load_case(cases[kind], {"contact.tangential": "coulomb"}))
            out = tmp_path / label / f"{kind}{name if label == 'hostile' else ''}"
            out.mkdir(parents=True)
            write_lammps_deck(scene, out, timestep=1e-5, steps=10, settle_steps=5,
                              r_max=scene.max_radius, fill="lammps")  # fmt: skip
            if kind == "clump":
                write_molecule(out / "grain.mol", scene)
            x = np.array([[0.01, 0.0, 0.003]])
            write_data(out / "data.fill", scene, x, np.zeros((1, 3)), np.zeros((1, 3)),
                       np.array([0.002]), np.array([1e-4]))  # fmt: skip
            texts[label, kind] = {p.name: p.read_text() for p in sorted(out.iterdir())}
    for kind in ("spheres", "clump"):
        ref, got = texts["plain", kind], texts["hostile", kind]
        assert sorted(ref) == sorted(got)
        assert lammps_commands(got["in.lammps"]) == lammps_commands(ref["in.lammps"])
        for file in set(got) - {"in.lammps"}:  # a title line, then the same lines
            assert len(got[file].split("\n")) == len(ref[file].split("\n")), file
            assert got[file].split("\n")[1:] == ref[file].split("\n")[1:], file


def test_an_stl_name_and_a_clump_name_stay_on_their_lines(tmp_path):
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], dtype=float)
    text = write_stl(tmp_path / "t.stl", tri, name="pan\nendsolid pan\nsolid x").read_text()
    lines = text.split("\n")  # solid, facet, outer loop, 3 vertices, endloop, endfacet, endsolid
    assert lines[0] == "solid pan\\x0aendsolid pan\\x0asolid x" and lines[-1] == ""
    assert len(lines) == 10 and sum(line.startswith("endsolid") for line in lines) == 1


def _liggghts() -> str | None:
    return shutil.which("liggghts")


@pytest.mark.integration
@NEEDS_LAMMPS
def test_lammps_runs_a_deck_of_a_hostile_name_and_executes_nothing(tmp_path):
    """The LAMMPS deck and data file of a case folder named to inject ``shell``, with three
    grains for a fill and the runs cut to one step: LAMMPS reads it all and touches nothing."""
    from dem.io.lammps.launcher import find_lammps

    name = "x\nshell touch PWNED #&"
    case_dir = _hostile_cases(tmp_path, name)["spheres"]
    scene = resolve(load_case(case_dir, {"contact.tangential": "coulomb"}))
    out = tmp_path / f"deck{name}"
    out.mkdir()
    x = np.array([[0.005, 0.0, 0.002], [0.015, 0.0, 0.002], [0.025, 0.0, 0.002]])
    zeros = np.zeros((3, 3))
    write_data(out / "data.fill", scene, x, zeros, zeros, np.full(3, 0.002), np.full(3, 2.6e-4))
    deck = write_lammps_deck(scene, out, timestep=1e-6, steps=10, settle_steps=5, r_max=0.002)
    deck.write_text(re.sub(r"^run \d+", "run 1", deck.read_text(), flags=re.MULTILINE))
    lmp, _ = find_lammps()
    done = subprocess.run([lmp, "-in", "in.lammps", "-log", "none"], cwd=out,
                          capture_output=True, text=True, timeout=300, check=False,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))  # fmt: skip
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert "x\\x0ashell touch PWNED" in deck.read_text()
    assert not list(tmp_path.rglob("PWNED"))


@pytest.mark.integration
@pytest.mark.skipif(
    _liggghts() is None, reason="LIGGGHTS is not on PATH (apt-get install liggghts)"
)
def test_liggghts_runs_a_deck_of_a_hostile_name_and_executes_nothing(tmp_path):
    """The exported deck of a case folder named to inject ``shell``, its runs cut to one step."""
    name = "x\nshell touch PWNED #&"
    case_dir = _hostile_cases(tmp_path, name)["spheres"]
    out = tmp_path / f"deck{name}"
    _liggghts_files(case_dir, out)
    deck = (out / "in.dem").read_text()
    short = re.sub(r"^run \d+", "run 1", deck, flags=re.MULTILINE)
    (out / "in.dem").write_text(short)
    done = subprocess.run([_liggghts(), "-in", "in.dem", "-log", "none"], cwd=out,
                          capture_output=True, text=True, timeout=300, check=False,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))  # fmt: skip
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert not list(tmp_path.rglob("PWNED"))
