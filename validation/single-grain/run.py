"""One DEM grain (a sphere, rotation locked: a block) against the point-mass model.

Regenerates the CSV files and figures of this folder (README.md says what each shows):

    .venv/bin/python validation/single-grain/run.py sliding     # Gamma < 1, 126 points, ~14 min
    .venv/bin/python validation/single-grain/run.py stiffness   # error against k_n, ~4 min
    .venv/bin/python validation/single-grain/run.py hopping     # Fig. 6 and 7 conditions, ~6 min
    .venv/bin/python validation/single-grain/run.py all
    .venv/bin/python validation/single-grain/run.py figures     # redraw from the CSV files

Base case: cases/single-sphere as shipped (r = 2 mm, rho = 7800, linear k_n = 4e6 N/m,
eps_n = 0, eps_t = 0.8, tangential = "coulomb" with k_t / k_n from eps_t, rotation locked).
The block is placed at rest on the floor (dem.engine.setup.from_grains) and measured over whole
drive cycles (measure_cycles): the public library, no private copy of the run loop.
"""

import argparse
import csv
import dataclasses
import math
import sys
import time
from multiprocessing import Pool
from pathlib import Path

import numpy as np

from dem import pointmass
from dem.config import GRAVITY
from dem.engine import setup
from dem.engine.simulation import measure_cycles
from dem.physics.measure import conveying_velocity
from dem.pointmass.bounded import coulomb_bounded_velocity
from dem.scene.case import load_case
from dem.studies import calibrate

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import header  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
ANGLES = (15.0, 25.0, 45.0)
FRICTIONS = (0.25, 0.35, 0.6)
THROW_NUMBERS = tuple(np.round(np.linspace(0.2, 0.95, 7), 4))


def base_case():
    return load_case(ROOT / "cases" / "single-sphere")


def variant(case, *, angle=None, throw_number=None, friction=None, stiffness=None,
            eps_t=None, tangential=None, kappa=None, cycles=20, settle=40):  # fmt: skip
    """The case with another drive, friction, stiffness, eps_t or tangential law."""
    c = case.with_drive(
        angle=angle if angle is not None else case.drive.angle,
        throw_number=throw_number if throw_number is not None else case.drive.throw_number,
    )
    mat = dataclasses.replace(
        c.material,
        friction=c.material.friction if friction is None else friction,
        restitution_tangential=c.material.restitution_tangential if eps_t is None else eps_t,
    )
    contact = c.contact
    if stiffness is not None:
        contact = dataclasses.replace(contact, stiffness=stiffness)
    if tangential is not None:
        contact = dataclasses.replace(
            contact,
            tangential=tangential,
            tangential_damping_ratio=None,
            tangential_stiffness_ratio=2 / 7 if tangential == "liggghts" else None,
        )
    if kappa is not None:
        contact = dataclasses.replace(contact, tangential_stiffness_ratio=kappa)
    run = dataclasses.replace(c.run, cycles=cycles, settle_cycles=settle)
    return dataclasses.replace(c, material=mat, contact=contact, run=run)


def block_velocity(case) -> dict:
    """v / (A omega cos phi) of the block (mean and standard error over measured cycles)."""
    r, k = case.particles.radius, case.contact.stiffness
    mass = case.material.density * 4 / 3 * math.pi * r**3
    z = r - mass * GRAVITY / k
    t0 = time.perf_counter()
    sim = setup.from_grains(case, [[0.5 * case.trough.length, 0.0, z]])
    per_cycle = measure_cycles(sim, case.run.cycles, settle_cycles=case.run.settle_cycles)
    d, m = case.drive, case.material
    v = conveying_velocity(per_cycle, scale=d.velocity_scale)
    pm = pointmass.velocity(
        d.throw_number, d.angle, m.friction, case.trough.inclination,
        m.restitution_tangential, m.restitution_normal,
    )  # fmt: skip
    return {
        "angle": d.angle,
        "friction": m.friction,
        "throw_number": d.throw_number,
        "eps_t": m.restitution_tangential,
        "stiffness": k,
        "tangential": case.contact.tangential,
        "kappa": case.contact.tangential_stiffness_ratio,
        "dem_velocity_norm": v.norm,
        "dem_stderr": v.norm_stderr,
        "pointmass_velocity_norm": pm.velocity_norm,
        "regime": pm.regime,
        "timestep": sim.dt,
        "wall_time_s": round(time.perf_counter() - t0, 2),
    }


def calibrated(case) -> tuple:
    """The case with k_t / k_n fitted by dem calibrate's fit; and the fit."""
    cal = calibrate.calibrate(case)
    return variant(case, kappa=cal.kappa), cal


