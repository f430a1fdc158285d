"""Speed and compile time of two checkouts of dem, interleaved: did a change cost anything?

Each trial runs one small job in a fresh process for each checkout, alternating which goes
first: the job builds a case (``dem.engine.setup.from_case`` or, for old checkouts, the
classmethod), settles it for a few hundred steps, switches the drive on and times ``--steps`` steps
after a warm-up. Per process it reports

- compile: wall time of the first ``run`` call with an empty numba cache (``NUMBA_CACHE_DIR``
  a fresh folder per process), which compiles every kernel the run needs;
- rate: particle-steps per second of the timed steps (spheres, clump members counted).

Ratios new / old are taken per trial (both runs of a trial see about the same load) and
summarised by their median and range. The load average is recorded beside every run. With
``--busy`` a second process spins a core for the whole measurement, as on a shared workstation.

    .venv/bin/python validation/performance/compare_commits.py --old /tmp/old --new . \
        --case cases/sphere-bed --trials 5 --threads 2 --out refactor_sphere-bed.json

``--old`` is a checkout (e.g. ``git worktree add /tmp/old <commit>``); each process runs with
``PYTHONPATH`` set to the checkout and its folder as working directory.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from dem import provenance

JOB = r"""
import json, os, sys, time
import numba
import dem
try:  # the layer folders (issue 27); before them the modules sat at dem/'s top level
    from dem.scene.case import load_case
except ImportError:
    from dem.case import load_case
case = load_case(sys.argv[1])
steps = int(sys.argv[2])
if os.path.exists(os.path.join(dem.__path__[0], "engine", "setup.py")):
    from dem.engine.setup import from_case
elif os.path.exists(os.path.join(dem.__path__[0], "setup.py")):
    from dem.setup import from_case
else:  # before dem.setup (an editable install would supply the new module to an old tree)
    from dem.simulation import Simulation
    from_case = Simulation.from_case
print("dem from", dem.__path__[0], file=sys.stderr)
sim = from_case(case)
t0 = time.perf_counter()
sim.run(1)
compile_s = time.perf_counter() - t0
sim.run(499)
sim.start_drive()
sim.run(max(steps // 5, 1))
t0 = time.perf_counter()
sim.run(steps)
wall = time.perf_counter() - t0
print(json.dumps({"compile_s": compile_s, "rate": sim.spheres.n * steps / wall,
                  "spheres": sim.spheres.n, "dt": sim.dt, "threads": numba.get_num_threads(),
                  "load": os.getloadavg()[0]}))
"""


def run_one(checkout: Path, case: Path, steps: int, threads: int) -> dict:
    """One job in a fresh process with an empty numba cache; its JSON line as a dict."""
    with tempfile.TemporaryDirectory() as cache:
        env = os.environ | {
            "PYTHONPATH": str(checkout),
            "NUMBA_CACHE_DIR": cache,
            "NUMBA_NUM_THREADS": str(threads),
        }
        done = subprocess.run(
            [sys.executable, "-c", JOB, str(case), str(steps)],
            cwd=checkout, env=env, capture_output=True, text=True,
        )  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"job failed in {checkout}:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def _plain_copy(case_dir: Path) -> Path:
    """The case in a temporary folder with ``settle_cycles = "auto"`` written as 0.

    Older checkouts cannot read "auto"; the job never uses the settle cycles (it steps a fixed
    number of times), so the two checkouts still run the same scene.
    """
    import shutil

    out = Path(tempfile.mkdtemp(prefix="dem-bench-")) / case_dir.name
    shutil.copytree(case_dir, out, ignore=shutil.ignore_patterns("output"))
    text = (out / "case.toml").read_text()
    lines = [
        "settle_cycles = 0" if line.strip().startswith("settle_cycles") else line
        for line in text.splitlines()
    ]
    (out / "case.toml").write_text("\n".join(lines) + "\n")
    return out


def _spin(stop_at: float) -> None:
    x = 0
    while time.time() < stop_at:
        x += 1


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, required=True)
    parser.add_argument("--new", type=Path, default=Path("."))
    parser.add_argument(
        "--case", type=Path, default=Path("validation/liggghts-bulk/sphere-bed-5e7")
    )
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--trials", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--busy", action="store_true", help="spin one core meanwhile")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    case = _plain_copy(args.case.resolve())
    old, new = args.old.resolve(), args.new.resolve()
    spinner = None
    if args.busy:
        spinner = multiprocessing.Process(target=_spin, args=(time.time() + 10 * 3600,))
        spinner.start()
    rows = []
    try:
        for trial in range(args.trials):
            order = [("old", old), ("new", new)]
            if trial % 2:
                order.reverse()
            result = {}
            for name, checkout in order:
                result[name] = run_one(checkout, case, args.steps, args.threads)
            rows.append(result)
            o, n = result["old"], result["new"]
            print(
                f"trial {trial}: rate old {o['rate']:.3g} new {n['rate']:.3g} "
                f"(new/old {n['rate'] / o['rate']:.3f}); compile old {o['compile_s']:.1f} s "
                f"new {n['compile_s']:.1f} s; load {o['load']:.2f}/{n['load']:.2f}",
                flush=True,
            )
    finally:
        if spinner is not None:
            spinner.terminate()
    rate = [r["new"]["rate"] / r["old"]["rate"] for r in rows]
    comp = [r["new"]["compile_s"] / r["old"]["compile_s"] for r in rows]
    summary = {
        "case": str(args.case),
        "steps": args.steps,
        "threads": args.threads,
        "busy_process": args.busy,
        "old": str(old),
        "new": str(new),
        "rate_ratio_median": statistics.median(rate),
        "rate_ratio_range": [min(rate), max(rate)],
        "compile_ratio_median": statistics.median(comp),
        "compile_ratio_range": [min(comp), max(comp)],
        "rate_old_median": statistics.median(r["old"]["rate"] for r in rows),
        "rate_new_median": statistics.median(r["new"]["rate"] for r in rows),
        "compile_old_median_s": statistics.median(r["old"]["compile_s"] for r in rows),
        "compile_new_median_s": statistics.median(r["new"]["compile_s"] for r in rows),
        "trials": rows,
        "provenance": provenance.record(),
    }
    print(json.dumps({k: v for k, v in summary.items() if k not in ("trials",)}, indent=1))
    if args.out:
        args.out.write_text(json.dumps(summary, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
