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
import datetime
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))

from dem import __version__  # noqa: E402
from dem.case import load_case  # noqa: E402
from dem.io.liggghts import DECK_NAME, LOOP_RE, VERSION_RE, machine_info, write_deck  # noqa: E402


def machine() -> dict:
    """The machine, plus the load average now: the machine may be shared (fastest kept)."""
    load = [round(x, 2) for x in os.getloadavg()] if hasattr(os, "getloadavg") else None
    return machine_info() | {"load_average_at_start": load}


def wait_until_quiet(args) -> float | None:
    """Wait (up to --max-wait s) until the 1-minute load average is below --max-load.

    On a machine shared with other work a timing is only as good as the cores left to it.
    Returns the load average at the start of the timing.
    """
    if not hasattr(os, "getloadavg"):
        return None
    waited = 0.0
    while args.max_load is not None and os.getloadavg()[0] > args.max_load:
        if waited >= args.max_wait:
            print(f"load still {os.getloadavg()[0]:.2f} after {waited:.0f} s; timing anyway")
            break
        time.sleep(10.0)
        waited += 10.0
    return round(os.getloadavg()[0], 2)


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


def run_liggghts(args, case) -> dict:
    """Time LIGGGHTS on the exported deck; the rate comes from its last 'Loop time' line."""
    exe = shutil.which("liggghts")
    if exe is None:
        msg = "liggghts is not on PATH: LIGGGHTS half skipped (apt-get install -y liggghts)"
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
        command = [*prefix, exe, "-in", DECK_NAME]
        best = None
        for repeat in range(args.repeat):
            work = scratch / f"np{ranks}"
            if work.exists():
                shutil.rmtree(work)
            shutil.copytree(deck_dir, work)
            load = wait_until_quiet(args)
            done = subprocess.run(command, cwd=work, capture_output=True, text=True)
            (work / "stdout.txt").write_text(done.stdout + done.stderr)
            loops = LOOP_RE.findall(done.stdout)
            if done.returncode != 0 or not loops:
                raise SystemExit(
                    f"LIGGGHTS failed ({' '.join(command)} in {work}):\n{done.stdout[-2000:]}"
                    f"{done.stderr[-2000:]}"
                )
            found = VERSION_RE.search(done.stdout)
            version = found.group(1) if found else version
            loop_time, procs, n_steps, atoms = loops[-1]
            loop_time, n_steps, atoms = float(loop_time), int(n_steps), int(atoms)
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
                    "ranks": int(procs),
                    "command": f"cd {deck_dir.relative_to(ROOT)} && "
                    + " ".join(Path(c).name if os.path.isabs(c) else c for c in command),
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
import dataclasses, json, sys
sys.path.insert(0, {root!r})
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
                root=str(ROOT),
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
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "machine": machine(),
        "dem_version": __version__,
    }
    halves = [("liggghts", run_liggghts, args.skip_liggghts), ("dem", run_dem, args.skip_dem)]
    for name, bench, skip in halves:
        if skip:
            continue
        results[name] = {**stamp, **bench(args, case)}
        path.write_text(json.dumps(results, indent=2) + "\n")  # after each half
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