def _calibrated_row(case):
    c, cal = calibrated(case)
    row = block_velocity(c)
    row.update(calibrated_eps_t=cal.eps_t, reachable=cal.reachable, landings=len(cal.impacts))
    d, m = case.drive, case.material
    row["pointmass_coulomb_bounded"] = coulomb_bounded_velocity(
        d.throw_number, d.angle, m.friction, m.restitution_tangential
    )
    return row


def write_csv(rows, name):
    path = HERE / name
    with open(path, "w", newline="") as fh:
        header.write_csv_header(fh)
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {path}")


def pool_map(func, cases):
    with Pool(2) as pool:
        return pool.map(func, cases)


# --- studies -------------------------------------------------------------------------------------


def sliding():
    """Gamma < 1: 63 points, both tangential conventions."""
    base = base_case()
    cases = [
        variant(base, angle=a, friction=f, throw_number=float(g), tangential=t)
        for t in ("coulomb", "liggghts")
        for a in ANGLES
        for f in FRICTIONS
        for g in THROW_NUMBERS
    ]
    rows = pool_map(block_velocity, cases)
    write_csv(rows, "sliding.csv")
    plot_sliding(rows, HERE / "sliding.png", ANGLES, FRICTIONS)
    return rows


def stiffness():
    """Error against k_n at sliding points, both conventions: the observed order."""
    base = base_case()
    points = [(25.0, 0.35, 0.4), (25.0, 0.35, 0.9), (15.0, 0.25, 0.95), (45.0, 0.6, 0.8)]
    cases = [
        variant(base, angle=a, friction=f, throw_number=g, stiffness=k, tangential=t)
        for t in ("coulomb", "liggghts")
        for k in (2.5e5, 1e6, 4e6, 1.6e7, 6.4e7)
        for a, f, g in points
    ]
    rows = pool_map(block_velocity, cases)
    write_csv(rows, "stiffness.csv")
    plot_stiffness(rows, HERE / "stiffness.png")
    return rows


def hopping(parts=("fig6", "fig7")):
    """Fig. 6 (phi 25, mu 0.35, Gamma 0.2-5, eps_t 0.2/0.5/0.8) and Fig. 7 (Gamma 1.8, phi
    10-70, mu 0.25/0.35/0.60) conditions, each point calibrated for its own landings."""
    base = base_case()
    gammas = np.round(np.concatenate([np.arange(0.2, 1.0, 0.2), np.arange(1.1, 5.05, 0.15)]), 3)
    fig6 = [
        variant(base, angle=25.0, friction=0.35, throw_number=float(g), eps_t=e)
        for e in (0.2, 0.5, 0.8)
        for g in gammas
    ]
    fig7 = [
        variant(base, angle=float(a), friction=f, throw_number=1.8)
        for f in FRICTIONS[:2] + (0.6,)
        for a in range(10, 71, 5)
    ]
    for part, cases in (("fig6", fig6), ("fig7", fig7)):
        if part in parts:
            write_csv(pool_map(_calibrated_row, cases), f"hopping_{part}.csv")
    figures()


