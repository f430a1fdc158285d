"""The validation matrix: dem against LIGGGHTS-PUBLIC 3.8 and the point mass, spheres and screws.

Every point is one shipped case (``cases/sphere-bed``: 1500 Hertz spheres; ``cases/screw-trough``:
200 screws of 8 spheres) at a vibration angle phi, a throw number Gamma and an inclination
alpha, at two fill levels (the case's count, ``deep``, and half of it, ``shallow``):

- spheres: phi in {15, 25, 35, 50} deg x Gamma in {1.8, 3.0}, alpha = 0;
- screws: phi in {15, 25, 35, 45} deg x Gamma in {1.8, 3.0}, alpha = 0;
- uphill: phi = 25 deg, Gamma = 1.8, alpha = +3 deg (conveying up the slope), both shapes.

Each point runs, one simulation at a time (dem on one numba thread, LIGGGHTS on one rank):

1. **LIGGGHTS**: the deck ``dem.io.liggghts.write_deck`` exports for the point with
   LIGGGHTS's conventions (``with_tangential("liggghts")``, eps_n = 0.06 since LIGGGHTS refuses
   e <= 0.05), the mean x-velocity of every step binned into dem's drive cycles;
2. **dem, LIGGGHTS's conventions**: the same case through ``dem.run.runner.run_case``;
3. **dem, defaults**: the shipped case's own conventions (eps_n = 0, the calibrated tangential
   law for eps_t = 0.8), at the same drive, step and cycles;
4. **dem, LIGGGHTS's tangential law with eps_n = 0** (deep fills only): splits the difference
   between 2 and 3 into the normal restitution's part and the tangential law's;
5. **point mass**: ``dem.pointmass.velocity`` with the paper's eps_n = 0, eps_t = 0.8.

Both codes use the same time step: the case's step (screws: run.timestep = 8e-6 s; spheres: the
automatic step), but never above half of dem's stability limit for the point. Both run
SETTLE_CYCLES driven cycles unmeasured and CYCLES measured. The error of a mean velocity is
``dem.physics.measure.correlated_stderr`` of the per-cycle means (Sokal's integrated autocorrelation
time), since a screw bed's per-cycle means are correlated over tens of cycles
(validation/liggghts-screws, part D).

    nice -n 10 .venv/bin/python validation/liggghts/matrix.py            # all points, resumable
    .venv/bin/python validation/liggghts/matrix.py --only screw_phi25     # points matching
    .venv/bin/python validation/liggghts/matrix.py --report-only          # table + figure

Results go to results.json after every run (a point already there with the same settings is
not rerun); results.csv, matrix.png and the README table come from them.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from dem import pointmass, provenance
from dem.io.liggghts import DECK_NAME, LIGGGHTS_INSTALL, find_liggghts
from dem.physics.measure import correlated_stderr
from dem.scene.case import load_case
from dem.scene.timestep import timestep_for

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import header, pair, replicas  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
RESULTS = HERE / "results.json"
DECKS = HERE / "decks"
SCRATCH = HERE / "scratch"
CASES = {
    "sphere": ROOT / "validation" / "liggghts-bulk" / "sphere-bed-5e7",
    "screw": ROOT / "cases" / "screw-trough",
}
#: The settings the matrix was measured at: the shipped cases until 2026-11-26 (the sphere bed
#: is the LIGGGHTS-parity case above; the screws were shipped at 5e8 Pa and 8e-6 s then).
AS_MEASURED = {"sphere": {}, "screw": {"contact.youngs_modulus": 5.0e8, "run.timestep": 8.0e-6}}
ANGLES = {"sphere": (15.0, 25.0, 35.0, 50.0), "screw": (15.0, 25.0, 35.0, 45.0)}
GAMMAS = (1.8, 3.0)
UPHILL = (25.0, 1.8, 3.0)  # phi, Gamma, alpha (deg)
FILLS = {"deep": 1.0, "shallow": 0.5}
SETTLE_CYCLES, CYCLES = 10, 40
LIGGGHTS_RESTITUTION = 0.06  # LIGGGHTS refuses e <= 0.05
POINTMASS_EPS_T, POINTMASS_EPS_N = 0.8, 0.0
MAX_LIMIT_FRACTION = 0.5  # dt <= this fraction of dem's stability limit at the point
AGREE_PERCENT, AGREE_SIGMA = 5.0, 2.0  # the criterion: 5 % or 2 combined se


@dataclasses.dataclass(frozen=True)
class Point:
    shape: str
    angle: float
    gamma: float
    alpha: float
    fill: str
    seed: int = 1

    @property
    def name(self) -> str:
        tail = "" if self.seed == 1 else f"_s{self.seed}"
        return f"{self.shape}_phi{self.angle:g}_G{self.gamma:g}_a{self.alpha:g}_{self.fill}{tail}"


def points() -> list[Point]:
    out = []
    for fill in FILLS:
        for shape in ("sphere", "screw"):
            out += [Point(shape, a, g, 0.0, fill) for a in ANGLES[shape] for g in GAMMAS]
            out.append(Point(shape, *UPHILL, fill))
    return out


def cases_for(p: Point) -> tuple:
    """(dem default case, LIGGGHTS-equivalent case) of a point, with the same step and cycles."""
    base = load_case(CASES[p.shape], AS_MEASURED[p.shape])
    base = dataclasses.replace(
        base,
        trough=dataclasses.replace(base.trough, inclination=p.alpha),
        particles=dataclasses.replace(
            base.particles, count=int(round(base.particles.count * FILLS[p.fill]))
        ),
    )
    base = base.with_drive(angle=p.angle, throw_number=p.gamma)
    pinned = base.run.timestep
    auto = timestep_for(dataclasses.replace(base, run=dataclasses.replace(base.run, timestep=None)))
    dt = min(pinned if pinned is not None else auto.dt, MAX_LIMIT_FRACTION * auto.limit)
    run = dataclasses.replace(
        base.run, timestep=dt, settle_cycles=SETTLE_CYCLES, cycles=CYCLES, seed=p.seed
    )
    default = dataclasses.replace(base, run=run)
    lig = default.with_tangential("liggghts")
    lig = dataclasses.replace(
        lig, material=dataclasses.replace(lig.material, restitution_normal=LIGGGHTS_RESTITUTION)
    )
    return default, lig, auto.limit


def split_case(default):
    """dem with LIGGGHTS's tangential law but the case's own eps_n (0): splits the conventions'
    effect into the normal restitution's and the tangential law's."""
    return default.with_tangential("liggghts")


def settings(p: Point, case, limit: float) -> dict:
    d = case.drive
    return {
        "shape": p.shape,
        "angle_deg": p.angle,
        "throw_number": p.gamma,
        "inclination_deg": p.alpha,
        "fill": p.fill,
        "count": case.particles.count,
        "amplitude_m": d.amplitude,
        "frequency_hz": d.frequency,
        "timestep_s": case.run.timestep,
        "dem_stability_limit_s": limit,
        "settle_cycles": SETTLE_CYCLES,
        "cycles": CYCLES,
        "youngs_modulus_pa": case.contact.youngs_modulus,
    }


def statistics(per_cycle) -> dict:
    v = np.asarray(per_cycle, dtype=float)
    se, tau = correlated_stderr(v)
    return {
        "mean_velocity": float(v.mean()),
        "stderr": se,
        "naive_stderr": replicas.replica_stderr(v),  # as if the cycles were independent
        "tau_int_cycles": tau,
        "per_cycle_velocity": [float(u) for u in v],
    }


def run_liggghts_point(p: Point, case) -> dict:
    """LIGGGHTS on the point's deck (validation/_lib/pair.py), per-cycle means in dem's cycles."""
    lig = pair.run_reference(
        case, DECKS / p.name, SCRATCH / "liggghts" / p.name, min_loops=3, strict_settle=False
    )
    run, deck, work = lig.run, lig.deck, lig.work
    members = 1 if case.particles.shape == "sphere" else case.particles.grain.count
    per_cycle = lig.per_cycle
    driven = run.loop_times[-2:]
    driven_s = sum(x.seconds for x in driven)
    driven_steps = sum(x.steps for x in driven)
    return {
        **statistics(per_cycle),
        "version": run.version,
        "deck": str(deck.relative_to(ROOT)),
        "command": f"cd {work.relative_to(ROOT)} && liggghts -in {DECK_NAME}",
        "wall_time_s": run.wall_s,
        "driven_loop_s": driven_s,
        "grain_steps_per_s": case.particles.count * driven_steps / driven_s,
        "sphere_steps_per_s": case.particles.count * members * driven_steps / driven_s,
        "load_average": os.getloadavg()[0],
    }


def run_dem_point(p: Point, case, label: str) -> dict:
    out = SCRATCH / "dem" / f"{p.name}_{label}"
    dem = pair.run_dem(case, out, threads=1)
    s, wall = dem.summary, dem.wall_s
    members = 1 if case.particles.shape == "sphere" else case.particles.grain.count
    return {
        **statistics(s["per_cycle_velocity"]),
        "command": f"run_case(case, {out.relative_to(ROOT)}, threads=1, progress=False, "
        "frames=False, overwrite=True)",
        "tangential": case.contact.tangential,
        "restitution_normal": case.material.restitution_normal,
        "wall_time_s": wall,
        "driven_loop_s": s["wall_time_s"],
        "sphere_steps_per_s": s["particle_steps_per_s"],
        "grain_steps_per_s": s["particle_steps_per_s"] / members,
        "load_average": os.getloadavg()[0],
    }


def point_mass(case) -> dict:
    d = case.drive
    r = pointmass.velocity(
        throw_number=d.throw_number, angle=d.angle, friction=case.material.friction,
        inclination=case.trough.inclination, eps_t=POINTMASS_EPS_T, eps_n=POINTMASS_EPS_N,
    )  # fmt: skip
    return {"velocity": r.velocity(d.frequency), "velocity_norm": r.velocity_norm,
            "regime": r.regime, "eps_t": POINTMASS_EPS_T, "eps_n": POINTMASS_EPS_N}  # fmt: skip


def difference(a: dict, b: dict) -> dict:
    """a - b in m/s, % of b and combined standard errors; agree by the issue's criterion."""
    d = replicas.difference(a["mean_velocity"], a["stderr"], b["mean_velocity"], b["stderr"])
    diff, sigma, percent = d["dem_minus_liggghts"], d["combined_stderr"], d["percent_of_liggghts"]
    return {
        "m_per_s": diff,
        "percent": percent,
        "combined_stderr": sigma,
        "sigma": d["sigma"],
        "agree": abs(percent) <= AGREE_PERCENT or abs(diff) <= AGREE_SIGMA * sigma,
    }


