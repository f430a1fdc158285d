"""The GPU engine's host cost of a step, measured without a GPU (launches replaced by no-ops).

On the H200 one replica alone ran 58 us a step and the 100-replica batch spent 67 us a step
queueing launches (gpu_h200_batch_queued.json): below some 1e5 spheres the host, not the
kernel, sets the pace. This script times the Python the engine runs for each queued step
(:meth:`dem.engine.gpu.engine.GpuEngine.steps`: the body accelerations of a chunk, the step launch's
arguments, the prepared launch's lookup and its changing scalars) with every
:class:`dem.kernels.cuda.launch.PreparedLaunch` replaced by one whose launch does nothing, in
numba's CUDA simulator (device arrays are host arrays there; the kernels themselves never run in
the timed loop). What remains is the host's share; a real launch adds the driver's few
microseconds. Interleaved and repeated, with the load average beside each figure.

Usage: NUMBA_ENABLE_CUDASIM=1 python validation/performance/host_step.py [--steps N] [--out JSON]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))


class _NoLaunch:
    """A prepared launch that takes its scalars and launches nothing."""

    def __init__(self, *args):
        self.kernelargs = list(args[-1])

    def set_float(self, index, value):
        self.kernelargs[index] = float(value)

    def set_int(self, index, value):
        self.kernelargs[index] = int(value)

    def set_bool(self, index, value):
        self.kernelargs[index] = bool(value)

    def __call__(self):
        pass


def _engine(clumps: bool):
    """A small driven scene on the GPU engine, with its launches prepared as no-ops."""
    from dem.engine.setup import from_case
    from dem.kernels.cuda import launch
    from dem.scene.case import load_case

    launch.prepare = lambda dispatcher, griddim, blockdim, args: _NoLaunch(args)
    root = HERE.parents[1] / "cases"
    case = load_case(root / ("screw-trough" if clumps else "sphere-bed") / "case.toml")
    sim = from_case(case)
    sim.device = "cuda"
    sim.start_drive()
    engine = sim.engine
    sim.advance(2)  # upload, first build, compile in the simulator
    engine.fast = True  # the GPU's path: prepared launches (no-ops here)
    return sim, engine


def time_steps(sim, engine, steps: int) -> float:
    """Host microseconds a queued step: the chunk loop of ``steps`` with no trip and no build."""
    drive = sim.drive_array()
    dt = sim.geom.dt
    engine.chunk = 64
    t0 = time.perf_counter()
    s = 0
    while s < steps:
        chunk = min(engine.chunk, steps - s)
        engine._accelerate(sim, drive, (np.arange(s, s + chunk) + 1) * dt)
        for k in range(s, s + chunk):
            engine._step(sim, k + 1, k - s, True, True)
        s += chunk
    return 1e6 * (time.perf_counter() - t0) / steps


def main() -> int:
    if os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":
        print("run with NUMBA_ENABLE_CUDASIM=1 (numba's CUDA simulator)", file=sys.stderr)
        return 2
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--steps", type=int, default=20000)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--out", default=str(HERE / "host_step.json"))
    args = p.parse_args()
    scenes = {"spheres": _engine(False), "screws": _engine(True)}
    rows = {name: [] for name in scenes}
    for _ in range(args.repeats):
        for name, (sim, engine) in scenes.items():
            us = time_steps(sim, engine, args.steps)
            rows[name].append({"us_per_step": round(us, 2), "loadavg": os.getloadavg()})
            print(f"{name}: {us:.1f} us a step (load {os.getloadavg()[0]:.2f})", flush=True)
    out = {
        "what": "the GPU engine's host cost of a queued step (GpuEngine._accelerate per chunk of "
        "64, _step per step) with prepared launches that launch nothing, in numba's CUDA "
        "simulator: the host's share of a step on a GPU, less the driver's launch",
        "command": "NUMBA_ENABLE_CUDASIM=1 python validation/performance/host_step.py",
        "machine": f"{platform.node()}, {os.cpu_count()} cores, Python {platform.python_version()}",
        "date": time.strftime("%Y-%m-%d"),
        "steps": args.steps,
        "median_us_per_step": {
            k: float(np.median([r["us_per_step"] for r in v])) for k, v in rows.items()
        },  # fmt: skip
        "runs": rows,
    }
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