# --- figures -----------------------------------------------------------------------------------


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_sliding(rows, path, angles, frictions):
    plt = _plt()
    fig, axes = plt.subplots(1, len(angles), figsize=(13, 4), sharey=True)
    fine = np.linspace(0.15, 0.99, 120)
    for ax, angle in zip(axes, angles, strict=True):
        for friction, color in zip(frictions, ("C0", "C1", "C2"), strict=True):
            pm = [pointmass.velocity(g, angle, friction).velocity_norm for g in fine]
            ax.plot(fine, pm, color=color, lw=1, label=f"point mass, mu = {friction}")
            for tangential, marker in (("coulomb", "o"), ("liggghts", "x")):
                sel = [r for r in rows if (r["angle"], r["friction"], r["tangential"])
                       == (angle, friction, tangential)]  # fmt: skip
                ax.plot([r["throw_number"] for r in sel], [r["dem_velocity_norm"] for r in sel],
                        marker, color=color, mfc="none", label=f"block, {tangential}")  # fmt: skip
        ax.set_title(f"phi = {angle:g} deg")
        ax.set_xlabel("throw number Gamma")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("v / (A omega cos phi)")
    axes[0].legend(fontsize=6)
    k = rows[0]["stiffness"]
    fig.suptitle(
        f"Sliding block (k_n = {k:.3g} N/m, eps_n = 0, eps_t = 0.8) against the point mass"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def plot_stiffness(rows, path):
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 4.2))
    keys = sorted({(r["tangential"], r["angle"], r["friction"], r["throw_number"]) for r in rows})
    for i, key in enumerate(keys):
        sel = sorted((r for r in rows if (r["tangential"], r["angle"], r["friction"],
                      r["throw_number"]) == key), key=lambda r: r["stiffness"])  # fmt: skip
        k = [r["stiffness"] for r in sel]
        err = [abs(r["dem_velocity_norm"] / r["pointmass_velocity_norm"] - 1) for r in sel]
        style = "-o" if key[0] == "coulomb" else "--x"
        ax.loglog(k, err, style, color=f"C{i % 4}", ms=4,
                  label=f"{key[0]}: phi {key[1]:g}, mu {key[2]:g}, Gamma {key[3]:g}")  # fmt: skip
    k = np.array([2.5e5, 6.4e7])
    ax.loglog(k, 0.05 * (k / k[0]) ** -0.5, ":", color="k", label="slope -1/2")
    ax.set_xlabel("k_n (N/m)")
    ax.set_ylabel("|v_dem / v_pm - 1|")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def plot_hopping(rows6, rows7, path):
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
    fine = np.linspace(0.1, 5.0, 400)
    for e, color in zip((0.2, 0.5, 0.8), ("C0", "C1", "C2"), strict=True):
        pm = [pointmass.velocity(g, 25.0, 0.35, eps_t=e).velocity_norm for g in fine]
        axes[0].plot(fine, pm, color=color, lw=1, label=f"point mass, eps_t = {e}")
        sel = [r for r in rows6 if r["eps_t"] == e]
        if e == 0.8:
            axes[0].plot([r["throw_number"] for r in sel],
                         [r["pointmass_coulomb_bounded"] for r in sel], ":", color=color, lw=1,
                         label="point mass, landing loss <= Coulomb")  # fmt: skip
        ok = [r for r in sel if r["reachable"]]
        no = [r for r in sel if not r["reachable"]]
        axes[0].plot([r["throw_number"] for r in ok], [r["dem_velocity_norm"] for r in ok], "o",
                     color=color, mfc="none", ms=4, label="block, calibrated")  # fmt: skip
        axes[0].plot([r["throw_number"] for r in no], [r["dem_velocity_norm"] for r in no], "x",
                     color=color, ms=5, label="block, not every landing in reach")  # fmt: skip
    axes[0].set_xlabel("throw number Gamma")
    axes[0].set_ylabel("v / (A omega cos phi)")
    axes[0].set_title("phi = 25 deg, mu = 0.35 (Fig. 6)")
    fine = np.linspace(5.0, 75.0, 200)
    for f, color in zip((0.25, 0.35, 0.6), ("C0", "C1", "C2"), strict=True):
        pm = [pointmass.velocity(1.8, a, f).velocity_norm for a in fine]
        axes[1].plot(fine, pm, color=color, lw=1, label=f"point mass, mu = {f}")
        sel = [r for r in rows7 if r["friction"] == f]
        axes[1].plot([r["angle"] for r in sel], [r["dem_velocity_norm"] for r in sel], "o",
                     color=color, mfc="none", ms=4, label=f"block, mu = {f}")  # fmt: skip
    axes[1].set_xlabel("vibration angle phi (deg)")
    axes[1].set_title("Gamma = 1.8, eps_t = 0.8 (Fig. 7)")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
    k = rows6[0]["stiffness"]
    fig.suptitle(f"Block (k_n = {k:.3g} N/m, eps_n = 0), k_t calibrated to eps_t at each point")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def read_csv(name):
    """Rows of a CSV written by write_csv, numbers converted."""

    def value(text):
        for kind in (int, float):
            try:
                return kind(text)
            except ValueError:
                pass
        return {"True": True, "False": False, "": None}.get(text, text)

    with open(HERE / name) as fh:
        lines = [line for line in fh if not line.startswith("#")]
    return [{k: value(v) for k, v in row.items()} for row in csv.DictReader(lines)]


def figures():
    """Redraw the figures from the recorded CSV files (no simulation)."""
    if (HERE / "sliding.csv").exists():
        plot_sliding(read_csv("sliding.csv"), HERE / "sliding.png", ANGLES, FRICTIONS)
    if (HERE / "stiffness.csv").exists():
        plot_stiffness(read_csv("stiffness.csv"), HERE / "stiffness.png")
    if (HERE / "hopping_fig6.csv").exists():
        rows6, rows7 = read_csv("hopping_fig6.csv"), read_csv("hopping_fig7.csv")
        plot_hopping(rows6, rows7, HERE / "hopping.png")


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("study", choices=("sliding", "stiffness", "hopping", "all", "figures"))
    parser.add_argument("--part", choices=("fig6", "fig7"), help="hopping: one figure only")
    args = parser.parse_args()
    if args.study == "figures":
        figures()
        return
    if args.part:
        hopping((args.part,))
        return
    for study in ("sliding", "stiffness", "hopping"):
        if args.study in (study, "all"):
            t0 = time.perf_counter()
            globals()[study]()
            print(f"{study}: {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
