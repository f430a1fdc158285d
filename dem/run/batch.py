"""Many runs as one GPU job: ``dem run --replicas N`` and ``dem sweep`` under ``--device cuda``.

A bed of a few thousand spheres keeps a GPU mostly idle (launches, not arithmetic, set its
pace); N runs of it stepped as one scene of N times the spheres
(:class:`dem.engine.gpu.replicas.GpuReplicas`) fill it. The runs are the replicas of a case
(seeds ``run.seed + k``) or the points of a sweep that differ only in their drive (angle,
amplitude or throw number), incline or seed: one section, one period, one law, one time step (the
smallest of their automatic ones). :func:`run_batch` leaves, for each run, what its own run would
have left: each is filled as alone; the batch settles them with the drive off until the last one
rests (each rests that long) and starts the drive in all at once; then every frame the batch
steps, each run's own :class:`~dem.engine.simulation.Simulation` takes its share of the state
(:meth:`GpuReplicas.scatter`), runs its own instability checks and goes through the single run's
writers, cycle records ("auto" settling decided per run) and summary (:mod:`dem.run.runner`). A
run whose measured cycles are done writes its summary and stops recording; the batch steps on
until the last one is done. :func:`dem.run.replicas.run_replicas` pools the replicas' summaries;
:func:`dem.studies.sweep.run_sweep` gathers the points'.

What differs from separate runs: the common settling time (the longest run's), the common time
step of a sweep, rebuilds of every pair list whenever one run needs one (this moves the last bits
of positions, not the physics), and the wall time: each summary's ``wall_time_s`` is its share of
the batch's step loop (the batch's time over the runs still recording), and ``gpu_batch`` gives
the batch's size, whole wall time and the step kernel that ran (with the engine's timings of the
plain and compact steps where it tried both: ``GpuEngine.step_scheme()``). An
interrupted batch writes every unfinished run's checkpoint; a rerun (``--resume``, or the sweep
again) continues them one by one, not as a batch. One run that blows up stops the batch: a sweep
then runs its points one by one.

Cost: the fill of each run (O(grains) each), then the batch's steps: one launch a step for all
runs, plus O(spheres + pairs log pairs) on the host at every frame for the scatter and the
checks.
"""

from __future__ import annotations

import sys
import time
from contextlib import ExitStack
from dataclasses import replace
from pathlib import Path

from dem.engine import setup
from dem.engine.gpu.replicas import GpuReplicas
from dem.physics.drive import cycle_edge
from dem.run import plan
from dem.run.checks import check_memory, compile_first, warn_plan
from dem.run.interrupts import RunInterrupted, SignalFlag, StopNow, file_size_limit_as_error
from dem.run.output import CHECKPOINT, RESULTS, locked, prepare_output
from dem.run.record import Progress, close_cycle
from dem.run.runner import fill_bar, finish, phase_bar, said_extended, write_frame
from dem.run.summary import fingerprint
from dem.run.writers import Checkpoints, HDF5Results, VTKFrames
from dem.scene.resolved import resolve


def batchable(case) -> str | None:
    """Why ``case``'s replicas cannot run as one GPU batch, or None when they can."""
    if case.run.device != "cuda":
        return "the case runs on the CPU"
    if case.feeder is not None:
        return "the GPU batches periodic sections only ([feeder])"
    return None


class _Replica:
    """One replica's scene, simulation, progress record and writers."""

    def __init__(self, k, scene, run_dir, cycles, lab_frame, keep_frames):
        self.k, self.scene, self.dir = k, scene, Path(run_dir)
        self.cycles, self.lab_frame, self.keep_frames = cycles, lab_frame, keep_frames
        self.sim = None
        self.progress = None
        self.writers = []
        self.checkpoints = None
        self.summary = None

    def open(self, settle_time, settle_wall, compile_wall, fill_wall) -> None:
        case = self.scene.case
        self.progress = Progress(
            case=fingerprint(case),
            total_cycles=None if case.run.settle_cycles is None
            else case.run.settle_cycles + self.cycles,
            settle_cycles=case.run.settle_cycles, cycles=self.cycles,
            settle_time_s=settle_time, settle_wall_time_s=settle_wall,
            compile_wall_time_s=compile_wall, fill_wall_time_s=fill_wall,
            frames=bool(self.keep_frames), lab_frame=bool(self.lab_frame),
        )  # fmt: skip
        if self.keep_frames:
            self.writers.append(VTKFrames(self.dir, self.sim, case, self.progress,
                                          lab_frame=self.lab_frame))  # fmt: skip
        self.writers.append(HDF5Results(self.dir / RESULTS, self.sim, case, self.progress,
                                        resume=False))  # fmt: skip
        self.checkpoints = Checkpoints(self.dir / CHECKPOINT, self.sim)
        self.writers.append(self.checkpoints)
        if self.keep_frames:
            write_frame(self.writers, self.sim, self.progress)

    def close(self) -> None:
        """Unfinished: the writers closed incomplete (the VTK collection lists every frame)."""
        if self.summary is None:
            for writer in self.writers:
                try:
                    writer.close(complete=False)
                except OSError:
                    pass


