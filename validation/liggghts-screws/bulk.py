"""Part A, bulk: 200 screws of cases/screw-trough in LIGGGHTS and in dem, per-cycle velocities.

Both codes get the same explicit time step, restitution and cycles (run.py's docstring and
README.md, section A). LIGGGHTS's windowed mean x-velocity of the bodies' centres of mass is
grouped into blocks of one drive period; dem's per-cycle means come from ``run_case``.
"""

from __future__ import annotations

import dataclasses
import re
import sys
from pathlib import Path

import numpy as np
from study import AS_MEASURED, CASE, DECKS, SCRATCH, fresh_copy, rel, write_results

from dem import provenance
from dem.io.liggghts import DECK_NAME, VX_FILE, run_liggghts, write_deck
from dem.scene.case import load_case
from dem.scene.timestep import timestep_for

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from validation._lib import pair, replicas  # noqa: E402

BULK_RESTITUTION = 0.06  # both codes; LIGGGHTS refuses e <= 0.05
BULK_SETTLE_CYCLES = 5
BULK_CYCLES = 10
BULK_SEEDS = (1, 2, 3)
BULK_LOCKED_SEED = 1
# Both codes get the same explicit step: 1/5482 of the 60 Hz period = 3.0402529490453606e-06 s,
# dem's automatic step for this case at commit 425bb6c (the hand runs). Pinned because dem's
# automatic clump step is being changed (6.36e-6 s in the working tree of 2026-11-21 17:50 UTC).
# The second value, twice as long, checks how much the comparison depends on dt.
BULK_STEPS_PER_PERIOD = (5482, 2741)
RUN_RE = re.compile(r"^run (\d+)", re.MULTILINE)


def bulk_cases() -> dict:
    """Seeds 1-3 with rotation and seed 1 with rotation locked, at each pinned time step."""
    base = load_case(CASE, AS_MEASURED)
    out = {}
    for k, per_period in enumerate(BULK_STEPS_PER_PERIOD):
        dt = 1.0 / (base.drive.frequency * per_period)
        for seed, rotation in [(s, True) for s in BULK_SEEDS] + [(BULK_LOCKED_SEED, False)]:
            case = dataclasses.replace(
                base.with_tangential("liggghts"),
                material=dataclasses.replace(base.material, restitution_normal=BULK_RESTITUTION),
                particles=dataclasses.replace(base.particles, rotation=rotation),
                run=dataclasses.replace(
                    base.run,
                    settle_cycles=BULK_SETTLE_CYCLES,
                    cycles=BULK_CYCLES,
                    seed=seed,
                    timestep=dt,
                ),
            )
            tag = f"seed{seed}" + ("" if rotation else "_rotlocked") + ("" if k == 0 else "_dt2x")
            out[tag] = case
    return out


def bulk_liggghts(case, tag: str, dt: float, edit=None) -> dict:
    """LIGGGHTS on the case's deck; per-cycle means from blocks of frames_per_cycle windows.

    ``edit``, if given, takes the deck's text and returns the text to run (extra output).
    """
    f, fpc = case.drive.frequency, case.output.frames_per_cycle
    steps = round(case.run.cycles / f / dt)
    deck_dir = DECKS / f"bulk_{tag}"
    deck = write_deck(case, deck_dir, timestep=dt, steps=steps)
    if edit is not None:
        deck.write_text(edit(deck.read_text()))
    runs = [int(n) for n in RUN_RE.findall(deck.read_text())]
    if len(runs) != 3:
        raise SystemExit(f"{deck}: expected three 'run N' lines (fill, settle, measure): {runs}")
    fill, settle, measured = runs
    work = SCRATCH / "liggghts" / f"bulk_{tag}"
    fresh_copy(deck_dir, work)
    run = run_liggghts(work, DECK_NAME)
    atoms = run.loop_times[-1].atoms
    members = case.particles.count * case.particles.grain.count
    if atoms != members:
        raise SystemExit(f"LIGGGHTS kept {atoms} spheres, not {members}")
    data = np.loadtxt(work / VX_FILE, comments="#", ndmin=2)
    start, end = fill + settle, fill + settle + measured
    inside = (data[:, 0] > start) & (data[:, 0] <= end)
    windows = data[inside]
    n_win = case.run.cycles * fpc
    if len(windows) < n_win:
        raise SystemExit(f"{work / VX_FILE}: {len(windows)} measured windows, not {n_win}")
    windows = windows[:n_win]
    sample = int(round(windows[1, 0] - windows[0, 0]))
    per_cycle = windows[:, 1].reshape(case.run.cycles, fpc).mean(axis=1)
    mean, stderr = replicas.series_mean(per_cycle)
    print(f"  LIGGGHTS {tag}: v = {mean:.5f} +- {stderr:.5f} m/s ({run.wall_s:.0f} s)")
    return {
        "version": run.version,
        "deck": rel(deck),
        "command": f"cd {rel(work)} && liggghts -in {DECK_NAME}",
        "write_deck": f"write_deck(case, {rel(deck_dir)}, timestep={dt!r}, steps={steps})",
        "timestep": dt,
        "fill_steps": fill,
        "settle_steps": settle,
        "measured_steps": measured,
        "window_steps": sample,
        "first_window_end_step": int(windows[0, 0]),
        "windows_per_cycle": fpc,
        "mean_velocity": mean,
        "mean_velocity_stderr": stderr,
        "per_cycle_velocity": [float(u) for u in per_cycle],
        "loop_times_s": [x.seconds for x in run.loop_times],
        "wall_time_s": run.wall_s,
    }


