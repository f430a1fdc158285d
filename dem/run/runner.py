"""``dem run``: a case from fill to summary, with frames, results, checkpoints and resume.

What one run does, in order:

1. at the door, once: resolve the case, refuse a ``run.device`` this machine or the GPU engine
   cannot do (:func:`dem.engine.device.check_device`), plan it (:func:`dem.run.plan.plan`) and
   refuse what the machine cannot hold or finish (:mod:`dem.run.checks`); then lock the output
   folder and refuse one that holds an earlier run, unless ``overwrite`` or ``resume``
   (:mod:`dem.run.output`);
2. fill and settle (:class:`dem.engine.simulation.Simulation`), then switch the drive on at phase 0;
3. for each cycle (``settle_cycles`` unmeasured, or with "auto" until the per-cycle velocity's
   transient has ended, :func:`dem.physics.measure.steady`; then ``cycles`` measured), in
   ``frames_per_cycle`` chunks: advance, then call the writers' ``frame``; at the end of the
   cycle close it (:func:`dem.run.record.close_cycle`) and call the writers' ``cycle``. The
   writers (:mod:`dem.run.writers`) are, in order: the VTK frames, results.h5, and
   ``checkpoint.npz`` every ``DEM_CHECKPOINT_EVERY`` cycles (state, pair history, the progress
   record with the writers' positions);
4. when SIGINT or SIGTERM arrives (checked between chunks, :mod:`dem.run.interrupts`), write
   the checkpoint and end the run with :class:`RunInterrupted`;
5. write ``summary.json`` (README, A DEM run, :mod:`dem.run.summary`; strict JSON, written
   whole by a rename) and close the writers (results.h5 marked complete, the checkpoint
   removed). A signal after the last cycle is recorded until then: the run finishes its
   summary and says so.

``resume=True`` reloads the checkpoint, trims results.h5 and the VTK collection back to what
the checkpoint had seen, and continues: the result is bit-identical to an uninterrupted run,
because the whole kernel state (contact history and stored forces included) is restored and
the chunk boundaries are the same.
"""

from __future__ import annotations

import signal
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numba

from dem import config
from dem.engine import setup
from dem.engine.device import check_device
from dem.engine.threads import ThreadGuard, busy_cores, starting_threads
from dem.errors import InputError, SimulationError
from dem.io import checkpoint as checkpoint_io
from dem.io.files import json_text, replace_text
from dem.io.hdf5 import check_resumable
from dem.io.tables import write_cycles_csv
from dem.physics import measure
from dem.physics.drive import cycle_edge
from dem.run import flight, plan, stiffness
from dem.run.checks import (
    check_duration,
    check_memory,
    compile_first,
    read_checkpoint,
    warn_plan,
)
from dem.run.interrupts import RunInterrupted, SignalFlag, StopNow, file_size_limit_as_error
from dem.run.output import CHECKPOINT, RESULTS, SUMMARY, locked, prepare_output
from dem.run.record import Progress, close_cycle
from dem.run.summary import fingerprint, summarize
from dem.run.writers import Checkpoints, Frame, HDF5Results, VTKFrames, Writer
from dem.scene.resolved import resolve


