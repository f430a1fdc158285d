"""LAMMPS's own fill against dem's: the same bed poured by LAMMPS or filled by dem, run in LAMMPS.

    nice -n 10 .venv/bin/python validation/lammps-bed/fills.py             # seeds 1-3
    .venv/bin/python validation/lammps-bed/fills.py --report-only

cases/screw-trough at 100 screws (and cases/sphere-bed with ``--beds spheres screws``), under
``contact.tangential = "coulomb"`` with 10 settling and 20 measured cycles: ``dem export lammps
... --run`` with ``--fill dem`` (dem fills and settles, the deck starts from ``data.fill``) and
with ``--fill lammps`` (the deck pours and settles its own, ``dem.io.lammps.pour``), one rank,
alternating which goes first. Each run's error bar is its correlated standard error over the
per-cycle means; the seeds (each fill's ``run.seed``) are pooled as independent replicas,
which is the error bar that covers a refill (validation/bulk-convergence: one screw bed's fills
differ by more than a run's own error). Written: results_fills.json and the table it prints.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))

from dem import provenance  # noqa: E402
from validation._lib import replicas  # noqa: E402

BEDS = {
    "screws": (ROOT / "cases" / "screw-trough", ["particles.count=100"]),
    "spheres": (ROOT / "cases" / "sphere-bed", []),
}
SETS = ["contact.tangential=coulomb", "run.settle_cycles=10"]
DEM = [sys.executable, "-m", "dem.cli"]
PATH = HERE / "results_fills.json"


def run(bed: str, fill: str, seed: int, work: Path) -> dict:
    case, extra = BEDS[bed]
    out = work / f"{bed}-{fill}-{seed}"
    sets = []
    for s in [*SETS, *extra, f"run.seed={seed}"]:
        sets += ["--set", s]
    subprocess.run([*DEM, "export", "lammps", str(case), str(out), "--run", "--fill", fill,
                    *sets], check=True)  # fmt: skip
    s = json.loads((out / "summary.json").read_text())
    return {"bed": bed, "fill": fill, "seed": seed, "mean_velocity": s["mean_velocity"],
            "mean_velocity_stderr": s["mean_velocity_stderr"], "wall_time_s": s["wall_time_s"],
            "load_average": os.getloadavg()[0]}  # fmt: skip


def report(results: dict) -> list[str]:
    rows = ["| bed | fill | seeds | v (m/s), each seed | pooled v (m/s) |",
            "| --- | --- | --- | --- | --- |"]  # fmt: skip
    notes = []
    for bed in BEDS:
        pooled = {}
        for fill in ("dem", "lammps"):
            runs = [r for r in results["runs"] if (r["bed"], r["fill"]) == (bed, fill)]
            if not runs:
                continue
            pooled[fill] = replicas.replica_mean([r["mean_velocity"] for r in runs])
            each = ", ".join(f"{r['mean_velocity']:.4f} +- {r['mean_velocity_stderr']:.4f}"
                             for r in runs)  # fmt: skip
            m, se = pooled[fill]
            rows.append(f"| {bed} | {fill} | {len(runs)} | {each} | {m:.4f} +- {se:.4f} |")
        if len(pooled) == 2:
            d = replicas.difference(*pooled["lammps"], *pooled["dem"])
            notes.append(f"{bed}: LAMMPS's fill - dem's = {d['percent_of_liggghts']:+.2f} % of "
                         f"dem's fill's v, {d['sigma']:+.2f} combined standard errors")  # fmt: skip
    return [*rows, "", *notes]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--beds", nargs="+", default=["screws"], choices=list(BEDS))
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--report-only", action="store_true")
    args = ap.parse_args(argv)
    results = json.loads(PATH.read_text()) if PATH.exists() else {"runs": []}
    if not args.report_only:
        kept = [r for r in results["runs"]
                if r["bed"] not in args.beds or r["seed"] not in args.seeds]  # fmt: skip
        results = {"command": " ".join(["validation/lammps-bed/fills.py", *sys.argv[1:]]),
                   "sets": SETS, "beds": {k: [str(c.relative_to(ROOT)), e]
                                          for k, (c, e) in BEDS.items()},
                   "runs": kept}  # fmt: skip
        with tempfile.TemporaryDirectory() as tmp:
            trials = [(b, s) for b in args.beds for s in args.seeds]
            for k, (bed, seed) in enumerate(trials):
                fills = ("dem", "lammps") if k % 2 == 0 else ("lammps", "dem")
                for fill in fills:
                    results["runs"].append(run(bed, fill, seed, Path(tmp)))
                    PATH.write_text(json.dumps(results, indent=1) + "\n")
                    print(json.dumps(results["runs"][-1]))
        results["provenance"] = provenance.record()
        PATH.write_text(json.dumps(results, indent=1) + "\n")
    print("\n".join(report(results)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
