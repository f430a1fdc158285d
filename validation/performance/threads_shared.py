"""Threads on a shared machine: dem's step rate on 1 and 2 threads, idle and beside a busy process.

    .venv/bin/python validation/performance/threads_shared.py [--repeat 2] [--steps 4000]

Each configuration runs in a fresh process (OpenMP reads its environment once), on
cases/sphere-bed (1500 spheres) settled and driven for two cycles (one state, prepared once and
loaded from a checkpoint): 300 untimed steps (the kernels load from the cache), then ``--steps``
timed steps. Configurations:

- ``1 thread``: NUMBA_NUM_THREADS=1;
- ``2 threads``: NUMBA_NUM_THREADS=2, libgomp's default wait policy (spin, then sleep);
- ``2 -> 1 (set_num_threads)``: a 2-thread process that runs its loops on one thread, as the
  runner's thread guard does when two threads fall behind;
- ``2 threads, PASSIVE``: OMP_WAIT_POLICY=PASSIVE (waiting threads sleep at once);
- ``2 threads, SPINCOUNT 1e4``: GOMP_SPINCOUNT=10000 (spin briefly, then sleep);
- ``2 threads + guard``: what ``dem run`` does, :class:`dem.engine.threads.ThreadGuard`.

Each is measured with the machine otherwise idle and beside one busy process (a Python loop),
the configurations interleaved and repeated; the 1-minute load average is recorded beside each.
Writes threads_shared.json and prints the table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CONFIGS = {
    "1 thread": ({"NUMBA_NUM_THREADS": "1"}, None),
    "2 threads": ({"NUMBA_NUM_THREADS": "2"}, None),
    "2 -> 1 (set_num_threads)": ({"NUMBA_NUM_THREADS": "2"}, 1),
    "2 threads, PASSIVE": ({"NUMBA_NUM_THREADS": "2", "OMP_WAIT_POLICY": "PASSIVE"}, None),
    "2 threads, SPINCOUNT 1e4": ({"NUMBA_NUM_THREADS": "2", "GOMP_SPINCOUNT": "10000"}, None),
    "2 threads + guard": ({"NUMBA_NUM_THREADS": "2"}, "guard"),
}
WORKER = """
import sys, time, numba
from pathlib import Path
from dem.scene.case import load_case
from dem.engine import setup
from dem.engine.threads import ThreadGuard
from threads_shared import load
threads, steps = sys.argv[1], int(sys.argv[2])
sim = setup.from_case(load_case(sys.argv[3]))
load(sim, Path(sys.argv[4]))
if threads == "guard":
    sim.guard = ThreadGuard(2)
elif threads != "None":
    numba.set_num_threads(int(threads))
sim.run(300)
t0 = time.perf_counter()
sim.run(steps)
print(sim.spheres.n * steps / (time.perf_counter() - t0))
"""


def prepare(case: str, path: Path) -> None:
    """A settled bed driven for two cycles, written as a checkpoint."""
    from dem.engine import setup
    from dem.io import checkpoint
    from dem.scene.case import load_case

    sim = setup.from_case(load_case(case))
    sim.settle()
    sim.start_drive()
    sim.run(int(2 * sim.trough.period / sim.dt))
    # the state alone: a run's checkpoint also carries the runner's loop record, which a
    # benchmark that only steps the simulation has none of
    np.savez(path, **checkpoint.state_dict(sim))


def load(sim, path: Path) -> None:
    """Load the state :func:`prepare` wrote into ``sim`` (checked as a checkpoint's state is)."""
    from dem.io import checkpoint

    with np.load(path) as data:
        state = {k: data[k] for k in data.files}
    checkpoint.validate(state)
    checkpoint.load_state(sim, state)


def measure(name: str, steps: int, case: str, state: Path) -> float:
    env, threads = CONFIGS[name]
    full = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    full |= env | {"PYTHONPATH": str(HERE)}  # the worker imports load() from here
    out = subprocess.run([sys.executable, "-c", WORKER, str(threads), str(steps), case, str(state)],
                         env=full, capture_output=True, text=True, check=True)  # fmt: skip
    return float(out.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument(
        "--case", default=str(ROOT / "validation" / "liggghts-bulk" / "sphere-bed-5e7")
    )
    args = parser.parse_args()
    state = HERE / "scratch" / "threads_shared_state.npz"
    state.parent.mkdir(exist_ok=True)
    prepare(args.case, state)
    rows = []
    for rep in range(args.repeat):
        for busy in (False, True):
            hog = None
            if busy:
                hog = subprocess.Popen([sys.executable, "-c", "while True: pass"])
                time.sleep(1.0)
            try:
                for name in CONFIGS:
                    rate = measure(name, args.steps, args.case, state)
                    load = os.getloadavg()[0]
                    rows.append({"config": name, "busy": busy, "repeat": rep, "rate": rate,
                                 "load_1min": round(load, 2)})  # fmt: skip
                    print(f"{name:26s} {'busy' if busy else 'idle'}: {rate:.3g} particle-steps/s"
                          f" (load {load:.2f})", flush=True)  # fmt: skip
            finally:
                if hog is not None:
                    hog.kill()
                    hog.wait()
    head = f"{'idle (best)':>12s} {'busy (best)':>12s} {'busy / 1 thread':>16s}"
    print(f"\n{'configuration':26s} {head}")
    best = {}
    for name in CONFIGS:
        for busy in (False, True):
            best[name, busy] = max(r["rate"] for r in rows if r["config"] == name
                                   and r["busy"] == busy)  # fmt: skip
    for name in CONFIGS:
        ratio = best[name, True] / best["1 thread", True]
        print(f"{name:26s} {best[name, False]:12.3g} {best[name, True]:12.3g} {ratio:16.2f}")
    from dem import provenance

    (HERE / "threads_shared.json").write_text(json.dumps(
        {"provenance": provenance.record(), "steps": args.steps, "case": args.case,
         "rows": rows}, indent=1) + "\n")  # fmt: skip
    print("wrote threads_shared.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
