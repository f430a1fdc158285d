"""Long runs of the shipped beds at five drives: series to judge settle rules and error bars on.

Each run is ``dem run``'s path (:func:`dem.run.runner.run_case`) with ``run.settle_cycles = 0``:
every driven cycle from the moment the drive starts is recorded, so any settle rule can be replayed
on the series afterwards, cycle for cycle what ``dem run`` would have measured with it (the
dynamics do not depend on whether a cycle is called settling or measured). The shipped beds
(cases/screw-trough, cases/sphere-bed, as shipped: 2e9 Pa, their step), drives other than the
shipped ones, ``FILLS`` fills each (seeds 1..FILLS), ``CYCLES`` cycles a run.

    .venv/bin/python validation/steadiness/beds.py run [--workers 2] [--fills 6]
    .venv/bin/python validation/steadiness/beds.py collect     # scratch/ -> series.csv
    .venv/bin/python validation/steadiness/beds.py analyse     # series.csv -> rules.csv, series.png

Resumable: a run whose cycles.csv is in ``scratch/`` is not run again; runs go seed by seed over
every drive, so a study stopped early has the same number of fills at each drive. ``series.csv``
holds every cycle of every finished run; ``beds_provenance.json`` the command, versions, commit,
machine, load average and the cost of each run.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))

SCRIPT = "validation/steadiness/beds.py"
SCRATCH = HERE / "scratch"
#: (throw number, vibration angle in degrees): none is a shipped bed's drive (screws: 1.8 at
#: 25 deg; spheres: 3.06 at 25 deg); the hardening check's (1.2, 25) and (1.8, 10-50) among them,
#: one in the period-2 band of the point mass (4.0 > sqrt(4 + pi^2)).
DRIVES = ((1.2, 25.0), (1.8, 10.0), (1.8, 50.0), (2.5, 30.0), (4.0, 25.0))
BEDS = ("screw-trough", "sphere-bed")
CYCLES = {"screw-trough": 80, "sphere-bed": 60}
FILLS = 6


def drive_overrides(bed: str, gamma: float, angle: float) -> dict:
    """The drive of a point as overrides: the throw number, or for a case that gives its drive
    as an amplitude (cases/sphere-bed) the amplitude of that throw number (level trough)."""
    import math

    from dem.config import GRAVITY
    from dem.scene.case import load_case

    case = load_case(ROOT / "cases" / bed)
    if case.drive.given == "throw_number":
        return {"drive.throw_number": gamma, "drive.angle": angle}
    omega = 2.0 * math.pi * case.drive.frequency
    amplitude = gamma * GRAVITY / (omega**2 * math.sin(math.radians(angle)))
    return {"drive.amplitude": amplitude, "drive.angle": angle}


def run_name(bed: str, gamma: float, angle: float, seed: int) -> str:
    return f"{bed}_G{gamma:g}_phi{angle:g}_s{seed}"


def jobs(fills: int) -> list[tuple]:
    return [(bed, g, a, seed) for seed in range(1, fills + 1) for bed in BEDS
            for g, a in DRIVES]  # fmt: skip


def one(job: tuple) -> dict:
    """One long run into scratch/NAME (skipped when its cycles.csv is there)."""
    import numba

    from dem.run.runner import run_case
    from dem.scene.case import load_case

    bed, gamma, angle, seed = job
    out = SCRATCH / run_name(bed, gamma, angle, seed)
    if (out / "cycles.csv").exists():
        return {"name": out.name, "skipped": True}
    numba.set_num_threads(1)
    case = load_case(ROOT / "cases" / bed, {
        **drive_overrides(bed, gamma, angle), "run.seed": seed,
        "run.settle_cycles": 0, "run.cycles": CYCLES[bed]})  # fmt: skip
    t0 = time.perf_counter()
    try:
        s = run_case(case, out, threads=1, progress=False, frames=False, overwrite=True)
    except Exception as exc:  # reported, and the other runs go on
        return {"name": out.name, "error": f"{type(exc).__name__}: {exc}"}
    return {"name": out.name, "wall_time_s": round(time.perf_counter() - t0, 1),
            "particle_steps_per_s": s["particle_steps_per_s"],
            "mean_velocity_norm": s["mean_velocity_norm"]}  # fmt: skip


def run(workers: int, fills: int) -> None:
    from multiprocessing import get_context

    from dem import provenance
    from validation._lib.header import results_header

    SCRATCH.mkdir(exist_ok=True)
    todo = jobs(fills)
    path = HERE / "beds_provenance.json"
    record = json.loads(path.read_text()) if path.exists() else {"runs": {}}
    record.update(results_header(SCRIPT, dated=True))
    record.setdefault("load_averages_at_start", []).append(provenance.load_average())
    t0 = time.perf_counter()
    with get_context("spawn").Pool(workers) as pool:
        for i, r in enumerate(pool.imap(one, todo)):
            if not r.get("skipped"):
                record["runs"][r["name"]] = {**r, "load_average": provenance.load_average()}
                path.write_text(json.dumps(record, indent=2) + "\n")
            print(f"{i + 1}/{len(todo)} {r} ({time.perf_counter() - t0:.0f} s)", flush=True)
    collect()


def collect() -> None:
    rows = []
    for bed, gamma, angle, seed in jobs(99):
        f = SCRATCH / run_name(bed, gamma, angle, seed) / "cycles.csv"
        if not f.exists():
            continue
        with open(f) as fh:
            for r in csv.DictReader(line for line in fh if not line.startswith("#")):
                rows.append({"bed": bed, "throw_number": gamma, "angle_deg": angle, "seed": seed,
                             "cycle": int(r["cycle"]),
                             "velocity_norm": float(r["velocity_norm"])})  # fmt: skip
    if not rows:  # never overwrite the recorded series with nothing
        raise SystemExit(f"no finished runs in {SCRATCH}: series.csv left as it is")
    with open(HERE / "series.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"series.csv: {len(rows)} cycles", flush=True)


def load_series() -> dict:
    """series.csv as {(bed, gamma, angle): {seed: per-cycle v_norm array}}."""
    import numpy as np

    out: dict = {}
    with open(HERE / "series.csv") as fh:
        for r in csv.DictReader(fh):
            key = (r["bed"], float(r["throw_number"]), float(r["angle_deg"]))
            out.setdefault(key, {}).setdefault(int(r["seed"]), []).append(float(r["velocity_norm"]))
    return {k: {s: np.array(v) for s, v in d.items()} for k, d in out.items()}


#: The measured cycles a default run of the shipped beds takes (their case.toml's run.cycles).
MEASURED = 20
#: The long-run mean of a drive: the mean over the fills of each fill's cycles from here on.
LATE_FRACTION = 0.5


def settle_floors() -> dict:
    """The automatic settle's least cycles per bed and drive (``dem.run.record.settle_floor``)."""
    from dem.run.record import settle_floor
    from dem.scene.case import load_case

    out = {}
    for bed in BEDS:
        for g, a in DRIVES:
            case = load_case(ROOT / "cases" / bed, drive_overrides(bed, g, a))
            out[(bed, g, a)] = (settle_floor(case), case.drive.velocity_scale)
    return out


