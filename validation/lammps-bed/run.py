"""dem against LAMMPS on the sphere bed: the same case, the same fill, fills from two seeds.

    nice -n 10 .venv/bin/python validation/lammps-bed/run.py            # seeds 1 and 2
    nice -n 10 .venv/bin/python validation/lammps-bed/run.py --beds screws  # keeps the rest
    .venv/bin/python validation/lammps-bed/run.py --report-only         # the table again

cases/sphere-bed (1500 spheres of 2 mm, Hertz at E = 2e9 Pa, 60 Hz, 25 deg, Gamma 3.06) and
cases/screw-trough (200 screws of 2.5 g: rigid bodies in LAMMPS, fix rigid/small), and
cases/u-trough and cases/v-trough (150 screws in mesh pans: plane walls in LAMMPS) with
``contact.tangential = "coulomb"`` (the law LAMMPS's mindlin expresses, dem.io.lammps.contact) and
10 settling cycles instead of "auto", so both engines measure the same 20 cycles, at three
drives (:data:`DRIVES`: as shipped; 40 deg, at A = 0.3 mm (Gamma 2.8) for the spheres and at
the case's Gamma 1.8 for the screws; uphill on a 3 deg incline; the pans as shipped only,
:data:`BED_DRIVES`). Per seed:
``dem run`` on one thread, then ``dem export lammps ... --run`` on one rank from dem's settled fill
of the same seed, alternating which engine goes first. Each run's error bar is its correlated
standard error over the 20 per-cycle means; the seeds are pooled as independent replicas
(validation/_lib/replicas). Written: results.json (every run, the load average beside it, the
versions), and the table of README.md.
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

#: The beds: 1500 spheres, 200 screws of 2.5 g (fix rigid/small bodies in LAMMPS), and 150 screws
#: in the U and V pans of cases/u-trough and cases/v-trough (meshes in dem, the intersections of
#: their face planes in LAMMPS, dem.io.lammps.walls).
CASES = {"spheres": ROOT / "cases" / "sphere-bed", "screws": ROOT / "cases" / "screw-trough",
         "u-pan": ROOT / "cases" / "u-trough", "v-pan": ROOT / "cases" / "v-trough"}  # fmt: skip
#: The drives each bed runs at (the pans: as shipped).
BED_DRIVES = {"u-pan": ("shipped",), "v-pan": ("shipped",)}
SETS = ["contact.tangential=coulomb", "run.settle_cycles=10"]
#: Three drives: the shipped one, 40 deg at a smaller amplitude (Gamma 2.8), conveying uphill.
DRIVES = {
    "shipped": [],
    "steep": ["drive.angle=40"],
    "uphill": ["trough.inclination=3"],
}
DEM = [sys.executable, "-m", "dem.cli"]


#: The steep drive's amplitude for the sphere bed (its case gives A; the screws' gives Gamma = 1.8,
#: which the steep drive keeps).
STEEP_SPHERES = ["drive.amplitude=0.0003"]


def _sets(kind: str, seed: int, drive: str) -> list[str]:
    extra = STEEP_SPHERES if (kind, drive) == ("spheres", "steep") else []
    out = []
    for s in [*SETS, *DRIVES[drive], *extra, f"run.seed={seed}"]:
        out += ["--set", s]
    return out


def run_dem(kind: str, seed: int, drive: str, work: Path) -> dict:
    out = work / f"dem-{kind}-{drive}-{seed}"
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    subprocess.run([*DEM, "run", str(CASES[kind]), "--out", str(out), "--no-frames",
                    "--threads", "1",
                    *_sets(kind, seed, drive)], check=True, env=env)  # fmt: skip
    return json.loads((out / "summary.json").read_text())


def run_lammps(kind: str, seed: int, drive: str, work: Path) -> dict:
    out = work / f"lammps-{kind}-{drive}-{seed}"
    subprocess.run([*DEM, "export", "lammps", str(CASES[kind]), str(out), "--run", "--ranks", "1",
                    *_sets(kind, seed, drive)], check=True)  # fmt: skip
    return json.loads((out / "summary.json").read_text())


KEEP = ("mean_velocity", "mean_velocity_stderr", "mean_velocity_norm", "mean_velocity_norm_stderr",
        "per_cycle_velocity", "particle_steps_per_s", "wall_time_s", "timestep", "steps",
        "engine_version")  # fmt: skip


def report(results: dict) -> list[str]:
    rows = ["| bed | drive | engine | seed | v (m/s) | v_norm | particle-steps/s (1 core) | load |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |"]  # fmt: skip
    notes = []
    for kind in CASES:
        for drive in DRIVES:
            pooled = {}
            for engine in ("dem", "lammps"):
                runs = [r for r in results["runs"] if r["engine"] == engine
                        and r["drive"] == drive and r["kind"] == kind]  # fmt: skip
                for r in runs:
                    v = f"{r['mean_velocity']:.4f} +- {r['mean_velocity_stderr']:.4f}"
                    rows.append(f"| {kind} | {drive} | {engine} | {r['seed']} | {v} | "
                                f"{r['mean_velocity_norm']:.4f} | "
                                f"{r['particle_steps_per_s']:.3g} | "
                                f"{r['load_average']:.2f} |")  # fmt: skip
                if runs:
                    pooled[engine] = replicas.replica_mean([r["mean_velocity"] for r in runs])
                    m, se = pooled[engine]
                    rows.append(f"| {kind} | {drive} | {engine} | pooled ({len(runs)}) | "
                                f"{m:.4f} +- {se:.4f} | | | |")  # fmt: skip
            if len(pooled) == 2:
                d = replicas.difference(*pooled["dem"], *pooled["lammps"])
                pct, sigma = d["percent_of_liggghts"], d["sigma"]
                notes.append(f"{kind}, {drive}: dem - LAMMPS = {pct:+.2f} % of LAMMPS's v, "
                             f"{sigma:+.2f} combined standard errors")  # fmt: skip
    return [*rows, "", *notes]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--beds", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--drives", nargs="+", default=list(DRIVES), choices=list(DRIVES))
    ap.add_argument("--report-only", action="store_true")
    args = ap.parse_args(argv)
    path = HERE / "results.json"
    results = json.loads(path.read_text()) if path.exists() else {"runs": []}
    for r in results["runs"]:  # runs recorded before the screws were added
        r.setdefault("drive", "shipped")
        r.setdefault("kind", "spheres")
    if not args.report_only:
        command = " ".join(["validation/lammps-bed/run.py", *sys.argv[1:]])
        kept = [r for r in results["runs"]
                if r["drive"] not in args.drives or r["kind"] not in args.beds]  # fmt: skip
        results = {"cases": {k: str(c.relative_to(ROOT)) for k, c in CASES.items()},
                   "sets": SETS, "drives": DRIVES, "runs": kept, "command": command}  # fmt: skip
        with tempfile.TemporaryDirectory() as tmp:
            trials = [(b, d, seed) for b in args.beds for d in args.drives for seed in args.seeds
                      if d in BED_DRIVES.get(b, DRIVES)]  # fmt: skip
            for k, (kind, drive, seed) in enumerate(trials):
                order = (("dem", run_dem), ("lammps", run_lammps))
                for engine, fn in order if k % 2 == 0 else order[::-1]:
                    s = fn(kind, seed, drive, Path(tmp))
                    row = {"engine": engine, "kind": kind, "drive": drive, "seed": seed,
                           **{key: s.get(key) for key in KEEP},
                           "load_average": os.getloadavg()[0],
                           "dem_commit": provenance.record()["git_commit"]}  # fmt: skip
                    results["runs"].append(row)
                    path.write_text(json.dumps(results, indent=1) + "\n")  # after every run
                    print(json.dumps({k: v for k, v in row.items() if k != "per_cycle_velocity"}))
        results["provenance"] = provenance.record()
        path.write_text(json.dumps(results, indent=1) + "\n")
    print("\n".join(report(results)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