def run_point(p: Point, results: dict, redo: bool) -> None:
    default, lig_case, limit = cases_for(p)
    want = settings(p, lig_case, limit)
    entry = results["points"].get(p.name)
    if entry is None or entry.get("settings") != want or redo:
        entry = results["points"][p.name] = {"settings": want}
    d = default.drive
    entry["v_norm"] = d.velocity_scale
    entry["point_mass"] = point_mass(default)
    runs = [
        ("liggghts", lambda: run_liggghts_point(p, lig_case)),
        ("dem_liggghts_conventions", lambda: run_dem_point(p, lig_case, "liggghts_conventions")),
        ("dem_defaults", lambda: run_dem_point(p, default, "defaults")),
    ]
    if p.fill == "deep":
        runs.append(("dem_liggghts_tangential", lambda: run_dem_point(
            p, split_case(default), "liggghts_tangential")))  # fmt: skip
    for key, run in runs:
        if key in entry:
            continue
        if key == "liggghts" and find_liggghts() is None:
            print(f"{p.name}: liggghts not on PATH ({LIGGGHTS_INSTALL}); skipped")
            continue
        entry[key] = {"date": provenance.utc_now(), **run()}
        write_results(results)
        r = entry[key]
        print(f"{p.name:32s} {key:25s} v = {r['mean_velocity']:.5f} +- {r['stderr']:.5f} m/s "
              f"(tau {r['tau_int_cycles']:.1f}) {r['wall_time_s']:.0f} s", flush=True)  # fmt: skip
    if "liggghts" in entry:
        for key in ("dem_liggghts_conventions", "dem_defaults", "dem_liggghts_tangential"):
            if key in entry:
                entry[f"{key}_minus_liggghts"] = difference(entry[key], entry["liggghts"])
    write_results(results)