def run_case(
    case,
    out_dir: Path,
    *,
    cycles: int | None = None,
    threads: int | None = None,
    progress: bool = True,
    overwrite: bool = False,
    resume: bool = False,
    frames: bool = True,
    lab_frame: bool = False,
    warn: bool = True,
) -> dict:
    """Run ``case`` into ``out_dir``; returns the summary (also written to summary.json).

    The case is resolved and planned once, here; the checks read that plan, and the run holds
    the folder's lock from before it touches the folder until it ends.

    Args:
        case: A :class:`dem.scene.resolved.Scene`, or a :class:`dem.scene.case.Case` resolved here.
        out_dir: Output folder: summary.json, results.h5, particles.pvd + frames/.
        cycles: Measured cycles (default ``case.run.cycles``).
        threads: numba threads (default all cores or NUMBA_NUM_THREADS).
        progress: Show a progress bar (cycles done, ETA).
        overwrite: Replace an earlier run in ``out_dir`` (otherwise it is refused).
        resume: Continue the interrupted run whose checkpoint is in ``out_dir``.
        frames: Write VTK and HDF5 particle frames (``output.frames_per_cycle`` per cycle).
        lab_frame: Write the VTK frames in the lab frame: grains and trough displaced by the
            drive s(t) and velocities plus ds/dt, so ParaView shows the trough shaking.
            Otherwise (default) in the trough frame. results.h5 is always in the trough frame.
        warn: Warn about the plan's advice before the fill (replicas after the first do not:
            the advice is the same for every fill).

    Raises:
        RunInterrupted: SIGINT or SIGTERM arrived before the last cycle ended; a checkpoint was
            written first (after the last cycle the summary is finished instead).

    """
    out_dir = Path(out_dir)
    if cycles is not None and int(cycles) < 1:  # checked before the folder is made
        raise InputError("--cycles", cycles, "a whole number >= 1")
    if resume:  # checked before the folder is touched
        prepare_output(out_dir, overwrite=False, resume=True)
    n_threads = _set_threads(threads)
    scene = resolve(case)
    check_device(scene.case.run.device, scene)
    cycles = scene.case.run.cycles if cycles is None else int(cycles)
    if cycles < 1:
        raise InputError("--cycles", cycles, "a whole number >= 1")
    estimate = plan.plan(scene, threads=n_threads, cycles=cycles, frames=frames)
    check_memory(scene.case, estimate)
    check_duration(scene.case, estimate)
    with locked(out_dir), file_size_limit_as_error():
        return _run(scene, out_dir, estimate, n_threads, cycles=cycles, show=progress,
                    overwrite=overwrite, resume=resume, frames=frames,
                    lab_frame=lab_frame, warn=warn)  # fmt: skip


