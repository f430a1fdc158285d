"""Instructions per particle-step at any commit or working tree: a speed figure without the noise.

    .venv/bin/python validation/performance/count_instructions.py 7798172 d285aa8 HEAD
    .venv/bin/python validation/performance/count_instructions.py /path/to/worktree --law impact

Timings on a shared VM scatter by up to 40 % from run to run, which defeated a bisect of the
step's slowdown on wall time (rate_at_commit.py). valgrind's callgrind counts the instructions
a run executes instead, the same count on a busy machine as on an idle one. For each commit (a
detached worktree under ``--work``) or folder this runs the benchmark's sphere deck
(validation/liggghts-bulk/sphere-bed-5e7, or cases/sphere-bed before that folder existed: the
same 1500 spheres at 5e7 Pa) as rate_at_commit.py does, with one settle cycle and one measured
cycle at dt 5e-6 s on one thread, twice:

1. natively, which compiles the kernels into the tree's own numba cache;
2. under ``valgrind --tool=callgrind --instr-atstart=no``: the fill runs uninstrumented (a few
   times slower than native), and the count starts when the fill's settle returns
   (``callgrind_control -i on``), so it covers the 6,667 drive steps and the summary.

The kernels are compiled for ``haswell`` (AVX2) in both runs, because valgrind does not run
AVX-512; the counts are a proxy for a change's cost, not the AVX-512 code users run. The
result per tree: the total, the four largest functions (numba's kernels have no symbols:
``???:0x...``; the largest is the pair loop, the next the sphere loop with the walls, by their
growth under changes to either), instructions per particle-step, the run's mean velocity
(for a change that must keep every bit) and the step count; appended to ``--out``.

Rows record the date and valgrind's version (the first four rows, 2026-11-28, valgrind-3.19.0,
Python 3.11.7, did not yet). Measured 2026-11-28 (liggghts law): 7798172 (2026-11-23) 9.14e9,
d285aa8 11.12e9, b6ab922 13.10e9 (validation/performance/README.md, "Instructions, not
seconds").
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from rate_at_commit import checkout  # noqa: E402  (this folder's script: the same worktrees)

JOB = r"""
import dataclasses, json, os, subprocess, sys, time
try:
    from dem.scene.case import load_case
    from dem.run.runner import run_case
    from dem.engine.simulation import Simulation
except ImportError:  # before the layer folders
    from dem.case import load_case
    from dem.runner import run_case
    from dem.simulation import Simulation
case = load_case(sys.argv[1]).with_tangential(sys.argv[3])
kw = dict(timestep=5e-6, settle_cycles=1, cycles=1)
if "replicas" in {f.name for f in dataclasses.fields(case.run)}:
    kw["replicas"] = 1
case = dataclasses.replace(case, run=dataclasses.replace(case.run, **kw))
settle = Simulation.settle
def counted(self, *a, **k):
    out = settle(self, *a, **k)
    if os.environ.get("DEM_COUNT_ON"):
        subprocess.Popen(["callgrind_control", "-i", "on", str(os.getpid())],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(2.0)  # callgrind takes the command at its next poll
    return out
Simulation.settle = counted
run_case(case, sys.argv[2], cycles=1, threads=1, progress=False, overwrite=True, frames=False)
s = json.load(open(os.path.join(sys.argv[2], "summary.json")))
print(json.dumps({k: s.get(k) for k in ("steps", "spheres", "mean_velocity", "neighbour_builds")}))
"""

ENV = {"NUMBA_CPU_NAME": "haswell", "NUMBA_CPU_FEATURES": "", "NUMBA_NUM_THREADS": "1"}


def tree_of(name: str, work: Path) -> tuple[str, Path]:
    """(label, tree): a folder as it is, or a commit's detached worktree under ``work``."""
    if Path(name).is_dir():
        return Path(name).name, Path(name).resolve()
    tree = checkout(name, work)
    return tree.name, tree


def count(label: str, tree: Path, law: str, work: Path) -> dict:
    deck = tree / "validation" / "liggghts-bulk" / "sphere-bed-5e7"
    if not deck.exists():
        deck = tree / "cases" / "sphere-bed"
    env = os.environ | ENV | {"PYTHONPATH": str(tree),
                              "NUMBA_CACHE_DIR": str(work / f"cache-{label}")}  # fmt: skip
    argv = [sys.executable, "-c", JOB, str(deck), str(work / f"out-{label}"), law]
    native = subprocess.run(argv, cwd="/", env=env, capture_output=True, text=True)
    if native.returncode != 0:
        raise SystemExit(f"{label} failed natively:\n{native.stderr[-2000:]}")
    cg = work / f"{label}-{law}.callgrind"
    t0 = time.perf_counter()
    done = subprocess.run(
        ["valgrind", "--tool=callgrind", "--instr-atstart=no", f"--callgrind-out-file={cg}",
         *argv], cwd="/", env=env | {"DEM_COUNT_ON": "1"}, capture_output=True, text=True,
    )  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"{label} failed under valgrind:\n{done.stderr[-2000:]}")
    total = int(re.search(r"Collected : (\d+)", done.stderr).group(1))
    ann = subprocess.run(["callgrind_annotate", str(cg)], capture_output=True, text=True).stdout
    top = [int(m.group(1).replace(",", "")) for m in re.finditer(r"^\s*([\d,]+) .*\?\?\?:0x", ann,
                                                                 re.M)][:4]  # fmt: skip
    run = json.loads(done.stdout.strip().splitlines()[-1])
    same = json.loads(native.stdout.strip().splitlines()[-1])
    return {
        "label": label, "law": law, "instructions": total, "largest_functions": top,
        "per_particle_step": total / (run["steps"] * run["spheres"]),
        "mean_velocity": run["mean_velocity"], "native_mean_velocity": same["mean_velocity"],
        "steps": run["steps"], "neighbour_builds": run["neighbour_builds"],
        "valgrind_wall_s": time.perf_counter() - t0,
        "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "valgrind": subprocess.run(["valgrind", "--version"], capture_output=True,
                                   text=True).stdout.strip(),
        "python": sys.version.split()[0],
    }  # fmt: skip


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trees", nargs="+", help="commits or working-tree folders")
    parser.add_argument("--law", default="liggghts", choices=("liggghts", "impact", "coulomb"))
    parser.add_argument("--work", type=Path, default=Path("/tmp/dem-count"))
    parser.add_argument("--out", type=Path, default=Path(__file__).with_name("instructions.json"))
    args = parser.parse_args(argv)
    args.work.mkdir(parents=True, exist_ok=True)
    rows = json.loads(args.out.read_text()) if args.out.exists() else []
    for name in args.trees:
        label, tree = tree_of(name, args.work)
        row = count(label, tree, args.law, args.work)
        print(f"{label} ({args.law}): {row['instructions']:.4g} instructions, "
              f"{row['per_particle_step']:.0f} a particle-step; largest "
              f"{', '.join(f'{t:.3g}' for t in row['largest_functions'])}; "
              f"v = {row['mean_velocity']!r}", flush=True)  # fmt: skip
        rows.append(row)
        args.out.write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
