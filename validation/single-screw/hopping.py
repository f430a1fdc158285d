"""The paper's screw hopping: Fig. 6 and Fig. 7 conditions against the point-mass model.

Regenerates hopping_fig6.csv, hopping_fig7.csv and hopping.png in this folder:

    .venv/bin/python validation/single-screw/hopping.py            # both, about 15 min, 2 cores
    .venv/bin/python validation/single-screw/hopping.py --part fig7
    .venv/bin/python validation/single-screw/hopping.py --figures  # redraw from the CSV files

One screw of cases/screw-trough (2.5 g, 8 spheres) lies along +x on head and tip
(run.lying_pose), linear contact k_n = 4e7 N/m per member, eps_n = 0, eps_t = 0.8, Coulomb-exact
tangential law. At every point k_t / k_n is fitted by dem.studies.calibrate.calibrate to the point
mass's landings at that drive, thrown in the lying pose (both contacts land together, as they
do in the run). Then

- rotation locked: the DEM twin of the point mass (the criterion, |error| <= 0.05);
- rotation free, same contact, same lying start: the screw may pitch and land on its head or
  tip first (information: how far a real screw departs from the point mass).

Each run: settle with the drive off, switch the drive on at phase 0, discard 40 cycles, measure
20 (dem.engine.simulation.measure_cycles; mean and standard error by
dem.physics.measure.conveying_velocity).
The dotted curve is the point mass whose landings never take more than Coulomb allows
(dem.pointmass.bounded).
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import sys
import time
from multiprocessing import Pool
from pathlib import Path

import numpy as np
import run as screw  # this folder's sliding study: the case, the pose, the time step

from dem import pointmass
from dem.engine.simulation import measure_cycles
from dem.kernels.rigid import quat_to_matrix
from dem.physics import measure
from dem.pointmass.bounded import coulomb_bounded_velocity
from dem.scene.case import load_case
from dem.studies import calibrate

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import header  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
#: The screw case as shipped when this was measured (2e9 Pa and 4e-6 s since 2026-11-26).
AS_MEASURED = {"contact.youngs_modulus": 5.0e8, "run.timestep": 8.0e-6}
GAMMAS = tuple(np.round(np.concatenate([np.arange(0.2, 1.0, 0.2), np.arange(1.1, 5.05, 0.15)]), 3))
FRICTIONS = (0.25, 0.35, 0.6)
ANGLES = tuple(range(10, 71, 5))
SETTLE, CYCLES = 40, 20
CONTACT = argparse.Namespace(stiffness=4.0e7, restitution_normal=0.0, tangential="coulomb")


def point_case(base, angle, friction, gamma, rotation):
    """cases/screw-trough at (phi, mu, Gamma), one screw, the study's contact."""
    return screw.make_case(base, angle, friction, gamma, CONTACT, rotation)


def with_kappa(case, kappa):
    """The case with k_t / k_n = kappa (zeta_t kept)."""
    return dataclasses.replace(
        case, contact=dataclasses.replace(case.contact, tangential_stiffness_ratio=kappa)
    )


def measure_screw(case):
    """v / (A omega cos phi) of the lying screw, its standard error, largest tilt (deg), dt."""
    sim = screw.lying_simulation(case)
    sim.settle()
    axis0 = quat_to_matrix(sim.bodies.q[0])[:, 0]
    per_cycle = measure_cycles(sim, CYCLES, settle_cycles=SETTLE)
    axis = quat_to_matrix(sim.bodies.q[0])[:, 0]
    tilt = float(np.degrees(np.arcsin(min(1.0, np.linalg.norm(np.cross(axis, axis0))))))
    d = case.drive
    stat = measure.conveying_velocity(per_cycle, scale=d.velocity_scale)
    return stat, tilt, sim.dt