def _run(scene, out_dir: Path, estimate, n_threads: int, *, cycles: int, show: bool,
         overwrite: bool, resume: bool, frames: bool, lab_frame: bool,
         warn: bool = True) -> dict:  # fmt: skip
    """The run itself, in the locked folder (:func:`run_case` has checked its arguments)."""
    case = scene.case
    prepare_output(out_dir, overwrite=overwrite, resume=resume)
    if not resume and warn:
        warn_plan(estimate)
        if case.output.contacts and not frames:  # the frames carry the contacts
            warnings.warn(f"{case.name}: output.contacts = true writes nothing without frames "
                          "(--no-frames, or a sweep or atlas point): run with frames to get "
                          "them", stacklevel=3)  # fmt: skip
    settle = case.run.settle_cycles  # None: until the transient has ended ("auto")
    per_frame = case.output.frames_per_cycle if frames else 1
    checkpoint = out_dir / CHECKPOINT

    record = fingerprint(case)
    if resume:  # the checkpoint and results.h5 are checked against the case before the fill
        state, progress = read_checkpoint(checkpoint, record, settle=settle, cycles=cycles,
                                          frames=frames, lab_frame=lab_frame)  # fmt: skip
        check_resumable(out_dir / RESULTS, progress.h5_cycles, progress.h5_frames,
                        ragged=case.feeder is not None)  # fmt: skip
    with StopNow() as stop:
        t0 = time.perf_counter()
        compile_first(case, show)
        compile_wall = time.perf_counter() - t0
        stop.phase = "filling"
        if show and not resume:  # a resume says so once the checkpoint's state is in
            print(f"dem: filling the trough with {case.particles.count} grains", file=sys.stderr,
                  flush=True)  # fmt: skip
        t0 = time.perf_counter()
        sim = setup.from_case(scene)
        fill_wall = time.perf_counter() - t0
    if config.DEM_THREAD_GUARD and n_threads > 1:
        busy = busy_cores()
        sim.guard = ThreadGuard(
            n_threads, start=starting_threads(n_threads, busy=busy),
            note=_note if show else None, busy=busy,
        )  # fmt: skip
    if resume:
        try:
            checkpoint_io.load_state(sim, state)
            sim.restore_overlap(progress.max_overlap)  # the running maximum so far
        except SimulationError as exc:
            raise InputError(
                "--resume", str(checkpoint), f"a checkpoint of this case: {exc}"
            ) from None
        if sim.feeder is not None:
            sim.feeder.restore(progress.feeder)
        if show:
            print(f"dem: resumed from {checkpoint.name} at cycle {progress.cycle}",
                  file=sys.stderr, flush=True)  # fmt: skip
    else:
        t0 = time.perf_counter()
        with StopNow() as stop:
            stop.phase = "settling"
            if show:
                print("dem: settling the fill (drive off, until at rest)", file=sys.stderr,
                      flush=True)  # fmt: skip
            settle_time = sim.settle(progress=fill_bar(case) if show else None)
            sim.start_drive()
        sim.stats[:] = 0.0
        progress = Progress(
            case=record,
            total_cycles=None if settle is None else settle + cycles,
            settle_cycles=settle,
            cycles=cycles,
            settle_time_s=settle_time,
            settle_wall_time_s=time.perf_counter() - t0,
            compile_wall_time_s=compile_wall,
            fill_wall_time_s=fill_wall,
            frames=bool(frames),
            lab_frame=bool(lab_frame),
        )
        if sim.grain_type is not None:  # each type's velocity: from the drive's start on
            sim.type_mark = sim.spheres.x[:, 0].copy()
    # the writers, called in this order on each trigger; the checkpoint last, after the others
    # have recorded their positions in the progress record
    writers: list[Writer] = []
    if frames:
        writers.append(VTKFrames(out_dir, sim, case, progress, lab_frame=lab_frame))
    writers.append(HDF5Results(out_dir / RESULTS, sim, case, progress, resume=resume))
    checkpoints = Checkpoints(checkpoint, sim)
    writers.append(checkpoints)
    if frames and not resume:
        write_frame(writers, sim, progress)  # frame 0, before the first cycle

    period = sim.trough.period
    bar = phase_bar(case, progress) if show else None
    summary = None
    # SIGINT/SIGTERM are recorded, not fatal, until summary.json is on disk: the summary's
    # point-mass model compiles for seconds on a fresh machine, and a signal there used to end
    # the run with no summary, no checkpoint and no message. After the last cycle the summary
    # is finished (the run's result) and the signal reported.
    try:
        with SignalFlag() as flag:
            while not progress.finished:
                c = progress.cycle
                k = progress.chunk
                end = cycle_edge(sim.drive_start_step, c + (k + 1) / per_frame, period, sim.dt)
                n = end - sim.step_index
                t1 = time.perf_counter()
                # a signal is honoured within DEM_CHECK_INTERVAL steps or DEM_STOP_LATENCY_S,
                # mid-frame too (a feeder: within its exchange interval): the run stops after a
                # whole chunk, so a resumed feeder's exchanges fall on the same steps
                done = sim.run(n, stop=flag.is_set)
                progress.wall_time_s += time.perf_counter() - t1
                progress.steps += done
                if done < n:  # stopped mid-frame: resume computes the rest from step_index
                    checkpoints.save(progress)
                    assert flag.signum is not None  # the flag's signal stopped it
                    raise RunInterrupted(flag.signum, checkpoint, progress.cycle)
                if frames:
                    write_frame(writers, sim, progress)
                progress.chunk = k + 1
                if progress.chunk == per_frame:
                    measuring, asked = progress.measuring, progress.cycles
                    row = close_cycle(sim, case, progress)
                    for writer in writers:
                        writer.cycle(row, progress)
                    if progress.cycles != asked:
                        said_extended(case, progress, bar, show)
                    if bar is not None:
                        bar.update(1)
                        if progress.measuring != measuring:  # the settling phase has ended
                            bar.close()
                            bar = phase_bar(case, progress)
                if flag.signum is not None and not progress.finished:
                    checkpoints.save(progress)
                    raise RunInterrupted(flag.signum, checkpoint, progress.cycle)
            if bar is not None:
                bar.close()
                bar = None
            summary = finish(scene, sim, progress, cycles, n_threads, estimate, out_dir, writers)
            late = flag.signum
    finally:
        if bar is not None:
            bar.close()
        if summary is None:  # stopped: the VTK collection lists every frame
            for writer in writers:
                try:
                    writer.close(complete=False)
                except OSError:  # a full disk: the error that stopped the run is the one to report
                    pass
    if late is not None and show:
        print(f"dem: {signal.Signals(late).name} arrived after the last cycle: the run finished "
              f"its summary first ({out_dir / SUMMARY})", file=sys.stderr)  # fmt: skip
    return summary


def said_extended(case, progress: Progress, bar, show: bool) -> None:
    """Say that the steadiness test added measured cycles, and give the bar its new total.

    :func:`dem.run.record.extend_if_unsteady` added them; the line goes to stderr.
    """
    if bar is not None:
        bar.total = progress.cycles
        bar.refresh()
    if show:
        t = measure.trend(progress.per_cycle)
        _note(f"{case.name}: the measured velocity still drifts ({t.z:+.1f} standard errors of "
              f"trend over {len(progress.per_cycle)} cycles): measuring "
              f"{progress.cycles - len(progress.per_cycle)} cycles more")  # fmt: skip


