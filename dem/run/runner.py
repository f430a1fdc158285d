"""``dem run``: a case from fill to summary, with frames, results, checkpoints and resume.

What one run does, in order:

1. refuse an output folder that holds an earlier run (unless ``overwrite`` or ``resume``);
2. fill and settle (:class:`dem.engine.simulation.Simulation`), then switch the drive on at phase 0;
3. for each cycle (``settle_cycles`` unmeasured, or with "auto" until the per-cycle velocity's
   transient has ended, :func:`dem.physics.measure.steady`; then ``cycles`` measured), in
   ``frames_per_cycle`` chunks: advance, write a VTK frame and a results.h5 frame; at the end of
   the cycle append its statistics to results.h5;
4. every ``DEM_CHECKPOINT_EVERY`` cycles, and when SIGINT or SIGTERM arrives (checked between
   chunks), write ``checkpoint.npz`` (state, pair history, loop counters, writer positions);
   a signal then ends the run with :class:`RunInterrupted`;
5. write ``summary.json`` (DESIGN.md section 6; strict JSON, written whole by a rename) and
   mark results.h5 complete. A signal after the last cycle is recorded until then: the run
   finishes its summary and says so.

The output folder holds only what dem made: a link under a name dem writes (``frames``,
``results.h5``, the lock ``.dem-run.lock``) is refused before anything is written, so nothing
is written, truncated or deleted through it.

``resume=True`` reloads the checkpoint, trims results.h5 and the VTK collection back to what
the checkpoint had seen, and continues: the result is bit-identical to an uninterrupted run,
because the whole kernel state (contact history and stored forces included) is restored and
the chunk boundaries are the same.
"""

from __future__ import annotations

import json
import math
import os
import re
import signal
import stat
import sys
import time
import warnings
from pathlib import Path

import numba
import numpy as np

from dem import config
from dem.engine import setup
from dem.engine.simulation import Simulation
from dem.engine.threads import ThreadGuard, starting_threads
from dem.errors import InputError, SimulationError
from dem.io import checkpoint as checkpoint_io
from dem.io.files import json_text, replace_text
from dem.io.hdf5 import ResultsWriter, package_versions
from dem.io.tables import CYCLES_CSV, sidecar_path, write_cycles_csv
from dem.io.vtk import FRAMES_DIR, PVD_NAME, TROUGH_FILE, VTKSeriesWriter
from dem.physics import measure
from dem.provenance import record
from dem.run import plan, stiffness
from dem.scene.resolved import resolve

CHECKPOINT = "checkpoint.npz"
SUMMARY = "summary.json"
RESULTS = "results.h5"
#: Files and folders a run writes; only these are removed by ``overwrite``.
RUN_OUTPUTS = (SUMMARY, RESULTS, CHECKPOINT, PVD_NAME, FRAMES_DIR, CYCLES_CSV,
               str(sidecar_path(Path(CYCLES_CSV))))  # fmt: skip


class RunInterrupted(Exception):
    """SIGINT/SIGTERM arrived; a checkpoint was written. ``signum`` says which."""

    def __init__(self, signum: int, checkpoint: Path | None, cycle: int, phase: str = ""):
        self.signum = signum
        self.checkpoint = checkpoint
        self.cycle = cycle
        name = signal.Signals(signum).name
        if checkpoint is None:
            super().__init__(
                f"{name} while {phase}, before the drive started: no checkpoint (nothing worth "
                "resuming: a new run fills again)"
            )
        else:
            super().__init__(f"{name} at cycle {cycle}; checkpoint written to {checkpoint}")


def _note(text: str) -> None:
    """One line on stderr that leaves a progress bar in place."""
    from tqdm import tqdm

    tqdm.write(f"dem: {text}", file=sys.stderr)


def _set_threads(threads: int | None) -> int:
    n = config.default_threads() if threads is None else int(threads)
    n = max(1, min(n, numba.config.NUMBA_NUM_THREADS))
    numba.set_num_threads(n)
    return n


def _pointmass_bounded(case) -> float | None:
    """The Coulomb-bounded point mass (the DEM's reference) on a line drive; None otherwise.

    It differs from the paper's model where Eq. 12 asks a landing for more tangential impulse
    than friction can give (:data:`dem.pointmass.model.IMPACT_LAWS`).
    """
    from dem import pointmass

    if case.drive.second_amplitude > 0.0:
        return None
    m = case.wall_material  # the point mass touches the floor only
    return pointmass.velocity(
        case.drive.throw_number, case.drive.angle, m.friction, case.trough.inclination,
        m.restitution_tangential, m.restitution_normal, impact="coulomb",
    ).velocity_norm  # fmt: skip


