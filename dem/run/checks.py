"""The checks at a run's door: what is refused before the folder is touched or the trough filled.

A run is refused when the state it needs exceeds the machine's memory, when the plan puts it
beyond a year (:func:`check_memory`, :func:`check_duration`; both read the one
:class:`dem.run.plan.Plan` the run computes), and on ``--resume`` when the checkpoint is not
one of this case with the same cycles and frames settings (:func:`read_checkpoint`). A plan
that asks far more or less than the case needs is a warning (:func:`warn_plan`).
:func:`compile_first` compiles the step kernels on a copy of two grains when numba's cache
lacks them, so the run's own trajectory does not depend on whether this process compiled.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from dem.engine import setup
from dem.errors import InputError
from dem.io import checkpoint as checkpoint_io
from dem.io.vtk import TROUGH_FILE
from dem.run import cost, plan
from dem.run.record import Progress
from dem.run.summary import fingerprint_changes


def read_checkpoint(
    path: Path, record: dict, *, settle: int | None, cycles: int, frames: bool, lab_frame: bool
) -> tuple[dict[str, np.ndarray], Progress]:
    """The state and the progress record of the checkpoint to resume, checked against the case.

    ``record``: the case's :func:`dem.run.summary.fingerprint`; ``settle``: its
    ``run.settle_cycles``; ``cycles``, ``frames``, ``lab_frame``: the run's settings, which
    must be those of the interrupted run. Read before the fill, so a refusal costs nothing.

    Raises:
        InputError: naming ``--resume`` (an unreadable file, another case, another frames
            setting) or ``--cycles``.

    """
    try:
        state, loop = checkpoint_io.read(path)
    except Exception as exc:  # a truncated or foreign file: zip, npy, JSON or key errors
        raise InputError(
            "--resume", str(path), f"a readable checkpoint of an interrupted run "
            f"({type(exc).__name__}: {exc}); start the run again without --resume",
        ) from None  # fmt: skip
    changed = fingerprint_changes(loop.get("case"), record)
    if changed:
        raise InputError(
            "--resume", str(path), "a checkpoint of the same case: it was made with "
            + "; ".join(changed) + ". Resume with the case it was made with, or start "
            "again with --overwrite",
        )  # fmt: skip
    if "cycles" not in loop:  # older checkpoints (setdefault would evaluate this every time,
        loop["cycles"] = loop["total_cycles"] - (settle or 0)  # and fail on an "auto" settle)
    loop.setdefault("settle_cycles", settle)
    _check_frames_setting(loop, path, frames=frames, lab_frame=lab_frame)
    asked = loop["cycles"] - loop.get("extended_cycles", 0)  # less what steadiness added
    if asked != cycles:
        raise InputError(
            "--cycles",
            cycles,
            f"the interrupted run has {asked}: resume with the same",
        )
    return state, Progress.from_checkpoint(loop)


def _check_frames_setting(loop: dict, checkpoint: Path, *, frames: bool, lab_frame: bool) -> None:
    """Refuse to resume with frames when the run wrote none, or the reverse (or another frame).

    A checkpoint records both settings; an older one tells by its frames (a run with frames
    writes frame 0 before the first cycle; in the lab frame every frame has its trough file).
    """
    entries = loop.get("vtk_entries") or []
    was_frames = loop.get("frames", loop.get("h5_frames", 0) > 0)
    was_lab = loop.get("lab_frame", bool(entries) and entries[0][2] != TROUGH_FILE)
    if was_frames != frames:
        said = "wrote no frames (--no-frames)" if not was_frames else "wrote frames"
        fix = "with --no-frames" if not was_frames else "without --no-frames"
        raise InputError(
            "--resume", str(checkpoint), f"a checkpoint of a run with the same frames setting: "
            f"the interrupted run {said}; resume it {fix}, or start again with --overwrite",
        )  # fmt: skip
    if frames and was_lab != lab_frame:
        said = "the lab frame (--lab-frame)" if was_lab else "the trough frame"
        fix = "with --lab-frame" if was_lab else "without --lab-frame"
        raise InputError(
            "--resume", str(checkpoint), f"a checkpoint of a run with the same frames: the "
            f"interrupted run wrote them in {said}; resume it {fix}, or start again with "
            "--overwrite",
        )  # fmt: skip


def compile_first(case, progress: bool) -> None:
    """Compile the kernels on two grains of the case, saying so, when none are cached yet.

    The run itself then starts from the cache, so its trajectory is the same whether or not this
    process compiled (a warm-up on the run's own grains would shift it by the warm-up's steps).
    """
    from dataclasses import replace

    from dem import kernels

    if kernels.compiled(clumps=case.particles.clumps, mesh=case.trough.mesh is not None):
        return
    from dem.run.progress import Status

    kind = case.particles.kind
    kind += " mesh-trough" if case.trough.mesh is not None else ""
    small = replace(case, particles=replace(case.particles, count=min(2, case.particles.count)))
    message = (f"compiling the {kind} step kernels for this machine, once (numba, no cache yet; "
               "about a minute, later runs start at once)")  # fmt: skip
    with Status(message, "compiled", enabled=progress):
        setup.from_case(small, check_limit=False).run(2)


def check_memory(case, estimate) -> None:
    """Refuse a case whose state (the estimate ``dem plan`` prints) exceeds this machine."""
    total = cost.physical_memory()
    if total and estimate.memory_bytes > total:
        raise InputError(
            "particles.count", case.particles.count, f"a count whose state fits this machine: "
            f"it needs {cost.format_size(estimate.memory_bytes)}, the machine has "
            f"{cost.format_size(total)} (dem plan {case.name} says more)",
            source=str(case.source),
        )  # fmt: skip


#: A run the plan estimates at more than this many seconds is refused at load (a year).
MAX_RUN_SECONDS = 365.25 * 86400.0


def check_duration(case, estimate) -> None:
    """Refuse a case whose steps (the estimate ``dem plan`` prints) would take over a year."""
    if estimate.wall_time_s > MAX_RUN_SECONDS:
        raise InputError(
            "run.cycles", estimate.cycles,
            f"a run this machine finishes within a year: {estimate.steps:.3g} steps "
            f"(dt = {estimate.timestep:.3g} s, {estimate.steps_per_cycle:.3g} a cycle) of "
            f"{estimate.spheres} spheres would take about "
            f"{cost.format_duration(estimate.wall_time_s)}; fewer cycles or grains, or a longer "
            f"step (a softer contact, larger grains) shorten it (dem plan {case.name} says more)",
            source=str(case.source),
        )  # fmt: skip


def warn_plan(estimate) -> None:
    """Warn once, before the fill, when the case asks for far more (or less) than it needs."""
    items = estimate.warnings()
    if items:
        text = "; ".join(f"{a.key}: {a.text}" for a in items)
        warnings.warn(
            f"{estimate.case}: {text} (dem plan {estimate.case} says more)",
            plan.PlanWarning,
            stacklevel=3,
        )