def write_results(results: dict) -> None:
    RESULTS.write_text(json.dumps(results, indent=2) + "\n")


RUN_KEYS = ("liggghts", "dem_liggghts_conventions", "dem_defaults", "dem_liggghts_tangential")


def pooled_points(results: dict) -> dict[str, dict]:
    """The points with their seeds pooled: per run, the mean over seeds and its standard error,
    the larger of the seed-to-seed one, std(ddof=1) / sqrt(n), and the runs' own propagated."""
    groups: dict[str, list[dict]] = {}
    for name, e in results["points"].items():
        base = name.rsplit("_s", 1)[0] if name.rsplit("_s", 1)[-1].isdigit() else name
        groups.setdefault(base, []).append(e)
    out = {}
    for base, entries in groups.items():
        first = entries[0]
        e = {"settings": first["settings"], "point_mass": first["point_mass"],
             "seeds": len(entries)}  # fmt: skip
        for key in RUN_KEYS:
            runs = [x[key] for x in entries if key in x]
            if len(runs) != len(entries):
                continue
            v = np.array([r["mean_velocity"] for r in runs])
            se = math.sqrt(sum(r["stderr"] ** 2 for r in runs)) / len(runs)
            if len(runs) > 1:
                se = max(se, replicas.replica_stderr(v))
            e[key] = {
                "mean_velocity": float(v.mean()),
                "stderr": se,
                "tau_int_cycles": float(np.mean([r["tau_int_cycles"] for r in runs])),
                "grain_steps_per_s": float(np.mean([r["grain_steps_per_s"] for r in runs])),
            }
        if "liggghts" in e:
            for key in RUN_KEYS[1:]:
                if key in e:
                    e[f"{key}_minus_liggghts"] = difference(e[key], e["liggghts"])
        out[base] = e
    return out