def bulk_dem(case, tag: str) -> dict:
    """dem's ``run_case`` on one thread (own fill and settling); its summary's numbers."""
    out = SCRATCH / "dem" / f"bulk_{tag}"
    dem = pair.run_dem(case, out, threads=1)
    s, wall = dem.summary, dem.wall_s
    print(f"  dem      {tag}: v = {s['mean_velocity']:.5f} +- {s['mean_velocity_stderr']:.5f} "
          f"m/s ({wall:.0f} s)")  # fmt: skip
    keys = (
        "mean_velocity", "mean_velocity_stderr", "mean_velocity_norm", "per_cycle_velocity",
        "timestep", "timestep_limit", "steps", "settle_time_s", "settle_wall_time_s",
        "wall_time_s", "threads", "pointmass_velocity_norm",
    )  # fmt: skip
    return {
        "command": f"run_case(case, {rel(out)}, threads=1, progress=False, frames=False, "
        "overwrite=True)",
        **{k: s[k] for k in keys},
        "total_wall_time_s": wall,
    }


def part_bulk(results: dict) -> None:
    """Every bulk run of both codes into ``results["bulk"]``; results.json after each."""
    section = results.setdefault("bulk", {})
    section.update(
        {
            "case": rel(CASE),
            "restitution_normal": BULK_RESTITUTION,
            "settle_cycles": BULK_SETTLE_CYCLES,
            "cycles": BULK_CYCLES,
        }
    )
    runs = section.setdefault("runs", {})
    cases = bulk_cases()
    first = next(iter(cases.values()))
    auto = timestep_for(
        dataclasses.replace(first, run=dataclasses.replace(first.run, timestep=None))
    )
    section["dem_automatic_timestep_now"] = auto.dt  # for the record only; not used
    for tag, case in cases.items():
        dt = case.run.timestep  # pinned, the same in both codes
        print(f"bulk {tag}: rotation {case.particles.rotation}, dt = {dt:.6g} s")
        d = case.drive
        entry = {
            "date": provenance.utc_now(),
            "seed": case.run.seed,
            "rotation": case.particles.rotation,
            "v_norm": d.velocity_scale,  # the velocity scale (m/s) v is normalised by
            "liggghts": bulk_liggghts(case, tag, dt),
            "dem": bulk_dem(case, tag),
        }
        entry["pointmass_velocity_norm"] = entry["dem"]["pointmass_velocity_norm"]
        lig, dem = entry["liggghts"], entry["dem"]
        d = replicas.difference(
            dem["mean_velocity"], dem["mean_velocity_stderr"],
            lig["mean_velocity"], lig["mean_velocity_stderr"],
        )  # fmt: skip
        entry["dem_minus_liggghts"] = {
            "m_per_s": d["dem_minus_liggghts"],
            "percent": d["percent_of_liggghts"],
            "sigma": d["sigma"],
        }
        runs[tag] = entry
        write_results(results)
    for suffix in ("", "_dt2x"):
        free = [runs[f"seed{s}{suffix}"] for s in BULK_SEEDS if f"seed{s}{suffix}" in runs]
        if len(free) < 2:
            continue
        lv = np.array([r["liggghts"]["mean_velocity"] for r in free])
        dv = np.array([r["dem"]["mean_velocity"] for r in free])
        section["seeds_pooled" + suffix] = {
            "liggghts_mean": float(lv.mean()),
            "liggghts_seed_stderr": replicas.replica_stderr(lv),
            "dem_mean": float(dv.mean()),
            "dem_seed_stderr": replicas.replica_stderr(dv),
            "percent": float(100.0 * (dv.mean() - lv.mean()) / lv.mean()),
        }
    write_results(results)
