"""A finite feeder in dem and in LIGGGHTS-PUBLIC 3.8: discharge and hold-up, both codes.

Regenerates results.json, discharge.png and decks/<run>/ here (the runs of the README):

    nice -n 10 .venv/bin/python validation/liggghts-feeder/run.py              # both cases, seed 1
    nice -n 10 .venv/bin/python validation/liggghts-feeder/run.py --seed 2
    .venv/bin/python validation/liggghts-feeder/run.py --report-only       # pooled + figure

Cases (``--cases``), each ``dem.scene.case.load_case(case, overrides=...)``:

- ``flat``: cases/feeder (a 0.15 m flat feeder, 2.5 g screws fed at 0.05 kg/s, 50 screws to
  start, Gamma 1.8, 150 start-up + 180 measured cycles);
- ``u-pan``: the U pan of cases/u-trough (0.12 m) as a feeder, with cases/feeder's feed.

Both codes use LIGGGHTS's conventions (``contact.tangential = "liggghts"``, Mindlin k_t,
``restitution_normal = 0.06``), the case's time step 8e-6 s and seed. LIGGGHTS runs the deck of
``dem.io.liggghts.write_deck`` unchanged (one rank); its ``balance.txt`` gives the grains in the
box, fed and discharged (``read_balance``), binned into dem's drive cycles
(``discharge_per_cycle``). dem runs ``dem.run.runner.run_case`` (one thread) and reports the same
per-cycle discharge and end-of-cycle hold-up (results.h5 /cycles). Per code: the steady
discharge rate and the hold-up (mean over the measured cycles, correlated standard errors of
``dem.physics.measure.correlated_stderr``), the grains fed, and the measured wall time.

What is compared: in the steady state both codes discharge what they are fed, so the discharge
rate checks the bookkeeping; the hold-up (kg in the trough at a given feed) is set by the
conveying speed, M = feed L / v, and is the physical comparison. Not part of the test suite.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from dem import __version__, provenance
from dem.engine.feeder import grain_mass
from dem.io.liggghts import (
    BALANCE_FILE,
    DECK_NAME,
    VX_FILE,
    discharge_per_cycle,
    machine_info,
    read_balance,
    run_liggghts,
    write_deck,
)
from dem.scene.case import load_case

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import cycles as drive_cycles  # noqa: E402
from validation._lib import pair, replicas  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CASES = ROOT / "cases"
COMMON = {
    "contact.tangential": "liggghts",
    "contact.tangential_stiffness_ratio": None,  # Hertz under "liggghts" takes Mindlin's k_t
    "contact.tangential_damping_ratio": None,
    "material.restitution_normal": 0.06,  # LIGGGHTS refuses e <= 0.05
    # cases/feeder as shipped when this was measured (2e9 Pa and 4e-6 s since 2026-11-26)
    "contact.youngs_modulus": 5.0e8,
    "run.timestep": 8.0e-6,
}
#: Balance lines per drive cycle in the LIGGGHTS run.
SAMPLES_PER_CYCLE = 8


def make_case(name: str, seed: int):
    overrides = {**COMMON, "run.seed": seed}
    if name == "flat":
        return load_case(CASES / "feeder", overrides=overrides), overrides
    feeder = load_case(CASES / "feeder")
    overrides.update({
        "feeder.feed_rate": feeder.feeder.feed_rate,
        "feeder.feed_length": feeder.feeder.feed_length,
        "particles.count": feeder.particles.count,
        "run.settle_cycles": feeder.run.settle_cycles,
        "run.cycles": feeder.run.cycles,
        "drive.ramp_cycles": feeder.drive.ramp_cycles,
        "output.frames_per_cycle": feeder.output.frames_per_cycle,
    })  # fmt: skip
    return load_case(CASES / "u-trough", overrides=overrides), overrides


def run_liggghts_case(name: str, case, args) -> dict:
    missing = pair.liggghts_missing()
    if missing is not None:
        return {"skipped": missing}
    period, dt = 1.0 / case.drive.frequency, case.run.timestep
    s, c = case.run.settle_cycles, case.run.cycles
    deck_dir = HERE / "decks" / name
    if deck_dir.exists():
        shutil.rmtree(deck_dir)
    steps_per_cycle = drive_cycles.steps_per_cycle(case)
    deck = write_deck(
        case,
        deck_dir,
        timestep=dt,
        steps=round(c * steps_per_cycle),
        settle_steps=round(s * steps_per_cycle),
        sample_steps=max(1, round(steps_per_cycle / SAMPLES_PER_CYCLE)),
    )
    work = Path(args.scratch) / "liggghts" / name
    pair.fresh_copy(deck_dir, work)
    run = run_liggghts(work, DECK_NAME, min_loops=3)
    members = 1 if case.particles.shape == "sphere" else case.particles.grain.count
    bal = read_balance(work / BALANCE_FILE, members)
    m = grain_mass(case)
    rates, _ = discharge_per_cycle(bal, period, 0.0, m)
    cycles = rates.size
    ends = period * np.arange(1, cycles + 1)
    held = np.interp(ends, bal.tau, bal.in_trough) * m
    rate, rate_se = replicas.series_mean(rates[s : s + c])
    hold, hold_se = replicas.series_mean(held[s : s + c])
    v, v_se = liggghts_velocity(work, case)
    print(
        f"  LIGGGHTS {name}: discharge {rate:.4f} +- {rate_se:.4f} kg/s, hold-up "
        f"{hold:.4f} +- {hold_se:.4f} kg ({run.wall_s:.0f} s)"
    )
    return {
        "version": run.version,
        "deck": str(deck.relative_to(ROOT)),
        "command": f"cd {work.relative_to(ROOT)} && liggghts -in {DECK_NAME}",
        "discharge_rate": rate,
        "discharge_rate_stderr": rate_se,
        "hold_up_kg": hold,
        "hold_up_stderr": hold_se,
        "per_cycle_discharge": rates.tolist(),
        "per_cycle_hold_up": held.tolist(),
        "mean_velocity": v,
        "mean_velocity_stderr": v_se,
        "charge_grains": bal.charge,
        "grains_fed": float(bal.fed[-1]),
        "feed_time_s": float(bal.tau[-1]),
        "loop_times_s": [x.seconds for x in run.loop_times],
        "loop_steps": [x.steps for x in run.loop_times],
        "wall_time_s": run.wall_s,
    }


def liggghts_velocity(work: Path, case) -> tuple[float, float]:
    """Mean x-velocity of the grains over the measured cycles in vx_mean.txt, and its se.

    The windows (1/SAMPLES_PER_CYCLE of a cycle) ending in each measured cycle are averaged
    into per-cycle means; the drive starts at the step in the deck's ``tau`` variable.
    """
    start = pair.drive_start_step(work / DECK_NAME)
    data = np.loadtxt(work / VX_FILE, comments="#", ndmin=2)
    tau = (data[:, 0] - start) * case.run.timestep
    period = 1.0 / case.drive.frequency
    s, c = case.run.settle_cycles, case.run.cycles
    k = np.floor(tau / period - 1e-9).astype(int)  # the cycle each window ends in
    per_cycle = [float(data[k == j, 1].mean()) for j in range(s, s + c) if np.any(k == j)]
    return replicas.series_mean(per_cycle)


def run_dem(name: str, case, args) -> dict:
    from dem.io.hdf5 import read_results

    out = Path(args.scratch) / "dem" / name
    dem = pair.run_dem(case, out, threads=1, cycles=case.run.cycles)
    summary, wall = dem.summary, dem.wall_s
    cyc = read_results(out / "results.h5")["cycles"]
    rates, held = cyc["discharge_rate"], cyc["mass_in_trough"]
    s, c = summary["settle_cycles"], case.run.cycles
    rate, rate_se = replicas.series_mean(rates[s : s + c])
    hold, hold_se = replicas.series_mean(held[s : s + c])
    f = summary["feeder"]
    print(
        f"  dem      {name}: discharge {rate:.4f} +- {rate_se:.4f} kg/s, hold-up "
        f"{hold:.4f} +- {hold_se:.4f} kg ({wall:.0f} s)"
    )
    return {
        "command": (
            f"dem.run.runner.run_case(case, {out.relative_to(ROOT)}, cycles={c}, threads=1, "
            "progress=False, overwrite=True, frames=False)"
        ),
        "discharge_rate": rate,
        "discharge_rate_stderr": rate_se,
        "summary_discharge_rate": f["discharge_rate"],
        "hold_up_kg": hold,
        "hold_up_stderr": hold_se,
        "per_cycle_discharge": rates.tolist(),
        "per_cycle_hold_up": held.tolist(),
        "grains_inserted": f["grains_inserted"],
        "mean_velocity": summary["mean_velocity"],
        "mean_velocity_stderr": summary["mean_velocity_stderr"],
        "particle_steps_per_s": summary.get("particle_steps_per_s"),
        "wall_time_s": wall,
    }


def compare(entry: dict, lig: dict | None = None) -> None:
    """entry["difference"]: dem - LIGGGHTS (the entry's own LIGGGHTS run, or the one given)."""
    dem, lig = entry.get("dem", {}), lig or entry.get("liggghts", {})
    if "hold_up_kg" not in dem or "hold_up_kg" not in lig:
        return
    out = {}
    errors = {"discharge_rate": "discharge_rate_stderr", "hold_up_kg": "hold_up_stderr",
              "mean_velocity": "mean_velocity_stderr"}  # fmt: skip
    for key, se in errors.items():
        if key not in lig:
            continue
        out[key] = replicas.difference(dem[key], dem[se], lig[key], lig[se])
    entry["difference"] = out


def pooled(results: dict) -> dict:
    """Per case over its seeds: each code's mean and seed-to-seed standard error."""
    kinds: dict[str, list[dict]] = {}
    for name, entry in results["cases"].items():
        if "difference" in entry and "dem_of" not in entry:
            kinds.setdefault(name.split("-seed")[0], []).append(entry)
    out = {}
    for kind, entries in kinds.items():
        row = {"seeds": sorted(e["seed"] for e in entries)}
        for code in ("dem", "liggghts"):
            for key in ("discharge_rate", "hold_up_kg", "mean_velocity"):
                if any(key not in e[code] for e in entries):
                    continue
                v = np.array([e[code][key] for e in entries])
                row[f"{code}_{key}"] = float(v.mean())
                if v.size > 1:
                    row[f"{code}_{key}_seed_stderr"] = replicas.replica_stderr(v)
        if len(entries) > 1:
            for key in ("discharge_rate", "hold_up_kg", "mean_velocity"):
                if f"dem_{key}_seed_stderr" not in row or f"liggghts_{key}_seed_stderr" not in row:
                    continue
                d = row[f"dem_{key}"] - row[f"liggghts_{key}"]
                sig = math.hypot(row[f"dem_{key}_seed_stderr"], row[f"liggghts_{key}_seed_stderr"])
                row[f"{key}_percent"] = 100.0 * d / row[f"liggghts_{key}"]
                row[f"{key}_sigma"] = d / sig if sig > 0 else math.nan
        out[kind] = row
    return out


def figure(results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = sorted(
        n for n, e in results["cases"].items() if "difference" in e and "dem_of" not in e
    )
    kinds = sorted({n.split("-seed")[0] for n in names})
    fig, axes = plt.subplots(2, len(kinds), figsize=(6 * len(kinds), 7), squeeze=False)
    colours = {"dem": "C0", "liggghts": "C3"}
    for col, kind in enumerate(kinds):
        for name in (n for n in names if n.split("-seed")[0] == kind):
            e = results["cases"][name]
            for code in ("dem", "liggghts"):
                rate = np.asarray(e[code]["per_cycle_discharge"])
                held = np.asarray(e[code]["per_cycle_hold_up"])
                t = (np.arange(rate.size) + 1) / e["frequency"]
                k = 10  # 10-cycle running mean of the discharge
                smooth = np.convolve(rate, np.ones(k) / k, mode="valid")
                first = name == next(n for n in names if n.split("-seed")[0] == kind)
                label = ("dem" if code == "dem" else "LIGGGHTS") if first else None
                axes[0, col].plot(t[k - 1 :], smooth, color=colours[code], lw=1, label=label)
                axes[1, col].plot(t, held, color=colours[code], lw=1, label=label)
        e = results["cases"][names[0]] if names else {}
        axes[0, col].axhline(e.get("feed_rate", 0.0), color="k", ls="--", lw=0.8, label="feed")
        axes[0, col].axvline(e.get("settle_cycles", 0) / e.get("frequency", 1.0), color="grey",
                             lw=0.8)  # fmt: skip
        axes[1, col].axvline(e.get("settle_cycles", 0) / e.get("frequency", 1.0), color="grey",
                             lw=0.8)  # fmt: skip
        axes[0, col].set_title(f"{kind}: discharge (10-cycle mean), every seed")
        axes[0, col].set_ylabel("discharge, kg/s")
        axes[1, col].set_ylabel("hold-up, kg")
        axes[1, col].set_xlabel("drive time, s (grey: measuring starts)")
        axes[0, col].legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", nargs="+", default=["flat", "u-pan"], choices=["flat", "u-pan"])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--scratch", default=str(HERE / "scratch"))
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--skip-liggghts", action="store_true")
    ap.add_argument("--skip-dem", action="store_true",
                    help="rerun LIGGGHTS only, keeping the case's earlier dem run")  # fmt: skip
    ap.add_argument(
        "--feed-at-trough-rest",
        action="store_true",
        help="dem feeds grains at rest in the trough's frame, as the LIGGGHTS deck does "
        "(dem.engine.feeder.FEED_AT_LAB_REST = False); stored as <case>-trough-rest, dem only",
    )
    args = ap.parse_args(argv)
    path = HERE / "results.json"
    results = json.loads(path.read_text()) if path.exists() else {"cases": {}}
    if not args.report_only:
        if args.feed_at_trough_rest:
            import dem.engine.feeder

            dem.engine.feeder.FEED_AT_LAB_REST = False
            args.skip_liggghts = True
        for kind in args.cases:
            name = kind if args.seed == 1 else f"{kind}-seed{args.seed}"
            if args.feed_at_trough_rest:
                name += "-trough-rest"
            case, overrides = make_case(kind, args.seed)
            print(f"{name}:")
            entry = {
                "seed": args.seed,
                "overrides": overrides,
                "frequency": case.drive.frequency,
                "feed_rate": case.feeder.feed_rate,
                "settle_cycles": case.run.settle_cycles,
                "cycles": case.run.cycles,
            }
            earlier = results["cases"].get(name, {})
            if args.skip_dem and "dem" in earlier:
                entry["dem"] = earlier["dem"]
                entry["liggghts_rerun"] = "LIGGGHTS rerun with --skip-dem; dem's run kept"
            else:
                entry["dem"] = run_dem(name, case, args)
            if not args.skip_liggghts:
                entry["liggghts"] = run_liggghts_case(name, case, args)
            compare(entry)
            entry["load_average"] = list(__import__("os").getloadavg())
            results["cases"][name] = entry
            results["provenance"] = {
                "dem": __version__,
                "git": provenance.git_commit(),
                "machine": machine_info(),
                "date": time.strftime("%Y-%m-%d"),
            }
            path.write_text(json.dumps(results, indent=1))
    for name, entry in results["cases"].items():  # runs made before the velocity was read
        work = Path(args.scratch) / "liggghts" / name
        lig = entry.get("liggghts", {})
        if "discharge_rate" in lig and "mean_velocity" not in lig and (work / VX_FILE).exists():
            case, _ = make_case(name.split("-seed")[0], entry["seed"])
            lig["mean_velocity"], lig["mean_velocity_stderr"] = liggghts_velocity(work, case)
        compare(entry)
    for name, entry in results["cases"].items():  # dem fed at trough rest: against the base
        base = results["cases"].get(name.removesuffix("-trough-rest"), {})
        if name.endswith("-trough-rest") and "liggghts" in base:
            compare(entry, base["liggghts"])
            entry["dem_of"] = name.removesuffix("-trough-rest")
    results["pooled"] = pooled(results)
    path.write_text(json.dumps(results, indent=1))
    for kind, row in results["pooled"].items():
        print(kind, {k: (round(v, 5) if isinstance(v, float) else v) for k, v in row.items()})
    figure(results, HERE / "discharge.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