def run_batch(cases: list, run_dirs: list[Path], *, cycles: int | None, progress: bool,
              overwrite: bool, frames: bool, lab_frame: bool,
              keep_frames: list[bool] | None = None) -> dict[int, dict]:  # fmt: skip
    """Run ``cases`` (replicas, or sweep points of one section, period and law) as one GPU job.

    Case k runs into ``run_dirs[k]``; ``keep_frames[k]``: it writes its frames (default: all,
    with ``frames``). Where the cases' automatic time steps differ (a throw-number sweep), all run
    at the smallest. Other arguments as :func:`dem.run.runner.run_case`. Returns each case's
    summary by k.

    Raises:
        RunInterrupted: a signal stopped the batch; every unfinished case left a checkpoint.

    """
    n = len(cases)
    scenes = [resolve(c) for c in cases]
    steps = {s.step.dt for s in scenes}
    if len(steps) > 1:
        scenes = [resolve(c, timestep=min(steps)) for c in cases]
    first = scenes[0].case
    cycles = first.run.cycles if cycles is None else int(cycles)
    estimate = plan.plan(scenes[0], threads=1, cycles=cycles, frames=frames)
    # the host holds every case's state, and the batch's besides
    check_memory(first, replace(estimate, memory_bytes=2 * n * estimate.memory_bytes))
    per_frame = first.output.frames_per_cycle if frames else 1
    keep = [frames] * n if keep_frames is None else [frames and k for k in keep_frames]
    runs = [_Replica(k, scenes[k], run_dirs[k], cycles, lab_frame, keep[k]) for k in range(n)]
    with ExitStack() as stack:
        for r in runs:
            stack.enter_context(locked(r.dir))
        stack.enter_context(file_size_limit_as_error())
        for r in runs:
            prepare_output(r.dir, overwrite=overwrite, resume=False)
        warn_plan(estimate)
        with StopNow() as stop:
            t0 = time.perf_counter()
            compile_first(first, progress)
            compile_wall = time.perf_counter() - t0
            stop.phase = "filling"
            _say(progress, f"filling {n} troughs with {first.particles.count} grains each")
            t0 = time.perf_counter()
            for r in runs:
                r.sim = setup.from_case(r.scene)
            fill_wall = (time.perf_counter() - t0) / n
            batch = GpuReplicas([r.sim for r in runs])
            t0 = time.perf_counter()
            stop.phase = "settling"
            settle_time = batch.settle(progress=fill_bar(first) if progress else None)
            batch.start_drive()
            settle_wall = (time.perf_counter() - t0) / n
        for r in runs:
            r.sim.stats[:] = 0.0
            r.open(settle_time, settle_wall, compile_wall, fill_wall)
        try:
            _cycles(batch, runs, per_frame, estimate, Path(run_dirs[0]), progress)
        finally:
            for r in runs:
                r.close()
    return {r.k: r.summary for r in runs}


def _cycles(batch, replicas, per_frame, estimate, out_dir, show) -> None:
    """Step the batch frame by frame until every replica's measured cycles are done.

    A progress bar follows replica 0 (settling, then measuring).
    """
    first = replicas[0]
    bar = [phase_bar(first.scene.case, first.progress) if show else None]
    try:
        _loop(batch, replicas, per_frame, estimate, out_dir, bar)
    finally:
        if bar[0] is not None:
            bar[0].close()


def _loop(batch, replicas, per_frame, estimate, out_dir, bar) -> None:
    sim = batch.sim
    period = sim.trough.period
    started = time.perf_counter()
    steps_done = 0
    with SignalFlag() as flag:
        while True:
            live = [r for r in replicas if not r.progress.finished]
            if not live:
                break
            lead = live[0].progress
            end = cycle_edge(sim.drive_start_step, lead.cycle + (lead.chunk + 1) / per_frame,
                             period, sim.dt)  # fmt: skip
            n = end - sim.step_index
            t1 = time.perf_counter()
            done = batch.run(n, stop=flag.is_set)
            wall = time.perf_counter() - t1
            steps_done += done
            for r in live:
                r.progress.wall_time_s += wall / len(live)
                r.progress.steps += done
            if done < n:
                for r in live:
                    r.checkpoints.save(r.progress)
                assert flag.signum is not None  # the flag's signal stopped it
                raise RunInterrupted(flag.signum, out_dir / CHECKPOINT, lead.cycle)
            for r in live:
                r.sim.check()  # the replica's own overlaps, speeds and grains
                if r.keep_frames:
                    write_frame(r.writers, r.sim, r.progress)
                r.progress.chunk += 1
                if r.progress.chunk == per_frame:
                    measuring = r.progress.measuring
                    asked = r.progress.cycles
                    row = close_cycle(r.sim, r.scene.case, r.progress)
                    for writer in r.writers:
                        writer.cycle(row, r.progress)
                    if r.progress.cycles != asked:
                        said_extended(r.scene.case, r.progress, bar[0] if r.k == 0 else None,
                                      bar[0] is not None)  # fmt: skip
                    if r.k == 0 and bar[0] is not None:
                        bar[0].update(1)
                        if r.progress.measuring != measuring:  # replica 0's settling has ended
                            bar[0].close()
                            bar[0] = phase_bar(r.scene.case, r.progress)
                if r.progress.finished:
                    if r.k == 0 and bar[0] is not None:
                        bar[0].close()
                        bar[0] = None
                    extra = {"gpu_batch": {
                        "replicas": len(replicas), "spheres": int(sim.spheres.n),
                        "steps": steps_done, "wall_time_s": time.perf_counter() - started,
                        "step": batch.step_scheme(),
                    }}  # fmt: skip
                    r.summary = finish(r.scene, r.sim, r.progress, r.cycles, 1, estimate,
                                        r.dir, r.writers, extra)  # fmt: skip
            if flag.signum is not None and any(not r.progress.finished for r in replicas):
                for r in replicas:
                    if not r.progress.finished:
                        r.checkpoints.save(r.progress)
                raise RunInterrupted(flag.signum, out_dir / CHECKPOINT, lead.cycle)


def _say(show: bool, text: str) -> None:
    if show:
        print(f"dem: {text}", file=sys.stderr, flush=True)
