"""A single screw lying along the trough (not rolling) against the point-mass model, Gamma < 1.

Regenerates results.csv and velocity.png in this folder:

    .venv/bin/python validation/single-screw/run.py                          # eps_n = 0
    .venv/bin/python validation/single-screw/run.py --tangential liggghts    # the recorded study

One screw of cases/screw-trough (L = 22 mm, shank radius 1.8 mm, head radius 3.6 mm, 2.5 g: a
rigid clump of 8 spheres) is laid along +x, the trough direction, with its head and its tip
sphere on the floor, at rest, rotation locked: a rigid sliding block on two contacts, the DEM
twin of the paper's point mass. Below Gamma = 1 the point mass never leaves the floor, so eps_n
and eps_t do not enter it; a locked block that slides on both contacts feels
sum_i mu N_i = mu N, so its centre of mass must follow the point mass. Swept over phi in
{15, 25, 45} deg, mu in {0.25, 0.35, 0.6} and Gamma in [0.2, 0.95], flat trough, 60 Hz, linear
contact k_n = 4e7 N/m per member. ``--tangential``: "coulomb" (default; eps_n = 0 as the paper,
k_t / k_n derived from eps_t = 0.8, dem.physics.tangential) or "liggghts" (k_t = 2/7 k_n, eps_n =
0.5: the law and contact the recorded results.csv were made with; README.md says why).

Each point is run again with rotation free from the same lying start (column
dem_velocity_norm_free_rotation; not part of the criterion, which is the locked block's).

Time step: the engine's own rule (dem.scene.timestep.timestep_limits: 1/50 of the linear collision
time, within the stability limit) applied to the effective mass a floor contact of the lying
screw actually has: M with rotation locked, 1 / max_n (1/M + (p x n) . I^-1 (p x n)) with it free.
dem.engine.setup.from_grains' automatic step (``--timestep auto``) bounds that mass for any pose: M
locked, dem.scene.shapes.Template.contact_mass (0.37 g) free (README.md: the bound of the
recording).

The screw is placed by dem.engine.setup.from_grains and measured cycle by cycle by
dem.engine.simulation.measure_cycles. Settling: after ``--min-settle-cycles`` driven cycles the run
measures as soon as one cycle's mean velocity differs from the previous one by less than
``--periodic-tol`` (normalised), at most after ``--max-settle-cycles``; then ``--cycles`` cycles.
"""

import argparse
import csv
import dataclasses
import math
import time
from pathlib import Path

import numba
import numpy as np

from dem import pointmass
from dem.engine import setup
from dem.engine.simulation import measure_cycles
from dem.kernels.rigid import quat_to_matrix
from dem.physics import measure
from dem.scene.case import load_case
from dem.scene.timestep import ContactLaw, timestep_limits
from dem.scene.trough import Trough

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
#: The screw case as shipped when this was measured (2e9 Pa and 4e-6 s since 2026-11-26).
AS_MEASURED = {"contact.youngs_modulus": 5.0e8, "run.timestep": 8.0e-6}
ANGLES = (15.0, 25.0, 45.0)
FRICTIONS = (0.25, 0.35, 0.6)
THROW_NUMBERS = tuple(np.round(np.linspace(0.2, 0.95, 7), 4))
STIFFNESS = 4.0e7
RESTITUTION_NORMAL = {"coulomb": 0.0, "liggghts": 0.5}  # the paper's; the recorded study's
RESTING = 0.02  # |v_pm| below this (normalised): the point mass rests, no relative error


def make_case(base, angle, friction, throw_number, args, rotation):
    """cases/screw-trough at (phi, mu, Gamma), one screw, the validation contact and law."""
    case = dataclasses.replace(
        base.with_drive(angle=angle, throw_number=throw_number),
        material=dataclasses.replace(
            base.material, friction=friction, restitution_normal=args.restitution_normal
        ),
        contact=dataclasses.replace(
            base.contact, model="linear", stiffness=args.stiffness, youngs_modulus=None
        ),
        particles=dataclasses.replace(base.particles, count=1, rotation=rotation),
        run=dataclasses.replace(base.run, timestep=None),
    )
    return case.with_tangential(args.tangential)  # linear: liggghts k_t = 2/7 k_n


