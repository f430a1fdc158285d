"""Bulk conveying velocity of dem against LIGGGHTS-PUBLIC 3.8 on the same sphere bed.

Regenerates results.json, results.csv, velocity.png and decks/phi_XX/in.dem in this folder
(defaults: phi = 5..55 deg, 15 settle + 30 measured cycles, seed 1, dem on 1 thread):

    .venv/bin/python validation/liggghts-bulk/run.py                      # both codes
    .venv/bin/python validation/liggghts-bulk/run.py --skip-liggghts      # dem only
    .venv/bin/python validation/liggghts-bulk/run.py --report-only        # csv + figure
    # second fill (seed 2), drawn hollow in velocity.png:
    .venv/bin/python validation/liggghts-bulk/run.py --seed 2 --no-report \
        --results validation/liggghts-bulk/seed2/results.json \
        --decks validation/liggghts-bulk/seed2/decks \
        --scratch validation/liggghts-bulk/scratch/seed2

Base case: sphere-bed-5e7 here, the LIGGGHTS-parity bed (cases/sphere-bed as shipped until
2026-11-26: 1500 Hertz spheres r = 2 mm, E = 5e7 Pa, nu = 0.3, mu = 0.35,
0.10 m x 0.04 m periodic section, 60 Hz, A = 0.5 mm), with restitution_normal = 0.06 in BOTH
codes (LIGGGHTS refuses e <= 0.05; README, A short tour), the same explicit time step and the
same number of settle and measured drive cycles. The vibration angle phi is swept at fixed
amplitude, so Gamma = A omega^2 sin(phi) / g changes with phi.

dem: dem.run.runner.run_case (no frames), per-cycle mass-weighted mean x-velocities from its
summary. LIGGGHTS: the deck of dem.io.liggghts.write_deck with ``sample_steps = 1``, so vx_mean.txt
holds the mean x-velocity of every step and is binned here into exactly the drive cycles dem uses
(cycle c = driven steps round(c P / dt) + 1 ... round((c + 1) P / dt)). Equal sphere masses, so the
plain mean is the mass-weighted mean. Skipped with a message if ``liggghts`` is not on PATH.

Both: v = mean of the per-cycle means, standard error = the correlated standard error of the
per-cycle means (``dem.physics.measure.correlated_stderr``; std(ddof=1) / sqrt(cycles) would
understate it, successive cycles of a bed being correlated). The run of both codes is
validation/_lib/pair.py's. Not part of the test suite.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from dem import pointmass
from dem.io.liggghts import DECK_NAME
from dem.scene.case import load_case

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import header, pair, replicas  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

ANGLES = (5.0, 15.0, 25.0, 35.0, 45.0, 55.0)
RESTITUTION = 0.06
POINTMASS_EPS_T, POINTMASS_EPS_N = 0.8, 0.0


def make_case(base, angle: float, args):
    """The base case at vibration angle ``angle`` (fixed amplitude) with the comparison settings."""
    return dataclasses.replace(
        base.with_drive(angle=angle, amplitude=base.drive.amplitude).with_tangential("liggghts"),
        material=dataclasses.replace(base.material, restitution_normal=RESTITUTION),
        run=dataclasses.replace(
            base.run,
            timestep=args.timestep,
            settle_cycles=args.settle_cycles,
            cycles=args.cycles,
            seed=args.seed,
        ),
    )


def diagnostics(per_cycle) -> dict:
    """Checks on the per-cycle standard error (not used for the comparison itself).

    stderr_pair_means: standard error from means over consecutive pairs of cycles (removes a
    period-2 alternation, which makes the per-cycle error too large); trend_per_10_cycles:
    least-squares slope of the per-cycle means (a drift left from the start-up makes the
    per-cycle error too small); lag1_autocorrelation of the per-cycle means.
    """
    u = np.asarray(per_cycle, dtype=float)
    pairs = u[: u.size // 2 * 2].reshape(-1, 2).mean(axis=1)
    x = np.arange(u.size)
    slope = float(np.polyfit(x, u, 1)[0]) if u.size > 2 else math.nan
    d = u - u.mean()
    r1 = float(np.dot(d[:-1], d[1:]) / np.dot(d, d)) if u.size > 2 else math.nan
    return {
        "stderr_pair_means": replicas.replica_stderr(pairs) if pairs.size > 1 else math.nan,
        "trend_per_10_cycles": 10.0 * slope,
        "lag1_autocorrelation": r1,
    }


def tag(angle: float) -> str:
    return f"phi_{angle:g}"


# --------------------------------------------------------------------------- the pair
def run_both(case, args) -> pair.Pair:
    """LIGGGHTS (unless --skip-liggghts), then dem (unless --skip-dem), at one angle."""
    name = tag(case.drive.angle)
    return pair.run_pair(
        case,
        deck_dir=Path(args.decks) / name,
        work=Path(args.scratch) / "liggghts" / name,
        dem_out=Path(args.scratch) / "dem" / name,
        threads=args.threads,
        skip_reference=args.skip_liggghts,
        skip_dem=args.skip_dem,
        min_loops=2,
        strict_settle=False,
    )


def liggghts_entry(case, lig: pair.ReferenceRun) -> dict:
    """results.json's LIGGGHTS half of a point: per-cycle means binned into dem's cycles."""
    run, work = lig.run, lig.work
    mean, se = replicas.series_mean(lig.per_cycle)
    print(f"  LIGGGHTS phi = {case.drive.angle:g}: v = {mean:.5f} +- {se:.5f} m/s "
          f"({run.wall_s:.0f} s)")  # fmt: skip
    return {
        "version": run.version,
        "deck": str(lig.deck.relative_to(ROOT)),
        "command": f"cd {work.relative_to(ROOT)} && liggghts -in {DECK_NAME}",
        "log": str((work / "log.liggghts").relative_to(ROOT)),
        "mean_velocity": mean,
        "mean_velocity_stderr": se,
        "per_cycle_velocity": lig.per_cycle,
        "settle_cycle_velocity": lig.settle_cycle,
        "drive_start_step": lig.drive_start,
        "loop_times_s": [x.seconds for x in run.loop_times],
        "wall_time_s": run.wall_s,
    }


def dem_entry(case, dem: pair.DemRun, args) -> dict:
    """results.json's dem half of a point: the numbers of run_case's summary."""
    summary, wall = dem.summary, dem.wall_s
    print(
        f"  dem      phi = {case.drive.angle:g}: v = {summary['mean_velocity']:.5f} +- "
        f"{summary['mean_velocity_stderr']:.5f} m/s ({wall:.0f} s)"
    )
    return {
        "command": (
            f"dem.run.runner.run_case(case, out, cycles={case.run.cycles}, threads={args.threads}, "
            "progress=False, overwrite=True, frames=False)"
        ),
        "mean_velocity": summary["mean_velocity"],
        "mean_velocity_stderr": summary["mean_velocity_stderr"],
        "per_cycle_velocity": summary["per_cycle_velocity"],
        "timestep": summary["timestep"],
        "timestep_limit": summary["timestep_limit"],
        "settle_time_s": summary["settle_time_s"],
        "steps": summary["steps"],
        "threads": summary["threads"],
        "wall_time_s": wall,
    }


# --------------------------------------------------------------------------- report
def point_mass(case) -> dict:
    d = case.drive
    r = pointmass.velocity(
        throw_number=d.throw_number,
        angle=d.angle,
        friction=case.material.friction,
        inclination=case.trough.inclination,
        eps_t=POINTMASS_EPS_T,
        eps_n=POINTMASS_EPS_N,
    )
    return {
        "velocity": r.velocity(d.frequency),
        "velocity_norm": r.velocity_norm,
        "regime": r.regime,
        "eps_t": POINTMASS_EPS_T,
        "eps_n": POINTMASS_EPS_N,
    }


def compare(entry: dict) -> None:
    dem, lig = entry.get("dem", {}), entry.get("liggghts", {})
    for half in (dem, lig):
        if "per_cycle_velocity" in half:
            half["diagnostics"] = diagnostics(half["per_cycle_velocity"])
    if "mean_velocity" in dem and "mean_velocity" in lig:
        entry["difference"] = replicas.difference(
            dem["mean_velocity"], dem["mean_velocity_stderr"],
            lig["mean_velocity"], lig["mean_velocity_stderr"],
        )  # fmt: skip


def table_rows(results: dict) -> list[dict]:
    rows = []
    for key in sorted(results["points"], key=lambda k: results["points"][k]["angle"]):
        p = results["points"][key]
        dem, lig, diff = p.get("dem", {}), p.get("liggghts", {}), p.get("difference", {})
        rows.append(
            {
                "phi_deg": p["angle"],
                "gamma": round(p["throw_number"], 4),
                "v_dem": dem.get("mean_velocity"),
                "se_dem": dem.get("mean_velocity_stderr"),
                "v_liggghts": lig.get("mean_velocity"),
                "se_liggghts": lig.get("mean_velocity_stderr"),
                "diff_sigma": diff.get("sigma"),
                "diff_percent": diff.get("percent_of_liggghts"),
                "v_pointmass": p["pointmass"]["velocity"],
                "pointmass_regime": p["pointmass"]["regime"],
            }
        )
    return rows


def write_tables(results: dict) -> list[dict]:
    rows = table_rows(results)
    with open(HERE / "results.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    return rows


def plot(rows, check_rows=None) -> None:
    """velocity.png: v(phi) of both codes and the point mass; below, dem - LIGGGHTS in %."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def col(rs, name):
        return np.array([np.nan if r[name] is None else r[name] for r in rs], dtype=float)

    phi = col(rows, "phi_deg")
    fig, (ax, bx) = plt.subplots(
        2, 1, figsize=(6.4, 6.4), sharex=True, gridspec_kw={"height_ratios": [2.2, 1]}
    )
    ax.errorbar(phi - 0.5, col(rows, "v_dem"), yerr=col(rows, "se_dem"), fmt="o", capsize=3,
                color="C0", label="dem (seed 1)")  # fmt: skip
    ax.errorbar(phi + 0.5, col(rows, "v_liggghts"), yerr=col(rows, "se_liggghts"), fmt="s",
                capsize=3, color="C1", label="LIGGGHTS-PUBLIC 3.8 (seed 1)")  # fmt: skip
    if check_rows:
        cphi = col(check_rows, "phi_deg")
        ax.errorbar(cphi - 1.2, col(check_rows, "v_dem"), yerr=col(check_rows, "se_dem"),
                    fmt="o", mfc="none", capsize=2, color="C0", label="dem (seed 2)")  # fmt: skip
        ax.errorbar(cphi + 1.2, col(check_rows, "v_liggghts"), yerr=col(check_rows, "se_liggghts"),
                    fmt="s", mfc="none", capsize=2, color="C1",
                    label="LIGGGHTS (seed 2)")  # fmt: skip
    ax.plot(phi, col(rows, "v_pointmass"), "k--^",
            label=r"point mass ($\epsilon_t$=0.8, $\epsilon_n$=0)")  # fmt: skip
    top = ax.secondary_xaxis("top")
    top.set_xticks(phi)
    top.set_xticklabels([f"{r['gamma']:.2f}" for r in rows])
    top.set_xlabel(r"$\Gamma$ = A$\omega^2$ sin$\varphi$ / g")
    ax.set_ylabel("mean conveying velocity (m/s)")
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, title="sphere-bed: 1500 Hertz spheres, e = 0.06", title_fontsize=7,
              loc="lower center")  # fmt: skip

    def rel(rs):
        d, lg = col(rs, "v_dem"), col(rs, "v_liggghts")
        se = np.hypot(col(rs, "se_dem"), col(rs, "se_liggghts"))
        return 100.0 * (d - lg) / lg, 100.0 * se / lg

    y, e = rel(rows)
    bx.errorbar(phi, y, yerr=e, fmt="D", color="C2", capsize=3, label="seed 1")
    if check_rows:
        y2, e2 = rel(check_rows)
        bx.errorbar(col(check_rows, "phi_deg") + 1.0, y2, yerr=e2, fmt="D", mfc="none",
                    color="C2", capsize=3, label="seed 2")  # fmt: skip
    bx.axhline(0.0, color="k", lw=0.8)
    bx.set_ylabel("(dem - LIGGGHTS) / LIGGGHTS (%)", fontsize=8)
    bx.set_xlabel(r"vibration angle $\varphi$ (deg), A = 0.5 mm, f = 60 Hz")
    bx.grid(alpha=0.3)
    bx.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(HERE / "velocity.png", dpi=120)