def replay_settle(x, floor: int, rule: str, z_settle: float) -> int:
    """The settling cycles the rule would have taken on the series ``x`` (v_norm per cycle).

    ``mser``: dem's rule as shipped (:func:`dem.physics.measure.steady`, the floor, the
    tolerance of ``DEM_AUTO_SETTLE_TOLERANCE`` in v_norm); ``mser+trend``: and no trend beyond
    ``z_settle`` over what MSER keeps of the settling series; ``fixed:N``: N cycles.
    """
    from dem import config
    from dem.physics import measure

    if rule.startswith("fixed:"):
        return int(rule.split(":")[1])
    cap = min(config.DEM_AUTO_SETTLE_MAX_CYCLES, len(x) - MEASURED)
    for n in range(1, cap + 1):
        head = x[:n]
        if not measure.steady(head, floor, config.DEM_AUTO_SETTLE_TOLERANCE):
            continue
        if rule == "mser+trend":
            kept = head[measure.transient_end(head) :]
            if abs(measure.trend(kept).z) > z_settle:
                continue
        return n
    return cap


def analyse() -> None:
    """Replays settle rules and error bars on series.csv: rules.csv and the coverage table."""
    import itertools

    import numpy as np

    from dem.physics import measure

    data = load_series()
    floors = settle_floors()
    rows = []
    for (bed, g, a), fills in sorted(data.items()):
        seeds = sorted(fills)
        if len(seeds) < 3:
            continue
        floor, _ = floors[(bed, g, a)]
        n = min(len(v) for v in fills.values())
        late = {s: float(np.mean(fills[s][int(LATE_FRACTION * n) : n])) for s in seeds}
        # is the long run itself still moving? the fills' mean series over the late half
        mean_late = np.mean([fills[s][int(LATE_FRACTION * n) : n] for s in seeds], axis=0)
        late_trend = measure.trend(mean_late)
        for rule in ("mser", "mser+trend", "fixed:20", "fixed:40"):
            for extend in (False, True):
                runs = {}
                for s in seeds:
                    x = fills[s][:n]
                    k = replay_settle(x, floor, rule, 2.0)
                    m = min(MEASURED, n - k)
                    measured = x[k : k + m]
                    extended = 0
                    while extend and extended < 2 and abs(measure.trend(measured).z) > 3.0:
                        if k + len(measured) + MEASURED > n:
                            break
                        measured = x[k : k + len(measured) + MEASURED]
                        extended += 1
                    se = measure.correlated_stderr(measured)[0]
                    runs[s] = (float(measured.mean()), se, k, len(measured))
                # judged against the other fills' long-run mean (no interval against itself)
                single = []
                for s in seeds:
                    ref = np.mean([late[t] for t in seeds if t != s])
                    mean, se, k, m = runs[s]
                    single.append((abs(mean - ref) <= 1.959964 * se, mean - ref, k, m))
                triples = []
                for tri in itertools.combinations(seeds, 3):
                    p = measure.pooled([runs[s][0] for s in tri], [runs[s][1] for s in tri])
                    ref = np.mean([late[t] for t in seeds if t not in tri] or [np.nan])
                    triples.append(abs(p.mean - ref) <= p.half_width)
                rows.append({
                    "bed": bed, "throw_number": g, "angle_deg": a, "fills": len(seeds),
                    "cycles_per_fill": n, "rule": rule, "extend": extend,
                    "settle_cycles_median": float(np.median([r[2] for r in single])),
                    "measured_cycles_mean": float(np.mean([r[3] for r in single])),
                    "bias_mean": float(np.mean([r[1] for r in single])),
                    "bias_rms": float(np.sqrt(np.mean([r[1] ** 2 for r in single]))),
                    "stderr_median": float(np.median([runs[s][1] for s in seeds])),
                    "fill_spread": float(np.std(list(late.values()), ddof=1)),
                    "long_run_mean": float(np.mean(list(late.values()))),
                    "late_trend_z": late_trend.z, "late_change": late_trend.change,
                    "covered_single": sum(r[0] for r in single),
                    "covered_triples": sum(triples), "triples": len(triples),
                })  # fmt: skip
    with open(HERE / "rules.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    _tables(rows)
    for rule in ("mser", "mser+trend", "fixed:20", "fixed:40"):
        for extend in (False, True):
            for bed in BEDS:
                sel = [r for r in rows if r["rule"] == rule and r["extend"] == extend
                       and r["bed"] == bed]  # fmt: skip
                if not sel:
                    continue
                c1 = sum(r["covered_single"] for r in sel) / sum(r["fills"] for r in sel)
                c3 = sum(r["covered_triples"] for r in sel) / sum(r["triples"] for r in sel)
                print(f"{bed:13s} {rule:11s} extend={extend!s:5s} one run {c1:6.1%}  "
                      f"3 fills {c3:6.1%}  settle {[r['settle_cycles_median'] for r in sel]} "
                      f"bias {[round(r['bias_mean'], 4) for r in sel]}")  # fmt: skip


def _tables(rows: list[dict]) -> None:
    """coverage.md: the coverage table (bed x rule) and the per-drive table of the README."""
    names = {
        ("mser", False): "MSER (before)",
        ("mser+trend", False): "MSER and trend",
        ("mser+trend", True): "MSER and trend, extended (now)",
        ("fixed:20", True): "20 cycles, extended",
        ("fixed:40", True): "40 cycles, extended",
    }
    out = ["| settle | bed | settling cycles (median per drive) | one run covers "
           "| 3 fills pooled cover |", "| --- | --- | --- | --- | --- |"]  # fmt: skip
    for (rule, extend), label in names.items():
        for bed in BEDS:
            sel = [r for r in rows if r["rule"] == rule and r["extend"] == extend
                   and r["bed"] == bed]  # fmt: skip
            if not sel:
                continue
            fills = sum(r["fills"] for r in sel)
            c1 = sum(r["covered_single"] for r in sel)
            n3 = sum(r["triples"] for r in sel)
            c3 = sum(r["covered_triples"] for r in sel)
            settle = ", ".join(f"{r['settle_cycles_median']:g}" for r in sel)
            out.append(f"| {label} | {bed} | {settle} | {c1}/{fills} ({100 * c1 / fills:.0f} %) | "
                       f"{c3}/{n3} ({100 * c3 / n3:.0f} %) |")  # fmt: skip
    out += ["", "| bed | Gamma | phi (deg) | fills | long-run mean | fill spread (sd) | one run's "
            "error (median) | its bias (mean) | late-half change (z) |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]  # fmt: skip
    for r in rows:
        if (r["rule"], r["extend"]) != ("mser+trend", True):
            continue
        out.append(f"| {r['bed']} | {r['throw_number']:g} | {r['angle_deg']:g} | {r['fills']} | "
                   f"{r['long_run_mean']:.4f} | {r['fill_spread']:.4f} | "
                   f"{r['stderr_median']:.4f} | {r['bias_mean']:+.4f} | "
                   f"{r['late_change']:+.4f} ({r['late_trend_z']:+.1f}) |")  # fmt: skip
    (HERE / "coverage.md").write_text("\n".join(out) + "\n")
    print("\n".join(out))


def figure() -> None:
    """series.png: every fill's per-cycle v_norm at each drive, where the settle rules end, and
    the long-run mean (the fills' late halves)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    data = load_series()
    floors = settle_floors()
    fig, axes = plt.subplots(len(BEDS), len(DRIVES), figsize=(17, 6.5), sharex="row")
    for i, bed in enumerate(BEDS):
        for j, (g, a) in enumerate(DRIVES):
            ax = axes[i, j]
            fills = data.get((bed, g, a), {})
            if not fills:
                continue
            n = min(len(v) for v in fills.values())
            floor, _ = floors[(bed, g, a)]
            for k, (_seed, x) in enumerate(sorted(fills.items())):
                color = f"C{k}"
                ax.plot(np.arange(n), x[:n], color=color, lw=0.8)
                old = replay_settle(x[:n], floor, "mser", 2.0)
                new = replay_settle(x[:n], floor, "mser+trend", 2.0)
                ax.plot(old, x[old], "v", color=color, ms=5)
                ax.plot(new, x[new], "o", color=color, ms=5, mfc="none")
            late = np.mean([np.mean(x[int(LATE_FRACTION * n) : n]) for x in fills.values()])
            ax.axhline(late, color="k", lw=1.2, ls="--")
            lo = min(float(np.min(x[5:n])) for x in fills.values())
            hi = max(float(np.max(x[5:n])) for x in fills.values())
            ax.set_ylim(lo - 0.01, hi + 0.01)
            ax.set_title(f"{bed}: Gamma {g:g}, phi {a:g} deg", fontsize=9)
            if j == 0:
                ax.set_ylabel("v / (A omega cos phi), per cycle")
            if i == len(BEDS) - 1:
                ax.set_xlabel("drive cycle")
    fig.suptitle(
        "Each fill's per-cycle velocity; settle ends: MSER (triangles), MSER and trend "
        "(circles); dashed: the long-run mean (the fills' late halves)",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(HERE / "series.png", dpi=110)
    print(f"wrote {HERE / 'series.png'}")


def main() -> None:
    global SCRATCH
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("part", choices=("run", "collect", "analyse", "figure"))
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--fills", type=int, default=FILLS)
    p.add_argument("--scratch", type=Path, default=SCRATCH, help="where the runs are")
    a = p.parse_args()
    SCRATCH = a.scratch
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    if a.part == "run":
        run(a.workers, a.fills)
    elif a.part == "collect":
        collect()
    elif a.part == "analyse":
        analyse()
        figure()
    else:
        figure()


if __name__ == "__main__":
    main()
