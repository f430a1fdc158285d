"""Speed bar: particle-steps per second of LIGGGHTS and of dem on the same case.

particle-steps/s = spheres * time steps / wall time of the step loop (DESIGN.md section 3); for
screws and clumps the spheres are the clump members (LIGGGHTS's atoms under fix multisphere).

LIGGGHTS half: the case is exported with dem.io.liggghts.write_deck (fill, settle, then the
measured driven steps as the last ``run``), run on 1 rank and, if ``mpirun`` exists, on 2 ranks;
the rate comes from LIGGGHTS's own "Loop time of T on P procs for S steps with N atoms" line of the
last run, so neither start-up nor the fill is timed. Skipped with a message if ``liggghts`` is not
on PATH.

dem half: ``dem.runner.run_case`` on the same case with the same time step, 1 and 2 threads,
each in its own process (numba's thread count is fixed per process); the rate is the
``particle_steps_per_s`` of its summary.json. Skipped with a message if the engine is missing.

Each configuration runs ``--repeat`` times and the fastest is kept (the machine is shared; the
slowest runs measure the neighbours). Results are merged into results_CASE.json: a half that is
skipped keeps its previous entry; the deck is kept in liggghts_deck_CASE/.

    .venv/bin/python validation/performance/bench_bulk.py               # sphere-bed, both halves
    .venv/bin/python validation/performance/bench_bulk.py --skip-dem
    .venv/bin/python validation/performance/bench_bulk.py --case cases/screw-trough --timestep 3e-6
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
from dem.case import load_case
from dem.io.liggghts import (
    DECK_NAME,
    LIGGGHTS_INSTALL,
    find_liggghts,
    machine_info,
    run_liggghts,
    write_deck,
)

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


def bench_case(args):
    """The case with the benchmark's time step and settle length."""
    case = load_case(args.case).with_tangential("liggghts")  # the deck's convention
    run = dataclasses.replace(
        case.run, timestep=args.timestep, settle_cycles=args.settle_cycles, cycles=args.cycles
    )
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


def bench_liggghts(args, case) -> dict:
    """Time LIGGGHTS on the exported deck; the rate comes from its last 'Loop time' line."""
    if find_liggghts() is None:
        msg = f"liggghts is not on PATH: LIGGGHTS half skipped ({LIGGGHTS_INSTALL})"
        print(msg)
        return {"skipped": msg}
    deck_dir = HERE / f"liggghts_deck_{case.name}"
    steps_per_cycle = 1.0 / (case.drive.frequency * args.timestep)
    steps = round(args.cycles * steps_per_cycle)
    deck = write_deck(case, deck_dir, timestep=args.timestep, steps=steps)
    print(f"deck: {deck}")
    scratch = HERE / "scratch" / "liggghts"
    runs, version = [], None
    for ranks in args.ranks:
        prefix = mpirun_prefix(ranks)
        if prefix is None:
            print(f"mpirun not found: {ranks}-rank LIGGGHTS run skipped")
            continue
        command = " ".join(os.path.basename(c) for c in [*prefix, "liggghts", "-in", DECK_NAME])
        best = None
        for repeat in range(args.repeat):
            work = scratch / f"np{ranks}"
            if work.exists():
                shutil.rmtree(work)
            shutil.copytree(deck_dir, work)
            load = wait_until_quiet(args)
            run = run_liggghts(work, DECK_NAME, prefix=prefix)
            version = run.version or version
            loop_time, procs, n_steps, atoms = run.loop_times[-1]
            if atoms != spheres(case) or n_steps != steps:
                raise SystemExit(f"LIGGGHTS ran {atoms} atoms x {n_steps} steps, not as asked")
            rate = atoms * n_steps / loop_time
            print(
                f"LIGGGHTS {ranks} rank(s), repeat {repeat + 1}: {loop_time:.3f} s for "
                f"{n_steps} steps x {atoms} spheres = {rate:.3g} particle-steps/s "
                f"(load average {load} at start)"
            )
            if best is None or rate > best["particle_steps_per_s"]:
                best = {
                    "ranks": procs,
                    "command": f"cd {deck_dir.relative_to(ROOT)} && {command}",
                    "loop_time_s": loop_time,
                    "steps": n_steps,
                    "spheres": atoms,
                    "particle_steps_per_s": rate,
                    "load_average_at_start": load,
                }
        best["repeats"] = args.repeat
        runs.append(best)
    return {
        "version": version,
        "deck": str((deck_dir / DECK_NAME).relative_to(ROOT)),
        "timestep": args.timestep,
        "settle_cycles": args.settle_cycles,
        "measured_steps": steps,
        "timing": "last 'Loop time' line (the measured driven run), fastest of the repeats",
        "runs": runs,
    }


DEM_CHILD = """
import dataclasses
from dem.case import load_case
from dem.runner import run_case
case = load_case({case!r}).with_tangential("liggghts")
run = dataclasses.replace(case.run, timestep={dt!r}, settle_cycles={settle!r}, cycles={cycles!r})
case = dataclasses.replace(case, run=run)
run_case(case, {out!r}, cycles={cycles!r}, threads={threads!r}, progress=False,
         overwrite=True, frames=False)
"""


def run_dem(args, case) -> dict:
    """Time dem.runner.run_case, one process per thread count."""
    try:
        import dem.simulation  # noqa: F401
    except ImportError as exc:
        msg = f"dem.simulation is not available ({exc}): dem half skipped"
        print(msg)
        return {"skipped": msg}
    runs = []
    for threads in args.threads:
        best = None
        for repeat in range(args.repeat):
            out = HERE / "scratch" / "dem" / f"threads{threads}"
            code = DEM_CHILD.format(
                case=str(Path(args.case).resolve()),
                dt=args.timestep,
                settle=args.settle_cycles,
                cycles=args.cycles,
                out=str(out),
                threads=threads,
            )
            env = {**os.environ, "NUMBA_NUM_THREADS": str(threads)}
            load = wait_until_quiet(args)
            try:
                subprocess.run(
                    [sys.executable, "-c", code], check=True, env=env, timeout=args.dem_timeout
                )
            except subprocess.TimeoutExpired:
                msg = f"dem with {threads} thread(s) did not finish in {args.dem_timeout} s"
                print(msg)
                best = {"threads": threads, "failed": msg}
                break
            summary = json.loads((out / "summary.json").read_text())
            rate = summary["particle_steps_per_s"]
            print(
                f"dem {threads} thread(s), repeat {repeat + 1}: {rate:.3g} particle-steps/s "
                f"(load average {load} at start)"
            )
            if best is None or rate > best["particle_steps_per_s"]:
                best = {
                    "threads": threads,
                    "particle_steps_per_s": rate,
                    "steps": summary["steps"],
                    "timestep": summary["timestep"],
                    "wall_time_s": summary["wall_time_s"],
                    "spheres": summary.get("spheres"),
                    "load_average_at_start": load,
                }
        best["repeats"] = args.repeat
        runs.append(best)
    return {
        "command": "validation/performance/bench_bulk.py (dem.runner.run_case, "
        "NUMBA_NUM_THREADS = threads)",
        "timestep": args.timestep,
        "settle_cycles": args.settle_cycles,
        "cycles": args.cycles,
        "runs": runs,
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", default=str(ROOT / "cases" / "sphere-bed"))
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
    halves = [("liggghts", bench_liggghts, args.skip_liggghts), ("dem", run_dem, args.skip_dem)]
    for name, bench, skip in halves:
        if skip:
            continue
        results[name] = {**stamp, **bench(args, case)}
        path.write_text(json.dumps(results, indent=2) + "\n")  # after each half
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
