"""``dem plan``'s wall time against the measured ``dem run``, for every shipped case.

    .venv/bin/python validation/performance/plan_check.py [--cases a,b] [--cold sphere-bed,...]

For each case in cases/ (or ``--cases``): ``dem plan CASE --json`` and then ``dem run CASE``
(default threads, frames as the case sets them, a scratch --out), each in a fresh process, the
run timed as a whole command (start-up, compile if the cache is cold, fill, rest, cycles, frames,
summary). With the kernels cached (the normal case: each case's kernels are compiled first, as
its first run would), and for the ``--cold`` cases once more with
an empty numba cache (NUMBA_CACHE_DIR pointing to a new folder: what a fresh clone pays). The
1-minute load average is recorded before each run. Writes plan_check.csv and plan_check.json
and prints predicted / measured (the requirement: within 1.5x either way on an idle machine).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DEM = str(Path(sys.executable).with_name("dem"))


WARM = """
import sys
from dem.scene.case import load_case
from dem.run.checks import compile_first
compile_first(load_case(sys.argv[1]), progress=False)
"""


def measure(case: str, env: dict, out: Path) -> dict:
    """Plan, then run, in fresh processes under ``env``."""
    path = str(ROOT / "cases" / case)
    planned = json.loads(subprocess.run([DEM, "plan", path, "--json"], env=env, check=True,
                                        capture_output=True, text=True).stdout)  # fmt: skip
    if out.exists():
        shutil.rmtree(out)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    subprocess.run([DEM, "run", path, "--out", str(out)], env=env, check=True,
                   capture_output=True, text=True)  # fmt: skip
    wall = time.perf_counter() - t0
    summary = json.loads((out / "summary.json").read_text())
    return {
        "case": case,
        "cache": "cold" if "NUMBA_CACHE_DIR" in env else "warm",
        "predicted_s": round(planned["wall_time_s"], 1),
        "predicted_compile_s": round(planned["compile_s"], 1),
        "predicted_fill_s": round(planned["fill_s"], 1),
        "measured_s": round(wall, 1),
        "predicted_frames_s": round(planned["frames_s"], 1),
        "measured_compile_s": round(summary["compile_wall_time_s"], 1),
        "measured_fill_s": round(summary["fill_wall_time_s"], 2),
        "measured_frames_s": round(summary["frames_wall_time_s"], 2),
        "frames": summary["frames_written"],
        "measured_settle_wall_s": round(summary["settle_wall_time_s"], 1),
        "measured_cycles_wall_s": round(summary["wall_time_s"], 1),
        "ratio_predicted_over_measured": round(planned["wall_time_s"] / wall, 3),
        "threads": summary["threads"],
        "load_1min_before": round(load, 2),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    shipped = sorted(p.parent.name for p in (ROOT / "cases").glob("*/case.toml"))
    parser.add_argument("--cases", default=",".join(shipped))
    parser.add_argument("--cold", default="sphere-bed,screw-trough",
                        help="cases also run with an empty numba cache")  # fmt: skip
    args = parser.parse_args()
    scratch = HERE / "scratch" / "plan_check"
    scratch.mkdir(parents=True, exist_ok=True)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    rows = []
    for case in args.cases.split(","):  # the "warm" rows: each case's kernels cached first
        subprocess.run([sys.executable, "-c", WARM, str(ROOT / "cases" / case)], env=env,
                       check=True, capture_output=True)  # fmt: skip
    for case in args.cases.split(","):
        rows.append(measure(case, env, scratch / case))
        print(json.dumps(rows[-1]), flush=True)
    for case in filter(None, args.cold.split(",")):
        with tempfile.TemporaryDirectory(prefix="numba-cold-") as cache:
            rows.append(measure(case, env | {"NUMBA_CACHE_DIR": cache}, scratch / case))
        print(json.dumps(rows[-1]), flush=True)
    print(f"\n{'case':14s} {'cache':5s} {'predicted (s)':>13s} {'measured (s)':>12s} "
          f"{'ratio':>6s}")  # fmt: skip
    for r in rows:
        print(f"{r['case']:14s} {r['cache']:5s} {r['predicted_s']:13.1f} {r['measured_s']:12.1f} "
              f"{r['ratio_predicted_over_measured']:6.2f}")  # fmt: skip
    worst = max(max(r["ratio_predicted_over_measured"], 1 / r["ratio_predicted_over_measured"])
                for r in rows)  # fmt: skip
    print(f"worst factor {worst:.2f} (requirement: 1.5)")
    with open(HERE / "plan_check.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    from dem import provenance

    (HERE / "plan_check.json").write_text(json.dumps(
        {"provenance": provenance.record(), "command": " ".join(sys.argv), "rows": rows,
         "worst_factor": worst}, indent=1) + "\n")  # fmt: skip
    return 0 if worst <= 1.5 else 1


if __name__ == "__main__":
    raise SystemExit(main())
