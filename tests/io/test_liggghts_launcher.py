"""The LIGGGHTS launcher of dem.io.liggghts, without LIGGGHTS: log parsing and a fake executable."""

import os
import stat

import pytest

from dem.io import liggghts
from dem.io.liggghts import (
    LiggghtsError,
    LoopTime,
    find_liggghts,
    liggghts_version,
    loop_times,
    run_liggghts,
)

# the lines a LIGGGHTS-PUBLIC 3.8.0 run of a write_deck deck prints, shortened
SAMPLE_STDOUT = """\
LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, compiled 2018-11-20-12:54:57 by buildd, git commit unknown)
Created orthogonal box = (0 -0.02 0) to (0.1 0.02 0.05)
Setting up run ...
Memory usage per processor = 6.11 Mbytes
Loop time of 20.5119 on 1 procs for 82548 steps with 1600 atoms

Pair  time (%) = 9.1 (44.4)
Loop time of 6.25e+00 on 2 procs for 27410 steps with 1600 atoms
Loop time of 12.0 on 1 procs for 54820 steps with 1600 atoms
"""


def _fake_liggghts(folder, body):
    """An executable ``liggghts`` shell script in ``folder`` running ``body``."""
    folder.mkdir(parents=True, exist_ok=True)
    exe = folder / "liggghts"
    exe.write_text("#!/bin/sh\n" + body)
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    return exe


def test_version_and_loop_times_are_parsed_from_a_log():
    assert liggghts_version(SAMPLE_STDOUT) == "LIGGGHTS-PUBLIC 3.8.0"
    assert liggghts_version("no banner here") is None
    loops = loop_times(SAMPLE_STDOUT)
    assert loops == [
        LoopTime(20.5119, 1, 82548, 1600),
        LoopTime(6.25, 2, 27410, 1600),
        LoopTime(12.0, 1, 54820, 1600),
    ]
    assert isinstance(loops[0].steps, int) and isinstance(loops[0].seconds, float)
    assert loop_times("") == []


def test_missing_executable_gives_the_install_hint(monkeypatch, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    assert find_liggghts() is None
    with pytest.raises(LiggghtsError, match="apt-get install -y liggghts"):
        run_liggghts(tmp_path)


def test_a_fake_liggghts_on_path_runs_in_the_work_dir(monkeypatch, tmp_path):
    # prints the banner and one Loop time line, and proves it ran in work_dir with -in DECK
    exe = _fake_liggghts(
        tmp_path / "bin",
        'test "$1" = "-in" && test -f "$2" || exit 3\n'
        'echo "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, compiled today)"\n'
        "echo 'Loop time of 1.5 on 1 procs for 100 steps with 7 atoms'\n"
        "echo done > ran_here.txt\n"
        "echo 'a warning' >&2\n",
    )
    monkeypatch.setenv("PATH", f"{exe.parent}{os.pathsep}{os.environ.get('PATH', '')}")
    assert find_liggghts() == str(exe)
    work = tmp_path / "work"
    work.mkdir()
    (work / "in.deck").write_text("run 100\n")
    run = run_liggghts(work, "in.deck", log_name="log.txt")
    assert run.version == "LIGGGHTS-PUBLIC 3.8.0"
    assert run.loop_times == [LoopTime(1.5, 1, 100, 7)]
    assert run.wall_s > 0.0
    assert "Loop time of 1.5" in run.stdout
    assert (work / "ran_here.txt").exists()
    log = (work / "log.txt").read_text()
    assert log.startswith("LIGGGHTS (Version") and log.endswith("a warning\n")
    # the default deck and log names
    (work / liggghts.DECK_NAME).write_text("run 100\n")
    run_liggghts(work)
    assert (work / liggghts.LIGGGHTS_STDOUT).exists()


def test_a_failed_run_quotes_the_end_of_its_output(monkeypatch, tmp_path):
    exe = _fake_liggghts(tmp_path / "bin", "echo 'ERROR: Unknown command: nonsense'\nexit 1\n")
    monkeypatch.setenv("PATH", f"{exe.parent}{os.pathsep}{os.environ.get('PATH', '')}")
    with pytest.raises(LiggghtsError, match="exit status 1") as failed:
        run_liggghts(tmp_path)
    assert "ERROR: Unknown command: nonsense" in str(failed.value)
    assert (tmp_path / liggghts.LIGGGHTS_STDOUT).read_text().startswith("ERROR")


def test_too_few_loop_time_lines_count_as_a_failure(monkeypatch, tmp_path):
    exe = _fake_liggghts(
        tmp_path / "bin", "echo 'Loop time of 1.5 on 1 procs for 100 steps with 7 atoms'\n"
    )
    monkeypatch.setenv("PATH", f"{exe.parent}{os.pathsep}{os.environ.get('PATH', '')}")
    assert len(run_liggghts(tmp_path).loop_times) == 1
    assert len(run_liggghts(tmp_path, prefix=("env",)).loop_times) == 1  # an MPI launcher's place
    with pytest.raises(LiggghtsError, match="1 'Loop time' lines, 2 expected"):
        run_liggghts(tmp_path, min_loops=2)