def table_rows(results: dict) -> list[dict]:
    rows = []
    for name, e in pooled_points(results).items():
        if not all(k in e for k in RUN_KEYS[:3]):
            continue
        s, lig = e["settings"], e["liggghts"]
        eq, de = e["dem_liggghts_conventions"], e["dem_defaults"]
        a, b = e["dem_liggghts_conventions_minus_liggghts"], e["dem_defaults_minus_liggghts"]
        pm = e["point_mass"]["velocity"]
        split = e.get("dem_liggghts_tangential")
        v_eq, v_de = eq["mean_velocity"], de["mean_velocity"]
        v_sp = split["mean_velocity"] if split else math.nan
        rows.append({
            "point": name, "shape": s["shape"], "phi_deg": s["angle_deg"],
            "gamma": s["throw_number"], "alpha_deg": s["inclination_deg"], "fill": s["fill"],
            "count": s["count"], "dt_s": s["timestep_s"], "seeds": e["seeds"],
            "v_liggghts": lig["mean_velocity"], "se_liggghts": lig["stderr"],
            "v_dem_eq": eq["mean_velocity"], "se_dem_eq": eq["stderr"],
            "eq_minus_L_percent": a["percent"], "eq_minus_L_sigma": a["sigma"],
            "agree": a["agree"],
            "v_dem_default": de["mean_velocity"], "se_dem_default": de["stderr"],
            "default_minus_L_percent": b["percent"], "default_minus_L_sigma": b["sigma"],
            "conventions_percent": 100.0 * (v_de - v_eq) / v_eq,
            "eps_n_part_percent": 100.0 * (v_sp - v_eq) / v_eq,
            "tangential_part_percent": 100.0 * (v_de - v_sp) / v_eq,
            "v_point_mass": pm,
            "bulk_over_point_mass": lig["mean_velocity"] / pm if pm else math.nan,
            "tau_L": lig["tau_int_cycles"], "tau_dem": eq["tau_int_cycles"],
            "grain_steps_per_s_liggghts": lig["grain_steps_per_s"],
            "grain_steps_per_s_dem": eq["grain_steps_per_s"],
            "dem_over_liggghts_speed": eq["grain_steps_per_s"] / lig["grain_steps_per_s"],
        })  # fmt: skip
    return rows