def _pointmass(case) -> tuple[float, str]:
    """The point mass's v / (velocity scale) on the case's drive, and the method that gave it.

    The paper's line drive: the event-driven model; two components: the point mass stepped in
    time on the same motion (:mod:`dem.pointmass.elliptic`).
    """
    from dem import pointmass

    m = case.wall_material  # the point mass touches the floor only
    if case.drive.second_amplitude > 0.0:
        from dem.pointmass import elliptic

        r = elliptic.velocity(
            case.drive.motion, m.friction, case.trough.inclination,
            m.restitution_tangential, m.restitution_normal,
        )  # fmt: skip
        return r.velocity_norm, "stepped (two-component drive)"
    return pointmass.velocity(
        throw_number=case.drive.throw_number,
        angle=case.drive.angle,
        friction=case.wall_material.friction,
        inclination=case.trough.inclination,
        eps_t=case.wall_material.restitution_tangential,
        eps_n=case.wall_material.restitution_normal,
    ).velocity_norm, "event-driven (the paper's model)"


def _feeder_summary(case, sim: Simulation, loop: dict) -> dict | None:
    """A finite feeder's discharge: its rate per measured cycle, steady value and balance."""
    f = sim.feeder
    if f is None:
        return None
    rates = np.array(loop.get("discharge_per_cycle", []), dtype=np.float64)
    hold = np.array(loop.get("hold_up_per_cycle", []), dtype=np.float64)
    mean = stderr = math.nan
    tau = 0.5
    if rates.size:
        mean = float(np.mean(rates))
        if rates.size > 1:
            stderr, tau = measure.correlated_stderr(rates)
    return {
        "length": f.discharge,
        "feed_rate": f.feed_rate,
        "feed_length": f.feed_length,
        "discharge_rate": mean,
        "discharge_rate_stderr": stderr,
        "discharge_autocorrelation_time": tau,
        "discharge_rate_per_cycle": [float(r) for r in rates],
        "mean_mass_in_trough": float(np.mean(hold)) if hold.size else sim.total_mass,
        "grains_inserted": f.inserted,
        "grains_in_trough": sim.n_grains,
        "grains_discharged": f.discharged,
        "mass_inserted": f.inserted_mass,
        "mass_discharged": f.discharged_mass,
        "feed_backlog": f.backlog,
        "domain_length": sim.trough.length,
    }


def _components(case) -> list[dict]:
    """The drive's components as the summary lists them (angles and phase in degrees)."""
    d = case.drive
    out = [{"amplitude": d.amplitude, "angle": d.angle, "phase": 0.0}]
    if d.second_amplitude > 0.0:
        out.append({"amplitude": d.second_amplitude, "angle": d.second_angle,
                    "phase": d.second_phase})  # fmt: skip
    return out


def _prepare_output(out_dir: Path, *, overwrite: bool, resume: bool) -> None:
    """Refuse to overwrite an earlier run silently; clear it only when asked to.

    A link under a name dem writes (a planted ``frames`` -> somewhere else) is refused in every
    mode: dem neither writes into nor deletes through a link it did not make.
    """
    _refuse_links(out_dir)
    earlier = [name for name in RUN_OUTPUTS if (out_dir / name).exists()]
    if resume:
        if not (out_dir / CHECKPOINT).exists():
            raise InputError(
                "--resume", str(out_dir), f"needs {CHECKPOINT} of an interrupted run in the folder"
            )
        return
    if earlier and not overwrite:
        raise InputError(
            "--out",
            str(out_dir),
            f"holds an earlier run ({', '.join(earlier)}): choose another --out, pass "
            "--overwrite to replace it, or --resume an interrupted run",
        )
    for name in earlier:  # all checked before anything is removed
        if (out_dir / name).is_dir() != (name == FRAMES_DIR):
            raise InputError(
                "--out", str(out_dir), f"a run folder ({name} here is not what dem writes "
                "under that name: move it away)",
            )  # fmt: skip
    for name in earlier:
        path = out_dir / name
        _remove_frames(path) if name == FRAMES_DIR else path.unlink()
    out_dir.mkdir(parents=True, exist_ok=True)


def _refuse_links(out_dir: Path) -> None:
    """Refuse a symbolic link at any name dem writes in ``out_dir`` (checked before any change)."""
    for name in RUN_OUTPUTS:
        path = out_dir / name
        if path.is_symlink():
            raise InputError(
                "--out", str(path), "a file or folder of dem's own, not a link (dem never writes "
                "or deletes through a link it did not make): remove the link or choose another "
                "--out",
            )  # fmt: skip


#: The files dem writes into ``frames/`` (:mod:`dem.io.vtk`); nothing else there is removed.
FRAME_FILE_RE = re.compile(r"(particles_\d{6}|grains_\d{6}|trough_\d{6}|trough)\.vtp")


