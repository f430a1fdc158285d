"""A small real DEM run written as a ParaView time series, for render.py to draw.

Runs the engine (dem.engine.simulation.Simulation) on cases/sphere-bed with fewer spheres: fill,
settle with the drive off, then a few driven cycles; frames are written with
dem.io.vtk.VTKSeriesWriter (trough frame): the settled bed as frame 0, then
``--frames-per-cycle`` frames per drive cycle.

    .venv/bin/python validation/paraview/make_sample.py [OUT_DIR] [--count N] [--cycles C]

OUT_DIR defaults to validation/paraview/scratch/sample (git-ignored). Takes well under a
minute on one core (most of it numba compilation on the first run).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from dem.engine import setup
from dem.engine.simulation import Simulation
from dem.io.vtk import VTKSeriesWriter
from dem.scene.case import load_case

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]


def write(writer: VTKSeriesWriter, sim: Simulation) -> None:
    s = sim.spheres
    ids = np.asarray(s.body, dtype=np.int64)
    t = sim.drive_time if sim.drive_on else 0.0
    writer.write_frame(
        time=sim.time,
        positions=s.x,
        radius=s.radius,
        velocity=s.v,
        grain_id=ids,
        clump_id=ids,
        contact_count=sim.contact_counts(),
        drive_displacement=sim.trough.displacement(t) if sim.drive_on else np.zeros(3),
        drive_velocity=sim.trough.velocity(t) if sim.drive_on else np.zeros(3),
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out_dir", nargs="?", type=Path, default=HERE / "scratch" / "sample")
    ap.add_argument("--case", type=Path, default=ROOT / "cases" / "sphere-bed")
    ap.add_argument("--count", type=int, default=500, help="spheres (default 500)")
    ap.add_argument("--cycles", type=int, default=5, help="driven cycles (default 5)")
    ap.add_argument("--frames-per-cycle", type=int, default=8)
    args = ap.parse_args()

    case = load_case(args.case)
    case = dataclasses.replace(
        case, particles=dataclasses.replace(case.particles, count=args.count)
    )
    t0 = time.perf_counter()
    sim = setup.from_case(case)
    settle = sim.settle()
    print(
        f"filled {sim.spheres.n} spheres, settled in {settle:.3f} s simulated "
        f"(dt = {sim.dt:.3g} s, {time.perf_counter() - t0:.1f} s wall)"
    )

    tr = case.trough
    with VTKSeriesWriter(args.out_dir, tr.length, tr.width, tr.inclination) as writer:
        write(writer, sim)
        sim.start_drive()
        period = sim.trough.period
        n_frames = args.cycles * args.frames_per_cycle
        for f in range(1, n_frames + 1):
            end = sim.drive_start_step + int(round(f * period / args.frames_per_cycle / sim.dt))
            sim.run(end - sim.step_index)
            write(writer, sim)
        print(
            f"wrote {writer.frame_count} frames to {writer.pvd_path} "
            f"(t = {sim.time:.4f} s, mean v_x = {sim.mean_velocity_x():.4f} m/s, "
            f"{time.perf_counter() - t0:.1f} s wall)"
        )


if __name__ == "__main__":
    main()
