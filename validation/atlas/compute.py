"""Compute the shipped atlas in the background, resumably: the grid, the held-out points, a
refill, the paper's drive; then ship the tables to dem/data/atlas with their provenance.

    nohup nice -n 10 .venv/bin/python validation/atlas/compute.py > validation/atlas/run/log 2>&1 &
    .venv/bin/python validation/atlas/compute.py --status      # how far, and what it cost so far
    .venv/bin/python validation/atlas/compute.py --ship        # copy the finished tables

Each stage is ``dem atlas GRID --out FOLDER`` (a rerun never reruns a finished point and
continues an interrupted one); SIGTERM or SIGINT to this script is passed to the running stage,
which writes its table and stops, and this script stops after it. When every point of every
stage is finished the tables are copied to ``dem/data/atlas/`` (``atlas.csv``, ``holdout.csv``,
``refill.csv``, ``paper_drive.csv`` with their ``.json`` sidecars) beside ``provenance.json``:
the grids, the
commands, dem's version and commit, the machine, and the cost (CPU seconds of the fills' step
loops and the wall seconds of the points, summed).
"""

from __future__ import annotations

import argparse
import json
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DATA = ROOT / "dem" / "data" / "atlas"
#: (grid file, output folder, shipped table name), in the order they run.
STAGES = (
    ("grid.toml", "run", "atlas"),
    ("holdout.toml", "run-holdout", "holdout"),
    ("refill.toml", "run-refill", "refill"),
    ("paper_drive.toml", "run-paper", "paper_drive"),
)


def command(grid: str, out: str) -> list[str]:
    dem = Path(sys.executable).with_name("dem")
    return [str(dem), "atlas", str(HERE / grid), "--out", str(HERE / out)]


def table_status(grid: str, out: str) -> dict:
    """A stage's points, those finished, and their cost, from the point folders themselves.

    The grid's points are counted from the grid file (no case is loaded); a point is finished
    where its atlas_point.json says so; the cost is read from the finished points' summaries.
    """
    from dem.studies import atlas

    points = len(atlas.read_grid(HERE / grid).points)
    done, cpu, wall = 0, 0.0, 0.0
    for record in (HERE / out / atlas.POINTS_DIR).glob(f"*/*/{atlas.RECORD}"):
        try:
            if not json.loads(record.read_text())["finished"]:
                continue
            summary = json.loads((record.parent / "summary.json").read_text())
        except (OSError, ValueError, KeyError):
            continue
        done += 1
        cpu += float(summary.get("wall_time_s") or 0.0)
        wall += float(summary.get("elapsed_s") or 0.0)
    return {"points": points, "done": done, "cpu_s": cpu, "elapsed_s": wall}


def status() -> list[dict]:
    return [{"grid": g, "out": o} | table_status(g, o) for g, o, _ in STAGES]


def ship() -> None:
    """Copy the finished tables to dem/data/atlas with provenance; refuse an unfinished one."""
    from dem.provenance import record

    stages = status()
    for s in stages:
        if s["done"] != s["points"] or not (HERE / s["out"] / "atlas.csv").is_file():
            raise SystemExit(f"{s['grid']}: {s['done']} of {s['points']} points finished: not "
                             "shipped (run this script to finish it)")  # fmt: skip
    DATA.mkdir(parents=True, exist_ok=True)
    for grid, out, name in STAGES:
        for suffix in (".csv", ".json"):
            shutil.copyfile(HERE / out / f"atlas{suffix}", DATA / f"{name}{suffix}")
        shutil.copyfile(HERE / grid, DATA / grid)
    provenance = {
        "what": "the shipped atlas: dem atlas over validation/atlas's grids",
        "commands": [" ".join(command(g, o)) for g, o, _ in STAGES],
        "stages": stages,
        "cpu_hours": sum(s["cpu_s"] for s in stages) / 3600.0,
        "wall_hours_of_points": sum(s["elapsed_s"] for s in stages) / 3600.0,
        **record(),
    }
    (DATA / "provenance.json").write_text(json.dumps(provenance, indent=1, default=str) + "\n")
    print(f"shipped {len(STAGES)} tables to {DATA}")


def run() -> int:
    current: dict = {}

    def forward(signum, frame):
        current["stopped"] = signum
        if current.get("proc") is not None:
            current["proc"].send_signal(signum)

    signal.signal(signal.SIGTERM, forward)
    signal.signal(signal.SIGINT, forward)
    for grid, out, _ in STAGES:
        t0 = time.time()
        print(f"atlas stage {grid} -> {out}", flush=True)
        current["proc"] = subprocess.Popen(command(grid, out))
        code = current["proc"].wait()
        current["proc"] = None
        print(f"atlas stage {grid}: exit {code} after {time.time() - t0:.0f} s", flush=True)
        if "stopped" in current:
            return 128 + current["stopped"]
        s = table_status(grid, out)
        if s["done"] != s["points"]:
            print(f"atlas stage {grid}: {s['done']} of {s['points']} points finished; rerun "
                  "this script to retry the rest", flush=True)  # fmt: skip
            return 1
    ship()
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--status", action="store_true", help="print how far, and stop")
    parser.add_argument("--ship", action="store_true", help="copy the finished tables")
    args = parser.parse_args()
    if args.status:
        for s in status():
            print(json.dumps(s))
        return 0
    if args.ship:
        ship()
        return 0
    return run()


if __name__ == "__main__":
    sys.exit(main())