def _remove_frames(frames: Path) -> None:
    """Remove the VTK files dem wrote into ``frames``, by name.

    Anything else stays (a link too, even under a frame's name), and so does the folder if
    anything is left in it.
    """
    for path in frames.iterdir():
        if not path.is_symlink() and path.is_file() and FRAME_FILE_RE.fullmatch(path.name):
            path.unlink()
    if not any(frames.iterdir()):
        frames.rmdir()


class _SignalFlag:
    """Record SIGINT/SIGTERM instead of dying, so the loop can checkpoint between chunks."""

    def __init__(self):
        self.signum: int | None = None
        self._old: dict[int, object] = {}

    def __enter__(self) -> _SignalFlag:
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                self._old[sig] = signal.signal(sig, self._handle)
            except ValueError:  # not the main thread: signals stay as they are
                pass
        return self

    def _handle(self, signum, frame) -> None:
        self.signum = signum

    def is_set(self) -> bool:
        """Whether a signal has arrived."""
        return self.signum is not None

    def __exit__(self, *exc) -> None:
        for sig, handler in self._old.items():
            signal.signal(sig, handler)


class _StopNow(_SignalFlag):
    """SIGINT/SIGTERM before the drive starts: stop at once, no checkpoint.

    While compiling, filling and settling a signal raises :class:`RunInterrupted` without a
    checkpoint; ``phase`` names what was going on. Python runs the handler between bytecodes,
    so a signal that arrives inside one compiled kernel call is honoured when the call returns
    (settling calls them in 5 ms chunks).
    """

    def __init__(self):
        super().__init__()
        self.phase = "compiling"

    def _handle(self, signum, frame) -> None:
        raise RunInterrupted(signum, None, 0, self.phase)


#: Lock file a run holds in its output folder while it writes there (``fcntl.flock``).
LOCK_FILE = ".dem-run.lock"