def report(results: dict) -> list[dict]:
    rows = table_rows(results)
    if not rows:
        return rows
    with open(HERE / "results.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print("| point | v LIGGGHTS | v dem (L conv.) | dem - L | v dem (defaults) | dem def. - L "
          "| v point mass | bulk / pm | tau L, dem | dem / L speed |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        ok = "" if r["agree"] else " **x**"
        fills = "" if r["seeds"] == 1 else f" ({r['seeds']} fills)"
        print(f"| {r['point']}{fills} | {r['v_liggghts']:.4f} +- {r['se_liggghts']:.4f} "
              f"| {r['v_dem_eq']:.4f} +- {r['se_dem_eq']:.4f} "
              f"| {r['eq_minus_L_percent']:+.1f} % ({r['eq_minus_L_sigma']:+.1f} s){ok} "
              f"| {r['v_dem_default']:.4f} +- {r['se_dem_default']:.4f} "
              f"| {r['default_minus_L_percent']:+.1f} % ({r['default_minus_L_sigma']:+.1f} s) "
              f"| {r['v_point_mass']:.4f} | {r['bulk_over_point_mass']:.2f} "
              f"| {r['tau_L']:.1f}, {r['tau_dem']:.1f} "
              f"| {r['dem_over_liggghts_speed']:.2f} |")  # fmt: skip
    print()
    print("| point | dem defaults - dem (L conv.) | of it: eps_n 0.06 -> 0 | tangential law |")
    print("|---|---|---|---|")
    for r in rows:
        if math.isfinite(r["eps_n_part_percent"]):
            print(f"| {r['point']} | {r['conventions_percent']:+.1f} % "
                  f"| {r['eps_n_part_percent']:+.1f} % "
                  f"| {r['tangential_part_percent']:+.1f} % |")  # fmt: skip
    summarise(rows)
    plot(rows)
    return rows


def summarise(rows: list[dict]) -> None:
    """Per shape: agreement count, worst and mean difference, bulk over point mass per fill, and
    the median speed ratio."""
    for shape in ("sphere", "screw"):
        sel = [r for r in rows if r["shape"] == shape]
        if not sel:
            continue
        d = np.array([r["eq_minus_L_percent"] for r in sel])
        ok = sum(r["agree"] for r in sel)
        print(f"{shape}s: {ok}/{len(sel)} agree; dem - L mean {d.mean():+.1f} %, worst "
              f"{d[np.argmax(np.abs(d))]:+.1f} %; dem / L grain-steps/s median "
              f"{np.median([r['dem_over_liggghts_speed'] for r in sel]):.2f}")  # fmt: skip
        for fill in FILLS:
            f = [r["bulk_over_point_mass"] for r in sel if r["fill"] == fill]
            if f:
                print(f"  {fill}: LIGGGHTS bulk / point mass {min(f):.2f} .. {max(f):.2f}")


def plot(rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 8), sharex="col")
    for i, shape in enumerate(("sphere", "screw")):
        for j, gamma in enumerate(GAMMAS):
            ax = axes[i, j]
            for fill, ls in (("deep", "-"), ("shallow", "--")):
                sel = sorted(
                    (r for r in rows if r["shape"] == shape and r["gamma"] == gamma
                     and r["fill"] == fill and r["alpha_deg"] == 0.0),
                    key=lambda r: r["phi_deg"],
                )  # fmt: skip
                if not sel:
                    continue
                phi = [r["phi_deg"] for r in sel]
                ax.errorbar(phi, [r["v_liggghts"] for r in sel], [r["se_liggghts"] for r in sel],
                            color="k", ls=ls, marker="o", mfc="none", capsize=3,
                            label=f"LIGGGHTS, {fill}")  # fmt: skip
                ax.errorbar(phi, [r["v_dem_eq"] for r in sel], [r["se_dem_eq"] for r in sel],
                            color="C0", ls=ls, marker="s", capsize=3,
                            label=f"dem, LIGGGHTS's conventions, {fill}")  # fmt: skip
                ax.errorbar(phi, [r["v_dem_default"] for r in sel],
                            [r["se_dem_default"] for r in sel], color="C1", ls=ls, marker="^",
                            capsize=3, label=f"dem, defaults, {fill}")  # fmt: skip
                if fill == "deep":
                    ax.plot(phi, [r["v_point_mass"] for r in sel], color="C2", ls=":", marker="x",
                            label="point mass (eps_n 0, eps_t 0.8)")  # fmt: skip
            up = [r for r in rows if r["shape"] == shape and r["gamma"] == gamma
                  and r["alpha_deg"] != 0.0]  # fmt: skip
            for r in up:
                ax.errorbar([r["phi_deg"] + 1.0], [r["v_dem_eq"]], [r["se_dem_eq"]], color="C0",
                            marker="v", ls="none", capsize=3)  # fmt: skip
                ax.errorbar([r["phi_deg"] + 1.0], [r["v_liggghts"]], [r["se_liggghts"]],
                            color="k", marker="v", mfc="none", ls="none", capsize=3)  # fmt: skip
                ax.annotate(f"uphill {r['alpha_deg']:g} deg, {r['fill']}",
                            (r["phi_deg"] + 1.0, r["v_liggghts"]), fontsize=7)  # fmt: skip
            ax.set_title(f"{shape}s, Gamma = {gamma:g}")
            ax.set_ylabel("mean conveying velocity (m/s)")
            ax.grid(alpha=0.3)
            if i == 1:
                ax.set_xlabel("vibration angle phi (deg)")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("dem against LIGGGHTS-PUBLIC 3.8 and the point mass (error bars: correlated se)")
    fig.tight_layout()
    fig.savefig(HERE / "matrix.png", dpi=120)
    plt.close(fig)

    # dem - LIGGGHTS in % of LIGGGHTS, every point, against the 5 % band
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, shape in zip(axes, ("sphere", "screw"), strict=True):
        sel = [r for r in rows if r["shape"] == shape]
        for k, r in enumerate(sel):
            x = k
            lig = r["v_liggghts"]
            for key, se_key, dx, style in (
                ("eq_minus_L_percent", "se_dem_eq", -0.15, dict(c="C0", marker="s")),
                ("default_minus_L_percent", "se_dem_default", 0.15, dict(c="C1", marker="^")),
            ):
                err = 100.0 * math.hypot(r[se_key], r["se_liggghts"]) / lig
                ax.errorbar(x + dx, r[key], err, capsize=2, ls="none", **style)
        ax.axhspan(-AGREE_PERCENT, AGREE_PERCENT, color="0.9", zorder=0)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xticks(range(len(sel)))
        ax.set_xticklabels(
            [f"{r['phi_deg']:g}/{r['gamma']:g}{'/up' if r['alpha_deg'] else ''}/"
             f"{r['fill'][0]}" for r in sel], rotation=90, fontsize=7,
        )  # fmt: skip
        ax.set_title(f"{shape}s: phi / Gamma / fill (d deep, s shallow)", fontsize=10)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("dem - LIGGGHTS (% of LIGGGHTS)")
    axes[0].errorbar([], [], [], c="C0", marker="s", ls="none", label="LIGGGHTS's conventions")
    axes[0].errorbar([], [], [], c="C1", marker="^", ls="none", label="dem's defaults")
    axes[0].legend(fontsize=8, loc="lower left")
    fig.suptitle("dem against LIGGGHTS-PUBLIC 3.8 (grey: the 5 % band; bars: 1 combined se)")
    fig.tight_layout()
    fig.savefig(HERE / "difference.png", dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default="", help="run only points whose name contains this")
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--redo", action="store_true", help="rerun points already in results.json")
    ap.add_argument("--seed", type=int, default=1, help="another fill of the chosen points")
    args = ap.parse_args(argv)
    results = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
    results.setdefault("points", {})
    if not args.report_only:
        results.setdefault("invocations", []).append({
            "command": header.invocation("validation/liggghts/matrix.py", argv or None),
            "git_commit": provenance.git_commit(),
            "date": provenance.utc_now(),
            "cores": os.cpu_count(),
            "numba_threads": 1,
            "liggghts_ranks": 1,
        })  # fmt: skip
        for p in points():
            p = dataclasses.replace(p, seed=args.seed)
            if args.only in p.name:
                run_point(p, results, args.redo)
    report(results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