def lying_pose(template):
    """Orientation and centre-of-mass height of a screw lying along +x on the floor z = 0.

    The head sphere (largest radius R_h) and the tip sphere (the member farthest from the head,
    radius r_t) both touch the floor: the axis from head to tip is tilted down by
    theta = asin((R_h - r_t) / |d_tip - d_head|) and lies in the x-z plane, tip towards +x
    (6.2 deg for this screw). The quaternion is the shortest-arc rotation taking the body-frame
    axis u onto w = (cos theta, 0, -sin theta); the height puts the lowest points of head and tip
    at z = 0 (zero overlap; gravity then presses each contact in by about M g / (2 k_n)).

    Returns:
        (q, z): unit quaternion (w, x, y, z) and the centre-of-mass height, m.

    """
    c, r = template.centres, template.radii
    head = int(np.argmax(r))
    tip = int(np.argmax(np.linalg.norm(c - c[head], axis=1)))
    span = float(np.linalg.norm(c[tip] - c[head]))
    u = (c[tip] - c[head]) / span
    theta = math.asin((r[head] - r[tip]) / span)
    w = np.array([math.cos(theta), 0.0, -math.sin(theta)])
    q = np.concatenate([[1.0 + u @ w], np.cross(u, w)])
    q /= np.linalg.norm(q)
    rot = quat_to_matrix(q)
    z = r[head] - (rot @ c[head])[2]
    lows = z + (c @ rot.T)[:, 2] - r  # lowest point of every member above the floor
    if max(abs(lows[head]), abs(lows[tip])) > 1e-12 or lows.min() < -1e-12:
        raise RuntimeError(f"screw not lying on head and tip: member gaps {lows}")
    return q, z


def floor_contact_mass(template, q, rotation):
    """Smallest effective mass of a floor contact of the screw in pose q, kg.

    A force f n at the contact point p (relative to the centre of mass) accelerates that point
    by f (1/M + (p x n) . I^-1 (p x n)) along n; the smallest effective mass is 1 over the largest
    eigenvalue of Id / M + [p]x^T I^-1 [p]x (trough-frame I^-1 = R diag(1/I_k) R^T), over the
    lowest points p = R d_i - r_i e_z of all members. Rotation locked: M.
    """
    if not rotation:
        return float(template.mass)
    rot = quat_to_matrix(q)
    inv_inertia = rot @ np.diag(1.0 / template.moments) @ rot.T
    smallest = math.inf
    for d, r in zip(template.centres, template.radii, strict=True):
        px, py, pz = rot @ d - np.array([0.0, 0.0, r])
        cross = np.array([[0.0, -pz, py], [pz, 0.0, -px], [-py, px, 0.0]])
        a = np.eye(3) / template.mass + cross.T @ inv_inertia @ cross
        smallest = min(smallest, 1.0 / float(np.linalg.eigvalsh(a)[-1]))
    return smallest


def lying_simulation(case, timestep="contact"):
    """One screw laid by lying_pose at mid length, y = 0, at rest (dem.engine.setup.from_grains).

    ``"auto"``: from_grains' automatic step. ``"contact"``: the same rule (timestep_limits) at
    the floor contact's actual effective mass (floor_contact_mass), shortened to a whole number
    of steps per drive period (a linear law's step ignores the impact speed); from_grains
    refuses it above its stability limit.
    """
    template = case.particles.grain
    q, z = lying_pose(template)
    dt = None
    if timestep == "contact":
        mass = floor_contact_mass(template, q, case.particles.rotation)
        trough = Trough.from_case(case)
        auto, _ = timestep_limits(
            ContactLaw.from_case(case), float(template.radii.min()), template.density,
            trough.drive_speed, rotation=case.particles.rotation, pairs=False, mass=mass,
        )  # fmt: skip
        dt = trough.period / math.ceil(trough.period / auto)
    return setup.from_grains(
        case, [[0.5 * case.trough.length, 0.0, z]], orientations=[q], timestep=dt
    )


