"""The dem-and-reference pair runner of the LIGGGHTS studies: one configuration, both codes.

For one case, :func:`run_reference` writes its LIGGGHTS deck (``dem.io.liggghts.write_deck``
with ``sample_steps = 1``, so that ``vx_mean.txt`` holds the mean x-velocity of every step), runs
it on one rank in a fresh copy of the deck folder and bins the velocities into exactly the drive
cycles dem uses (:mod:`validation._lib.cycles`); :func:`run_dem` runs the same case through
``dem.run.runner.run_case`` without frames; :func:`run_pair` runs both, LIGGGHTS first, and
returns the pair. The studies turn the pair into their own result entries.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dem import provenance
from dem.io.liggghts import (
    DECK_NAME,
    LIGGGHTS_INSTALL,
    VX_FILE,
    find_liggghts,
    run_liggghts,
    write_deck,
)

from .cycles import cycle_edges, cycle_means, drive_steps

#: The deck's drive clock, ``variable tau equal (step-N)*dt``: N is the step the drive starts at.


class ReferenceRun(NamedTuple):
    """A LIGGGHTS run of a case's deck, binned into dem's drive cycles.

    Attributes:
        deck: The deck written (``<deck_dir>/in.dem``).
        work: The folder LIGGGHTS ran in (a copy of the deck folder).
        run: What ``dem.io.liggghts.run_liggghts`` returned (version, loop times, wall time).
        drive_start: The step at which the drive started.
        per_cycle: Mean x-velocity of each measured cycle, m/s.
        settle_cycle: Mean x-velocity of each settle cycle, m/s (nan for a cycle without
            samples unless ``strict_settle``).
        date: When the deck was written (UTC, ISO 8601).

    """

    deck: Path
    work: Path
    run: object
    drive_start: int
    per_cycle: list[float]
    settle_cycle: list[float]
    date: str


class DemRun(NamedTuple):
    """A run of ``dem.run.runner.run_case``: its summary, its folder, its wall time (s) and
    when it started (UTC, ISO 8601)."""

    summary: dict
    out: Path
    wall_s: float
    date: str


class Pair(NamedTuple):
    """One configuration in both codes: ``dem`` and ``reference`` (None where skipped; a
    reference run is a string, the reason, when ``liggghts`` is not on PATH)."""

    dem: DemRun | None
    reference: ReferenceRun | str | None


def fresh_copy(source: Path, work: Path) -> None:
    """A clean copy of a deck folder to run LIGGGHTS in (scratch/ is git-ignored)."""
    if work.exists():
        shutil.rmtree(work)
    shutil.copytree(source, work)


def drive_start_step(deck: Path) -> int:
    """The step at which the deck's drive starts (its ``tau`` variable); SystemExit if none."""
    from dem.io.liggghts.drive import drive_start_step as start_of

    found = start_of(Path(deck).read_text())
    if found is None:
        raise SystemExit(f"no 'variable tau equal (step-N)*dt' line in {deck}")
    return found


def liggghts_missing() -> str | None:
    """Why the LIGGGHTS half cannot run (``liggghts`` is not on PATH), or None if it can."""
    if find_liggghts() is None:
        return f"liggghts is not on PATH: LIGGGHTS half skipped ({LIGGGHTS_INSTALL})"
    return None


def run_reference(
    case,
    deck_dir: Path,
    work: Path,
    *,
    min_loops: int = 3,
    edit: Callable[[Path], None] | None = None,
    strict_settle: bool = True,
    fresh_deck: bool = False,
) -> ReferenceRun:
    """LIGGGHTS on the case's deck; per-cycle mean x-velocities in dem's drive cycles.

    Args:
        case: The case, with ``run.timestep``, ``run.settle_cycles`` and ``run.cycles`` set.
        deck_dir: Where the deck is written (kept beside the study).
        work: Where LIGGGHTS runs (a fresh copy of ``deck_dir``).
        min_loops: ``run_liggghts``'s check on the log's ``Loop time`` lines.
        edit: Called with the copied deck's path before the run (extra output, options).
        strict_settle: Settle cycles must have one sample per step, like measured ones.
        fresh_deck: Remove ``deck_dir`` first (no file of an earlier deck is left in it).

    The run must keep every member sphere (SystemExit otherwise): a grain lost through a wall
    would change the mean.
    """
    date = provenance.utc_now()
    s, c = case.run.settle_cycles, case.run.cycles
    edges = cycle_edges(case, s + c)
    if fresh_deck and deck_dir.exists():
        shutil.rmtree(deck_dir)
    deck = write_deck(
        case,
        deck_dir,
        timestep=case.run.timestep,
        steps=edges[-1] - edges[s],
        settle_steps=edges[s],
        sample_steps=1,
    )
    drive_start = drive_start_step(deck)
    fresh_copy(deck_dir, work)
    if edit is not None:
        edit(work / DECK_NAME)
    run = run_liggghts(work, DECK_NAME, min_loops=min_loops)
    members = 1 if case.particles.shape == "sphere" else case.particles.grain.count
    atoms = run.loop_times[-1].atoms
    if atoms != case.particles.count * members:
        raise SystemExit(f"LIGGGHTS kept {atoms} spheres, not {case.particles.count * members}")
    steps, vx = drive_steps(np.loadtxt(work / VX_FILE, comments="#"), drive_start)
    per_cycle = cycle_means(steps, vx, edges, range(s, s + c), source=VX_FILE)
    settle = cycle_means(steps, vx, edges, range(s), strict=strict_settle, source=VX_FILE)
    return ReferenceRun(deck, work, run, drive_start, per_cycle, settle, date)


def run_dem(case, out: Path, *, threads: int = 1, cycles: int | None = None) -> DemRun:
    """``run_case(case, out, cycles=cycles, threads=threads, progress=False, overwrite=True,
    frames=False)`` and its wall time (compile, fill and settling included)."""
    from dem.run.runner import run_case

    date = provenance.utc_now()
    t0 = time.perf_counter()
    summary = run_case(
        case, out, cycles=cycles, threads=threads, progress=False, overwrite=True, frames=False
    )
    return DemRun(summary, Path(out), time.perf_counter() - t0, date)


def run_pair(
    case,
    *,
    deck_dir: Path,
    work: Path,
    dem_out: Path,
    threads: int = 1,
    skip_reference: bool = False,
    skip_dem: bool = False,
    **reference,
) -> Pair:
    """One configuration in both codes: :func:`run_reference` (first), then :func:`run_dem`.

    ``reference`` goes to :func:`run_reference` (min_loops, edit, strict_settle, fresh_deck).
    A skipped half is None; the LIGGGHTS half is :func:`liggghts_missing`'s reason if
    ``liggghts`` is not on PATH (printed).
    """
    lig = None
    if not skip_reference:
        lig = liggghts_missing()
        if lig is not None:
            print(lig)
        else:
            lig = run_reference(case, deck_dir, work, **reference)
    dem = None
    if not skip_dem:
        dem = run_dem(case, dem_out, threads=threads, cycles=case.run.cycles)
    return Pair(dem, lig)
