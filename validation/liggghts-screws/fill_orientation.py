"""Part D: the bulk gap is the fill's orientation, not the contact law.

Part A measured 10 cycles after 5 settle cycles, each code from its own fill. Part D asks whether
the 8-9 % there is a property of the two fills rather than of the two codes' dynamics. Part A's
seed-1 case (P/2741, E from part A's deck), ``MEASURED`` cycles after its 5 settle cycles:

- **D1, same bed.** LIGGGHTS runs the case with the template's orientation at insertion (as
  part A's deck did: LIGGGHTS's default) and writes its bed (every member's position, velocity
  and spin) at the end of the settle cycles (drive phase 0). The 200 screws are rebuilt from it
  (a rigid fit of dem's template to each group of 8 members; the centre-of-mass velocity and
  spin from the members' velocities) and dem runs from exactly that state. dem also runs from
  its own fill, as in part A.
- **D2, the cause aligned.** LIGGGHTS with ``orientation random`` (the deck as exported now)
  against dem's own fill, seeds 1-3.

Beside each per-cycle velocity the script records two measures of the bed's structure once per
cycle: the mean height of the centres of mass, and the order <u_x^2> of the screw axes u along
the conveying direction x (1/3 for random 3-D orientations, 1/2 for random directions in the
floor's plane).

    nice -n 10 .venv/bin/python validation/liggghts-screws/fill_orientation.py   # D1 + D2, ~9 min
    .venv/bin/python validation/liggghts-screws/fill_orientation.py --report-only   # order.png

Writes results.json "fill_orientation" and order.png.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
import time
from pathlib import Path

import numpy as np
from bulk import bulk_cases, bulk_liggghts
from lever_arm import deck_youngs_modulus
from study import HERE, RESULTS, SCRATCH, rel, write_results

from dem import provenance
from dem.engine import setup
from dem.engine.simulation import measure_cycles
from dem.kernels.rigid import matrix_to_quat, quat_to_matrix
from dem.physics.measure import correlated_stderr

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import replicas  # noqa: E402

TAG = "seed1_dt2x"
MEASURED = 60  # cycles after part A's 5 settle cycles
BED_FILE, ORDER_FILE = "bed.txt", "members.txt"
NEVER = 10**9  # dump period that never comes round again: the bed is written once


def add_dumps(cycle_steps: int):
    """The deck edit: the bed at the start of the measured run, members' positions per cycle."""

    def edit(text: str) -> str:
        lines = text.splitlines()
        k = max(i for i, line in enumerate(lines) if line.startswith("run "))
        extra = [
            "# --- same_bed.py: the bed at the start of the measured run, then positions per cycle",
            f"dump bed all custom {NEVER} {BED_FILE} id x y z vx vy vz omegax omegay omegaz",
            "dump_modify bed first yes sort id format '%d" + " %.17g" * 9 + "'",
            f"dump pos all custom {cycle_steps} {ORDER_FILE} id x y z",
            "dump_modify pos first yes sort id format '%d %.9g %.9g %.9g'",
        ]
        return "\n".join(lines[:k] + extra + lines[k:]) + "\n"

    return edit


def read_dump(path) -> list[tuple[int, np.ndarray]]:
    """(step, rows sorted by id) of every snapshot of a LIGGGHTS custom dump."""
    out, lines, i = [], path.read_text().splitlines(), 0
    while i < len(lines):
        step = int(lines[i + 1])
        n = int(lines[i + 3])
        rows = np.array([[float(v) for v in row.split()] for row in lines[i + 9 : i + 9 + n]])
        out.append((step, rows[np.argsort(rows[:, 0])]))
        i += 9 + n
    return out


def fit_bodies(members: np.ndarray, template, length: float):
    """Centres of mass and rotations of bodies from member positions (B k, 3), members in order.

    The members of a body are unwrapped along the periodic x against its first member, then a
    rigid fit (Kabsch) of the template's offsets gives X and R. Returns X (x wrapped), R and the
    largest residual, m.
    """
    k = template.count
    d = np.asarray(template.centres, dtype=float)  # body frame, centre of mass at 0
    p = members.reshape(-1, k, 3).copy()
    p[:, :, 0] -= length * np.round((p[:, :, 0] - p[:, :1, 0]) / length)
    c = p.mean(axis=1)
    h = np.einsum("kj,bki->bji", d - d.mean(axis=0), p - c[:, None, :])
    u, _, vt = np.linalg.svd(h)
    sign = np.sign(np.linalg.det(np.einsum("bij,bjk->bik", u, vt)))
    u[:, :, -1] *= sign[:, None]
    rot = np.einsum("bij,bjk->bik", u, vt).transpose(0, 2, 1)
    x = c - np.einsum("bij,j->bi", rot, d.mean(axis=0))
    resid = p - x[:, None, :] - np.einsum("bij,kj->bki", rot, d)
    x[:, 0] %= length
    return x, rot, float(np.abs(resid).max())


