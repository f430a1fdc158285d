"""Outcome map of the DEM time step: stable and accurate, stable but inaccurate, or unstable.

Regenerates dem_timestep.csv and dem_timestep.png in this folder:

    .venv/bin/python validation/stability/dem_timestep.py            # about 2 min on 2 cores
    .venv/bin/python validation/stability/dem_timestep.py --figures  # redraw from the CSV

Small beds of the shipped grains (60 spheres of cases/sphere-bed in a 30 x 20 mm section; 20
screws of cases/screw-trough in 60 x 40 mm), each run with dt = f x the stability limit that
``run.timestep`` is checked against (dem.scene.timestep.timestep_for: 0.3 of the critical step
2 / omega_0 of the stiffest single contact), f from 0.1 to 10, built with
``check_limit=False`` so that steps beyond the limit run at all. Configurations: spheres under
Hertz-Mindlin with the Coulomb and the LIGGGHTS tangential law, spheres under the linear law
(k_n = 2e4 N/m, about the Hertz tangent stiffness of these impacts), screws with rotation free
and locked. Each run fills, settles with the drive off, drives 4 cycles unmeasured and measures
16 (dem.engine.simulation.measure_cycles). Outcome:

- unstable: the engine's guard stopped the run (dem.errors.SimulationError; its message is kept);
- inaccurate: it ran, but v / (A omega cos phi) differs from the f = 0.1 run by more than 0.02
  and by more than 3 combined standard errors (a random bed's 16-cycle mean scatters by about
  0.01 from one trajectory to the next: a smaller difference is not the time step's);
- accurate: otherwise. ``state_finite`` says whether the state the guard stopped held
  non-finite values; a run writes its outputs only after the guard's check.

The map shows whether the limit is the real one: every f <= 1 should run, the single-contact
critical step is f = 1 / 0.3 = 3.3, and the guard should stop the runs that blow up before a
non-finite value reaches any output.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import sys
import time
from multiprocessing import Pool
from pathlib import Path

import numpy as np

from dem.engine import setup
from dem.engine.simulation import measure_cycles
from dem.errors import SimulationError
from dem.physics import measure
from dem.scene.case import load_case
from dem.scene.timestep import timestep_for

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import header  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
FACTORS = (0.1, 0.3, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0)
TOLERANCE = 0.02
CONFIGS = ("spheres hertz coulomb", "spheres hertz liggghts", "spheres linear coulomb",
           "screws rotation free", "screws rotation locked")  # fmt: skip


def config_case(name: str):
    """The small bed of one configuration (drive and material as shipped)."""
    if name.startswith("spheres"):
        case = load_case(ROOT / "validation" / "liggghts-bulk" / "sphere-bed-5e7")
        trough = dataclasses.replace(case.trough, length=0.03, width=0.02)
        particles = dataclasses.replace(case.particles, count=60)
        case = dataclasses.replace(case, trough=trough, particles=particles)
        if "liggghts" in name:
            case = case.with_tangential("liggghts")
        if "linear" in name:
            contact = dataclasses.replace(
                case.contact, model="linear", stiffness=2.0e4, youngs_modulus=None
            )
            case = dataclasses.replace(case, contact=contact)
    else:
        case = load_case(
            ROOT / "cases" / "screw-trough",  # as shipped when measured
            {"contact.youngs_modulus": 5.0e8, "run.timestep": 8.0e-6},
        )
        trough = dataclasses.replace(case.trough, length=0.06, width=0.04)
        particles = dataclasses.replace(case.particles, count=20, rotation="free" in name)
        case = dataclasses.replace(case, trough=trough, particles=particles)
    return dataclasses.replace(case, run=dataclasses.replace(case.run, settle_cycles=4, cycles=16))


def run_point(spec) -> dict:
    """One (configuration, f) run: outcome, velocity, wall time, the guard's message."""
    name, factor = spec
    case = config_case(name)
    limit = timestep_for(case).limit
    t0 = time.perf_counter()
    row = {"config": name, "factor": factor, "timestep": factor * limit, "limit": limit}
    try:
        sim = setup.from_case(case, timestep=factor * limit, check_limit=False)
        sim.settle()
        per_cycle = measure_cycles(sim, case.run.cycles, settle_cycles=case.run.settle_cycles)
        d = case.drive
        stat = measure.conveying_velocity(per_cycle, scale=d.velocity_scale)
        row |= {"velocity_norm": stat.norm, "stderr": stat.norm_stderr, "stopped_by_guard": False,
                "message": "", "state_finite": bool(np.isfinite(sim.spheres.x).all())}  # fmt: skip
    except SimulationError as err:
        state = locals().get("sim")
        finite = bool(np.isfinite(state.spheres.x).all()) if state is not None else True
        row |= {"velocity_norm": float("nan"), "stderr": float("nan"), "stopped_by_guard": True,
                "message": str(err).split(":")[0], "state_finite": finite}  # fmt: skip
    row["wall_time_s"] = round(time.perf_counter() - t0, 2)
    print(f"{name:24s} f = {factor:4.2f}: "
          + (f"guard: {row['message']}" if row["stopped_by_guard"]
             else f"v_norm {row['velocity_norm']:.4f}") + f" ({row['wall_time_s']} s)",
          flush=True)  # fmt: skip
    return row


