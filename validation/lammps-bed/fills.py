"""LAMMPS's own fill against dem's: the same bed poured by LAMMPS or filled by dem, run in LAMMPS.

    nice -n 10 .venv/bin/python validation/lammps-bed/fills.py             # seeds 1-3
    .venv/bin/python validation/lammps-bed/fills.py --report-only
    nice -n 10 .venv/bin/python validation/lammps-bed/fills.py --packing 1 2   # the packings

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


def _atoms(path: Path):
    """(diameter, z) of every atom in a LAMMPS data file (atom_style sphere)."""
    import numpy as np

    lines = path.read_text().split("\n")
    start = next(k for k, line in enumerate(lines) if line.startswith("Atoms")) + 2
    rows = []
    for line in lines[start:]:
        if not line.strip():
            break
        rows.append([float(w) for w in line.split()[:7]])
    a = np.array(rows)
    return a[:, 2], a[:, 6]


def packing(bed: str, seed: int, work: Path, below: float = 0.015) -> dict:
    """Each method's settled fill before the drive: the spheres' mean height and their solid
    fraction below ``below`` m over the section, from dem's data.fill and from the pour deck
    stopped where the drive would start (``write_data``)."""
    import math

    from dem.io.lammps.launcher import find_lammps
    from dem.scene.case import load_case

    case, extra = BEDS[bed]
    trough = load_case(case).trough
    sets = []
    for s in [*SETS, *extra, f"run.seed={seed}"]:
        sets += ["--set", s]
    out = {"seed": seed, "below_m": below}
    for fill in ("dem", "lammps"):
        d = work / f"pack-{bed}-{fill}-{seed}"
        subprocess.run([*DEM, "export", "lammps", str(case), str(d), "--fill", fill, *sets],
                       check=True, capture_output=True)  # fmt: skip
        name = "data.fill"
        if fill == "lammps":
            deck = (d / "in.lammps").read_text()
            (d / "in.lammps").write_text(
                deck.replace("reset_timestep 0\n", "write_data poured.data\nquit\n", 1)
            )
            subprocess.run([find_lammps()[0], "-in", "in.lammps", "-log", "none", "-screen",
                            "none"], cwd=d, check=True)  # fmt: skip
            name = "poured.data"
        diameter, z = _atoms(d / name)
        solid = float(sum(math.pi / 6.0 * diameter[z < below] ** 3))
        area = trough.length * trough.width
        out[fill] = {"mean_z_m": float(z.mean()), "solid_fraction_below": solid / (area * below)}
    return out


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
    for pk in results.get("packing", []):
        a, b = pk["dem"], pk["lammps"]
        notes.append(f"spheres, seed {pk['seed']}, settled before the drive: mean height "
                     f"{a['mean_z_m'] * 1e3:.2f} mm (dem's fill) and {b['mean_z_m'] * 1e3:.2f} "
                     f"mm (LAMMPS's pour); solid fraction below {pk['below_m'] * 1e3:g} mm "
                     f"{a['solid_fraction_below']:.3f} and "
                     f"{b['solid_fraction_below']:.3f}")  # fmt: skip
    return [*rows, "", *notes]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--beds", nargs="+", default=["screws"], choices=list(BEDS))
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--packing", type=int, nargs="+", metavar="SEED",
                    help="measure both fills' packing (spheres) at these seeds")  # fmt: skip
    args = ap.parse_args(argv)
    results = json.loads(PATH.read_text()) if PATH.exists() else {"runs": []}
    if args.packing:
        with tempfile.TemporaryDirectory() as tmp:
            results["packing"] = [packing("spheres", seed, Path(tmp)) for seed in args.packing]
        PATH.write_text(json.dumps(results, indent=1) + "\n")
    elif not args.report_only:
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