def order(members: np.ndarray, template, length: float) -> tuple[float, float]:
    """Mean centre-of-mass height (m) and <u_x^2> of the screw axes (body x) of a snapshot."""
    x, rot, _ = fit_bodies(members, template, length)
    return float(x[:, 2].mean()), float(np.mean(rot[:, 0, 0] ** 2))


def dem_from_bed(case, bed: np.ndarray, cycles: int) -> dict:
    """dem from LIGGGHTS's bed rows (id x y z vx vy vz wx wy wz): per-cycle velocity and order."""
    grain = case.particles.grain
    length = case.trough.length
    x, rot, resid = fit_bodies(bed[:, 1:4], grain, length)
    k = grain.count
    omega_m = bed[:, 7:10].reshape(-1, k, 3)
    omega = omega_m.mean(axis=1)
    spread = float(np.abs(omega_m - omega[:, None, :]).max())
    arm = np.einsum("bij,kj->bki", rot, np.asarray(grain.centres, dtype=float))
    v = (bed[:, 4:7].reshape(-1, k, 3) - np.cross(omega[:, None, :], arm)).mean(axis=1)
    q = np.array([matrix_to_quat(r) for r in rot])
    sim = setup.from_grains(
        case, x, orientations=q, velocities=v, spins=omega, timestep=case.run.timestep
    )
    return {
        "fit_residual_max_m": resid,
        "member_spin_spread_rad_s": spread,
        **drive_cycles(sim, 0, cycles),
    }


def drive_cycles(sim, settle: int, cycles: int) -> dict:
    """Drive on at phase 0; ``settle`` unmeasured cycles, then per measured cycle the velocity
    and, at its start, the bed's height and order.

    Each cycle is one call of ``dem.engine.simulation.measure_cycles``, which ends every cycle
    on a whole number of drive periods since the drive started.
    """
    measure_cycles(sim, 0, settle_cycles=settle)  # switches the drive on (phase 0)
    per_cycle, height, order_x = [], [], []
    for _ in range(cycles):
        z, s = order_of_sim(sim)
        height.append(z)
        order_x.append(s)
        per_cycle.append(float(measure_cycles(sim, 1)[0]))
    return {"per_cycle_velocity": per_cycle, "height": height, "order_x": order_x}


def order_of_sim(sim) -> tuple[float, float]:
    """Mean centre-of-mass height and <u_x^2> of a dem simulation's bodies."""
    b = sim.bodies
    ux = np.array([quat_to_matrix(q)[0, 0] for q in b.q])
    return float(b.x[:, 2].mean()), float(np.mean(ux**2))


def dem_own_fill(case, cycles: int) -> dict:
    """dem from its own fill and settling (part A): per-cycle velocity and order per cycle."""
    sim = setup.from_case(case)
    sim.settle()
    return drive_cycles(sim, case.run.settle_cycles, cycles)