def write_frame(writers: list[Writer], sim, progress: Progress) -> None:
    """Call every writer's ``frame``; their wall time counts in ``frames_wall_time_s``."""
    t0 = time.perf_counter()
    frame = Frame.of(sim)
    for writer in writers:
        writer.frame(frame, progress)
    progress.frames_wall_time_s += time.perf_counter() - t0


def finish(scene, sim, progress, cycles, n_threads, estimate, out_dir, writers,
            extra: dict | None = None) -> dict:  # fmt: skip
    """Write summary.json (strict JSON, whole or not at all), then close the writers.

    ``extra``: more fields of the summary. Returns the summary as a dict (an undefined value
    NaN, where the file has null).
    """
    case = scene.case
    summary = summarize(case, sim, progress, cycles, n_threads)
    summary.update(extra or {})
    # the grains in flight by phase, on cycles run after the measured ones and summarised (a
    # GPU batch's runs share one state: they are not stepped one by one)
    if "gpu_batch" in summary:
        summary["flight"] = flight.not_sampled(case, "a run of a GPU batch")
    else:
        summary["flight"] = flight.by_phase(sim, case)
    summary["plan"] = estimate.as_dict()
    # the bed's stiffness against the bulk study's rule: how far this answer may be from the
    # rigid material's (validation/bulk-convergence)
    summary["stiffness"] = stiffness.assessment(scene)
    # the deepest overlap at the checks; above the accuracy bound a warning, not a stop
    summary["max_overlap"] = sim.overlap_summary()
    summary["max_overlap_fraction"] = summary["max_overlap"]["fraction"]
    summary["warnings"] = sim.overlap_warnings()
    if sim.guard is not None:
        sim.guard.restore()
        summary["thread_guard"] = sim.guard.as_dict()
    write_cycles_csv(out_dir, summary)  # before summary.json: a summary means the table is there
    # strict JSON (an undefined value, a one-cycle run's stderr, is null, not NaN), written whole
    replace_text(out_dir / SUMMARY, json_text(summary) + "\n")
    for writer in writers:  # results.h5 marked complete, the checkpoint removed last
        writer.close(complete=True)
    for text in summary["warnings"]:
        warnings.warn(f"{case.name}: {text}", stacklevel=3)
    return summary


def _set_threads(threads: int | None) -> int:
    n = config.default_threads() if threads is None else int(threads)
    n = max(1, min(n, numba.config.NUMBA_NUM_THREADS))  # type: ignore[attr-defined]  # set at import
    numba.set_num_threads(n)
    return n


def _note(text: str) -> None:
    """One line on stderr that leaves a progress bar in place."""
    from tqdm import tqdm

    tqdm.write(f"dem: {text}", file=sys.stderr)


def phase_bar(case, progress: Progress):
    """A progress bar of the current phase, whose total never changes.

    Settling: its cycles, or with ``settle_cycles = "auto"`` the cap
    (``DEM_AUTO_SETTLE_MAX_CYCLES``), which the MSER test usually ends early; then the
    measured cycles.
    """
    from tqdm import tqdm

    settle = progress.settle_cycles
    if progress.measuring and settle is not None:  # measuring: settling has ended
        return tqdm(total=progress.cycles, initial=progress.cycle - settle, unit="cycle",
                    desc=f"dem {case.name}: measuring")  # fmt: skip
    if settle is None:
        return tqdm(total=config.DEM_AUTO_SETTLE_MAX_CYCLES, initial=progress.cycle,
                    unit="cycle",
                    desc=f"dem {case.name}: settling (until steady, at most)")  # fmt: skip
    return tqdm(total=settle, initial=progress.cycle, unit="cycle",
                desc=f"dem {case.name}: settling")  # fmt: skip


def fill_bar(case) -> Callable[[float, float, float, bool], None]:
    """The fill's settling (drive off): a callback for :meth:`Simulation.settle`.

    A bar of simulated time up to the cap, with the rms speed against the speed that counts as
    rest.
    """
    from tqdm import tqdm

    state: dict = {}

    def update(elapsed: float, rms: float, threshold: float, done: bool) -> None:
        if "bar" not in state:
            state["bar"] = tqdm(total=round(config.DEM_SETTLE_MAX_TIME * 1e3), unit="ms",
                                desc=f"dem {case.name}: resting the fill (drive off)")  # fmt: skip
        bar = state["bar"]
        bar.update(round(elapsed * 1e3) - bar.n)
        bar.set_postfix_str(f"rms speed {rms:.2g} m/s, at rest below {threshold:.2g}")
        if done:
            bar.close()

    return update
