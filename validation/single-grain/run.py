"""Sliding block (one sphere, rotation locked) against the point-mass model, Gamma < 1.

Regenerates results.csv and velocity.png in this folder:

    .venv/bin/python validation/single-grain/run.py

Base case: cases/single-sphere (r = 2 mm, rho = 7800, linear contact, rotation locked), with
k_n = 4e6 N/m and eps_n = 0.5 (see README.md for why), swept over phi in {15, 25, 45} deg,
mu in {0.25, 0.35, 0.6} and Gamma in [0.2, 0.95] (no flight: the point mass never leaves the
floor, so eps_n and eps_t do not enter it).
"""

import argparse
import csv
import dataclasses
import time
from pathlib import Path

import numpy as np

from dem import pointmass
from dem.case import load_case
from dem.runner import run_case

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
ANGLES = (15.0, 25.0, 45.0)
FRICTIONS = (0.25, 0.35, 0.6)
THROW_NUMBERS = tuple(np.round(np.linspace(0.2, 0.95, 7), 4))
STIFFNESS = 4.0e6
RESTITUTION_NORMAL = 0.5


def make_case(
    base, angle, friction, throw_number, stiffness, restitution_normal, settle_cycles, cycles
):
    """The base case at (phi, mu, Gamma) with the validation contact."""
    return dataclasses.replace(
        base.with_drive(angle=angle, throw_number=throw_number),
        material=dataclasses.replace(
            base.material, friction=friction, restitution_normal=restitution_normal
        ),
        contact=dataclasses.replace(base.contact, stiffness=stiffness),
        run=dataclasses.replace(base.run, settle_cycles=settle_cycles, cycles=cycles),
    )


def sweep(stiffness, restitution_normal, settle_cycles, cycles, out_csv):
    base = load_case(ROOT / "cases" / "single-sphere")
    rows = []
    for angle in ANGLES:
        for friction in FRICTIONS:
            for gamma in THROW_NUMBERS:
                case = make_case(
                    base, angle, friction, float(gamma), stiffness, restitution_normal,
                    settle_cycles, cycles,
                )  # fmt: skip
                t0 = time.perf_counter()
                s = run_case(
                    case, HERE / "output", progress=False, threads=1, overwrite=True, frames=False
                )
                pm = pointmass.velocity(throw_number=float(gamma), angle=angle, friction=friction)
                dem_v, pm_v = s["mean_velocity_norm"], pm.velocity_norm
                rows.append(
                    {
                        "angle": angle,
                        "friction": friction,
                        "throw_number": float(gamma),
                        "dem_velocity_norm": dem_v,
                        "dem_velocity_norm_stderr": s["mean_velocity_norm_stderr"],
                        "pointmass_velocity_norm": pm_v,
                        "regime": pm.regime,
                        "abs_error": dem_v - pm_v,
                        "rel_error": (dem_v - pm_v) / pm_v if abs(pm_v) > 0.02 else "",
                        "timestep": s["timestep"],
                        "wall_time_s": round(time.perf_counter() - t0, 2),
                    }
                )
                r = rows[-1]
                print(
                    f"phi={angle:4.0f} mu={friction:4.2f} Gamma={gamma:5.3f} "
                    f"dem={dem_v:+.5f} pm={pm_v:+.5f} ({pm.regime}) err={r['abs_error']:+.5f}",
                    flush=True,
                )
    with open(out_csv, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return rows


def plot(rows, out_png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(ANGLES), figsize=(13, 4), sharey=True)
    fine = np.linspace(0.15, 0.99, 120)
    for ax, angle in zip(axes, ANGLES, strict=True):
        for friction, color in zip(FRICTIONS, ("C0", "C1", "C2"), strict=True):
            pm = [pointmass.velocity(throw_number=g, angle=angle, friction=friction).velocity_norm
                  for g in fine]  # fmt: skip
            ax.plot(fine, pm, color=color, label=f"point mass, mu = {friction}")
            sel = [r for r in rows if r["angle"] == angle and r["friction"] == friction]
            ax.plot(
                [r["throw_number"] for r in sel],
                [r["dem_velocity_norm"] for r in sel],
                "o",
                color=color,
                mfc="none",
                label=f"DEM block, mu = {friction}",
            )
        ax.set_title(f"phi = {angle:g} deg")
        ax.set_xlabel("throw number Gamma")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("v / (A omega cos phi)")
    axes[0].legend(fontsize=7)
    fig.suptitle("Sliding block (DEM sphere, rotation locked) vs point mass, no flight")
    fig.tight_layout()
    fig.savefig(out_png, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--stiffness", type=float, default=STIFFNESS)
    parser.add_argument("--restitution-normal", type=float, default=RESTITUTION_NORMAL)
    parser.add_argument("--settle-cycles", type=int, default=60, help="driven cycles not measured")
    parser.add_argument("--cycles", type=int, default=10, help="measured cycles")
    parser.add_argument("--out", default="results.csv")
    args = parser.parse_args()
    rows = sweep(
        args.stiffness, args.restitution_normal, args.settle_cycles, args.cycles, HERE / args.out
    )
    if args.out == "results.csv":
        plot(rows, HERE / "velocity.png")
    rel = [abs(r["rel_error"]) for r in rows if r["rel_error"] != ""]
    absolute = [abs(r["abs_error"]) for r in rows]
    print(
        f"max |relative error| (|v_pm| > 0.02) {max(rel):.4f}, max |abs error| {max(absolute):.5f}"
    )


if __name__ == "__main__":
    main()