def summary(v) -> dict:
    """Mean, the naive se and the mean of each block of 10 cycles."""
    v = np.asarray(v)
    return {
        "mean": float(v.mean()),
        "naive_stderr": replicas.replica_stderr(v),  # as if the cycles were independent
        "blocks_of_10": [float(b) for b in v[: v.size // 10 * 10].reshape(-1, 10).mean(axis=1)],
    }


def template_orientation(text: str) -> str:
    """Part A's deck: the insertion without ``orientation random`` (LIGGGHTS's default)."""
    return text.replace(" orientation random", "")


def liggghts_with_order(case, tag: str, *, random_orientation: bool) -> tuple[dict, Path]:
    """LIGGGHTS on the case with the bed and per-cycle dumps; order measures added."""
    dt = case.run.timestep
    cycle_steps = round(1.0 / (case.drive.frequency * dt))
    dumps = add_dumps(cycle_steps)
    edit = dumps if random_orientation else (lambda text: dumps(template_orientation(text)))
    lig = bulk_liggghts(case, tag, dt, edit=edit)
    work = SCRATCH / "liggghts" / f"bulk_{tag}"
    snaps = read_dump(work / ORDER_FILE)
    grain, length = case.particles.grain, case.trough.length
    orders = [order(rows[:, 1:4], grain, length) for _, rows in snaps]
    lig["orientation"] = "random" if random_orientation else "template (LIGGGHTS's default)"
    lig["height"] = [z for z, _ in orders]
    lig["order_x"] = [s for _, s in orders]
    lig["order_steps"] = [step for step, _ in snaps]
    lig["summary"] = summary(lig["per_cycle_velocity"])
    return lig, work


def report(name: str, entry: dict) -> None:
    s = entry["summary"]
    blocks = " ".join(f"{b:.4f}" for b in s["blocks_of_10"])
    print(f"{name:34s} v = {s['mean']:.5f}  blocks {blocks}  <ux^2> {entry['order_x'][0]:.3f}"
          f" -> {entry['order_x'][-1]:.3f}  z {entry['height'][0] * 1e3:.2f} -> "
          f"{entry['height'][-1] * 1e3:.2f} mm", flush=True)  # fmt: skip


def case_for(tag: str):
    """Part A's case of this tag with part A's E (from its deck) and MEASURED cycles."""
    base = bulk_cases()[tag]
    return dataclasses.replace(
        base,
        contact=dataclasses.replace(base.contact, youngs_modulus=deck_youngs_modulus(tag)),
        run=dataclasses.replace(base.run, cycles=MEASURED),
    )


def part_same_bed(out: dict, results: dict) -> None:
    """D1: LIGGGHTS as part A ran it, dem from its bed, and dem from its own fill."""
    case = case_for(TAG)
    sec = out.setdefault("same_bed", {"case_tag": TAG})
    t0 = time.perf_counter()
    lig, work = liggghts_with_order(case, f"d1_{TAG}", random_orientation=False)
    sec["liggghts"] = lig
    write_results(results)
    ((_, bed),) = read_dump(work / BED_FILE)
    t0 = time.perf_counter()
    same = dem_from_bed(case, bed, MEASURED)
    same["wall_time_s"] = time.perf_counter() - t0
    same["summary"] = summary(same["per_cycle_velocity"])
    same["bed"] = rel(work / BED_FILE)
    sec["dem_from_liggghts_bed"] = same
    write_results(results)
    t0 = time.perf_counter()
    own = dem_own_fill(case, MEASURED)
    own["wall_time_s"] = time.perf_counter() - t0
    own["summary"] = summary(own["per_cycle_velocity"])
    sec["dem_own_fill"] = own
    write_results(results)
    for key in ("liggghts", "dem_from_liggghts_bed", "dem_own_fill"):
        report(f"D1 {key}", sec[key])


def part_random(out: dict, results: dict) -> None:
    """D2: LIGGGHTS with ``orientation random`` (the deck now) against dem, seeds 1-3."""
    sec = out.setdefault("random_orientation", {})
    for seed in (1, 2, 3):
        tag = f"seed{seed}_dt2x"
        case = case_for(tag)
        lig, _ = liggghts_with_order(case, f"d2_{tag}", random_orientation=True)
        t0 = time.perf_counter()
        own = dem_own_fill(case, MEASURED)
        own["wall_time_s"] = time.perf_counter() - t0
        own["summary"] = summary(own["per_cycle_velocity"])
        sec[tag] = {"liggghts": lig, "dem": own}
        write_results(results)
        report(f"D2 {tag} LIGGGHTS", lig)
        report(f"D2 {tag} dem", own)


def plot(out: dict) -> None:
    """order.png: each run's mean velocity against its bed's initial <u_x^2>."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    runs = []
    sb = out.get("same_bed", {})
    for key, label, style in (
        ("liggghts", "LIGGGHTS, template orientation (part A's deck)", dict(c="k", marker="o")),
        ("dem_from_liggghts_bed", "dem from that LIGGGHTS bed", dict(c="C3", marker="s")),
    ):
        if key in sb:
            runs.append((sb[key], label, style))
    for e in out.get("random_orientation", {}).values():
        runs.append((e["liggghts"], "LIGGGHTS, orientation random (the deck now)",
                     dict(c="k", marker="o", mfc="none")))  # fmt: skip
        runs.append((e["dem"], "dem, own fill", dict(c="C0", marker="^")))
    seen = set()
    for e, label, style in runs:
        v = np.asarray(e["per_cycle_velocity"])
        se, _ = correlated_stderr(v)
        ax.errorbar(e["order_x"][0], v.mean(), se, ls="none", capsize=3, ms=7,
                    label=None if label in seen else label, **style)  # fmt: skip
        seen.add(label)
    ax.axvline(1 / 3, color="0.7", ls=":", lw=1)
    ax.axvline(1 / 2, color="0.7", ls=":", lw=1)
    ax.text(1 / 3, ax.get_ylim()[0], " random 3-D", fontsize=7, va="bottom")
    ax.text(1 / 2, ax.get_ylim()[0], " random in the floor", fontsize=7, va="bottom")
    ax.set_xlabel("order of the screw axes along x at the first measured cycle, <u_x^2>")
    ax.set_ylabel(f"mean conveying velocity over {MEASURED} cycles (m/s)")
    ax.set_title("200 screws, phi 25 deg, Gamma 1.8, E 5e7 Pa: the bed decides", fontsize=10)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(HERE / "order.png", dpi=120)


def main() -> int:
    parts = sys.argv[1:] or ["same_bed", "random"]  # or one of them
    results = json.loads(RESULTS.read_text())
    if parts == ["--report-only"]:
        plot(results["fill_orientation"])
        return 0
    out = results.setdefault("fill_orientation", {})
    out.update(
        script="validation/liggghts-screws/fill_orientation.py",
        git_commit=provenance.git_commit(),
        date=provenance.utc_now(),
        measured_cycles=MEASURED,
        load_average_start=os.getloadavg()[0],
    )
    if "same_bed" in parts:
        part_same_bed(out, results)
    if "random" in parts:
        part_random(out, results)
    out["load_average_end"] = os.getloadavg()[0]
    write_results(results)
    plot(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
