"""Running LIGGGHTS on a deck: finding the executable, starting it and reading its timings.

The launcher the validation studies share (validation/liggghts-bulk, liggghts-screws and
performance/bench_bulk.py): :func:`run_liggghts` runs ``liggghts -in in.dem`` in a deck's
directory (:func:`dem.io.liggghts.deck.write_deck`), keeps its output beside the deck, and
returns the wall time and the ``Loop time`` of every stage (:mod:`dem.io.liggghts.readers`);
:func:`machine_info` records the machine a reference run was made on.
"""

from __future__ import annotations

import os
import platform
import shutil
import subprocess
import time
from pathlib import Path
from typing import NamedTuple

from dem.io.files import replace_text
from dem.io.liggghts.deck import DECK_NAME
from dem.io.liggghts.readers import LoopTime, liggghts_version, loop_times

#: How to install LIGGGHTS where it is missing (Debian/Ubuntu package, LIGGGHTS-PUBLIC 3.8).
LIGGGHTS_INSTALL = "apt-get install -y liggghts"
#: File inside the run directory that :func:`run_liggghts` writes LIGGGHTS's stdout and stderr to.
LIGGGHTS_STDOUT = "stdout.txt"
#: Characters of stdout and of stderr quoted when a run fails.
FAILURE_TAIL = 2000


class LiggghtsError(RuntimeError):
    """LIGGGHTS is not on PATH, or a run of it failed; the message says which, and how to fix."""


class LiggghtsRun(NamedTuple):
    """A finished LIGGGHTS run (:func:`run_liggghts`).

    Attributes:
        stdout: LIGGGHTS's standard output.
        wall_s: Wall time of the whole process (start-up, every ``run``, the output), s.
        loop_times: The ``Loop time`` lines, one per ``run`` command of the deck, in order; the
            last one of a deck from :func:`write_deck` times the measured driven steps alone.
        version: The version in the log banner, e.g. "LIGGGHTS-PUBLIC 3.8.0" (None if absent).

    """

    stdout: str
    wall_s: float
    loop_times: list[LoopTime]
    version: str | None


def find_liggghts() -> str | None:
    """Path of the ``liggghts`` executable on PATH, or None if there is none."""
    return shutil.which("liggghts")


def machine_info() -> dict:
    """Cores, CPU model and platform: the machine a reference run was made on (provenance)."""
    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cores": os.cpu_count(), "cpu": cpu, "platform": platform.platform()}


def run_liggghts(
    work_dir: str | os.PathLike,
    deck_name: str = DECK_NAME,
    *,
    log_name: str = LIGGGHTS_STDOUT,
    prefix: tuple[str, ...] | list[str] = (),
    min_loops: int = 1,
) -> LiggghtsRun:
    """Run ``liggghts -in deck_name`` in ``work_dir`` and wait for it.

    The deck's relative paths (``grain.multisphere``, ``vx_mean.txt``) are taken from and
    written to ``work_dir``; LIGGGHTS's stdout and stderr go to ``work_dir / log_name`` as well.

    Args:
        work_dir: The run directory (a copy of a deck directory from :func:`write_deck`).
        deck_name: The input deck inside it.
        log_name: File for LIGGGHTS's stdout followed by its stderr.
        prefix: Words before the executable, e.g. ``("mpirun", "-np", "2")``.
        min_loops: Fewer ``Loop time`` lines than this count as a failed run (a deck from
            :func:`write_deck` prints one per stage).

    Raises:
        LiggghtsError: ``liggghts`` is not on PATH (the message says how to install it), or it
            exited non-zero or printed too few ``Loop time`` lines (the message quotes the last
            :data:`FAILURE_TAIL` characters of its stdout and stderr).

    """
    exe = find_liggghts()
    if exe is None:
        raise LiggghtsError(f"liggghts is not on PATH ({LIGGGHTS_INSTALL})")
    work = Path(work_dir)
    command = [*prefix, exe, "-in", deck_name]
    t0 = time.perf_counter()
    # errors="replace": LIGGGHTS can print raw bytes (a clump template's name, a garbled error
    # line) that are not UTF-8; its message must still reach the user
    done = subprocess.run(command, cwd=work, capture_output=True, text=True, errors="replace")
    wall = time.perf_counter() - t0
    replace_text(work / log_name, done.stdout + done.stderr)
    loops = loop_times(done.stdout)
    if done.returncode != 0 or len(loops) < min_loops:
        raise LiggghtsError(
            f"LIGGGHTS failed ({' '.join(command)} in {work}: exit status {done.returncode}, "
            f"{len(loops)} 'Loop time' lines, {min_loops} expected); the end of its output:\n"
            f"{done.stdout[-FAILURE_TAIL:]}{done.stderr[-FAILURE_TAIL:]}"
        )
    return LiggghtsRun(done.stdout, wall, loops, liggghts_version(done.stdout))


#: The summary a run of an exported deck writes beside it (``dem export liggghts --run``).
SUMMARY_NAME = "summary.json"


def summarize_run(plan, deck_dir: Path, run: LiggghtsRun) -> dict:
    """``summary.json`` of a LIGGGHTS run of an exported deck, as ``dem run`` reports one.

    ``plan`` is the export's :class:`dem.io.liggghts.export.ExportPlan`; the deck wrote the mean
    x-velocity of every step (``sample_steps = 1``) from the drive's start (its ``tau``
    variable), cut here into dem's own cycles (:func:`dem.io.lammps.launcher.
    per_cycle_velocities`). A run that ended early raises :class:`LiggghtsError`, one line.
    """
    import numpy as np

    from dem.io.lammps.launcher import per_cycle_velocities, write_engine_summary
    from dem.io.liggghts.deck import VX_FILE
    from dem.io.liggghts.drive import drive_start_step

    case = plan.scene.case
    deck = (deck_dir / DECK_NAME).read_text(encoding="utf-8", errors="replace")
    start = drive_start_step(deck)
    if start is None:
        raise LiggghtsError(f"{deck_dir / DECK_NAME}: no drive (variable tau) in the deck")
    try:
        vx = np.loadtxt(deck_dir / VX_FILE, comments="#", ndmin=2)
    except (OSError, ValueError) as exc:
        raise LiggghtsError(f"{deck_dir / VX_FILE}: unreadable ({exc})") from None
    per_cycle = per_cycle_velocities(vx, plan.scene.trough.period, plan.timestep,
                                     plan.settle_cycles, case.run.cycles, start=start,
                                     error=LiggghtsError)  # fmt: skip
    return write_engine_summary(plan, deck_dir, per_cycle, engine="liggghts",
                                version=run.version,
                                measured=run.loop_times[-1] if run.loop_times else None,
                                wall=run.wall_s)  # fmt: skip