def drive_and_measure(sim, case, min_settle, max_settle, tol, cycles):
    """Settle with the drive off, switch it on at phase 0, wait for periodicity, measure.

    Each cycle is one call of dem.engine.simulation.measure_cycles (whole drive cycles from phase 0,
    as ``dem run`` measures; the first call switches the drive on). Driven cycles are discarded
    until at least ``min_settle`` have run and the last one changed by less than ``tol``
    A omega cos phi (or ``max_settle`` have run); the next ``cycles`` are measured
    (dem.physics.measure.conveying_velocity: mean and standard error of the per-cycle means).

    Returns:
        (VelocityStatistics, settling cycles, largest tilt of the screw axis from its start
        over the whole drive in degrees, largest |y| drift of the centre of mass in m).

    """
    sim.settle()
    axis0 = quat_to_matrix(sim.bodies.q[0])[:, 0]
    y0 = float(sim.bodies.x[0, 1])
    scale = case.drive.velocity_scale
    per_cycle, tilt, drift, settle = [], 0.0, 0.0, None
    c = 0
    while settle is None or c < settle + cycles:
        per_cycle.append(float(measure_cycles(sim, 1)[0]))
        axis = quat_to_matrix(sim.bodies.q[0])[:, 0]
        turned = float(np.linalg.norm(np.cross(axis, axis0)))  # sine of the angle turned
        tilt = max(tilt, math.degrees(math.asin(min(1.0, turned))))
        drift = max(drift, abs(float(sim.bodies.x[0, 1]) - y0))
        c += 1
        if settle is None and c >= min_settle:
            if abs(per_cycle[-1] - per_cycle[-2]) < tol * scale or c >= max_settle:
                settle = c
    stat = measure.conveying_velocity(np.array(per_cycle[settle:]), scale=case.drive.velocity_scale)
    return stat, settle, tilt, drift


def run_point(base, angle, friction, gamma, args, rotation):
    """One DEM run; returns (statistics, settle cycles, tilt deg, drift m, dt s, wall s)."""
    t0 = time.perf_counter()
    case = make_case(base, angle, friction, gamma, args, rotation)
    sim = lying_simulation(case, args.timestep)
    stat, settle, tilt, drift = drive_and_measure(
        sim, case, args.min_settle_cycles, args.max_settle_cycles, args.periodic_tol, args.cycles
    )
    return stat, settle, tilt, drift, sim.dt, time.perf_counter() - t0