def _lock_output(out_dir: Path):
    """Hold an exclusive lock on ``out_dir``: a second run into the same folder is refused.

    Returns the open lock file (closing it releases the lock; the kernel releases it too if the
    process dies). The lock file is made afresh (``O_EXCL``) and written only then; one left by
    a run that died (its lock gone with it) is removed and made again, so it never blocks a new
    run. It is opened without following a link (``O_NOFOLLOW``): a link planted under its name
    is refused (exit 2) and its target is neither written nor truncated.
    """
    import fcntl

    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / LOCK_FILE
    cloexec = getattr(os, "O_CLOEXEC", 0)
    while True:
        created = True
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | cloexec, 0o644)
        except FileExistsError:
            created = False
            try:
                fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW | cloexec)
            except FileNotFoundError:  # the run before removed it between our two opens
                continue
            except OSError as err:  # ELOOP: a link; EISDIR: a folder
                raise _lock_refused(path, err) from None
        stream = os.fdopen(fd, "r+")  # noqa: SIM115 - held until the run ends
        if not stat.S_ISREG(os.fstat(fd).st_mode):  # a FIFO or a device under the lock's name
            stream.close()
            raise _lock_refused(path, None)
        try:
            fcntl.flock(stream, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = stream.read(200).strip() or "another process"
            stream.close()
            raise InputError(
                "--out", str(out_dir), f"a folder no other run is writing ({holder} is writing "
                "it now: wait for it, or choose another --out)",
            ) from None  # fmt: skip
        if _same_file(path, stream):
            if created:
                break
            os.unlink(path)  # a stale lock of a run that died: made again, never written into
        stream.close()
    stream.write(f"dem run pid {os.getpid()}\n")
    stream.flush()
    return stream


def _same_file(path: Path, stream) -> bool:
    """Whether ``path`` (not followed if a link) is the file ``stream`` has open."""
    try:
        return os.lstat(path).st_ino == os.fstat(stream.fileno()).st_ino
    except FileNotFoundError:
        return False


def _lock_refused(path: Path, err: OSError | None) -> InputError:
    what = "a link" if path.is_symlink() else "not a plain file"
    if err is not None and not path.is_symlink():
        what = err.strerror or what
    return InputError(
        "--out", str(path), f"dem's own lock file ({what} here: dem does not open a lock it did "
        "not make; remove it, or choose another --out)",
    )  # fmt: skip


def _ignore_file_size_signal():
    """Ignore SIGXFSZ (returns the handler it replaced; None where it cannot be set).

    Its default action kills the process with a core dump at the file size limit (``ulimit
    -f``); ignored, the write fails with EFBIG and the run ends in one line, exit 1, like a full
    disk. Python's own start-up ignores it already; a program embedding dem may not.
    """
    if not hasattr(signal, "SIGXFSZ"):
        return None
    try:
        return signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    except ValueError:  # not the main thread: signals stay as they are
        return None


def run_case(case, out_dir: Path, **kwargs) -> dict:
    """Run ``case`` into ``out_dir`` holding the folder's lock; see :func:`_run_case`.

    ``case`` is a :class:`dem.scene.resolved.Scene`, or a :class:`dem.scene.case.Case` resolved
    here once for
    the plan, the checks and the run.
    """
    out_dir = Path(out_dir)
    cycles = kwargs.get("cycles")
    if cycles is not None and int(cycles) < 1:  # checked before the folder is made
        raise InputError("--cycles", cycles, "a whole number >= 1")
    if kwargs.get("resume"):  # checked before the folder is touched
        _prepare_output(out_dir, overwrite=False, resume=True)
    n_threads = _set_threads(kwargs.get("threads"))
    scene = resolve(case)
    estimate = plan.plan(scene, threads=n_threads, cycles=kwargs.get("cycles"),
                         frames=kwargs.get("frames", True))  # fmt: skip
    _check_memory(scene.case, estimate)
    _check_duration(scene.case, estimate)
    made = not out_dir.exists()
    lock = _lock_output(out_dir)
    size_signal = _ignore_file_size_signal()
    try:
        return _run_case(scene, out_dir, **kwargs)
    finally:
        if size_signal is not None:
            signal.signal(signal.SIGXFSZ, size_signal)
        if _same_file(out_dir / LOCK_FILE, lock):  # still held: no one else has it
            (out_dir / LOCK_FILE).unlink()
        lock.close()
        if made and out_dir.is_dir() and not any(out_dir.iterdir()):
            out_dir.rmdir()  # a run refused before it wrote anything leaves no folder


def _run_case(
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
) -> dict:
    """Run ``case`` into ``out_dir``; returns the summary (also written to summary.json).

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

    Raises:
        RunInterrupted: SIGINT or SIGTERM arrived before the last cycle ended; a checkpoint was
            written first (after the last cycle the summary is finished instead).

    """
    scene = resolve(case)
    case = scene.case
    cycles = case.run.cycles if cycles is None else int(cycles)
    if cycles < 1:
        raise InputError("--cycles", cycles, "a whole number >= 1")
    out_dir = Path(out_dir)
    n_threads = _set_threads(threads)
    estimate = plan.plan(scene, threads=n_threads, cycles=cycles, frames=frames)
    _prepare_output(out_dir, overwrite=overwrite, resume=resume)
    if not resume:
        _warn_plan(estimate)
    settle = case.run.settle_cycles  # None: until the transient has ended ("auto")
    per_frame = case.output.frames_per_cycle if frames else 1
    checkpoint = out_dir / CHECKPOINT

    record = fingerprint(case)
    if resume:  # the checkpoint is checked against the case before the fill
        try:
            state, loop = checkpoint_io.read(checkpoint)
        except Exception as exc:  # a truncated or foreign file: zip, npy, JSON or key errors
            raise InputError(
                "--resume", str(checkpoint), f"a readable checkpoint of an interrupted run "
                f"({type(exc).__name__}: {exc}); start the run again without --resume",
            ) from None  # fmt: skip
        changed = fingerprint_changes(loop.get("case"), record)
        if changed:
            raise InputError(
                "--resume", str(checkpoint), "a checkpoint of the same case: it was made with "
                + "; ".join(changed) + ". Resume with the case it was made with, or start "
                "again with --overwrite",
            )  # fmt: skip
        loop.setdefault("cycles", loop["total_cycles"] - (settle or 0))  # older checkpoints
        loop.setdefault("settle_cycles", settle)
        _check_frames_setting(loop, checkpoint, frames=frames, lab_frame=lab_frame)
        if loop["cycles"] != cycles:
            raise InputError(
                "--cycles",
                cycles,
                f"the interrupted run has {loop['cycles']}: resume with the same",
            )
    with _StopNow() as stop:
        t0 = time.perf_counter()
        _compile_first(case, progress)
        compile_wall = time.perf_counter() - t0
        stop.phase = "filling"
        if progress:
            print(f"dem: filling the trough with {case.particles.count} grains", file=sys.stderr,
                  flush=True)  # fmt: skip
        t0 = time.perf_counter()
        sim = setup.from_case(scene)
        fill_wall = time.perf_counter() - t0
    if config.DEM_THREAD_GUARD and n_threads > 1:
        sim.guard = ThreadGuard(n_threads, start=starting_threads(n_threads),
                                note=_note if progress else None)  # fmt: skip
    if resume:
        try:
            checkpoint_io.load_state(sim, state)
            sim.restore_overlap(loop.get("max_overlap"))  # the running maximum so far
        except SimulationError as exc:
            raise InputError(
                "--resume", str(checkpoint), f"a checkpoint of this case: {exc}"
            ) from None
        if sim.feeder is not None:
            sim.feeder.restore(loop["feeder"])
    else:
        t0 = time.perf_counter()
        with _StopNow() as stop:
            stop.phase = "settling"
            if progress:
                print("dem: settling the fill (drive off, until at rest)", file=sys.stderr,
                      flush=True)  # fmt: skip
            settle_time = sim.settle(progress=_fill_bar(case) if progress else None)
            sim.start_drive()
        sim.stats[:] = 0.0
        loop = {
            "case": record,
            "discharged_mark": 0.0,
            "cycle": 0,
            "chunk": 0,
            "total_cycles": None if settle is None else settle + cycles,
            "settle_cycles": settle,
            "cycles": cycles,
            "settle_series": [],
            "steps": 0,
            "wall_time_s": 0.0,
            "settle_time_s": settle_time,
            "settle_wall_time_s": time.perf_counter() - t0,
            "compile_wall_time_s": compile_wall,
            "fill_wall_time_s": fill_wall,
            "frames_wall_time_s": 0.0,
            "per_cycle": [],
            "vtk_entries": [],
            "h5_cycles": 0,
            "h5_frames": 0,
            "frames": bool(frames),
            "lab_frame": bool(lab_frame),
        }
    vtk = results = None
    if frames:
        vtk = VTKSeriesWriter(
            out_dir, sim.trough.extent, case.trough.width, case.trough.inclination,
            entries=[tuple(e) for e in loop["vtk_entries"]], lab_frame=lab_frame, mesh=sim.mesh,
            period=sim.trough.length, back_wall=sim.trough.finite,
        )  # fmt: skip
    results = ResultsWriter(
        out_dir / RESULTS,
        case=case.as_dict(),
        versions=package_versions(),
        seed=case.run.seed,
        timestep=sim.dt,
        resume_at=(loop["h5_cycles"], loop["h5_frames"]) if resume else None,
        ragged=sim.feeder is not None,
    )
    loop.setdefault("frames_wall_time_s", 0.0)  # older checkpoints
    if frames and not resume:
        _write_frame(sim, vtk, results, loop)
        loop["vtk_entries"] = vtk.entries
        loop["h5_frames"] = 1

    period = sim.trough.period
    bar = _phase_bar(case, loop) if progress else None
    summary = None
    # SIGINT/SIGTERM are recorded, not fatal, until summary.json is on disk: the summary's
    # point-mass model compiles for seconds on a fresh machine, and a signal there used to end
    # the run with no summary, no checkpoint and no message. After the last cycle the summary
    # is finished (the run's result) and the signal reported.
    try:
        with _SignalFlag() as flag:
            while loop["settle_cycles"] is None or loop["cycle"] < loop["total_cycles"]:
                c = loop["cycle"]
                k = loop["chunk"]
                end = sim.drive_start_step + int(round((c + (k + 1) / per_frame) * period / sim.dt))
                n = end - sim.step_index
                t1 = time.perf_counter()
                # a signal is honoured within DEM_CHECK_INTERVAL steps or DEM_STOP_LATENCY_S,
                # mid-frame too (a feeder: within its exchange interval): the run stops after a
                # whole chunk, so a resumed feeder's exchanges fall on the same steps
                done = sim.run(n, stop=flag.is_set)
                loop["wall_time_s"] += time.perf_counter() - t1
                loop["steps"] += done
                if done < n:  # stopped mid-frame: resume computes the rest from step_index
                    _checkpoint(checkpoint, sim, loop)
                    raise RunInterrupted(flag.signum, checkpoint, loop["cycle"])
                if frames:
                    _write_frame(sim, vtk, results, loop)
                    loop["h5_frames"] += 1
                    loop["vtk_entries"] = vtk.entries
                loop["chunk"] = k + 1
                if loop["chunk"] == per_frame:
                    measuring = _measuring(loop)
                    _end_cycle(sim, case, results, loop)
                    if bar is not None:
                        bar.update(1)
                        if _measuring(loop) != measuring:  # the settling phase has ended
                            bar.close()
                            bar = _phase_bar(case, loop)
                    if loop["cycle"] % config.DEM_CHECKPOINT_EVERY == 0:
                        _checkpoint(checkpoint, sim, loop)
                unfinished = loop["settle_cycles"] is None or loop["cycle"] < loop["total_cycles"]
                if flag.signum is not None and unfinished:
                    _checkpoint(checkpoint, sim, loop)
                    raise RunInterrupted(flag.signum, checkpoint, loop["cycle"])
            if bar is not None:
                bar.close()
                bar = None
            summary = _finish(case, sim, loop, cycles, n_threads, estimate, out_dir, results, vtk,
                              progress)  # fmt: skip
            checkpoint.unlink(missing_ok=True)
            late = flag.signum
    finally:
        if bar is not None:
            bar.close()
        if vtk is not None and summary is None:  # stopped: the collection lists every frame
            try:
                vtk.close()
            except OSError:  # a full disk: the error that stopped the run is the one to report
                pass
    if late is not None and progress:
        print(f"dem: {signal.Signals(late).name} arrived after the last cycle: the run finished "
              f"its summary first ({out_dir / SUMMARY})", file=sys.stderr)  # fmt: skip
    return summary


def _finish(case, sim, loop, cycles, n_threads, estimate, out_dir, results, vtk, progress):
    """Write summary.json (strict JSON, whole or not at all), mark results.h5 complete.

    Returns the summary as a dict (an undefined value NaN, where the file has null).
    """
    summary = _summary(case, sim, loop, cycles, n_threads)
    summary["plan"] = estimate.as_dict()
    # the bed's stiffness against the bulk study's rule: how far this answer may be from the
    # rigid material's (validation/bulk-convergence)
    summary["stiffness"] = stiffness.assessment(resolve(case))
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
    results.close()
    if vtk is not None:
        vtk.close()
    for text in summary["warnings"]:
        warnings.warn(f"{case.name}: {text}", stacklevel=3)
    return summary


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


def _compile_first(case, progress: bool) -> None:
    """Compile the kernels on two grains of the case, saying so, when none are cached yet.

    The run itself then starts from the cache, so its trajectory is the same whether or not this
    process compiled (a warm-up on the run's own grains would shift it by the warm-up's steps).
    """
    from dataclasses import replace

    from dem import kernels

    if kernels.compiled(clumps=case.particles.shape != "sphere", mesh=case.trough.mesh is not None):
        return
    from dem.run.progress import Status

    kind = "clump" if case.particles.shape != "sphere" else "sphere"
    kind += " mesh-trough" if case.trough.mesh is not None else ""
    small = replace(case, particles=replace(case.particles, count=min(2, case.particles.count)))
    message = (f"compiling the {kind} step kernels for this machine, once (numba, no cache yet; "
               "about a minute, later runs start at once)")  # fmt: skip
    with Status(message, "compiled", enabled=progress):
        setup.from_case(small, check_limit=False).run(2)


def _check_memory(case, estimate) -> None:
    """Refuse a case whose state (the estimate ``dem plan`` prints) exceeds this machine."""
    total = plan.physical_memory()
    if total and estimate.memory_bytes > total:
        raise InputError(
            "particles.count", case.particles.count, f"a count whose state fits this machine: "
            f"it needs {plan.format_size(estimate.memory_bytes)}, the machine has "
            f"{plan.format_size(total)} (dem plan {case.name} says more)",
            source=str(case.source),
        )  # fmt: skip


#: A run the plan estimates at more than this many seconds is refused at load (a year).
MAX_RUN_SECONDS = 365.25 * 86400.0


def _check_duration(case, estimate) -> None:
    """Refuse a case whose steps (the estimate ``dem plan`` prints) would take over a year."""
    if estimate.wall_time_s > MAX_RUN_SECONDS:
        raise InputError(
            "run.cycles", estimate.cycles,
            f"a run this machine finishes within a year: {estimate.steps:.3g} steps "
            f"(dt = {estimate.timestep:.3g} s, {estimate.steps_per_cycle:.3g} a cycle) of "
            f"{estimate.spheres} spheres would take about "
            f"{plan.format_duration(estimate.wall_time_s)}; fewer cycles or grains, or a longer "
            f"step (a softer contact, larger grains) shorten it (dem plan {case.name} says more)",
            source=str(case.source),
        )  # fmt: skip


def _warn_plan(estimate) -> None:
    """Warn once, before the fill, when the case asks for far more (or less) than it needs."""
    items = estimate.warnings()
    if items:
        text = "; ".join(f"{a.key}: {a.text}" for a in items)
        warnings.warn(
            f"{estimate.case}: {text} (dem plan {estimate.case} says more)",
            plan.PlanWarning,
            stacklevel=3,
        )


#: Case keys a resumed run may change: how long it runs and where its name comes from.
RESUMABLE_KEYS = ("name", "directory", "source", "run.cycles")


def fingerprint(case) -> dict:
    """The resolved case as flat JSON data, {"table.key": value}: what a checkpoint records."""
    flat: dict = {}

    def walk(prefix: str, value) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                walk(f"{prefix}.{k}" if prefix else k, v)
        else:
            flat[prefix] = value

    walk("", json.loads(json.dumps(case.as_dict(), default=str)))
    for key in RESUMABLE_KEYS:
        flat.pop(key, None)
    return flat


def fingerprint_changes(before: dict | None, now: dict) -> list[str]:
    """Each key that differs, as "key = old (now new)"; none for a checkpoint without a record."""
    if before is None:
        return []
    keys = sorted(set(before) | set(now))
    return [
        f"{k} = {before.get(k)!r} (now {now.get(k)!r})" for k in keys if before.get(k) != now.get(k)
    ]


def _checkpoint(path: Path, sim: Simulation, loop: dict) -> None:
    """Write a checkpoint; a finite feeder's counters and generator travel in the loop JSON."""
    if sim.feeder is not None:
        loop["feeder"] = sim.feeder.state()
    loop["max_overlap"] = sim.overlap_summary()
    checkpoint_io.write(path, sim, loop)


def _write_frame(sim: Simulation, vtk: VTKSeriesWriter, results: ResultsWriter, loop) -> None:
    t0 = time.perf_counter()
    _write_frame_files(sim, vtk, results)
    loop["frames_wall_time_s"] += time.perf_counter() - t0


def _write_frame_files(sim: Simulation, vtk: VTKSeriesWriter, results: ResultsWriter) -> None:
    s = sim.spheres
    orientation = sim.bodies.q if sim.bodies is not None else None
    counts = sim.contact_counts()
    t = sim.drive_time
    shift = sim.trough.displacement(t) if sim.drive_on else np.zeros(3)
    lab_v = sim.trough.velocity(t) if sim.drive_on else np.zeros(3)
    grain_id = sim.grain_id[s.body]
    vtk.write_frame(
        t, s.x, s.radius, s.v, grain_id, s.body, counts, orientation,
        drive_displacement=shift, drive_velocity=lab_v, bodies=sim.bodies,
    )  # fmt: skip
    balance = None
    if sim.feeder is not None:
        f = sim.feeder
        balance = {
            "grains_inserted": np.int64(f.inserted),
            "grains_in_trough": np.int64(sim.n_grains),
            "grains_discharged": np.int64(f.discharged),
            "mass_inserted": np.float64(f.inserted_mass),
            "mass_in_trough": np.float64(sim.total_mass),
            "mass_discharged": np.float64(f.discharged_mass),
        }
    results.append_frame(
        t, s.x, s.v, radius=s.radius, grain_id=grain_id, contact_count=counts,
        orientation=orientation, grain_index=s.body, per_frame=balance,
    )  # fmt: skip


def _measuring(loop: dict) -> bool:
    """True once the cycles about to run are measured ones (settling is over)."""
    settle = loop["settle_cycles"]
    return settle is not None and loop["cycle"] >= settle


def _phase_bar(case, loop: dict):
    """A progress bar of the current phase, whose total never changes.

    Settling: its cycles, or with ``settle_cycles = "auto"`` the cap
    (``DEM_AUTO_SETTLE_MAX_CYCLES``), which the MSER test usually ends early; then the
    measured cycles.
    """
    from tqdm import tqdm

    settle = loop["settle_cycles"]
    if _measuring(loop):
        return tqdm(total=loop["cycles"], initial=loop["cycle"] - settle, unit="cycle",
                    desc=f"dem {case.name}: measuring")  # fmt: skip
    if settle is None:
        return tqdm(total=config.DEM_AUTO_SETTLE_MAX_CYCLES, initial=loop["cycle"], unit="cycle",
                    desc=f"dem {case.name}: settling (until steady, at most)")  # fmt: skip
    return tqdm(total=settle, initial=loop["cycle"], unit="cycle",
                desc=f"dem {case.name}: settling")  # fmt: skip


def _wall_summary(case) -> dict:
    """The grain-wall values in use, and which ``[wall]`` gave (the rest are the material's)."""
    w = case.wall_material
    return {"friction": w.friction, "restitution_normal": w.restitution_normal,
            "restitution_tangential": w.restitution_tangential,
            "rolling_friction": w.rolling_friction,
            "given": list(case.wall.given) if case.wall is not None else []}  # fmt: skip


def _fill_bar(case):
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


def _end_cycle(sim: Simulation, case, results: ResultsWriter, loop: dict) -> None:
    """Close a cycle: its mass-weighted mean x-velocity from the step loop's momentum sums.

    With ``run.settle_cycles = "auto"`` a settling cycle also tests the settling velocities so
    far for the end of the transient (:func:`dem.physics.measure.steady`); the first cycle after it
    is
    measured. At ``DEM_AUTO_SETTLE_MAX_CYCLES`` the run measures anyway and says so.
    """
    velocity = sim.cycle_velocity()
    settle = loop["settle_cycles"]
    measured = settle is not None and loop["cycle"] >= settle
    if measured:
        loop["per_cycle"].append(velocity)
    elif settle is None:
        series = loop["settle_series"]
        series.append(velocity)
        scale = case.drive.velocity_scale
        done = (
            measure.steady(
                series, config.DEM_AUTO_SETTLE_MIN_CYCLES, config.DEM_AUTO_SETTLE_TOLERANCE * scale
            )
            and len(series) >= case.drive.ramp_cycles
        )  # the start-up ramp is no steady state
        if done or len(series) >= config.DEM_AUTO_SETTLE_MAX_CYCLES:
            loop["settle_cycles"] = loop["cycle"] + 1
            loop["total_cycles"] = loop["settle_cycles"] + loop["cycles"]
            loop["settle_detected"] = bool(done)
            if not done:
                warnings.warn(
                    f"{case.name}: the per-cycle velocity still drifts after "
                    f"{len(series)} settling cycles (DEM_AUTO_SETTLE_MAX_CYCLES); measuring anyway",
                    stacklevel=2,
                )
    feeder = {}
    if sim.feeder is not None:
        f = sim.feeder
        mass = f.discharged_mass - loop.get("discharged_mark", 0.0)
        loop["discharged_mark"] = f.discharged_mass
        feeder = {
            "discharged_mass": mass,
            "discharge_rate": mass / sim.trough.period,
            "mass_in_trough": sim.total_mass,
            "grains_in_trough": sim.n_grains,
            "grains_inserted": f.inserted,
            "grains_discharged": f.discharged,
            "feed_backlog": f.backlog,
        }
        if measured:
            loop.setdefault("discharge_per_cycle", []).append(mass / sim.trough.period)
            loop.setdefault("hold_up_per_cycle", []).append(sim.total_mass)
    results.append_cycle(
        cycle=loop["cycle"],
        time=sim.drive_time,
        mean_velocity=velocity,
        kinetic_energy=sim.kinetic_energy(),
        contacts=int(sim.contact_counts().sum()),
        measured=int(measured),
        **feeder,
    )
    loop["h5_cycles"] += 1
    sim.stats[:] = 0.0
    loop["cycle"] += 1
    loop["chunk"] = 0


def _summary(case, sim: Simulation, loop: dict, cycles: int, n_threads: int) -> dict:
    per_cycle = np.array(loop["per_cycle"])
    stat = measure.conveying_velocity(per_cycle, scale=case.drive.velocity_scale)
    d = case.drive
    pm_norm, pm_method = _pointmass(case)
    total_mass = sim.total_mass
    flow = measure.mass_flow_rate(total_mass, stat.mean, case.trough.length)
    feeder = _feeder_summary(case, sim, loop)
    if feeder is not None:  # the mass changed: the mean mass in the trough over the cycles
        flow = measure.mass_flow_rate(feeder["mean_mass_in_trough"], stat.mean, case.trough.length)
    wall = loop["wall_time_s"]
    provenance = record()  # versions, commit, date, host and load (the load bears on wall_time_s)
    return {
        "case": case.name,
        "overrides": dict(case.overrides),
        "mean_velocity": stat.mean,
        "mean_velocity_stderr": stat.stderr,
        "mean_velocity_norm": stat.norm,
        "mean_velocity_norm_stderr": stat.norm_stderr,
        "cycle_autocorrelation_time": stat.autocorrelation_time,
        "mean_velocity_stderr_independent": stat.stderr_independent,
        "replicas": 1,
        "error_bar": "within this run (autocorrelated per-cycle means): it excludes the "
        "fill-to-fill spread; pool fills with run.replicas",
        "mass_flow_rate": flow,
        "mass_flow_rate_per_width": flow / case.trough.width,
        "amplitude": case.drive.amplitude,
        "throw_number": d.effective_throw_number(case.trough.inclination),
        "velocity_scale": d.velocity_scale,
        "drive_components": _components(case),
        "ramp_cycles": d.ramp_cycles,
        "frequency": case.drive.frequency,
        "angle": case.drive.angle,
        "inclination": case.trough.inclination,
        "friction": case.material.friction,
        "wall": _wall_summary(case),
        "contact_model": case.contact.model,
        **sim.law.tangential_coefficients(),
        "grains": sim.n_grains,
        "spheres": sim.spheres.n,
        "total_mass": total_mass,
        "timestep": sim.dt,
        "timestep_limit": sim.timestep_limit,
        "steps": loop["steps"],
        "settle_cycles": loop["settle_cycles"],
        "settle_cycles_auto": case.run.settle_cycles is None,
        "settle_transient_ended": loop.get("settle_detected"),
        "cycles": cycles,
        "per_cycle_velocity": [float(u) for u in per_cycle],
        "settle_time_s": loop["settle_time_s"],
        "settle_wall_time_s": loop["settle_wall_time_s"],
        # compile and fill of the process that filled the trough; frames of every process
        "compile_wall_time_s": loop.get("compile_wall_time_s"),
        "fill_wall_time_s": loop.get("fill_wall_time_s"),
        "frames_wall_time_s": loop.get("frames_wall_time_s"),
        "frames_written": loop["h5_frames"] if loop.get("frames") else 0,
        "wall_time_s": wall,
        "particle_steps_per_s": sim.spheres.n * loop["steps"] / wall if wall > 0 else None,
        "neighbour_builds": sim.pairs.builds,
        "threads": n_threads,
        "seed": case.run.seed,
        "feeder": feeder,
        "pointmass_velocity_norm": pm_norm,
        "pointmass_method": pm_method,
        "pointmass_bounded_velocity_norm": _pointmass_bounded(case),
        "dem_version": provenance["versions"]["dem"],
        "git_commit": provenance["git_commit"],
        "provenance": provenance,
    }
