"""What a run leaves in its folder when the world misbehaves (hardening issue, items 3-6).

A file size limit (``ulimit -f``, EFBIG) or a quota (EDQUOT) ends a run like a full disk: one
line, exit 1, results.h5 readable, no crash at exit. A signal after the last cycle, while the
summary is computed, no longer kills the run without a summary. The resume hint repeats every
option the resume needs, and a resume with another frames setting is refused. summary.json is
strict JSON. The planted links of item 1 and 2 are door cases: tests/scene/test_hostile_input.py.
"""

import json
import math
import os
import shlex
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from small_case import SMALL_CASE, sigterm_at_check, write_case

from dem.cli import main
from dem.io.hdf5 import read_results
from dem.run.output import LOCK_FILE
from dem.run.runner import run_case
from dem.scene.case import load_case

ROOT = Path(__file__).resolve().parents[2]


def _case_dir(tmp_path: Path, cycles: int = 6) -> Path:
    return write_case(tmp_path / "case", SMALL_CASE.replace("cycles = 6", f"cycles = {cycles}"))


def _strict(text: str):
    """json.loads that refuses NaN, Infinity and -Infinity (not JSON, RFC 8259)."""

    def refuse(name):
        raise ValueError(f"{name} is not JSON")

    return json.loads(text, parse_constant=refuse)


def _dem(args: list[str], *, script: str = "", preexec_fn=None, timeout: float = 600):
    """``python -c`` running ``script`` (patches) and then ``dem ARGS``, in a new process."""
    code = f"import sys\n{script}\nfrom dem.cli import main\nsys.exit(main(sys.argv[1:]))\n"
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    return subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=timeout,
        preexec_fn=preexec_fn, env=env, cwd=ROOT,
    )  # fmt: skip


def _error_lines(stderr: str) -> list[str]:
    return [x for x in stderr.replace("\r", "\n").splitlines() if x.startswith("dem: error")]


# --- item 3: a file size limit or a quota -------------------------------------------------------

#: The room check switched off: a write fails inside HDF5, as under a quota no check foresees.
NO_ROOM_CHECK = "import dem.io.hdf5_guard as h; h.check_room = lambda path, need: None"


#: (patch, file size limit): the limit results.h5 meets after a dozen cycles of the 60, with
#: the room check (1 MiB of headroom kept below the limit) and without it.
@pytest.mark.parametrize("script, limit", [("", 1_300_000), (NO_ROOM_CHECK, 300_000)],
                         ids=["foreseen", "unforeseen"])  # fmt: skip
@pytest.mark.integration
def test_a_file_size_limit_ends_in_one_line_exit_1_and_no_crash(tmp_path, script, limit):
    """EFBIG used to print the one line and then segfault at exit (exit 139): HDF5's exit handler
    closed again a dataset whose write had failed. Now the write is refused before HDF5 starts
    it (the file size limit checked like the free space), and a write that fails all the same
    is dropped inside HDF5's file driver, so the file closes and the process exits cleanly."""
    import resource

    def set_limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))

    case_dir = _case_dir(tmp_path, cycles=60)
    out = tmp_path / "out"
    done = _dem(["run", str(case_dir), "--out", str(out), "--threads", "1"], script=script,
                preexec_fn=set_limit)  # fmt: skip
    assert done.returncode == 1, done.stderr[-3000:]
    lines = _error_lines(done.stderr)
    assert len(lines) == 1 and "File too large" in lines[0] and str(out / "results.h5") in lines[0]
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr
    assert not list(out.rglob("*.tmp*")) and not (out / LOCK_FILE).exists()
    r = read_results(out / "results.h5")  # every cycle and frame written before
    assert 5 <= len(r["cycles"]["mean_velocity"]) < 60 and not r["complete"]


def test_the_room_check_names_a_file_size_limit(tmp_path, monkeypatch):
    import errno

    from dem.io import hdf5, hdf5_guard

    monkeypatch.setattr(hdf5_guard.resource, "getrlimit", lambda which: (1000, -1))
    with pytest.raises(OSError) as info:
        hdf5.ResultsWriter(tmp_path / "results.h5", case={}, versions={}, seed=1, timestep=1.0)
    assert info.value.errno == errno.EFBIG and "ulimit -f" in str(info.value)
    assert not (tmp_path / "results.h5").exists()


# --- item 4: a signal while the summary is written ----------------------------------------------

#: The point-mass model of the summary compiles for seconds on a fresh machine: the signal then.
SIGNAL_IN_SUMMARY = """
import os, signal
import dem.run.summary as summary
pointmass_reference = summary.pointmass_reference
def late(case):
    os.kill(os.getpid(), signal.{sig})
    return pointmass_reference(case)
summary.pointmass_reference = late
"""