def sweep(args, out_csv):
    """All (phi, mu, Gamma) points, locked and (unless --no-free) free rotation; writes the CSV."""
    base = load_case(ROOT / "cases" / "screw-trough", AS_MEASURED)
    rows = []
    for angle in args.angles:
        for friction in args.frictions:
            for gamma in args.throw_numbers:
                gamma = float(gamma)
                pm = pointmass.velocity(throw_number=gamma, angle=angle, friction=friction)
                pm_v = pm.velocity_norm
                stat, settle, _, _, dt, wall = run_point(base, angle, friction, gamma, args, False)
                row = {
                    "angle": angle,
                    "friction": friction,
                    "throw_number": gamma,
                    "dem_velocity_norm": stat.norm,
                    "dem_velocity_norm_stderr": stat.norm_stderr,
                    "pointmass_velocity_norm": pm_v,
                    "regime": pm.regime,
                    "abs_error": stat.norm - pm_v,
                    "rel_error": (stat.norm - pm_v) / pm_v if abs(pm_v) > RESTING else "",
                    "settle_cycles": settle,
                    "timestep": dt,
                    "wall_time_s": round(wall, 2),
                }
                line = (
                    f"phi={angle:4.0f} mu={friction:4.2f} Gamma={gamma:5.3f} "
                    f"dem={stat.norm:+.5f} pm={pm_v:+.5f} ({pm.regime}) "
                    f"err={row['abs_error']:+.5f} settle={settle}"
                )
                if args.free:
                    free, settle, tilt, drift, dt, wall = run_point(
                        base, angle, friction, gamma, args, True
                    )
                    row |= {
                        "dem_velocity_norm_free_rotation": free.norm,
                        "free_rotation_stderr": free.norm_stderr,
                        "free_rotation_settle_cycles": settle,
                        "free_rotation_max_tilt_deg": tilt,
                        "free_rotation_max_y_drift": drift,
                        "free_rotation_timestep": dt,
                        "free_rotation_wall_time_s": round(wall, 2),
                    }
                    line += f" | free={free.norm:+.5f} tilt={tilt:.2g} deg settle={settle}"
                rows.append(row)
                print(line, flush=True)
    with open(out_csv, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return rows


def plot(rows, out_png):
    """DEM points (locked: circles, free: crosses) on the point-mass curves, one panel per phi."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    angles = sorted({r["angle"] for r in rows})
    frictions = sorted({r["friction"] for r in rows})
    fig, axes = plt.subplots(1, len(angles), figsize=(4.4 * len(angles), 4), sharey=True)
    axes = np.atleast_1d(axes)
    fine = np.linspace(0.15, 0.99, 120)
    for ax, angle in zip(axes, angles, strict=True):
        for k, friction in enumerate(frictions):
            color = f"C{k}"
            pm = [pointmass.velocity(throw_number=g, angle=angle, friction=friction).velocity_norm
                  for g in fine]  # fmt: skip
            ax.plot(fine, pm, color=color, label=f"point mass, mu = {friction}")
            sel = [r for r in rows if r["angle"] == angle and r["friction"] == friction]
            gammas = [r["throw_number"] for r in sel]
            ax.plot(gammas, [r["dem_velocity_norm"] for r in sel], "o", color=color, mfc="none",
                    label=f"DEM screw, locked, mu = {friction}")  # fmt: skip
            if "dem_velocity_norm_free_rotation" in sel[0]:
                ax.plot(gammas, [r["dem_velocity_norm_free_rotation"] for r in sel], "x",
                        color=color, label=f"DEM screw, free, mu = {friction}")  # fmt: skip
        ax.set_title(f"phi = {angle:g} deg")
        ax.set_xlabel("throw number Gamma")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("v / (A omega cos phi)")
    axes[0].legend(fontsize=6)
    fig.suptitle("Single screw lying along the trough (DEM clump) vs point mass, no flight")
    fig.tight_layout()
    fig.savefig(out_png, dpi=120)


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--stiffness", type=float, default=STIFFNESS, help="k_n per member, N/m")
    parser.add_argument(
        "--tangential", choices=("coulomb", "liggghts"), default="coulomb",
        help="tangential law; liggghts (with eps_n = 0.5) is the recorded study's",
    )  # fmt: skip
    parser.add_argument(
        "--restitution-normal", type=float, default=None,
        help="eps_n; default 0 with coulomb (the paper's), 0.5 with liggghts (the recorded)",
    )  # fmt: skip
    parser.add_argument("--timestep", choices=("contact", "auto"), default="contact")
    parser.add_argument("--min-settle-cycles", type=int, default=10)
    parser.add_argument("--max-settle-cycles", type=int, default=100)
    parser.add_argument("--periodic-tol", type=float, default=1e-5)
    parser.add_argument("--cycles", type=int, default=10, help="measured cycles")
    parser.add_argument("--angles", type=float, nargs="+", default=ANGLES)
    parser.add_argument("--frictions", type=float, nargs="+", default=FRICTIONS)
    parser.add_argument("--throw-numbers", type=float, nargs="+", default=THROW_NUMBERS)
    parser.add_argument("--no-free", dest="free", action="store_false", help="locked runs only")
    parser.add_argument("--out", default="results.csv", help="CSV name in this folder")
    args = parser.parse_args()
    if args.restitution_normal is None:
        args.restitution_normal = RESTITUTION_NORMAL[args.tangential]
    numba.set_num_threads(1)
    t0 = time.perf_counter()
    rows = sweep(args, HERE / args.out)
    if args.out == "results.csv":
        plot(rows, HERE / "velocity.png")
    rel = [abs(r["rel_error"]) for r in rows if r["rel_error"] != ""]
    absolute = [abs(r["abs_error"]) for r in rows]
    print(
        f"max |relative error| (|v_pm| > {RESTING}) {max(rel, default=0.0):.4f}, "
        f"max |abs error| {max(absolute):.5f}, wall {time.perf_counter() - t0:.0f} s"
    )


if __name__ == "__main__":
    main()
