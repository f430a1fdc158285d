"""Time dem's step loop on N numba threads on this (possibly shared) machine.

    NUMBA_NUM_THREADS=2 .venv/bin/python validation/liggghts-bulk/threads_check.py 2
    OMP_WAIT_POLICY=passive NUMBA_NUM_THREADS=2 .venv/bin/python \\
        validation/liggghts-bulk/threads_check.py 2

sphere-bed (1500 spheres), dt = 5e-6 s, the fresh fill falling (few contacts), so the time is
mostly the per-step cost of the parallel regions. See README.md, "Notes".
"""

import dataclasses
import sys
import time
from pathlib import Path

import numba

from dem.engine import setup
from dem.scene.case import load_case

ROOT = Path(__file__).resolve().parents[2]

n = int(sys.argv[1]) if len(sys.argv) > 1 else 1
case = load_case(ROOT / "validation" / "liggghts-bulk" / "sphere-bed-5e7")
case = dataclasses.replace(case, run=dataclasses.replace(case.run, timestep=5e-6))
sim = setup.from_case(case)
numba.set_num_threads(n)
sim.run(200)  # compile / warm up
for steps in (500, 2000):
    t = time.perf_counter()
    sim.run(steps)
    w = time.perf_counter() - t
    print(
        f"threads={n} layer={numba.threading_layer()} steps={steps} wall={w:.2f}s "
        f"rate={sim.spheres.n * steps / w:.3g} particle-steps/s",
        flush=True,
    )