def classify(rows: list[dict]) -> None:
    """Add ``outcome`` and ``error`` (against the configuration's f = 0.1 run) to each row."""
    for name in CONFIGS:
        sel = [r for r in rows if r["config"] == name]
        ref = next(r for r in sel if r["factor"] == min(FACTORS))
        for r in sel:
            if r["stopped_by_guard"]:
                r["outcome"], r["error"] = "unstable", float("nan")
                continue
            r["error"] = r["velocity_norm"] - ref["velocity_norm"]
            noise = 3.0 * math.hypot(r["stderr"], ref["stderr"])
            r["outcome"] = "accurate" if abs(r["error"]) <= max(TOLERANCE, noise) else "inaccurate"


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colors = {"accurate": "C2", "inaccurate": "C1", "unstable": "C3"}
    fig, ax = plt.subplots(figsize=(9, 3.8))
    for i, name in enumerate(CONFIGS):
        for r in (r for r in rows if r["config"] == name):
            ax.scatter(r["factor"], i, s=160, color=colors[r["outcome"]], marker="s")
    for outcome, color in colors.items():
        ax.scatter([], [], color=color, marker="s", label=outcome)
    ax.axvline(1.0, color="k", lw=1, ls="--")
    ax.set_yticks(range(len(CONFIGS)), CONFIGS)
    ax.set_xscale("log")
    ax.set_xticks(FACTORS, [f"{f:g}" for f in FACTORS])
    ax.axvline(1.0 / 0.3, color="k", lw=1, ls=":")
    ax.set_xlabel("dt / stability limit checked at load (dashed: the limit; dotted: 2 / omega_0)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(f"accurate: v / (A omega cos phi) within {TOLERANCE} (or 3 standard errors) of "
                 "dt = 0.1 x limit", fontsize=10)  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def read_rows(path: Path) -> list[dict]:
    """Rows of dem_timestep.csv with their numbers and flags converted (for ``--figures``)."""
    with open(path) as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    for r in rows:
        r["factor"] = float(r["factor"])
    return rows


def main() -> int:
    import sys

    if "--figures" in sys.argv[1:]:
        plot(read_rows(HERE / "dem_timestep.csv"), HERE / "dem_timestep.png")
        return 0
    specs = [(name, f) for name in CONFIGS for f in FACTORS]
    with Pool(2) as pool:
        rows = pool.map(run_point, specs, chunksize=1)
    classify(rows)
    path = HERE / "dem_timestep.csv"
    with open(path, "w", newline="") as fh:
        header.write_csv_header(fh, "validation/stability/dem_timestep.py")
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, HERE / "dem_timestep.png")
    print(f"wrote {path} and dem_timestep.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
