"""The writers of a run: plug-ins the run loop calls on its triggers.

A writer is any object with the three methods of :class:`Writer`. The run
(:func:`dem.run.runner.run_case`) holds a list of them and calls, in list order:

- ``frame(frame, progress)`` after frame 0 (before the first cycle) and after every chunk of
  ``1 / frames_per_cycle`` of a cycle, only where the run writes frames;
- ``cycle(row, progress)`` at the end of every cycle, after ``progress`` has moved to the next
  cycle (:func:`dem.run.record.close_cycle`);
- ``close(complete)`` once: ``complete=True`` after summary.json is written, ``False`` when the
  run stops before (a signal or an error; then an OSError of a writer is not reported, the
  error that stopped the run is).

Each writer keeps its position in ``progress`` (which the checkpoint saves), so a resumed run
picks up where the files end. A new output is one class here and one entry in the run's list.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from dem import config
from dem.engine.simulation import Simulation
from dem.io import checkpoint as checkpoint_io
from dem.io.hdf5 import ResultsWriter, package_versions
from dem.io.vtk import VTKSeriesWriter
from dem.run.record import CycleRow, Progress


@dataclass(frozen=True)
class Frame:
    """What every frame writer reads at one instant, computed once per frame.

    ``time``: drive time, s; ``contact_count``: touching neighbours and walls per sphere, (n,);
    ``grain_id``: grain id of each sphere, (n,); ``orientation``: the clumps' unit quaternions
    (w, x, y, z), (bodies, 4), None for plain spheres.
    """

    sim: Simulation
    time: float
    contact_count: np.ndarray
    grain_id: np.ndarray
    orientation: np.ndarray | None

    @functools.cached_property
    def contacts(self) -> dict:
        """Every contact of the frame (:meth:`Simulation.contact_snapshot`).

        Evaluated once for all the writers that ask (``output.contacts``).
        """
        return self.sim.contact_snapshot()

    @classmethod
    def of(cls, sim: Simulation) -> Frame:
        """The frame ``sim`` stands at now."""
        orientation = sim.bodies.q if sim.bodies is not None else None
        counts = sim.contact_counts()
        return cls(sim, sim.drive_time, counts, sim.grain_id[sim.spheres.body], orientation)


class Writer(Protocol):
    """An output of a run, called on the run's triggers (see the module docstring)."""

    def frame(self, frame: Frame, progress: Progress) -> None:
        """Write one frame of the particles."""

    def cycle(self, row: CycleRow, progress: Progress) -> None:
        """Take the row of the cycle that has just ended."""

    def close(self, complete: bool) -> None:
        """End the output: ``complete`` after the run's summary is written, else stopped."""


class VTKFrames:
    """ParaView frames: ``particles.pvd`` and ``frames/*.vtp`` (:class:`VTKSeriesWriter`).

    ``lab_frame``: grains and trough displaced by the drive s(t), velocities plus ds/dt.
    """

    def __init__(self, out_dir: Path, sim: Simulation, case, progress: Progress, *,
                 lab_frame: bool):  # fmt: skip
        self.series = VTKSeriesWriter(
            out_dir, sim.trough.extent, case.trough.width, case.trough.inclination,
            entries=[tuple(e) for e in progress.vtk_entries], lab_frame=lab_frame, mesh=sim.mesh,
            period=sim.trough.length, back_wall=sim.trough.finite,
        )  # fmt: skip
        self.contacts = case.output.contacts

    def frame(self, frame: Frame, progress: Progress) -> None:
        """Write the frame's spheres (and the trough, and clump grains) and the collection."""
        sim = frame.sim
        s = sim.spheres
        t = frame.time
        shift = sim.trough.displacement(t) if sim.drive_on else np.zeros(3)
        lab_v = sim.trough.velocity(t) if sim.drive_on else np.zeros(3)
        self.series.write_frame(
            t, s.x, s.radius, s.v, frame.grain_id, s.body, frame.contact_count,
            frame.orientation, drive_displacement=shift, drive_velocity=lab_v, bodies=sim.bodies,
            contacts=frame.contacts if self.contacts else None, grain_type=sim.grain_type,
        )  # fmt: skip
        progress.vtk_entries = self.series.entries

    def cycle(self, row: CycleRow, progress: Progress) -> None:
        """Nothing: the frames are written per frame."""

    def close(self, complete: bool) -> None:
        """Write the collection a last time: it lists every frame written."""
        self.series.close()


class HDF5Results:
    """results.h5 (:class:`ResultsWriter`): one row per cycle, and the frames if asked for.

    With ``output.contacts`` each frame's contacts and the trough's loads go with it. It carries the
    case, the package versions, the seed and the time step; ``resume``: the file is trimmed back to
    the rows and frames ``progress`` has counted.
    """

    def __init__(self, path: Path, sim: Simulation, case, progress: Progress, *, resume: bool):
        self.results = ResultsWriter(
            path,
            case=case.as_dict(),
            versions=package_versions(),
            seed=case.run.seed,
            timestep=sim.dt,
            resume_at=(progress.h5_cycles, progress.h5_frames) if resume else None,
            ragged=sim.feeder is not None,
        )
        self.contacts = case.output.contacts

    def frame(self, frame: Frame, progress: Progress) -> None:
        """Append the frame's spheres, and a finite feeder's grain and mass balance."""
        sim = frame.sim
        s = sim.spheres
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
        self.results.append_frame(
            frame.time, s.x, s.v, radius=s.radius, grain_id=frame.grain_id,
            contact_count=frame.contact_count, orientation=frame.orientation,
            grain_index=s.body, per_frame=balance,
            contacts=frame.contacts if self.contacts else None,
        )  # fmt: skip
        progress.h5_frames += 1

    def cycle(self, row: CycleRow, progress: Progress) -> None:
        """Append the cycle's row to ``/cycles``."""
        self.results.append_cycle(**row.stats())
        progress.h5_cycles += 1

    def close(self, complete: bool) -> None:
        """Mark the file complete, only when the run is (a stopped run's file stays open-ended)."""
        if complete:
            self.results.close()


class Checkpoints:
    """checkpoint.npz (:mod:`dem.io.checkpoint`): every ``DEM_CHECKPOINT_EVERY`` cycles.

    It must come last in the run's list: it saves the positions the writers before it have
    just recorded. The run also calls :meth:`save` when a signal stops it. A finished run
    removes the file.
    """

    def __init__(self, path: Path, sim: Simulation):
        self.path = path
        self.sim = sim

    def save(self, progress: Progress) -> None:
        """Write a checkpoint; a finite feeder's counters and generator travel in the record."""
        sim = self.sim
        if sim.feeder is not None:
            progress.feeder = sim.feeder.state()
        progress.max_overlap = sim.overlap_summary()
        checkpoint_io.write(self.path, sim, progress.to_checkpoint())

    def frame(self, frame: Frame, progress: Progress) -> None:
        """Nothing: checkpoints fall on cycle ends."""

    def cycle(self, row: CycleRow, progress: Progress) -> None:
        """Save after every ``DEM_CHECKPOINT_EVERY``-th cycle."""
        if progress.cycle % config.DEM_CHECKPOINT_EVERY == 0:
            self.save(progress)

    def close(self, complete: bool) -> None:
        """Remove the checkpoint of a complete run (a stopped run keeps it for ``--resume``)."""
        if complete:
            self.path.unlink(missing_ok=True)
