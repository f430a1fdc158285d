"""Cost per particle-step and peak memory against the number of spheres, on 1 and 2 threads.

    .venv/bin/python validation/performance/scaling.py            # about 3 min on 2 cores
    .venv/bin/python validation/performance/scaling.py --figures  # redraw from scaling.csv

A dense bed of cases/sphere-bed's spheres (r = 2 mm, Hertz E = 5e7 Pa, the drive on) stacked on
a simple cubic lattice, ten layers deep (vertical spacing 1.999 r), in a section 2.5 times as
long as wide that grows with N (periodic in x), so every sphere touches its neighbours as in a
settled bed whatever N. Each (N, threads) runs in a fresh process: build (the grains
are given, no fill), 50 untimed steps, then steps timed for about two seconds; the process's
peak resident memory (ru_maxrss) minus that of the same process before the build is the
memory of N spheres. Writes scaling.csv (with provenance) and scaling.png.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
SIZES = (1_000, 10_000, 100_000, 1_000_000)
THREADS = (1, 2)
JOB = r"""
import json, resource, sys, time
import numpy as np
from dem.scene.case import load_case
from dem.engine import setup
n = int(sys.argv[1])
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
r = 0.002
layers = 10
per_layer = -(-n // layers)
ny = max(5, int((per_layer / 2.5) ** 0.5))
nx = -(-per_layer // ny)
case = load_case(sys.argv[2], {"trough.length": nx * 2 * r, "trough.width": ny * 2 * r + 1e-4,
                               "particles.count": n})
i = np.arange(n)
a = 1.999 * r
pos = np.stack([(i % nx + 0.5) * 2 * r, ((i // nx) % ny - (ny - 1) / 2) * 2 * r,
                r + (i // (nx * ny)) * a], axis=1)
t0 = time.perf_counter()
sim = setup.from_grains(case, pos, impact_speed=1.0)
build = time.perf_counter() - t0
sim.start_drive()
sim.run(50)
steps = max(20, int(2.0e7 / n))
t0 = time.perf_counter()
sim.run(steps)
wall = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"n": n, "steps": steps, "wall": wall, "build_s": build,
                  "kb": (peak - base), "pairs": int(sim.pairs.counters[0]),
                  "layers": layers}))
"""


def run(n: int, threads: int) -> dict:
    env = os.environ | {"NUMBA_NUM_THREADS": str(threads)}
    case = ROOT / "validation" / "liggghts-bulk" / "sphere-bed-5e7"
    out = subprocess.run([sys.executable, "-c", JOB, str(n), str(case)],
                         env=env, capture_output=True, text=True, check=True)  # fmt: skip
    row = json.loads(out.stdout.strip().splitlines()[-1])
    return {
        "spheres": n, "threads": threads, "layers": row["layers"], "steps": row["steps"],
        "ns_per_particle_step": 1e9 * row["wall"] / (n * row["steps"]),
        "particle_steps_per_s": n * row["steps"] / row["wall"],
        "bytes_per_sphere": 1024 * row["kb"] / n, "pairs_per_sphere": row["pairs"] / n,
        "build_s": row["build_s"], "load_1min": round(os.getloadavg()[0], 2),
    }  # fmt: skip


def plot(rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    for t in THREADS:
        sel = [r for r in rows if int(r["threads"]) == t]
        a.plot([int(r["spheres"]) for r in sel], [float(r["ns_per_particle_step"]) for r in sel],
               "o-", label=f"{t} thread{'s' if t > 1 else ''}")  # fmt: skip
    sel = [r for r in rows if int(r["threads"]) == 1]
    b.plot([int(r["spheres"]) for r in sel], [float(r["bytes_per_sphere"]) for r in sel], "o-")
    a.set_xscale("log")
    a.set_xlabel("spheres")
    a.set_ylabel("ns per particle-step")
    a.set_ylim(bottom=0)
    a.legend()
    b.set_xscale("log")
    b.set_xlabel("spheres")
    b.set_ylabel("peak resident memory per sphere, B")
    b.set_ylim(bottom=0)
    fig.suptitle("dense sphere bed on a lattice: cost and memory against N", fontsize=10)
    fig.tight_layout()
    fig.savefig(HERE / "scaling.png", dpi=120)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figures", action="store_true")
    args = parser.parse_args()
    path = HERE / "scaling.csv"
    if args.figures:
        with open(path) as fh:
            plot(list(csv.DictReader(line for line in fh if not line.startswith("#"))))
        return 0
    rows = []
    for n in SIZES:
        for t in THREADS:
            row = run(n, t)
            rows.append(row)
            print(f"{n:>9d} spheres, {t} thread(s): {row['ns_per_particle_step']:.0f} ns per "
                  f"particle-step, {row['bytes_per_sphere']:.0f} B per sphere, "
                  f"{row['pairs_per_sphere']:.2f} pairs per sphere (load {row['load_1min']})",
                  flush=True)  # fmt: skip
    from dem import provenance

    with open(path, "w", newline="") as fh:
        fh.write("\n".join(provenance.header_lines(__file__)) + "\n")
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows)
    print("wrote scaling.csv and scaling.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