@pytest.mark.integration
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_while_the_summary_is_written_still_gives_the_summary(tmp_path, sig):
    """It used to end the run with exit 143, no message, no summary, no checkpoint, and the
    folder refused both a rerun and --resume. Now the run finishes the summary, says so and
    releases its folder."""
    case_dir = _case_dir(tmp_path, cycles=2)
    out = tmp_path / "out"
    script = SIGNAL_IN_SUMMARY.format(sig=sig.name)
    done = _dem(["run", str(case_dir), "--out", str(out), "--threads", "1"], script=script)
    assert done.returncode == 0, done.stderr[-3000:]
    assert f"{sig.name} arrived after the last cycle" in done.stderr
    summary = _strict((out / "summary.json").read_text())
    assert len(summary["per_cycle_velocity"]) == 2
    assert read_results(out / "results.h5")["complete"]
    assert not (out / "checkpoint.npz").exists() and not (out / LOCK_FILE).exists()


@pytest.mark.integration
def test_a_stale_lock_of_a_dead_run_does_not_block_a_new_one(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / LOCK_FILE).write_text("dem run pid 999999999\n")  # its run was killed: no flock
    run_case(load_case(_case_dir(tmp_path, cycles=1)), out, progress=False, threads=1,
             frames=False)  # fmt: skip
    assert (out / "summary.json").is_file() and not (out / LOCK_FILE).exists()


# --- item 5: the resume hint and the frames setting ---------------------------------------------


@pytest.mark.integration
@pytest.mark.parametrize("options", [["--no-frames"], ["--lab-frame", "--cycles", "4"]])
def test_the_resume_hint_repeats_every_option_the_resume_needs(tmp_path, monkeypatch, capsys,
                                                               options):  # fmt: skip
    """The hint was ``dem run CASE --resume``: without --out it resumed another folder, without
    --cycles it was refused, without --no-frames it mixed frames into a run that had none."""
    case_dir = _case_dir(tmp_path)
    out = tmp_path / "elsewhere"
    sigterm_at_check(monkeypatch, 12)
    code = main(["run", str(case_dir), "--out", str(out), "--threads", "1", *options])
    monkeypatch.undo()
    err = capsys.readouterr().err
    assert code == 128 + signal.SIGTERM, err
    hint = [x for x in err.splitlines() if x.startswith("dem: continue with: ")]
    assert len(hint) == 1
    argv = shlex.split(hint[0].removeprefix("dem: continue with: "))
    assert argv[:2] == ["dem", "run"] and "--resume" in argv and str(out) in argv
    assert all(o in argv for o in options)
    assert main(argv[1:]) == 0
    err = capsys.readouterr().err
    # issue 48, item 8: a resume said "filling the trough"
    assert "filling the trough" not in err and "resumed from checkpoint.npz at cycle" in err
    summary = _strict((out / "summary.json").read_text())
    assert summary["cycles"] == (4 if "--cycles" in options else 6)


@pytest.mark.parametrize(
    "first, resumed",
    [(["--no-frames"], []), ([], ["--no-frames"]), ([], ["--lab-frame"])],
    ids=["frames-on-a-run-without", "no-frames-on-a-run-with", "lab-frame-on-trough-frame"],
)
@pytest.mark.integration
def test_a_resume_with_another_frames_setting_is_refused_and_changes_nothing(
    tmp_path, monkeypatch, capsys, first, resumed
):
    case_dir = _case_dir(tmp_path)
    out = tmp_path / "out"
    sigterm_at_check(monkeypatch, 12)
    assert main(["run", str(case_dir), "--out", str(out), "--threads", "1", *first]) == 143
    monkeypatch.undo()
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    code = main(["run", str(case_dir), "--out", str(out), "--threads", "1", "--resume", *resumed])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert str(out / "checkpoint.npz") in err and "frame" in err
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before


# --- item 6: strict JSON ------------------------------------------------------------------------


@pytest.mark.integration
def test_summary_of_a_one_cycle_run_is_strict_json(tmp_path):
    """One measured cycle has no standard error: summary.json said NaN, which is not JSON."""
    out = tmp_path / "out"
    summary = run_case(load_case(_case_dir(tmp_path, cycles=1)), out, progress=False, threads=1,
                       frames=False)  # fmt: skip
    written = _strict((out / "summary.json").read_text())
    assert written["mean_velocity_stderr"] is None and math.isnan(summary["mean_velocity_stderr"])
    assert written["mean_velocity"] == summary["mean_velocity"]


@pytest.mark.integration
def test_summary_json_is_written_whole_by_a_rename(tmp_path, monkeypatch):
    """summary.json goes to a temporary file renamed over it: never a part-written summary."""
    import dem.io.files as files

    renamed = []
    original = files.os.replace

    def record(src, dst):
        renamed.append(Path(dst).name)
        return original(src, dst)

    monkeypatch.setattr(files.os, "replace", record)
    run_case(load_case(_case_dir(tmp_path, cycles=1)), tmp_path / "out", progress=False,
             threads=1, frames=False)  # fmt: skip
    assert "summary.json" in renamed