def seed_check_rows(args) -> list[dict] | None:
    path = Path(args.seed_check)
    if not path.exists() or path.resolve() == Path(args.results).resolve():
        return None
    rows = table_rows(json.loads(path.read_text()))
    return [r for r in rows if r["v_dem"] is not None and r["v_liggghts"] is not None] or None


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", default=str(HERE / "sphere-bed-5e7"))
    parser.add_argument("--angles", type=float, nargs="+", default=list(ANGLES))
    parser.add_argument("--timestep", type=float, default=5e-6, help="s, both codes")
    parser.add_argument("--settle-cycles", type=int, default=15)
    parser.add_argument("--cycles", type=int, default=30, help="measured drive cycles")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--threads", type=int, default=1,
        help="dem numba threads (1: on a shared 2-core machine 2 OpenMP threads crawl)",
    )  # fmt: skip
    parser.add_argument(
        "--seed-check", default=str(HERE / "seed2" / "results.json"),
        help="results.json of a second-seed run, drawn hollow in velocity.png if it exists",
    )  # fmt: skip
    parser.add_argument("--skip-liggghts", action="store_true")
    parser.add_argument("--skip-dem", action="store_true")
    parser.add_argument("--results", default=str(HERE / "results.json"))
    parser.add_argument("--decks", default=str(HERE / "decks"), help="deck folders go here")
    parser.add_argument("--scratch", default=str(HERE / "scratch"), help="run folders go here")
    parser.add_argument("--no-report", action="store_true", help="no results.csv/velocity.png")
    parser.add_argument(
        "--report-only", action="store_true", help="rewrite results.csv/velocity.png only"
    )
    args = parser.parse_args(argv)
    for name in ("results", "decks", "scratch", "seed_check"):
        setattr(args, name, str(Path(getattr(args, name)).resolve()))

    base = load_case(args.case)
    path = Path(args.results)
    results = json.loads(path.read_text()) if path.exists() else {}
    if args.report_only:
        plot(write_tables(results), seed_check_rows(args))
        return
    top = header.results_header("validation/liggghts-bulk/run.py", argv)
    results.update(
        {
            "case": str(Path(args.case).resolve().relative_to(ROOT)),
            "script": top.pop("script"),
            "restitution_normal": RESTITUTION,
            "timestep": args.timestep,
            "settle_cycles": args.settle_cycles,
            "cycles": args.cycles,
            "seed": args.seed,
            **top,  # dem_version, git_commit, machine
        }
    )
    results.setdefault("points", {})
    t_start = time.perf_counter()
    for angle in args.angles:
        case = make_case(base, angle, args)
        print(f"phi = {angle:g} deg, Gamma = {case.drive.throw_number:.3f}")
        key = tag(angle)
        entry = results["points"].get(key, {})
        entry.update(
            {
                "angle": angle,
                "amplitude": case.drive.amplitude,
                "throw_number": case.drive.throw_number,
                "frequency": case.drive.frequency,
                "pointmass": point_mass(case),
            }
        )
        stamp = header.stamp()
        both = run_both(case, args)
        if isinstance(both.reference, str):  # liggghts is not on PATH
            if "mean_velocity" in entry.get("liggghts", {}):
                print("  keeping the earlier LIGGGHTS result of this point")
            else:
                entry["liggghts"] = {**stamp, "skipped": both.reference}
        elif both.reference is not None:
            entry["liggghts"] = {**stamp, **liggghts_entry(case, both.reference)}
        if both.dem is not None:
            entry["dem"] = {**stamp, **dem_entry(case, both.dem, args)}
        compare(entry)
        results["points"][key] = entry
        path.write_text(json.dumps(results, indent=2) + "\n")  # after each point
    results["total_wall_time_s_last_invocation"] = time.perf_counter() - t_start
    path.write_text(json.dumps(results, indent=2) + "\n")
    if args.no_report:
        return
    rows = write_tables(results)
    plot(rows, seed_check_rows(args))
    print(f"wrote {path}, results.csv, velocity.png ({time.perf_counter() - t_start:.0f} s)")


if __name__ == "__main__":
    main()