def point(spec) -> dict:
    """One (phi, mu, Gamma) point: calibrate k_t on the lying pose, run locked and free."""
    angle, friction, gamma, eps_t = spec
    t0 = time.perf_counter()
    base = load_case(ROOT / "cases" / "screw-trough", AS_MEASURED)
    base = dataclasses.replace(
        base, material=dataclasses.replace(base.material, restitution_tangential=eps_t)
    )
    locked = point_case(base, angle, friction, gamma, False)
    q, _ = screw.lying_pose(locked.particles.grain)
    cal = calibrate.calibrate(locked, poses=np.array([q]))
    locked = with_kappa(locked, cal.kappa)
    stat, _, dt = measure_screw(locked)
    free = with_kappa(point_case(base, angle, friction, gamma, True), cal.kappa)
    free_stat, tilt, free_dt = measure_screw(free)
    pm = pointmass.velocity(gamma, angle, friction, eps_t=eps_t)
    row = {
        "angle": angle,
        "friction": friction,
        "throw_number": gamma,
        "eps_t": eps_t,
        "kappa": cal.kappa,
        "calibrated_eps_t": cal.eps_t,
        "reachable": cal.reachable,
        "landings": len(cal.impacts),
        "dem_velocity_norm": stat.norm,
        "dem_stderr": stat.norm_stderr,
        "pointmass_velocity_norm": pm.velocity_norm,
        "pointmass_coulomb_bounded": coulomb_bounded_velocity(gamma, angle, friction, eps_t),
        "regime": pm.regime,
        "dem_free_rotation": free_stat.norm,
        "free_rotation_stderr": free_stat.norm_stderr,
        "free_rotation_max_tilt_deg": tilt,
        "timestep": dt,
        "free_rotation_timestep": free_dt,
        "wall_time_s": round(time.perf_counter() - t0, 1),
    }
    print(
        f"phi {angle:4.1f} mu {friction:4.2f} Gamma {gamma:5.3f}: locked {stat.norm:+.4f} "
        f"free {free_stat.norm:+.4f} pm {pm.velocity_norm:+.4f} (kappa {cal.kappa:.4g}, "
        f"{row['wall_time_s']} s)",
        flush=True,
    )
    return row


def write_csv(rows, name):
    path = HERE / name
    with open(path, "w", newline="") as fh:
        header.write_csv_header(fh, "validation/single-screw/hopping.py")
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {path}")


def read_csv(name):
    with open(HERE / name) as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    out = []
    for r in rows:
        out.append({k: (v == "True" if v in ("True", "False") else
                        (float(v) if k != "regime" else v)) for k, v in r.items()})  # fmt: skip
    return out


def plot(rows6, rows7, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
    fine = np.linspace(0.1, 5.0, 400)
    axes[0].plot(fine, [pointmass.velocity(g, 25.0, 0.35).velocity_norm for g in fine], "k",
                 lw=1, label="point mass, eps_t = 0.8")  # fmt: skip
    g6 = [r["throw_number"] for r in rows6]
    axes[0].plot(g6, [r["pointmass_coulomb_bounded"] for r in rows6], ":k", lw=1,
                 label="point mass, landing loss <= Coulomb")  # fmt: skip
    axes[0].plot(g6, [r["dem_velocity_norm"] for r in rows6], "o", color="C0", mfc="none", ms=4,
                 label="screw, rotation locked")  # fmt: skip
    axes[0].plot(g6, [r["dem_free_rotation"] for r in rows6], "x", color="C3", ms=4,
                 label="screw, rotation free")  # fmt: skip
    axes[0].set_xlabel("throw number Gamma")
    axes[0].set_ylabel("v / (A omega cos phi)")
    axes[0].set_title("phi = 25 deg, mu = 0.35 (Fig. 6)")
    fine = np.linspace(5.0, 75.0, 200)
    for f, color in zip(FRICTIONS, ("C0", "C1", "C2"), strict=True):
        axes[1].plot(fine, [pointmass.velocity(1.8, a, f).velocity_norm for a in fine],
                     color=color, lw=1, label=f"point mass, mu = {f}")  # fmt: skip
        sel = [r for r in rows7 if r["friction"] == f]
        axes[1].plot([r["angle"] for r in sel], [r["dem_velocity_norm"] for r in sel], "o",
                     color=color, mfc="none", ms=4, label="locked")  # fmt: skip
        axes[1].plot([r["angle"] for r in sel], [r["dem_free_rotation"] for r in sel], "x",
                     color=color, ms=4, label="free")  # fmt: skip
    axes[1].set_xlabel("vibration angle phi (deg)")
    axes[1].set_title("Gamma = 1.8, eps_t = 0.8 (Fig. 7)")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
    fig.suptitle("One screw lying on head and tip (k_n = 4e7 N/m per member, eps_n = 0), "
                 "k_t calibrated at each point")  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", choices=("fig6", "fig7", "both"), default="both")
    parser.add_argument("--figures", action="store_true", help="only redraw from the CSV files")
    args = parser.parse_args(argv)
    parts = {
        "fig6": [(25.0, 0.35, float(g), 0.8) for g in GAMMAS],
        "fig7": [(float(a), f, 1.8, 0.8) for f in FRICTIONS for a in ANGLES],
    }
    if not args.figures:
        for name, specs in parts.items():
            if args.part in (name, "both"):
                with Pool(2) as pool:
                    write_csv(pool.map(point, specs, chunksize=1), f"hopping_{name}.csv")
    plot(read_csv("hopping_fig6.csv"), read_csv("hopping_fig7.csv"), HERE / "hopping.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
